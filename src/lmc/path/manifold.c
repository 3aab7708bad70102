/*
 * manifold.c: the manifold walk (Jakob and Marschner 2012); see
 * manifold.h for the chain, its constraints, the walk and the generalized
 * geometry term, and docs/manifold.md for the derivations.
 *
 * Frames and conventions: directions point away from the surface; each
 * vertex's tangent frame is frame_from_z of its shading normal (the
 * shading frame scene_intersect makes where no bump map or anisotropic
 * lobe turns it); eta is intIOR / extIOR, the shading normal pointing to
 * the ext side. Every vertex is re-evaluated from (mesh, triangle,
 * barycentrics) with the formulas of scene_intersect and mesh_hit_normals
 * ("locate, then re-evaluate", as path.c does), in plain doubles for the
 * constraint values and in duals (src/ad) for the Jacobian blocks.
 * After a direction start, x_0 is at infinity: wi at x_1 is -d, and the
 * projection's ray comes along d from outside the bounding sphere. The
 * last section reads chains from path-space paths (pathspace.h) and
 * writes walked chains back into them.
 */
#include "lmc/path/manifold.h"

#include <math.h>
#include <string.h>

#include "ad/dual.h"
#include "ad/dual_math.h"
#include "ad/dual_vec3.h"
#include "render/bsdf/bsdf_model.h"

/* Duals one constraint makes (about 70; room to spare). */
#define MF__ARENA_DUALS 256
/* Tangent length: the barycentrics of x_{i-1}, x_i, x_{i+1}. */
#define MF__NVAR 6
/* The arena's doubles: MF__ARENA_DUALS tangents of MF__NVAR padded to
 * AD_LANES (8), plus the zero tangent (ad_arena_size). */
#define MF__ARENA_DOUBLES (8 * (MF__ARENA_DUALS + 1))
/* A 2 x 2 array as the const pointer the helpers take. */
#define MF__C2(x) ((const double(*)[2])(x))

const char *mf_status_str(int status) {
  switch (status) {
#define MF__STATUS_TEXT(name, value, text) \
  case value:                              \
    return text;
    MF_STATUS_MAP(MF__STATUS_TEXT)
#undef MF__STATUS_TEXT
  default:
    return "unknown status";
  }
}

void mf_options_default(const scene *sc, mf_options *OUT) {
  OUT->tol = 1e-7 * (sc && sc->radius > 0.0 ? sc->radius : 1.0);
  OUT->max_traces = 64;
  OUT->min_beta = 1.0 / (1 << 20);
  OUT->off_start = 0;
}

/* ---- Vertices in plain arithmetic ------------------------------------------ */

/* The mesh and triangle of v, or NULL when they do not exist. */
static const mesh *mf__mesh(const scene *sc, const mf_vertex *v) {
  if (v->mesh < 0 || v->mesh >= sc->n_meshes) return NULL;
  const mesh *m = &sc->meshes[v->mesh];
  if (v->prim < 0 || v->prim >= m->n_triangles) return NULL;
  return m;
}

/* A vertex's corners, position, normals (mesh_hit_normals) and the edge
 * vectors e1 = p1 - p0, e2 = p2 - p0 (dp / db1, dp / db2). */
typedef struct mf__geo {
  vec3 p, ns, ng, e1, e2;
} mf__geo;

static int mf__geom(const scene *sc, const mf_vertex *v, mf__geo *g) {
  const mesh *m = mf__mesh(sc, v);
  if (!m) return 0;
  const uint32_t *tri = m->idx + 3 * v->prim;
  vec3 p0 = mesh_position(m, tri[0]), p1 = mesh_position(m, tri[1]), p2 = mesh_position(m, tri[2]);
  double b0 = 1.0 - v->b1 - v->b2;
  /* scene_intersect's point and normals. */
  g->p = v3_add(v3_add(v3_scale(p0, b0), v3_scale(p1, v->b1)), v3_scale(p2, v->b2));
  g->ng = mesh_hit_normals(m, v->prim, p0, p1, p2, v->b1, v->b2, &g->ns);
  g->e1 = v3_sub(p1, p0);
  g->e2 = v3_sub(p2, p0);
  return 1;
}

int mf_vertex_set(const scene *sc, mf_vertex *v, int mi, int64_t prim, double b1, double b2) {
  mf_vertex t = *v;
  t.mesh = mi;
  t.prim = prim;
  t.b1 = b1;
  t.b2 = b2;
  mf__geo g;
  if (!mf__geom(sc, &t, &g)) return MF_EINVAL;
  t.p = g.p;
  t.ns = g.ns;
  t.ng = g.ng;
  *v = t;
  return MF_OK;
}

static int mf__chain_ok(const mf_chain *c) {
  if (!c || c->k < 1 || c->k > MF_MAX_CHAIN) return 0;
  if (c->start == MF_START_POINT) return v3_isfinite(c->x0);
  return c->start == MF_START_DIRECTION && v3_isfinite(c->d) && v3_len2(c->d) > 0.0;
}

/* wi at x_1 after a direction start: against the first segment's travel. */
static vec3 mf__start_wi(const mf_chain *c) { return v3_neg(v3_normalize(c->d)); }

