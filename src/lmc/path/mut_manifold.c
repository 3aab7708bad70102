/*
 * mut_manifold.c: the manifold perturbation on chains of smooth and glossy
 * vertices, its sky form, and HSLT's half-vector perturbation over the
 * whole path (mut_manifold.h states the moves and their densities).
 * Kaplanyan et al. 2014 was read for HSLT's facts (a path as its ends and
 * the half vectors between them, steps in those coordinates by each
 * vertex's roughness, the change of measure by the constraints'
 * Jacobian). Mitsuba 0.6's
 * manifold perturbation (src/libbidir/mut_manifold.cpp) was read for the
 * method's facts (a walk of the chain behind the perturbed vertex towards
 * its new position, the reverse walk computed and a move whose reverse
 * does not return refused); the code here is lmc's own, on the walk of
 * manifold.h and the caches of pathspace.h.
 */
#include "lmc/path/mut_manifold.h"

#include <math.h>
#include <string.h>

#include "render/bsdf/bsdf_model.h"

#define MM_PI 3.14159265358979323846
/* The chain behind x_b: from x_c, glossy vertices kept at their half vectors. */
#define MF_LIGHT_CHAIN (MF_PATH_FROM_B | MF_PATH_GLOSSY)

void mut_manifold_init(mut_manifold *mm, const ps_context *ctx, const mut_perturb *mp) {
  memset(mm, 0, sizeof *mm);
  mm->ctx = ctx;
  mm->mp = mp;
  mf_options_default(ctx->sc, &mm->walk);
  /* Tighter than the default: the walk converges quadratically near its
   * end, and the reverse move must land on x to within back_tol. */
  mm->walk.tol = 1e-10 * ctx->sc->radius;
  mm->back_tol = 1e-6 * ctx->sc->radius;
  mm->test_jac_power = 1.0;
  mm->test_glossy_power = 1.0;
}

void mut_manifold_init_hslt(mut_manifold *mm, const ps_context *ctx, const mut_perturb *mp,
                            double step) {
  mut_manifold_init(mm, ctx, mp);
  mm->hslt = 1;
  mm->hslt_step = step;
  mm->walk.off_start = 1; /* the walks start at the new half vectors */
  /* A walk that has not converged in 8 projections seldom does: on the
   * torus and the Veach door the acceptance is the same as with 64, at
   * half and a third of the projections. */
  mm->walk.max_traces = MUT_HSLT_MAX_TRACES;
}

/* The flags of the chain behind x_b: from x_c, glossy vertices (under
 * HSLT every vertex that is not S) held at their half vectors. */
static unsigned mm__flags(const mut_manifold *mm) {
  return mm->hslt ? MF_PATH_FROM_B | MF_PATH_ANY : MF_LIGHT_CHAIN;
}

double mut_manifold_hslt_width(const ps_context *ctx, const ps_path *x, int j) {
  (void)ctx;
  const bsdf *bs = x->x[j].v.hit.bsdf;
  double r = bs && bs->model->roughness ? bs->model->roughness(bs) : 0.0;
  return r > 0.0 ? fmin(r, MUT_HSLT_MAX_WIDTH) : 0.0;
}

/* Whether vertex i of x is a chain vertex: S (delta) or G (ps_glossy). */
static int mm__specular(const ps_context *ctx, const ps_path *x, int i) {
  return x->x[i].delta || ps_glossy(ctx, x, i);
}

/* The sky form: the camera's chain reaches the emitter end, a direction
 * at infinity that a ray can meet (not a directional light's), or a point
 * on an area light. */
static int mm__sky_form(const mut_manifold *mm, const ps_path *x) {
  const ps_context *ctx = mm->ctx;
  int k = x->k;
  const bdpt_vertex *e = &x->x[k].v;
  if (k < 2 || k - 1 > MF_MAX_CHAIN) return 0;
  if (x->x[k].inf ? e->light >= 0 && !light_is_infinite(&ctx->sc->lights[e->light])
                  : !(e->light >= 0 && ctx->sc->lights[e->light].type == LIGHT_AREA))
    return 0;
  for (int j = 1; j < k; j++) {
    mf_kind kind;
    double eta;
    if (x->x[j].v.type != BDPT_VERTEX_SURFACE ||
        mf_path_vertex(ctx, x, j, MF_PATH_GLOSSY, &kind, &eta) != MF_OK)
      return 0;
  }
  return 1;
}

