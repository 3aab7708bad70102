/*
 * path.c: the differentiable path sampler (see path.h): pt_li's estimator
 * written once in dual arithmetic, run twice ("locate, then re-evaluate").
 * The emitters in duals are light.c's (light_ad.h; path_lights.c notes
 * their choices in the topology), one bidirectional strategy
 * in path_bdpt.c; path_internal.h is what they share.
 *
 * Pass 1 (tangent length 0) traces rays with Embree on the values and
 * records, in order, every number drawn, every closest-hit result (mesh and
 * triangle, or a miss) and every shadow-ray result. Pass 2 replays the
 * same code with one tangent slot per continuous coordinate; instead of
 * tracing, it reads the record. Since values never depend on tangents,
 * pass 2 computes exactly the values of pass 1 and takes the same
 * branches, and its tangents are the derivatives of that very formula.
 *
 * What depends on u, and how (the chain the tangents follow):
 *  camera      rx = u0 W, ry = u1 H; the pinhole ray direction
 *              normalize(to_world (x, y, 1)) with x = -(2 rx / W - 1) tan_half_x
 *              (camera.c's formula).
 *  vertices    Moller-Trumbore on the recorded triangle (the formula of
 *              mesh_intersect_triangle, which scene_intersect uses too):
 *              b1, b2 from the dual ray, p = b0 p0 + b1 p1 + b2 p2, the
 *              shading normal normalize(b0 n0 + b1 n1 + b2 n2) (turned to the
 *              geometric side), its frame (Duff et al. 2017) and the texture
 *              coordinates, all as in scene_intersect.
 *  lights      light.c's sampling routines in duals (light_ad.h, one
 *              source with the plain ones): an area light's triangle is
 *              chosen by the discrete part of u1 (fixed), the remapped u1'
 *              = (u1 - cdf_i) / width_i keeps derivative 1 / width_i; the
 *              envmap's pixel is fixed and the position inside it moves
 *              with derivative 1 / (n width) per axis (inverse CDF of a
 *              piecewise-constant density); radiance is piecewise constant
 *              (derivative 0) and the solid-angle density 1 / sin(theta)
 *              inside a pixel is differentiated through theta.
 *  BSDFs       bsdf_ad.h (bsdf_eval_ad, bsdf_pdf_ad, bsdf_sample_f_ad).
 *  MIS         the power heuristic a^2 / (a^2 + b^2) on dual densities.
 *  roulette    the survival probability q = min(0.95, max(beta) eta^2) is a
 *              dual: the estimator divides by it.
 *
 * Where a value comes from a plain routine whose derivative is known in
 * closed form (a scalar remap), the dual is built as (plain value, chain
 * rule tangent), so values agree with the plain integrators to rounding.
 *
 * What this file shares with path_bdpt.c (the bidirectional strategies)
 * is declared in path_internal.h: the context, the record, the vertex
 * re-evaluation, the camera ray, the emitters in duals and the driver.
 *
 * Arena: each bounce rewinds the arena, keeping only the duals the next
 * bounce needs (radiance, throughput, previous density and position, the
 * ray), so memory is bounded by one bounce and stays in cache.
 */
#include "render/integrators/path.h"

#include <stdlib.h>
#include <string.h>

#include "render/integrators/path_internal.h"
#include "render/warp.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif


lmc_status path_scratch_create(path_scratch **OUT_scratch, lmc_error *err) {
  path_scratch *ps = calloc(1, sizeof *ps);
  if (!ps) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for a path scratch");
  ps->arena_cap = ad_arena_size(AD_CAPACITY, PATH__ARENA_DUALS);
  ps->arena_buf = malloc(ps->arena_cap * sizeof(double));
  if (!ps->arena_buf) {
    free(ps);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for a path arena");
  }
  *OUT_scratch = ps;
  return LMC_OK;
}

void path_scratch_destroy(path_scratch *ps) {
  if (!ps) return;
  free(ps->arena_buf);
  free(ps->arena2_buf);
  free(ps->hfull);
  free(ps);
}

/* ---------------------------------------------------------------------------
 * The evaluation context: pass 1 (record) or pass 2 (replay).
 */