/* The relative index eta_r of a vertex for wi on the side of ns given by
 * cos_wi_ns: 1 for a reflection; for a refraction the index on wo's side
 * over the index on wi's side. */
static double mf__eta_r(const mf_vertex *v, double cos_wi_ns) {
  if (v->kind != MF_REFRACT) return 1.0;
  return cos_wi_ns > 0.0 ? v->eta : 1.0 / v->eta;
}

int mf_half_vector(const scene *sc, const mf_chain *c, int i, double OUT[2]) {
  if (!mf__chain_ok(c) || i < 1 || i > c->k) return MF_EINVAL;
  /* The three vertices. */
  mf__geo gp, gi, gn;
  if (i > 1 && !mf__geom(sc, &c->v[i - 1], &gp)) return MF_EINVAL;
  if (!mf__geom(sc, &c->v[i], &gi) || !mf__geom(sc, &c->v[i + 1], &gn)) return MF_EINVAL;
  /* wi towards x_{i-1} (against d after a direction start). */
  vec3 wi = i == 1 && c->start == MF_START_DIRECTION
                ? mf__start_wi(c)
                : v3_normalize(v3_sub(i > 1 ? gp.p : c->x0, gi.p));
  mf_vertex v = c->v[i];
  v.ns = gi.ns;
  mf_half_vector_dirs(&v, wi, v3_normalize(v3_sub(gn.p, gi.p)), OUT);
  return MF_OK;
}

/* h = normalize(wi + eta_r wo) on the side of ns, and |wi + eta_r wo|. */
static vec3 mf__half(const mf_vertex *v, vec3 wi, vec3 wo, double *OUT_len, double *OUT_eta_r) {
  double eta_r = mf__eta_r(v, v3_dot(wi, v->ns));
  vec3 ht = v3_add(wi, v3_scale(wo, eta_r));
  double len = v3_len(ht);
  vec3 h = v3_scale(ht, 1.0 / len);
  if (OUT_len) *OUT_len = len;
  if (OUT_eta_r) *OUT_eta_r = eta_r;
  return v3_dot(h, v->ns) < 0.0 ? v3_neg(h) : h;
}

void mf_half_vector_dirs(const mf_vertex *v, vec3 wi, vec3 wo, double OUT[2]) {
  vec3 h = mf__half(v, wi, wo, NULL, NULL);
  /* Its projection on the shading frame's tangent plane. */
  frame f = frame_from_z(v->ns);
  OUT[0] = v3_dot(h, f.s);
  OUT[1] = v3_dot(h, f.t);
}

double mf_half_vector_dir_jacobian(const mf_vertex *v, vec3 wi, vec3 wo) {
  double len, eta_r;
  vec3 h = mf__half(v, wi, wo, &len, &eta_r);
  /* dh = +-(I - h h^T) eta_r dwo / len; dwo = a t1 + b t2 on wo's tangent
   * plane; the 2 x 2 matrix of (dh . s, dh . t) over (a, b). */
  frame f = frame_from_z(v->ns), g = frame_from_z(wo);
  double M[2][2];
  vec3 rows[2] = {f.s, f.t}, cols[2] = {g.s, g.t};
  for (int r = 0; r < 2; r++)
    for (int q = 0; q < 2; q++)
      M[r][q] = v3_dot(rows[r], cols[q]) - v3_dot(rows[r], h) * v3_dot(h, cols[q]);
  double k = eta_r / len;
  return k * k * fabs(M[0][0] * M[1][1] - M[0][1] * M[1][0]);
}

int mf_constraint(const scene *sc, const mf_chain *c, int i, double OUT[2]) {
  int st = mf_half_vector(sc, c, i, OUT);
  if (st != MF_OK) return st;
  OUT[0] -= c->v[i].target[0];
  OUT[1] -= c->v[i].target[1];
  return MF_OK;
}

/* ---- Vertices and constraints in duals --------------------------------------- */

static vec3 mf__val(adv3 a) { return v3(a.x.v, a.y.v, a.z.v); }

/* a + b1 u + b2 w per component (a, u, w constant vectors). */
static adv3 mf__affine(ad_arena *A, vec3 a, vec3 u, vec3 w, ad b1, ad b2) {
  return (adv3){ad_add_s(A, ad_lincomb(A, u.x, b1, w.x, b2), a.x),
                ad_add_s(A, ad_lincomb(A, u.y, b1, w.y, b2), a.y),
                ad_add_s(A, ad_lincomb(A, u.z, b1, w.z, b2), a.z)};
}

/* Vertex v re-evaluated on its triangle in duals: its barycentrics are the
 * variables var0 and var0 + 1; p = p0 + b1 e1 + b2 e2 and (when ns is not
 * NULL) the shading normal normalize(n0 + b1 (n1 - n0) + b2 (n2 - n0)), or
 * the constant winding normal, as mesh_hit_normals. */