/* HSLT's form: x_1 .. x_{b-1} S, x_b not, at least one chain vertex
 * between x_b and the emitter end x_k, both chains readable. */
static int mm__hslt_form(const mut_manifold *mm, const ps_path *x, int *OUT_b, int *OUT_c) {
  const ps_context *ctx = mm->ctx;
  int k = x->k, b = 1;
  while (b < k && x->x[b].delta) b++;
  if (b + 1 >= k || mf_path_chain_fits(ctx, x, b, k, mm__flags(mm)) != MF_OK) return 0;
  if (b > 1 && mf_path_chain_fits(ctx, x, 0, b, MF_PATH_GLOSSY) != MF_OK) return 0;
  *OUT_b = b, *OUT_c = k;
  return 1;
}

int mut_manifold_form(const mut_manifold *mm, const ps_path *x, int *OUT_b, int *OUT_c) {
  const ps_context *ctx = mm->ctx;
  if (mm->hslt) return mm__hslt_form(mm, x, OUT_b, OUT_c);
  int k = x->k, b = 1;
  while (b < k && mm__specular(ctx, x, b)) b++;
  if (b == k) {
    if (!mm__sky_form(mm, x)) return 0;
    *OUT_b = *OUT_c = k;
    return 1;
  }
  if (b + 1 >= k || !mm__specular(ctx, x, b + 1)) return 0;
  int c = b + 1;
  while (c < k && mm__specular(ctx, x, c)) c++;
  /* x_c is fixed: a D surface or the emitter end; both chains readable
   * (their lengths at most MF_MAX_CHAIN among the rest). */
  if (mf_path_chain_fits(ctx, x, b, c, MF_LIGHT_CHAIN) != MF_OK) return 0;
  if (b > 1 && mf_path_chain_fits(ctx, x, 0, b, MF_PATH_GLOSSY) != MF_OK) return 0;
  *OUT_b = b, *OUT_c = c;
  return 1;
}

/* The walk of chain `from` (x_c .. x_b of a path) towards `target`. */
static int mm__walk(const mut_manifold *mm, const mf_chain *from, vec3 target, mf_chain *OUT,
                    int64_t *rays, mut_manifold_tally *tally) {
  mf_walk_info info;
  memset(&info, 0, sizeof info);
  int st = mf_walk(mm->ctx->sc, from, target, &mm->walk, OUT, &info);
  if (rays) *rays += info.traces;
  if (tally) {
    tally->walks++;
    tally->traces += info.traces;
    tally->walked += st == MF_OK;
  }
  return st == MF_OK;
}

int mut_manifold_half_vectors(const mut_manifold *mm, const ps_path *x,
                              double OUT_h[2 * PS_MAX_VERTICES]) {
  int b, c;
  mf_chain ch;
  memset(OUT_h, 0, 2 * PS_MAX_VERTICES * sizeof *OUT_h);
  if (!mut_manifold_form(mm, x, &b, &c) || b == c ||
      mf_chain_from_path(mm->ctx, x, b, c, mm__flags(mm), &ch) != MF_OK)
    return 0;
  /* Chain vertex i is x_{c - i}. */
  for (int i = 1; i <= ch.k; i++) {
    if (x->x[c - i].delta) continue;
    OUT_h[2 * (c - i)] = ch.v[i].target[0];
    OUT_h[2 * (c - i) + 1] = ch.v[i].target[1];
  }
  return 1;
}

/* HSLT: the targets h (mut_manifold_half_vectors' layout) set on chain ch
 * (x_c .. x_b of path p), which is then off their manifold until the
 * walk's first projection; 0 when one is not inside the unit disk. */
static int mm__retarget(const ps_path *p, int c, const double *h, mf_chain *ch) {
  for (int i = 1; i <= ch->k; i++) {
    int j = c - i;
    if (p->x[j].delta) continue;
    if (!(h[2 * j] * h[2 * j] + h[2 * j + 1] * h[2 * j + 1] < 1.0)) return 0;
    ch->v[i].target[0] = h[2 * j];
    ch->v[i].target[1] = h[2 * j + 1];
  }
  return 1;
}