/* Mixes a discrete choice into the topology hash. */
void path__topo(path__ctx *c, int64_t x) {
  c->topo = rng_hash64(c->topo ^ (uint64_t)x) + 0x9e3779b97f4a7c15ull;
}

void path__use_stream(path__ctx *c, int stream) {
  if (!c->replay) sampler_use_stream(c->smp, stream);
  c->stream = stream;
}

/* The next number of the current stream; `diff` asks for a tangent slot
 * (continuous use). */
ad path__draw(path__ctx *c, int diff) {
  path_scratch *ps = c->ps;
  if (c->replay) {
    int k = c->k_draw++;
    if (k >= ps->n_draw) return ad_const(c->A, 0.5); /* unreachable: replay only when complete */
    return ps->dvar[k] >= 0 ? ad_var(c->A, ps->du[k], ps->dvar[k]) : ad_const(c->A, ps->du[k]);
  }
  double u = sampler_next(c->smp);
  int k = ps->n_draw;
  if (k < PATH_MAX_DRAWS) {
    ps->du[k] = u;
    ps->dstream[k] = (signed char)c->stream;
    ps->dpos[k] = c->spos[c->stream];
    int var = -1;
    if (diff) {
      if (c->n_var < AD_CAPACITY)
        var = c->n_var++;
      else
        c->lost = 1;
    }
    ps->dvar[k] = var;
    ps->n_draw++;
  } else {
    c->lost = 1;
  }
  c->spos[c->stream]++;
  return ad_const(c->A, u);
}

/* The second-order arena's sizes: PATH__ARENA2_DUALS duals times a power
 * of 4, up to PATH__ARENA2_MAX_BYTES at tangent length n. An evaluation
 * tries them upwards from the last size this scratch grew to (no larger
 * than the largest admissible at n) until its tape fits, so whether a path
 * gets its Hessian depends on the path alone, not on what the scratch
 * evaluated before: chains share a thread's scratch. */
static int path__fits2(int n, size_t duals) {
  return ad_arena_size2(n, duals) <= PATH__ARENA2_MAX_BYTES / sizeof(double);
}

/* Makes ps's second-order buffer hold `duals` duals of tangent length n;
 * returns duals, or 0 when that is above the limit or memory is short (the
 * caller then evaluates the gradient alone). The buffer's old contents are
 * not kept. */
static size_t path__arena2(path_scratch *ps, int n, size_t duals) {
  if (!path__fits2(n, duals)) return 0;
  size_t cap = ad_arena_size2(n, duals);
  if (ps->arena2_cap < cap) {
    free(ps->arena2_buf);
    ps->arena2_cap = 0;
    ps->arena2_buf = malloc(cap * sizeof(double));
    if (!ps->arena2_buf) return 0;
    ps->arena2_cap = cap;
  }
  if (!ps->hfull) ps->hfull = malloc((size_t)AD_H_CAPACITY * AD_H_CAPACITY * sizeof(double));
  if (!ps->hfull) return 0;
  if (duals > ps->arena2_duals) ps->arena2_duals = duals;
  return duals;
}

/* The first size an evaluation of tangent length n tries. */
static size_t path__arena2_first(path_scratch *ps, int n) {
  size_t duals = PATH__ARENA2_DUALS;
  while (duals < ps->arena2_duals && path__fits2(n, 4 * duals)) duals *= 4;
  return path__arena2(ps, n, duals);
}

/* Carries duals over an arena rewind to `mark`: their tangents are copied
 * out, the arena rewinds, and they are remade at the bottom. */
void path__keep(path__ctx *c, size_t mark, ad *const *v, int n) {
  ad_arena *A = c->A;
  size_t lanes = A->lanes;
  if (ad_arena_keeps_all(A)) return; /* second order: no rewinds */
  if (lanes == 0 || n > PATH__KEEP) {
    if (lanes == 0) ad_arena_rewind(A, mark);
    return;
  }
  double *tmp = c->ps->keep_tmp;
  for (int i = 0; i < n; i++) memcpy(tmp + (size_t)i * lanes, v[i]->d, lanes * sizeof(double));
  ad_arena_rewind(A, mark);
  for (int i = 0; i < n; i++) *v[i] = ad_from_block(A, v[i]->v, tmp + (size_t)i * lanes);
}