static void mf__vertex_ad(ad_arena *A, const mesh *m, const mf_vertex *v, int var0, adv3 *p,
                          adv3 *ns) {
  const uint32_t *tri = m->idx + 3 * v->prim;
  vec3 p0 = mesh_position(m, tri[0]), p1 = mesh_position(m, tri[1]), p2 = mesh_position(m, tri[2]);
  ad b1 = ad_var(A, v->b1, var0), b2 = ad_var(A, v->b2, var0 + 1);
  *p = mf__affine(A, p0, v3_sub(p1, p0), v3_sub(p2, p0), b1, b2);
  if (!ns) return;
  vec3 ng = mesh_corners_normal(m, p0, p1, p2);
  adv3 n = adv3_const(A, ng.x, ng.y, ng.z);
  if (mesh_uses_vertex_normals(m)) {
    vec3 n0 = mesh_vertex_normal(m, tri[0]), n1 = mesh_vertex_normal(m, tri[1]),
         n2 = mesh_vertex_normal(m, tri[2]);
    adv3 ni = mf__affine(A, n0, v3_sub(n1, n0), v3_sub(n2, n0), b1, b2);
    if (v3_len(mf__val(ni)) > 1e-12) n = adv3_normalize(A, ni);
  }
  *ns = n;
}

/* c_i in duals (variables 0, 1: x_{i-1}; 2, 3: x_i; 4, 5: x_{i+1}). */
static void mf__constraint_ad(ad_arena *A, const scene *sc, const mf_chain *c, int i, ad OUT[2]) {
  const mf_vertex *vi = &c->v[i];
  adv3 xp, xi, xn, ns;
  int dir_start = i == 1 && c->start == MF_START_DIRECTION;
  if (i > 1)
    mf__vertex_ad(A, &sc->meshes[c->v[i - 1].mesh], &c->v[i - 1], 0, &xp, NULL);
  else
    xp = adv3_const(A, c->x0.x, c->x0.y, c->x0.z);
  mf__vertex_ad(A, &sc->meshes[vi->mesh], vi, 2, &xi, &ns);
  mf__vertex_ad(A, &sc->meshes[c->v[i + 1].mesh], &c->v[i + 1], 4, &xn, NULL);

  /* The directions away from x_i; after a direction start wi = -d, a
   * constant (A_1 = 0 either way). */
  vec3 wd = dir_start ? mf__start_wi(c) : v3(0.0, 0.0, 0.0);
  adv3 wi = dir_start ? adv3_const(A, wd.x, wd.y, wd.z) : adv3_normalize(A, adv3_sub(A, xp, xi));
  adv3 wo = adv3_normalize(A, adv3_sub(A, xn, xi));

  /* h = normalize(wi + eta_r wo), turned to ns's side (a choice on values). */
  double eta_r = mf__eta_r(vi, v3_dot(mf__val(wi), mf__val(ns)));
  adv3 h = adv3_normalize(A, adv3_add(A, wi, adv3_scale_s(A, wo, eta_r)));
  if (v3_dot(mf__val(h), mf__val(ns)) < 0.0) h = adv3_neg(A, h);

  /* Projection on the shading frame's tangent axes, minus the target. */
  ad_frame f = adv3_frame_from_z(A, ns);
  OUT[0] = ad_sub_s(A, adv3_dot(A, h, f.s), vi->target[0]);
  OUT[1] = ad_sub_s(A, adv3_dot(A, h, f.t), vi->target[1]);
}

static int mf__chain_valid(const scene *sc, const mf_chain *c) {
  if (!mf__chain_ok(c)) return 0;
  for (int i = 1; i <= c->k + 1; i++) {
    if (!mf__mesh(sc, &c->v[i])) return 0;
    if (i <= c->k && c->v[i].kind == MF_REFRACT && !(c->v[i].eta > 0.0)) return 0;
  }
  return 1;
}

int mf_jacobian(const scene *sc, const mf_chain *c, mf_jac *OUT) {
  if (!mf__chain_valid(sc, c)) return MF_EINVAL;
  double buf[MF__ARENA_DOUBLES];
  ad_arena A;
  if (ad_arena_init(&A, buf, sizeof buf / sizeof buf[0], MF__NVAR) != 0) return MF_EINVAL;
  memset(OUT, 0, sizeof *OUT);
  OUT->k = c->k;
  for (int i = 1; i <= c->k; i++) {
    ad_arena_reset(&A);
    ad ci[2];
    mf__constraint_ad(&A, sc, c, i, ci);
    if (!ad_arena_ok(&A)) return MF_EINVAL; /* unreachable: the arena holds a constraint */
    for (int r = 0; r < 2; r++) {
      OUT->c[i][r] = ci[r].v;
      for (int j = 0; j < 2; j++) {
        OUT->A[i][r][j] = i > 1 ? ad_deriv(&A, ci[r], j) : 0.0;
        OUT->B[i][r][j] = ad_deriv(&A, ci[r], 2 + j);
        OUT->C[i][r][j] = ad_deriv(&A, ci[r], 4 + j);
      }
    }
  }
  return MF_OK;
}

/* ---- The block tridiagonal solve ------------------------------------------------ */

/* The inverse of a 2 x 2 matrix; 0 when it is singular (its determinant
 * below 1e-14 of the size of its products, or not finite). */