/* Chain vertex j of path p as the walk's vertex: its place, and its kind,
 * eta and target (its half vector, for a G vertex) from path x, whose
 * form p keeps (x may be p). */
static int mm__vertex(const ps_context *ctx, const ps_path *p, const ps_path *x, int j,
                      mf_vertex *OUT) {
  const surface_hit *h = &p->x[j].v.hit, *hx = &x->x[j].v.hit;
  memset(OUT, 0, sizeof *OUT);
  if (mf_path_vertex(ctx, x, j, MF_PATH_GLOSSY, &OUT->kind, &OUT->eta) != MF_OK) return 0;
  if (!x->x[j].delta) {
    mf_vertex vx = *OUT;
    if (mf_vertex_set(ctx->sc, &vx, hx->mesh, hx->prim, hx->b1, hx->b2) != MF_OK) return 0;
    mf_half_vector_dirs(&vx, ps_dir(x, j, j - 1), ps_dir(x, j, j + 1), OUT->target);
  }
  return mf_vertex_set(ctx->sc, OUT, h->mesh, h->prim, h->b1, h->b2) == MF_OK;
}

/* The sky form's y: the camera ray through (rx, ry) traced through x_1 ..
 * x_{k-1}, each about its held half vector (an S vertex's is zero), and
 * out to the sky, or to x_k's area light. */
static int mm__generate_sky(const mut_manifold *mm, const ps_path *x, double rx, double ry,
                            ps_path *y, int64_t *rays) {
  const ps_context *ctx = mm->ctx;
  int k = x->k;
  if (!mut_perturb_first_hit(ctx, rx, ry, &y->x[0].v, &y->x[1].v, rays)) return 0;
  for (int i = 1; i < k; i++) {
    mf_vertex v;
    vec3 wo;
    if (!mm__vertex(ctx, y, x, i, &v) ||
        mf_scatter(&v, v3_normalize(v3_sub(y->x[i - 1].v.p, y->x[i].v.p)), &wo) != MF_OK)
      return 0;
    if (i + 1 < k) {
      if (!mut_perturb_trace(ctx, &y->x[i].v, wo, TRANSPORT_RADIANCE, &y->x[i + 1].v, rays))
        return 0;
      continue;
    }
    /* The last direction must leave the scene, or meet x_k's area light. */
    if (x->x[k].inf ? !mut_perturb_trace_sky(ctx, &y->x[i].v, wo, &y->x[k].v, rays)
                    : !mut_perturb_trace(ctx, &y->x[i].v, wo, TRANSPORT_RADIANCE, &y->x[k].v,
                                         rays) ||
                          y->x[k].v.light != x->x[k].v.light)
      return 0;
  }
  for (int i = 1; i < k; i++) y->x[i].v.delta = x->x[i].v.delta;
  ps_update(ctx, y, 0, k);
  for (int i = 1; i < k; i++)
    if (y->x[i].delta != x->x[i].delta || ps_glossy(ctx, y, i) != ps_glossy(ctx, x, i)) return 0;
  if (y->x[k].inf != x->x[k].inf) return 0;
  ps_total(y);
  return 1;
}