/* ---------------------------------------------------------------------------
 * Vertices: locate (Embree, pass 1) or read the record (pass 2), then
 * re-evaluate on the triangle in duals.
 */


/* The surface point of triangle `prim` of mesh `mi` hit by the dual ray
 * (org, dir): scene_intersect's formulas on Moller-Trumbore barycentrics. */
void path__hit_eval(path__ctx *c, int mi, int64_t prim, adv3 org, adv3 dir,
                           path__hit *h) {
  ad_arena *A = c->A;
  const mesh *m = &c->sc->meshes[mi];
  const uint32_t *tri = m->idx + 3 * prim;
  vec3 p0 = mesh_position(m, tri[0]), p1 = mesh_position(m, tri[1]), p2 = mesh_position(m, tri[2]);
  vec3 e1 = v3_sub(p1, p0), e2 = v3_sub(p2, p0);

  /* Barycentrics: b1 = (tv . pv) / det, b2 = (dir . qv) / det. */
  adv3 pv = path__cross_c(A, dir, e2);
  ad det = path__dot_c(A, e1, pv);
  ad inv = ad_inv(A, det);
  adv3 tv = {ad_sub_s(A, org.x, p0.x), ad_sub_s(A, org.y, p0.y), ad_sub_s(A, org.z, p0.z)};
  /* qv = tv x e1 */
  adv3 qv = path__cross_c(A, tv, e1);
  ad b1 = ad_mul(A, adv3_dot(A, tv, pv), inv);
  ad b2 = ad_mul(A, adv3_dot(A, dir, qv), inv);
  ad b0 = ad_sub(A, ad_s_sub(A, 1.0, b1), b2);

  h->mesh = mi;
  h->prim = prim;
  h->p = path__bary(A, p0, p1, p2, b0, b1, b2);
  /* Normals as scene_intersect orients them (mesh.h's mesh_hit_normals):
   * the shading normal interpolated and normalised, the geometric normal
   * (constant on the triangle) turned to its side by the values alone, the
   * derivatives following the sign chosen. */
  h->ng = mesh_face_normal(m, prim);
  adv3 ns = path__cv(A, h->ng);
  if (mesh_uses_vertex_normals(m)) {
    adv3 ni = path__bary(A, mesh_vertex_normal(m, tri[0]), mesh_vertex_normal(m, tri[1]),
                         mesh_vertex_normal(m, tri[2]), b0, b1, b2);
    double l = v3_len(path__val(ni));
    if (l > 1e-12) {
      ns = adv3_normalize(A, ni);
      if (v3_dot(h->ng, path__val(ns)) < 0.0) h->ng = v3_neg(h->ng);
    }
  }
  h->sh = adv3_frame_from_z(A, ns);

  /* Texture coordinates (the barycentrics when the mesh has none). */
  if (m->uv) {
    const float *uv = m->uv;
    h->tu = ad_add(A, ad_add(A, ad_mul_s(A, b0, uv[2 * tri[0]]), ad_mul_s(A, b1, uv[2 * tri[1]])),
                   ad_mul_s(A, b2, uv[2 * tri[2]]));
    h->tv = ad_add(A,
                   ad_add(A, ad_mul_s(A, b0, uv[2 * tri[0] + 1]), ad_mul_s(A, b1, uv[2 * tri[1] + 1])),
                   ad_mul_s(A, b2, uv[2 * tri[2] + 1]));
  } else {
    h->tu = b1;
    h->tv = b2;
  }
  /* (an index-matched boundary between media has none: bsdf -1) */
  h->bsdf = m->bsdf >= 0 ? &c->sc->bsdfs[m->bsdf] : NULL;
  h->light = m->light;
  /* A bump map or an anisotropic lobe (scene_intersect's rule). */
  vec3 dpdu, dpdv;
  if (h->bsdf && bsdf_needs_tangents(h->bsdf) &&
      mesh_uv_tangents(m, prim, p0, p1, p2, &dpdu, &dpdv))
    h->sh = bsdf_shading_frame_ad(A, h->bsdf, h->tu, h->tv, dpdu, dpdv, h->sh.n, h->ng);
}