static int mf__inv2(const double M[2][2], double R[2][2]) {
  double det = M[0][0] * M[1][1] - M[0][1] * M[1][0];
  double scale = fabs(M[0][0] * M[1][1]) + fabs(M[0][1] * M[1][0]);
  if (!isfinite(det) || !(fabs(det) > 1e-14 * scale) || !(scale > 0.0)) return 0;
  double id = 1.0 / det;
  R[0][0] = M[1][1] * id;
  R[0][1] = -M[0][1] * id;
  R[1][0] = -M[1][0] * id;
  R[1][1] = M[0][0] * id;
  return 1;
}

static void mf__mul2(const double X[2][2], const double Y[2][2], double R[2][2]) {
  double t[2][2];
  for (int r = 0; r < 2; r++)
    for (int c = 0; c < 2; c++) t[r][c] = X[r][0] * Y[0][c] + X[r][1] * Y[1][c];
  memcpy(R, t, sizeof t);
}

static void mf__mulv(const double X[2][2], const double v[2], double out[2]) {
  double a = X[0][0] * v[0] + X[0][1] * v[1], b = X[1][0] * v[0] + X[1][1] * v[1];
  out[0] = a;
  out[1] = b;
}

int mf_solve(const mf_jac *J, const double *r, const double d_end[2], double *OUT_d) {
  int k = J->k;
  if (k < 1 || k > MF_MAX_CHAIN) return MF_EINVAL;
  /* Forward elimination: Bp_i = B_i - A_i Bp_{i-1}^-1 C_{i-1},
   * y_i = r_i - A_i Bp_{i-1}^-1 y_{i-1}; the last right-hand side less
   * C_k d_{k+1}. Bp_i^-1 is kept for the back substitution. */
  double Binv[MF_MAX_CHAIN + 1][2][2], y[MF_MAX_CHAIN + 1][2];
  for (int i = 1; i <= k; i++) {
    double Bp[2][2];
    memcpy(Bp, J->B[i], sizeof Bp);
    y[i][0] = r ? r[2 * i] : 0.0;
    y[i][1] = r ? r[2 * i + 1] : 0.0;
    if (i == k) {
      double cd[2];
      mf__mulv(J->C[k], d_end, cd);
      y[i][0] -= cd[0];
      y[i][1] -= cd[1];
    }
    if (i > 1) {
      double L[2][2], LC[2][2], Ly[2];
      mf__mul2(J->A[i], MF__C2(Binv[i - 1]), L);
      mf__mul2(MF__C2(L), J->C[i - 1], LC);
      mf__mulv(MF__C2(L), y[i - 1], Ly);
      for (int a = 0; a < 2; a++) {
        for (int b = 0; b < 2; b++) Bp[a][b] -= LC[a][b];
        y[i][a] -= Ly[a];
      }
    }
    if (!mf__inv2(MF__C2(Bp), Binv[i])) return MF_ESINGULAR;
  }
  /* Back substitution: d_i = Bp_i^-1 (y_i - C_i d_{i+1}). */
  OUT_d[0] = OUT_d[1] = 0.0;
  mf__mulv(MF__C2(Binv[k]), y[k], OUT_d + 2 * k);
  for (int i = k - 1; i >= 1; i--) {
    double cd[2], t[2];
    mf__mulv(J->C[i], OUT_d + 2 * (i + 1), cd);
    t[0] = y[i][0] - cd[0];
    t[1] = y[i][1] - cd[1];
    mf__mulv(MF__C2(Binv[i]), t, OUT_d + 2 * i);
  }
  return MF_OK;
}

/* ---- Projection: tracing a chain --------------------------------------------- */

/* Refraction of wi about the unit normal n with relative index eta = int/ext
 * (n towards ext), the formula of adv3_refract: with sigma the side of wi,
 * e = eta or 1 / eta, c = sigma (wi . n), cos_t^2 = 1 - (1 - c^2) / e^2,
 * wt = -wi / e + (c / e - cos_t) sigma n. 0 on total internal reflection. */
static int mf__refract(vec3 wi, vec3 n, double eta, vec3 *wt) {
  double cos_wn = v3_dot(wi, n);
  double sigma = cos_wn < 0.0 ? -1.0 : 1.0;
  double e = sigma > 0.0 ? eta : 1.0 / eta;
  double c = sigma * cos_wn;
  double cos_t2 = 1.0 - (1.0 - c * c) / (e * e);
  if (!(cos_t2 > 0.0)) return 0;
  double cos_t = sqrt(cos_t2);
  *wt = v3_add(v3_scale(wi, -1.0 / e), v3_scale(n, sigma * (c / e - cos_t)));
  return 1;
}

/* The distance s back along the unit direction d from x to a point
 * outside the bounding sphere: (x - center) . d + 2 radius. */
static double mf__far_back(const scene *sc, vec3 d, vec3 x) {
  return v3_dot(v3_sub(x, sc->center), d) + 2.0 * sc->radius;
}

int mf_start_ray(const scene *sc, const mf_chain *c, vec3 x1, vec3 *OUT_org, vec3 *OUT_dir) {
  if (!mf__chain_ok(c) || !v3_isfinite(x1)) return MF_EINVAL;
  if (c->start == MF_START_POINT) {
    vec3 w = v3_sub(x1, c->x0);
    if (!(v3_len2(w) > 0.0)) return MF_EINVAL;
    *OUT_org = c->x0;
    *OUT_dir = v3_normalize(w);
    return MF_OK;
  }
  /* Along d, from far enough back that the ray enters the scene. */
  vec3 d = v3_normalize(c->d);
  *OUT_org = v3_fma(x1, d, -mf__far_back(sc, d, x1));
  *OUT_dir = d;
  return MF_OK;
}