int mut_manifold_generate(const mut_manifold *mm, const ps_path *x, double rx, double ry,
                          const double *h, ps_path *OUT_y, int64_t *rays,
                          mut_manifold_tally *tally) {
  const ps_context *ctx = mm->ctx;
  const scene *sc = ctx->sc;
  int b, c;
  if (!mut_manifold_form(mm, x, &b, &c)) return 0;
  if (!(rx >= 0.0 && rx < sc->cam.width && ry >= 0.0 && ry < sc->cam.height)) return 0;
  ps_path *y = OUT_y;
  *y = *x;
  y->rays = 0;
  if (b == x->k) return mm__generate_sky(mm, x, rx, ry, y, rays);
  /* The camera's chain retraced to a new y_b: each S vertex through its
   * lobe, each G vertex about the microfacet normal of its half vector. */
  if (!mut_perturb_first_hit(ctx, rx, ry, &y->x[0].v, &y->x[1].v, rays)) return 0;
  if (b > 1) {
    mf_chain cam, cam_y;
    if (mf_chain_from_path(ctx, x, 0, b, MF_PATH_GLOSSY, &cam) != MF_OK) return 0;
    vec3 dir = v3_normalize(v3_sub(y->x[1].v.p, y->x[0].v.p));
    if (rays) *rays += b;
    if (mf_trace(sc, &cam, dir, &cam_y) != MF_OK) return 0;
    if (mf_chain_to_path(sc, &cam_y, 0, b, MF_PATH_GLOSSY, y) != MF_OK) return 0;
  }
  /* The chain behind x_b walked to it, its end on y_b's surface (under
   * HSLT first moved onto the manifold of the new targets). */
  mf_chain cx, cy;
  if (mf_chain_from_path(ctx, x, b, c, mm__flags(mm), &cx) != MF_OK) return 0;
  if (y->x[b].v.hit.mesh != cx.v[cx.k + 1].mesh) return 0;
  if (mm->hslt && (!h || !mm__retarget(x, c, h, &cx))) return 0;
  if (!mm__walk(mm, &cx, y->x[b].v.p, &cy, rays, tally)) return 0;
  bdpt_vertex yb = y->x[b].v;
  if (mf_chain_to_path(sc, &cy, b, c, mm__flags(mm), y) != MF_OK) return 0;
  y->x[b].v = yb; /* the retraced vertex, which the walk's end reached within its tolerance */
  ps_update(ctx, y, 0, c + 1 > y->k ? y->k : c + 1);
  /* x's form: the kinds of every changed vertex. */
  for (int i = 1; i < c; i++)
    if (y->x[i].delta != x->x[i].delta || ps_glossy(ctx, y, i) != ps_glossy(ctx, x, i)) return 0;
  /* y_b joins y_{b+1}; the walk traced the rest of the chain. */
  if (rays) (*rays)++;
  if (ps_edge_blocked(ctx, y, b)) {
    y->f = rgb_zero();
    y->lum = 0.0;
    return 1;
  }
  ps_total(y);
  return 1;
}

int mut_manifold_reversible(const mut_manifold *mm, const ps_path *x, const ps_path *y,
                            int64_t *rays, mut_manifold_tally *tally) {
  int b, c;
  if (!mut_manifold_form(mm, x, &b, &c)) return 0;
  if (b == x->k) return 1; /* the sky form: no walk, the trace is its own inverse */
  mf_chain cy, cz;
  if (mf_chain_from_path(mm->ctx, y, b, c, mm__flags(mm), &cy) != MF_OK) return 0;
  if (mm->hslt) {
    double hx[2 * PS_MAX_VERTICES];
    if (!mut_manifold_half_vectors(mm, x, hx) || !mm__retarget(y, c, hx, &cy)) return 0;
  }
  if (!mm__walk(mm, &cy, x->x[b].v.p, &cz, rays, tally)) return 0;
  /* Chain vertex i is x_{c - i}. */
  for (int i = 1; i <= cz.k; i++)
    if (!(v3_len(v3_sub(cz.v[i].p, x->x[c - i].v.p)) <= mm->back_tol)) return 0;
  return 1;
}