/* Closest hit along the dual ray in (tmin, tmax), among the surfaces with
 * a BSDF, or with `media` also the index-matched boundaries between media
 * (scene_intersect_media: their hits have bsdf NULL); 0 on a miss. */
static int path__trace(path__ctx *c, adv3 org, adv3 dir, double tmin, double tmax, int media,
                       path__hit *h) {
  path_scratch *ps = c->ps;
  int mi;
  int64_t prim;
  if (c->replay) {
    int k = c->k_hit++;
    if (k >= ps->n_hit) return 0;
    mi = ps->hit_mesh[k];
    prim = ps->hit_prim[k];
  } else {
    surface_hit sh;
    c->rays++;
    vec3 o = path__val(org), d = path__val(dir);
    int hit = media ? scene_intersect_media(c->sc, o, d, tmin, tmax, &sh)
                    : scene_intersect(c->sc, o, d, tmin, tmax, &sh);
    mi = hit ? sh.mesh : -1;
    prim = hit ? sh.prim : -1;
    if (ps->n_hit < PATH__MAX_HITS) {
      ps->hit_mesh[ps->n_hit] = mi;
      ps->hit_prim[ps->n_hit] = prim;
      ps->n_hit++;
    } else {
      c->lost = 1;
    }
  }
  path__topo(c, mi);
  path__topo(c, prim);
  if (mi < 0) return 0;
  path__hit_eval(c, mi, prim, org, dir, h);
  return 1;
}

/* Closest hit along the dual ray; 0 on a miss. */
int path__intersect(path__ctx *c, adv3 org, adv3 dir, double tmin, path__hit *h) {
  return path__trace(c, org, dir, tmin, INFINITY, 0, h);
}

/* Shadow ray: 1 when blocked (recorded in pass 1, read in pass 2). */
int path__blocked(path__ctx *c, vec3 p, vec3 wi, vec3 lp, int infinite) {
  path_scratch *ps = c->ps;
  if (c->replay) {
    int k = c->k_vis++;
    return k < ps->n_vis ? ps->vis[k] : 1;
  }
  path__topo(c, 1000);
  c->rays++;
  int blocked = infinite ? scene_occluded_ray(c->sc, p, wi) : scene_occluded_segment(c->sc, p, lp);
  if (ps->n_vis < PATH__MAX_VIS)
    ps->vis[ps->n_vis++] = (unsigned char)blocked;
  else
    c->lost = 1;
  path__topo(c, blocked);
  return blocked;
}

/* ---------------------------------------------------------------------------
 * The camera (camera.c's formulas): rx = u0 W, ry = u1 H, and the pinhole
 * ray normalize(to_world (x, y, 1)) with x = -(2 rx / W - 1) tan_half_x,
 * y = -(2 ry / H - 1) tan_half_y.
 */

void path__camera_ray(path__ctx *c, ad u0, ad u1, ad *OUT_rx, ad *OUT_ry, adv3 *OUT_org,
                      adv3 *OUT_dir) {
  ad_arena *A = c->A;
  const camera *cam = &c->sc->cam;
  double rxv = u0.v * cam->width, ryv = u1.v * cam->height;
  *OUT_rx = path__chain(A, rxv, cam->width, u0);
  *OUT_ry = path__chain(A, ryv, cam->height, u1);
  double xv = -(2.0 * rxv / cam->width - 1.0) * cam->tan_half_x;
  double yv = -(2.0 * ryv / cam->height - 1.0) * cam->tan_half_y;
  adv3 dloc = {path__chain(A, xv, -2.0 * cam->tan_half_x, u0),
               path__chain(A, yv, -2.0 * cam->tan_half_y, u1), ad_const(A, 1.0)};
  *OUT_dir = adv3_normalize(A, path__mat_vec(A, (const double (*)[4])cam->to_world.m, dloc));
  *OUT_org = path__cv(A, cam->pos);
}

/* ---------------------------------------------------------------------------
 * The unidirectional estimator: pt_li's walk (pt_generic.h) with its dual hooks.
 */

/* Adds beta * c to L and notes what contributed. */
static void path__add(path__ctx *c, adrgb *L, adrgb beta, adrgb contrib, unsigned emit,
                      unsigned lobes, int length) {
  if (path__rgb_black(contrib) || path__rgb_black(beta)) return;
  *L = path__rgb_fma(c->A, *L, beta, contrib);
  c->flags |= emit | lobes;
  if (length > c->length) c->length = length;
}