int mf_scatter(const mf_vertex *v, vec3 wi, vec3 *OUT_wo) {
  /* The normal it scatters about: ns, or the microfacet normal whose
   * projection on the shading frame is the target. */
  vec3 m = v->ns;
  double t0 = v->target[0], t1 = v->target[1];
  if (t0 != 0.0 || t1 != 0.0) {
    double z2 = 1.0 - t0 * t0 - t1 * t1;
    if (!(z2 > 0.0)) return MF_EINVAL;
    frame f = frame_from_z(v->ns);
    m = v3_normalize(frame_to_world(&f, v3(t0, t1, sqrt(z2))));
  }
  /* Reflect or refract; the new direction must leave on the right side of
   * both the shading and the geometric normal. */
  vec3 wo;
  double ci_s = v3_dot(wi, v->ns), ci_g = v3_dot(wi, v->ng), side;
  if (v->kind == MF_REFLECT) {
    wo = v3_normalize(v3_reflect(wi, m));
    side = 1.0;
  } else {
    if (v3_dot(wi, m) * ci_s <= 0.0) return MF_ESIDE;
    if (!mf__refract(wi, m, v->eta, &wo)) return MF_ETIR;
    wo = v3_normalize(wo);
    side = -1.0;
  }
  if (!(side * ci_s * v3_dot(wo, v->ns) > 0.0) || !(side * ci_g * v3_dot(wo, v->ng) > 0.0))
    return MF_ESIDE;
  *OUT_wo = wo;
  return MF_OK;
}

/* The chain traced from org along the unit direction d (mf_trace's loop). */
static int mf__trace_ray(const scene *sc, const mf_chain *proto, vec3 org, vec3 d, mf_chain *OUT) {
  int k = proto->k;
  mf_chain out = *proto;
  for (int i = 1; i <= k + 1; i++) {
    /* The next hit, on the prototype's mesh. */
    surface_hit h;
    if (!scene_intersect(sc, org, d, scene_ray_eps(sc, org), INFINITY, &h)) return MF_EMISS;
    if (proto->v[i].mesh >= 0 && h.mesh != proto->v[i].mesh) return MF_ESHAPE;
    mf_vertex *v = &out.v[i];
    if (mf_vertex_set(sc, v, h.mesh, h.prim, h.b1, h.b2) != MF_OK) return MF_EINVAL;
    if (i == k + 1) break;

    if (v->kind == MF_REFRACT) {
      const bsdf *b = &sc->bsdfs[sc->meshes[h.mesh].bsdf];
      if (!b->model->refracts) return MF_EBSDF;
      v->eta = b->eta;
    }
    vec3 wo;
    int st = mf_scatter(v, v3_neg(d), &wo);
    if (st != MF_OK) return st;
    org = v->p;
    d = wo;
  }
  *OUT = out;
  return MF_OK;
}

int mf_trace(const scene *sc, const mf_chain *proto, vec3 dir, mf_chain *OUT) {
  if (!mf__chain_ok(proto) || proto->start != MF_START_POINT || !v3_isfinite(dir) ||
      !(v3_len2(dir) > 0.0))
    return MF_EINVAL;
  return mf__trace_ray(sc, proto, proto->x0, v3_normalize(dir), OUT);
}

int mf_trace_through(const scene *sc, const mf_chain *proto, vec3 x1, mf_chain *OUT) {
  vec3 org, d;
  int st = mf_start_ray(sc, proto, x1, &org, &d);
  if (st != MF_OK) return st;
  return mf__trace_ray(sc, proto, org, d, OUT);
}

/* ---- The walk ------------------------------------------------------------------- */

/* The barycentric change d of vertex v whose move e1 d_0 + e2 d_1 is the
 * part of delta in the plane of its triangle (least squares). */
static int mf__plane_coords(const mf__geo *g, vec3 delta, double d[2]) {
  double a = v3_dot(g->e1, g->e1), b = v3_dot(g->e1, g->e2), c = v3_dot(g->e2, g->e2);
  double r0 = v3_dot(g->e1, delta), r1 = v3_dot(g->e2, delta);
  double det = a * c - b * b;
  if (!(det > 1e-14 * a * c)) return 0;
  d[0] = (c * r0 - b * r1) / det;
  d[1] = (a * r1 - b * r0) / det;
  return 1;
}