/* The area of a unit of barycentrics on chain vertex v's triangle. */
static double mm__bary_area(const scene *sc, const mf_vertex *v) {
  const mesh *m = &sc->meshes[v->mesh];
  const uint32_t *tri = m->idx + 3 * v->prim;
  vec3 p0 = mesh_position(m, tri[0]), p1 = mesh_position(m, tri[1]), p2 = mesh_position(m, tri[2]);
  return v3_len(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
}

/* The density of chain vertex i + 1 reached through G vertex i with its
 * half vector held: |det dc_i / dA_{i+1}| (mut_manifold.h). */
static double mm__glossy_factor(const mut_manifold *mm, const mf_chain *ch, const mf_jac *J,
                                int i) {
  double det = J->C[i][0][0] * J->C[i][1][1] - J->C[i][0][1] * J->C[i][1][0];
  return pow(fabs(det) / mm__bary_area(mm->ctx->sc, &ch->v[i + 1]), mm->test_glossy_power);
}

/* The lens part of T(x -> y) but the offset's density: the raster-to-area
 * Jacobian at y_1 and each further camera-side vertex's factor. */
static double mm__camera_density(const mut_manifold *mm, const ps_path *y, int b) {
  const ps_context *ctx = mm->ctx;
  const camera *cam = &ctx->sc->cam;
  double jac = (double)cam->width * cam->height * y->x[1].pdf_cam;
  if (b == 1 || !(jac > 0.0)) return jac;
  mf_chain ch;
  mf_jac J;
  if (mf_chain_from_path(ctx, y, 0, b, MF_PATH_GLOSSY, &ch) != MF_OK ||
      mf_jacobian(ctx->sc, &ch, &J) != MF_OK)
    return 0.0;
  /* Chain vertex i is y_i. */
  for (int i = 1; i < b; i++)
    jac *= y->x[i].delta ? ps_area_jacobian(ctx, y, i, i + 1)
                         : mm__glossy_factor(mm, &ch, &J, i);
  return jac;
}

/* The chain's part of T(x -> y): Phi(y) / G(y) (mut_manifold.h). */
static double mm__chain_density(const mut_manifold *mm, const ps_path *y, int b, int c) {
  const ps_context *ctx = mm->ctx;
  mf_chain ch;
  mf_jac J;
  if (mf_chain_from_path(ctx, y, b, c, mm__flags(mm), &ch) != MF_OK ||
      mf_jacobian(ctx->sc, &ch, &J) != MF_OK)
    return 0.0;
  double phi = y->x[c].inf ? fabs(v3_dot(ps_dir(y, c - 1, c), y->x[c - 1].v.n))
                           : ps_area_jacobian(ctx, y, c, c - 1);
  /* Chain vertex i is y_{c - i}; y_{c - i - 1} is reached through it. */
  for (int i = 1; i < c - b; i++) {
    int j = c - i;
    phi *= y->x[j].delta ? ps_forced_density(ctx, y, j, j + 1, j - 1, 1)
                         : mm__glossy_factor(mm, &ch, &J, i);
  }
  ch.n0 = v3(0.0, 0.0, 0.0); /* d omega at x_c, without its cosine */
  double G;
  if (!(phi > 0.0) || mf_geometry_term(ctx->sc, &ch, &G) != MF_OK || !(G > 0.0) || !isfinite(G))
    return 0.0;
  return phi / pow(G, mm->test_jac_power);
}

/* The sky form's density but the offset's: the raster-to-area Jacobian at
 * y_1 and each further vertex's, the last a direction (solid angle) or a
 * point on the area light (area). */
static double mm__sky_density(const mut_manifold *mm, const ps_path *y) {
  const ps_context *ctx = mm->ctx;
  const camera *cam = &ctx->sc->cam;
  int k = y->k;
  double jac = (double)cam->width * cam->height * y->x[1].pdf_cam;
  for (int i = 1; i < k && jac > 0.0; i++) {
    double area = i + 1 < k    ? ps_area_jacobian(ctx, y, i, i + 1)
                  : y->x[k].inf ? 1.0
                                : pow(ps_area_jacobian(ctx, y, i, k), mm->test_jac_power);
    if (y->x[i].delta) {
      jac *= area;
      continue;
    }
    mf_vertex v;
    if (!mm__vertex(ctx, y, y, i, &v)) return 0.0;
    double jw = mf_half_vector_dir_jacobian(&v, ps_dir(y, i, i - 1), ps_dir(y, i, i + 1));
    jac *= pow(jw, mm->test_glossy_power) * area;
  }
  return jac;
}

/* HSLT: the density of y's half vectors drawn about x's, prod_j q(h'_j |
 * h_j) (mut_manifold.h); a vertex of zero width keeps its half vector. */
static double mm__hslt_density(const mut_manifold *mm, const ps_path *x, const ps_path *y) {
  double hx[2 * PS_MAX_VERTICES], hy[2 * PS_MAX_VERTICES];
  if (!mut_manifold_half_vectors(mm, x, hx) || !mut_manifold_half_vectors(mm, y, hy)) return 0.0;
  int b, c;
  mut_manifold_form(mm, x, &b, &c);
  double q = 1.0;
  for (int j = b + 1; j < c; j++) {
    double s = mm->hslt_step * mut_manifold_hslt_width(mm->ctx, x, j);
    if (x->x[j].delta || !(s > 0.0)) continue;
    double dx = hy[2 * j] - hx[2 * j], dy = hy[2 * j + 1] - hx[2 * j + 1];
    q *= exp(-(dx * dx + dy * dy) / (2.0 * s * s)) / (2.0 * MM_PI * s * s);
  }
  return q;
}

double mut_manifold_density(const mut_manifold *mm, const ps_path *x, const ps_path *y) {
  int bx, cx, by, cy;
  if (y->k != x->k || !mut_manifold_form(mm, x, &bx, &cx) || !mut_manifold_form(mm, y, &by, &cy) ||
      by != bx || cy != cx)
    return 0.0;
  double dr = hypot(y->rx - x->rx, y->ry - x->ry);
  double p = mut_perturb_log_pdf(mm->mp->r1, mm->mp->r2, dr) / (2.0 * MM_PI * dr);
  if (!(p > 0.0)) return 0.0;
  if (bx == x->k) return p * mm__sky_density(mm, y);
  p *= mm__camera_density(mm, y, bx) * mm__chain_density(mm, y, bx, cx);
  return mm->hslt && p > 0.0 ? p * mm__hslt_density(mm, x, y) : p;
}

/* HSLT: x's half vectors, each that is not S moved by sigma_j times a
 * standard normal pair (Box-Muller), into OUT_h; 0 when one leaves the
 * unit disk (no proposal). */
static int mm__hslt_draw(const mut_manifold *mm, rng *r, const ps_path *x,
                         double OUT_h[2 * PS_MAX_VERTICES]) {
  if (!mut_manifold_half_vectors(mm, x, OUT_h)) return 0;
  int b, c;
  mut_manifold_form(mm, x, &b, &c);
  for (int j = b + 1; j < c; j++) {
    double s = mm->hslt_step * mut_manifold_hslt_width(mm->ctx, x, j);
    if (x->x[j].delta || !(s > 0.0)) continue;
    double rad = s * sqrt(-2.0 * log(1.0 - rng_uniform(r))), a = 2.0 * MM_PI * rng_uniform(r);
    OUT_h[2 * j] += rad * cos(a);
    OUT_h[2 * j + 1] += rad * sin(a);
    if (!(OUT_h[2 * j] * OUT_h[2 * j] + OUT_h[2 * j + 1] * OUT_h[2 * j + 1] < 1.0)) return 0;
  }
  return 1;
}

int mut_manifold_propose(const mut_manifold *mm, rng *r, const ps_path *x, ps_path *OUT_y,
                         double *OUT_ratio, int64_t *rays, mut_manifold_tally *tally) {
  *OUT_ratio = 0.0;
  if (!mut_manifold_applies(mm, x)) return 0;
  double size = mut_perturb_log_sample(mm->mp->r1, mm->mp->r2, rng_uniform(r));
  double phi = 2.0 * MM_PI * rng_uniform(r);
  double h[2 * PS_MAX_VERTICES];
  if (mm->hslt && !mm__hslt_draw(mm, r, x, h)) return 0;
  if (!mut_manifold_generate(mm, x, x->rx + size * cos(phi), x->ry + size * sin(phi),
                             mm->hslt ? h : NULL, OUT_y, rays, tally))
    return 0;
  double t_fwd = mut_manifold_density(mm, x, OUT_y);
  if (!(t_fwd > 0.0)) return 0;
  if (!(OUT_y->lum > 0.0) || !(x->lum > 0.0)) return 1;
  if (!mut_manifold_reversible(mm, x, OUT_y, rays, tally)) {
    if (tally) tally->irreversible++;
    return 1;
  }
  double t_rev = mut_manifold_density(mm, OUT_y, x);
  double ratio = OUT_y->lum * t_rev / (x->lum * t_fwd);
  *OUT_ratio = isfinite(ratio) ? ratio : 0.0;
  return 1;
}