/* An infinite light's radiance along dir (its envmap pixel is part of the
 * topology). */
static rgb path__le_infinite(path__ctx *c, const light *l, adv3 dir) {
  rgb le = light_le_infinite(l, path__val(dir));
  if (l->type == LIGHT_ENVMAP) path__topo(c, (int64_t)(1e6 * rgb_luminance(le))); /* the pixel */
  return le;
}

/* ---------------------------------------------------------------------------
 * Through participating media (media_trace_generic.h's flight and shadow
 * ray, written once with media_trace.c's plain forms, here in duals): the
 * boundaries' hits re-evaluated on the dual rays, each piece's
 * length the distance between them, so that the distances, the
 * transmittances and the scattering points move with the path.
 */

/* |b - a| in duals. */
static ad path__dist(ad_arena *A, adv3 a, adv3 b) { return adv3_length(A, adv3_sub(A, b, a)); }

#define R_DUAL 1
#include "render/real.h"
#define MT_FLY path__fly
#define MT_TRANSMIT path__transmit
#define MT_CTX path__ctx *c
#define MT_SC (c->sc)
#define MT_ARENA ad_arena *A = c->A;
#define MT_HIT path__hit
#define MT_TRACE_FLY(org, dir, tmin, h) path__trace(c, (org), (dir), (tmin), INFINITY, 1, (h))
#define MT_SEGMENT(org, dir, tmin, tmax) path__topo(c, (tmax) > (tmin))
#define MT_TRACE_SEG(org, dir, tmin, tmax, h) path__trace(c, (org), (dir), (tmin), (tmax), 1, (h))
#define MT_LEN(org, h) path__dist(A, (org), (h)->p)
#define MT_DIST(a, b) path__dist(A, (a), (b))
#define MT_FULL(p, lp, dist) (isinf(dist) ? ad_const(A, INFINITY) : path__dist(A, (p), (lp)))
#define MT_BLOCKED(p, wi, lp, dist) \
  path__blocked(c, path__val(p), path__val(wi), path__val(lp), isinf(dist))
#define MT_TOPO(x) path__topo(c, (x))
#include "render/integrators/media_trace_generic.h"

#define PT_CTX path__ctx *c
#define PT_SCENE (c->sc)
#define PT_RS (c->rs)
#define PT_ARENA ad_arena *A = c->A;
#define PT_HIT path__hit
#define PT_LI path__li
#define PT_INTERSECT(org, dir, tmin, h) path__intersect(c, (org), (dir), (tmin), (h))
#define PT_BLOCKED(p, wi, lp, dist) \
  path__blocked(c, path__val(p), path__val(wi), (lp), isinf(dist))
#define PT_DRAW(diff) path__draw(c, (diff))
#define PT_TOPO(x) path__topo(c, (x))
#define PT_LE_INFINITE(l, dir, pdf) path__le_infinite(c, (l), (dir))
#define PT_PDF_INFINITE(l, dir, ref, pdf) \
  ((void)(pdf), path__pdf_li(c, (l), (ref), (dir), (ref), v3(0.0, 0.0, 0.0)))
#define PT_PDF_LI(l, ref, w, p, n) path__pdf_li(c, (l), (ref), (w), (p), (n))
#define PT_SAMPLE_LI(l, ref, u1, u2, ls) path__sample_li(c, (l), (ref), (u1), (u2), (ls))
#define PT_MIS(a, b) path__mis(A, (a), (b))
#define PT_SCALE_C(col, w) path__rgb_scale_c(A, (col), (w))
#define PT_ADD(L, beta, contrib, emit, lobes, length) \
  path__add(c, &(L), (beta), (contrib), (emit), (lobes), (length))
#define PT_RR_Q(beta, eta) \
  ad_fmin(A, ad_const(A, 0.95), ad_mul_s(A, ad_fmax(A, (beta).r, ad_fmax(A, (beta).g, (beta).b)), (eta)))