int mf_walk(const scene *sc, const mf_chain *c, vec3 target, const mf_options *o, mf_chain *OUT,
            mf_walk_info *info) {
  mf_walk_info inf = {0, 0, INFINITY, MF_OK};
  mf_options opt;
  if (o)
    opt = *o;
  else
    mf_options_default(sc, &opt);
  if (!mf__chain_valid(sc, c) || !v3_isfinite(target)) {
    if (info) *info = inf;
    return MF_EINVAL;
  }
  mf_chain cur = *c;
  int k = cur.k, status = MF_ENOCONV;
  mf__geo ge;
  mf__geom(sc, &cur.v[k + 1], &ge);
  /* Off its manifold the end's distance says nothing: any projection that
   * succeeds brings the chain onto it and is taken. */
  inf.dist = opt.off_start ? INFINITY : v3_len(v3_sub(target, ge.p));
  double beta = 1.0;

  for (;;) {
    /* Within tolerance: done. */
    if (inf.dist <= opt.tol) {
      status = MF_OK;
      break;
    }
    if (inf.traces >= opt.max_traces) break;

    /* The Newton step in the tangent space: the end's change onto the
     * target (in its triangle's plane), the chain's constraint residual
     * to zero; the block solve gives x_1's change. */
    mf_jac J;
    double r[2 * (MF_MAX_CHAIN + 1)], d[2 * (MF_MAX_CHAIN + 1)], d_end[2];
    if (mf_jacobian(sc, &cur, &J) != MF_OK) {
      status = MF_EINVAL;
      break;
    }
    mf__geom(sc, &cur.v[k + 1], &ge);
    if (!mf__plane_coords(&ge, v3_sub(target, ge.p), d_end)) {
      status = MF_ESINGULAR;
      break;
    }
    for (int i = 1; i <= k; i++) {
      r[2 * i] = -J.c[i][0];
      r[2 * i + 1] = -J.c[i][1];
    }
    if (mf_solve(&J, r, d_end, d) != MF_OK) {
      status = MF_ESINGULAR;
      break;
    }
    mf__geo g1;
    mf__geom(sc, &cur.v[1], &g1);
    vec3 dx1 = v3_add(v3_scale(g1.e1, d[2]), v3_scale(g1.e2, d[3]));

    /* Project: trace through x_1 + beta dx_1; halve beta until the end
     * comes nearer (or the step size or the budget runs out). */
    int taken = 0;
    while (!taken) {
      if (inf.traces >= opt.max_traces || beta < opt.min_beta) break;
      vec3 x1 = v3_fma(g1.p, dx1, beta);
      mf_chain next;
      int st = mf_trace_through(sc, &cur, x1, &next);
      inf.traces++;
      if (st == MF_OK) {
        double nd = v3_len(v3_sub(target, next.v[k + 1].p));
        if (nd < inf.dist) {
          cur = next;
          inf.dist = nd;
          inf.steps++;
          beta = fmin(1.0, 2.0 * beta);
          taken = 1;
          break;
        }
        inf.last_fail = MF_ENOCONV;
      } else {
        inf.last_fail = st;
      }
      beta *= 0.5;
    }
    if (!taken) {
      status = inf.traces >= opt.max_traces || inf.last_fail == MF_OK ? MF_ENOCONV : inf.last_fail;
      break;
    }
  }
  *OUT = cur;
  if (info) *info = inf;
  return status;
}

/* ---- The generalized geometry term ------------------------------------------------ */

int mf_geometry_term(const scene *sc, const mf_chain *c, double *OUT_G) {
  mf_jac J;
  int st = mf_jacobian(sc, c, &J);
  if (st != MF_OK) return st;
  int k = c->k;
  /* M = d b_1 / d b_{k+1}: the block of the inverse Jacobian, column by
   * column. */
  double d[2 * (MF_MAX_CHAIN + 1)], M[2][2];
  for (int col = 0; col < 2; col++) {
    double e[2] = {col == 0 ? 1.0 : 0.0, col == 1 ? 1.0 : 0.0};
    st = mf_solve(&J, NULL, e, d);
    if (st != MF_OK) return st;
    M[0][col] = d[2];
    M[1][col] = d[3];
  }
  /* In area: J_1 / J_{k+1}, each the area of a unit of barycentrics. */
  mf__geo g1, ge;
  mf__geom(sc, &c->v[1], &g1);
  mf__geom(sc, &c->v[k + 1], &ge);
  double area1 = v3_len(v3_cross(g1.e1, g1.e2)), areae = v3_len(v3_cross(ge.e1, ge.e2));
  double det = fabs(M[0][0] * M[1][1] - M[0][1] * M[1][0]) * area1 / areae;
  /* After a direction start: |cos theta_1| per unit of perpendicular area. */
  if (c->start == MF_START_DIRECTION) {
    *OUT_G = fabs(v3_dot(g1.ng, v3_normalize(c->d))) * det;
    return MF_OK;
  }
  /* G(x_0, x_1) with the geometric normal's cosine at x_1. */
  vec3 w = v3_sub(g1.p, c->x0);
  double dist2 = v3_len2(w);
  w = v3_scale(w, 1.0 / sqrt(dist2));
  double cos0 = v3_len2(c->n0) > 0.0 ? fabs(v3_dot(c->n0, w)) : 1.0;
  double cos1 = fabs(v3_dot(g1.ng, w));
  *OUT_G = cos0 * cos1 / dist2 * det;
  return MF_OK;
}

/* ---- Chains of path-space paths ------------------------------------------------------ */

/* The vertex order of the chain of p's x_a .. x_b: *OUT_s the path index of
 * x_0, *OUT_step +1 or -1 (x_i is path vertex s + i step). 0 when both ends
 * are at infinity. */