#define PT_LOBE(flags) path__lobe_flag(flags)
#define PT_FOOTPRINT(h, depth, org) ((void)0)
#define PT_MEDIA_CODE 1
#define PT_MEDIA_ON (c->media)
#define PT_TRANSMIT(at, w, sample, cur, T) \
  path__transmit(c, (at), (w), (sample).pd, (sample).dist, (cur), (T))
#define PT_FLY(org, dir, tmin, med, u_ch, u_t, h, vp, fw) \
  path__fly(c, (org), (dir), (tmin), (med), (u_ch), (u_t), (h), (vp), NULL, NULL, (fw))
#define PT_MEDIUM_AFTER(h, cur, dir) scene_medium_across(c->sc, (h)->mesh, (h)->ng, (cur), (dir))
#include "render/integrators/pt_generic.h"

/* The unidirectional estimator: the film position and the camera ray, then
 * pt_li's walk (pt_generic.h) in duals. */
static void path__pt(path__ctx *c, adrgb *OUT_L, ad *OUT_rx, ad *OUT_ry) {
  path__use_stream(c, LMC_STREAM_CAMERA);
  ad u0 = path__draw(c, 1), u1 = path__draw(c, 1);
  adv3 org, dir;
  path__camera_ray(c, u0, u1, OUT_rx, OUT_ry, &org, &dir);
  *OUT_L = pt__walk(c, org, dir, OUT_rx, OUT_ry);
}

/* ---------------------------------------------------------------------------
 * The two passes.
 */

static void path__ctx_init(path__ctx *c, const scene *sc, const render_settings *rs,
                           path_scratch *ps, lmc_sampler *smp, int replay) {
  memset(c, 0, sizeof *c);
  c->sc = sc;
  c->rs = rs;
  c->ps = ps;
  c->A = &ps->A;
  c->smp = smp;
  c->replay = replay;
  c->jac = 1.0;
  c->media = render_media_on(sc, rs); /* (the unidirectional estimator's) */
}

void path__run(const scene *sc, const render_settings *rs, lmc_sampler *smp, int want_grad,
               path_scratch *ps, path_eval *ev, int64_t *rays, path__estimator est,
               const void *arg) {
  memset(ev, 0, sizeof *ev);
  ps->n_draw = ps->n_hit = ps->n_vis = 0;

  /* Pass 1: values, with Embree, recording the topology. */
  path__ctx c;
  path__ctx_init(&c, sc, rs, ps, smp, 0);
  c.arg = arg;
  ad_arena_init(&ps->A, ps->arena_buf, ps->arena_cap, 0);
  adrgb L;
  ad rx, ry;
  est(&c, &L, &rx, &ry);
  if (rays) *rays += c.rays;
  ev->value = adrgb_value(L);
  ev->lum = rgb_luminance(ev->value);
  ev->jac = c.jac;
  ev->rx = rx.v;
  ev->ry = ry.v;
  ev->flags = c.flags;
  ev->length = c.length;
  ev->topology = c.topo;
  ev->n_coords = ps->n_draw;
  ev->coords = ps->coords;
  ev->hlum = NULL;
  ev->hess_ok = 0;
  for (int k = 0; k < ps->n_draw; k++) {
    path_coord *pc = &ps->coords[k];
    memset(pc, 0, sizeof *pc);
    pc->var = -1;
    pc->stream = ps->dstream[k];
    pc->pos = ps->dpos[k];
    pc->u = ps->du[k];
    pc->diff = ps->dvar[k] >= 0;
  }
  if (!want_grad || c.lost || !(ev->lum > 0.0) || !isfinite(ev->lum)) return;

  /* Pass 2: the same function on the record, with tangents (and with
   * Hessians in a second-order arena when they are asked for). */
  int n_var = c.n_var;
  size_t duals2 = want_grad >= PATH_WANT_HESS && n_var <= AD_H_CAPACITY
                      ? path__arena2_first(ps, n_var)
                      : 0; /* 0: a first-order arena */
  int order2;
  for (;;) {
    path__ctx_init(&c, sc, rs, ps, NULL, 1);
    c.arg = arg;
    order2 = duals2 > 0;
    if (order2)
      ad_arena_init2(&ps->A, ps->arena2_buf, ad_arena_size2(n_var, duals2), n_var);
    else
      ad_arena_init(&ps->A, ps->arena_buf, ps->arena_cap, n_var);
    est(&c, &L, &rx, &ry);
    /* A second-order arena keeps every dual of the path: when they do not
     * fit, again in one four times as large, and past the limit in a
     * first-order arena (the gradient alone). */
    if (ad_arena_ok(&ps->A) || !order2) break;
    duals2 = path__arena2(ps, n_var, 4 * duals2);
  }
  ev->n_diff = n_var;
  if (!ad_arena_ok(&ps->A)) return;
  ad lum = adrgb_luminance(&ps->A, L);
  for (int k = 0; k < ps->n_draw; k++) {
    int j = ps->dvar[k];
    if (j < 0) continue;
    path_coord *pc = &ps->coords[k];
    const ad_arena *A = &ps->A;
    pc->var = j;
    pc->dlum = ad_deriv(A, lum, j);
    pc->drgb = rgb_make(ad_deriv(A, L.r, j), ad_deriv(A, L.g, j), ad_deriv(A, L.b, j));
    pc->drx = ad_deriv(A, rx, j);
    pc->dry = ad_deriv(A, ry, j);
  }
  ev->grad_ok = ad_arena_ok(&ps->A);
  if (order2 && ev->grad_ok && ad_hessian(&ps->A, lum, ps->hfull) == 0) {
    /* path_eval.hlum's layout: the upper triangle row by row. */
    size_t q = 0;
    for (int i = 0; i < n_var; i++)
      for (int j = i; j < n_var; j++) ps->hlum[q++] = ps->hfull[(size_t)i * (size_t)n_var + (size_t)j];
    ev->hlum = ps->hlum;
    ev->hess_ok = 1;
  }
}