static int mf__path_order(const ps_path *p, int a, int b, unsigned flags, int *OUT_s,
                          int *OUT_step) {
  int inf_a = p->x[a].inf, inf_b = p->x[b].inf;
  if (inf_a && inf_b) return 0;
  int from_b = inf_b || (!inf_a && (flags & MF_PATH_FROM_B));
  *OUT_s = from_b ? b : a;
  *OUT_step = from_b ? -1 : 1;
  return 1;
}

/* Whether a, b name a chain of p that fits: indices in range, 1 <= k <=
 * MF_MAX_CHAIN, an order. */
static int mf__path_range(const ps_path *p, int a, int b, unsigned flags, int *OUT_s,
                          int *OUT_step) {
  if (!p || a < 0 || b > p->k || p->k >= PS_MAX_VERTICES) return 0;
  if (b - a - 1 < 1 || b - a - 1 > MF_MAX_CHAIN) return 0;
  return mf__path_order(p, a, b, flags, OUT_s, OUT_step);
}

int mf_path_vertex(const ps_context *ctx, const ps_path *p, int j, unsigned flags,
                   mf_kind *OUT_kind, double *OUT_eta) {
  const ps_vertex *x = &p->x[j];
  int glossy = (flags & MF_PATH_ANY) || ((flags & MF_PATH_GLOSSY) && ps_glossy(ctx, p, j));
  if (!x->delta && !glossy) return MF_EINVAL;
  const bsdf *bs = x->v.hit.bsdf;
  if (!bs || bsdf_needs_tangents(bs)) return MF_EBSDF;
  double sp = v3_dot(ps_dir(p, j, j - 1), x->v.n), sn = v3_dot(ps_dir(p, j, j + 1), x->v.n);
  *OUT_kind = MF_REFLECT;
  if (sp * sn > 0.0) return MF_OK;
  if (bs->masked || !bs->model->refracts || !(bs->eta > 0.0))
    return MF_EBSDF;
  *OUT_kind = MF_REFRACT;
  *OUT_eta = bs->eta;
  return MF_OK;
}

/* The ends of the chain of p's x_a .. x_b in the order s, step: the start
 * a direction at infinity or a non-delta point, the end a non-delta
 * surface record. */
static int mf__path_ends(const ps_path *p, int s, int e) {
  const ps_vertex *xs = &p->x[s], *xe = &p->x[e];
  if (xs->inf ? !v3_isfinite(xs->v.dir) || !(v3_len2(xs->v.dir) > 0.0) : xs->delta) return 0;
  return !xe->inf && !xe->delta && xe->v.type == BDPT_VERTEX_SURFACE;
}

int mf_path_chain_fits(const ps_context *ctx, const ps_path *p, int a, int b, unsigned flags) {
  int s, step;
  if (!mf__path_range(p, a, b, flags, &s, &step)) return MF_EINVAL;
  int k = b - a - 1;
  if (!mf__path_ends(p, s, s + (k + 1) * step)) return MF_EINVAL;
  for (int i = 1; i <= k + 1; i++)
    if (p->x[s + i * step].v.type != BDPT_VERTEX_SURFACE) return MF_EINVAL;
  for (int i = 1; i <= k; i++) {
    mf_kind kind;
    double eta;
    int st = mf_path_vertex(ctx, p, s + i * step, flags, &kind, &eta);
    if (st != MF_OK) return st;
  }
  return MF_OK;
}

int mf_chain_from_path(const ps_context *ctx, const ps_path *p, int a, int b, unsigned flags,
                       mf_chain *OUT) {
  const scene *sc = ctx->sc;
  int s, step;
  if (!mf__path_range(p, a, b, flags, &s, &step)) return MF_EINVAL;
  int k = b - a - 1, e = s + (k + 1) * step;
  mf_chain c;
  memset(&c, 0, sizeof c);
  c.k = k;

  /* The start: a direction at infinity, or a point that is an endpoint or
   * a non-specular surface. */
  if (!mf__path_ends(p, s, e)) return MF_EINVAL;
  const ps_vertex *xs = &p->x[s];
  if (xs->inf) {
    c.start = MF_START_DIRECTION;
    c.d = v3_normalize(xs->v.dir);
  } else {
    c.start = MF_START_POINT;
    c.x0 = xs->v.p;
    if (xs->v.type == BDPT_VERTEX_CAMERA)
      c.n0 = sc->cam.forward; /* the optical axis' cosine, as pathspace.h's G */
    else
      c.n0 = xs->v.n; /* a surface's or an area light's; zero at a point or spot light */
  }

  /* Every vertex from x_1 to the end: its place on its triangle. */
  for (int i = 1; i <= k + 1; i++) {
    const ps_vertex *x = &p->x[s + i * step];
    const surface_hit *h = &x->v.hit;
    mf_vertex *v = &c.v[i];
    if (x->v.type != BDPT_VERTEX_SURFACE) return MF_EINVAL;
    if (mf_vertex_set(sc, v, h->mesh, h->prim, h->b1, h->b2) != MF_OK) return MF_EINVAL;
    v->kind = MF_REFLECT;
  }

  /* The specular vertices: their kinds and indices (mf__path_vertex). */
  for (int i = 1; i <= k; i++) {
    int st = mf_path_vertex(ctx, p, s + i * step, flags, &c.v[i].kind, &c.v[i].eta);
    if (st != MF_OK) return st;
  }

  /* Glossy vertices keep their current half vector as their target. */
  for (int i = 1; i <= k; i++) {
    if (p->x[s + i * step].delta) continue;
    double hv[2];
    if (mf_half_vector(sc, &c, i, hv) != MF_OK) return MF_EINVAL;
    c.v[i].target[0] = hv[0];
    c.v[i].target[1] = hv[1];
  }
  *OUT = c;
  return MF_OK;
}