lmc_status path_eval_pt(const scene *sc, const render_settings *rs, lmc_sampler *smp,
                        int want_grad, path_scratch *ps, path_eval *OUT_eval, int64_t *rays) {
  path__run(sc, rs, smp, want_grad, ps, OUT_eval, rays, path__pt, NULL);
  return LMC_OK;
}

/* ---------------------------------------------------------------------------
 * The vector sampler.
 */

static double path__vec_next(lmc_sampler *self) {
  path_vec_sampler *s = (path_vec_sampler *)self;
  int k = s->stream;
  if (s->pos[k] < s->n[k]) return s->u[k][s->pos[k]++];
  double u = rng_uniform(&s->r);
  if (s->n[k] == s->cap[k]) {
    int ncap = s->cap[k] ? 2 * s->cap[k] : 256;
    double *nu = realloc(s->u[k], (size_t)ncap * sizeof(double));
    if (!nu) return u; /* not stored: the next replay draws afresh */
    s->u[k] = nu;
    s->cap[k] = ncap;
  }
  s->u[k][s->n[k]++] = u;
  s->pos[k]++;
  return u;
}

static void path__vec_use_stream(lmc_sampler *self, int stream) {
  path_vec_sampler *s = (path_vec_sampler *)self;
  if (stream >= 0 && stream < LMC_STREAM_COUNT) s->stream = stream;
}

lmc_status path_vec_sampler_init(path_vec_sampler *s, uint64_t seed, lmc_error *err) {
  (void)err;
  memset(s, 0, sizeof *s);
  s->base.next = path__vec_next;
  s->base.use_stream = path__vec_use_stream;
  rng_seed(&s->r, rng_hash64(seed), 0x9e3779b97f4a7c15ull);
  return LMC_OK;
}

void path_vec_sampler_free(path_vec_sampler *s) {
  if (!s) return;
  for (int k = 0; k < LMC_STREAM_COUNT; k++) free(s->u[k]);
  memset(s->u, 0, sizeof s->u);
}

void path_vec_sampler_clear(path_vec_sampler *s) {
  for (int k = 0; k < LMC_STREAM_COUNT; k++) s->n[k] = s->pos[k] = 0;
  s->stream = LMC_STREAM_CAMERA;
}

void path_vec_sampler_rewind(path_vec_sampler *s) {
  for (int k = 0; k < LMC_STREAM_COUNT; k++) s->pos[k] = 0;
  s->stream = LMC_STREAM_CAMERA;
}