/* What scene_intersect makes of a hit on (mesh, prim, b1, b2) at distance
 * t: the same point, normals, frame and texture coordinates. */
static void mf__surface_hit(const scene *sc, const mf_vertex *v, double t, surface_hit *h) {
  const mesh *m = &sc->meshes[v->mesh];
  const uint32_t *tri = m->idx + 3 * v->prim;
  vec3 p0 = mesh_position(m, tri[0]), p1 = mesh_position(m, tri[1]), p2 = mesh_position(m, tri[2]);
  double b0 = 1.0 - v->b1 - v->b2;
  memset(h, 0, sizeof *h);
  h->t = t;
  h->mesh = v->mesh;
  h->prim = v->prim;
  h->b1 = v->b1;
  h->b2 = v->b2;
  h->p = v3_add(v3_add(v3_scale(p0, b0), v3_scale(p1, v->b1)), v3_scale(p2, v->b2));
  vec3 ns;
  h->ng = mesh_hit_normals(m, v->prim, p0, p1, p2, v->b1, v->b2, &ns);
  h->sh = frame_from_z(ns);
  if (m->uv) {
    const float *uv = m->uv;
    h->tu = b0 * uv[2 * tri[0]] + v->b1 * uv[2 * tri[1]] + v->b2 * uv[2 * tri[2]];
    h->tv = b0 * uv[2 * tri[0] + 1] + v->b1 * uv[2 * tri[1] + 1] + v->b2 * uv[2 * tri[2] + 1];
  } else {
    h->tu = v->b1;
    h->tv = v->b2;
  }
  h->bsdf = &sc->bsdfs[m->bsdf];
  h->light = m->light;
  vec3 dpdu, dpdv;
  if (bsdf_needs_tangents(h->bsdf) && mesh_uv_tangents(m, v->prim, p0, p1, p2, &dpdu, &dpdv))
    h->sh = bsdf_shading_frame(h->bsdf, h->tu, h->tv, dpdu, dpdv, h->sh.n, h->ng);
}

/* Whether record r's hit is chain vertex v's state, bit for bit. */
static int mf__same_state(const bdpt_vertex *r, const mf_vertex *v) {
  return r->hit.mesh == v->mesh && r->hit.prim == v->prim && r->hit.b1 == v->b1 &&
         r->hit.b2 == v->b2;
}

int mf_chain_to_path(const scene *sc, const mf_chain *c, int a, int b, unsigned flags,
                     ps_path *p) {
  int s, step;
  if (!mf__chain_ok(c) || !mf__path_range(p, a, b, flags, &s, &step) || c->k != b - a - 1)
    return MF_EINVAL;
  int k = c->k;
  /* Check everything before writing anything; note which records move and
   * each one's side (the neighbour its old wo points to: its walk's). */
  int moved[MF_MAX_CHAIN + 2], side[MF_MAX_CHAIN + 2];
  for (int i = 1; i <= k + 1; i++) {
    int j = s + i * step;
    const bdpt_vertex *r = &p->x[j].v;
    if (r->type != BDPT_VERTEX_SURFACE || j <= 0 || !mf__mesh(sc, &c->v[i])) return MF_EINVAL;
    moved[i] = !mf__same_state(r, &c->v[i]);
    if (j == p->k)
      side[i] = j - 1;
    else
      side[i] = v3_dot(r->wo, ps_dir(p, j, j - 1)) >= v3_dot(r->wo, ps_dir(p, j, j + 1)) ? j - 1
                                                                                        : j + 1;
  }
  /* The moved records: what scene_intersect makes of their points. */
  for (int i = 1; i <= k + 1; i++) {
    if (!moved[i]) continue;
    bdpt_vertex *r = &p->x[s + i * step].v;
    mf__surface_hit(sc, &c->v[i], r->hit.t, &r->hit);
    r->p = r->hit.p;
    r->n = r->hit.ng;
    r->light = r->hit.light;
  }
  /* Their wo and t, now that every neighbour is in place: towards the
   * neighbour of their own walk, t the distance from it (from outside the
   * bounding sphere when it is at infinity, as mf_start_ray). */
  for (int i = 1; i <= k + 1; i++) {
    if (!moved[i]) continue;
    int j = s + i * step, n = side[i];
    bdpt_vertex *r = &p->x[j].v;
    r->wo = ps_dir(p, j, n);
    if (p->x[n].inf)
      r->hit.t = mf__far_back(sc, v3_neg(r->wo), r->p);
    else
      r->hit.t = v3_len(v3_sub(p->x[n].v.p, r->p));
  }
  return MF_OK;
}
