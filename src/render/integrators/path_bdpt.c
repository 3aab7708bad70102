/*
 * path_bdpt.c: one bidirectional strategy (s, t) of BDPT (Veach and Guibas
 * 1995; Veach 1997, chapter 10) in dual arithmetic, with its
 * power-heuristic MIS weight over all strategies: the per-state
 * contribution of multiplexed MLT (Hachisuka et al. 2014) and its exact
 * gradient in primary sample space, for Langevin Monte Carlo (Luan et al.
 * 2020).
 *
 * This is integrator_bdpt.c's bdpt_camera_subpath, bdpt_light_subpath,
 * bdpt_connect and bdpt_mis_weight over duals, from the same source
 * (bdpt_generic.h: the walks, the densities, the MIS weight and the
 * connections); this file gives that source its dual hooks (numbers drawn
 * and recorded, rays replayed, the emitters' and the camera's densities in
 * duals) and runs one strategy. For the same numbers the value is
 * bdpt_connect's (tests/test_path_grad*.c check it to 1e-9 relative). It runs on the machinery of path.c (path_internal.h):
 * numbers are drawn and recorded by path__draw, closest hits and shadow
 * rays are traced in pass 1 and replayed in pass 2 (path__intersect,
 * path__blocked), each vertex is re-evaluated on its recorded triangle
 * (path__hit_eval), the camera ray and the emitters' direct sampling and
 * densities are path.c's (path__camera_ray, path__sample_li, path__pdf_li,
 * path__area_point, the envmap routines). What only BDPT needs lives here:
 * emission sampling (light_sample_le, with the concentric disk and the
 * sphere, cone and cosine warps), emission densities (light_pdf_le), the
 * camera's importance and direction density, and the random walks with
 * their forward and reverse densities.
 *
 * Numbers (integrator.h's BDPT layout):
 *   LMC_STREAM_CAMERA   t >= 2 only: 2 for the film position (rx = u0 W,
 *                       ry = u1 H, as path_eval_pt), then per camera-subpath
 *                       surface vertex: lobe (discrete), direction (2),
 *                       roulette (discrete). t = 1 draws nothing here: the
 *                       splat's raster position is that of the light vertex.
 *   LMC_STREAM_LIGHT    s >= 2 only: light choice (discrete), position (2),
 *                       direction (2), then per light-subpath surface vertex
 *                       as the camera's.
 *   LMC_STREAM_CONNECT  s = 1 only: the triple of camera vertex t, i.e.
 *                       positions 3 (t - 2) ... 3 (t - 2) + 2 (light choice,
 *                       point on the light); the 3 (t - 2) numbers before it
 *                       are drawn too (they belong to other t) and do not
 *                       change f.
 * Tangent slots go to the continuous numbers only: 2 + 2 per camera vertex
 * after z_0, 4 + 2 per light vertex after y_0, 2 for a connection.
 *
 * Differentiated: every vertex position (Moller-Trumbore on its triangle,
 * or the emitter's sampled point: area-light triangle points, the disk of
 * lights at infinity), direction, shading frame and texture coordinate;
 * BSDF values and densities (bsdf_ad.h); emission densities (cosine of an
 * area light, the envmap's 1 / sin theta inside its pixel, the camera's
 * 1 / cos^3); the spot falloff; geometry terms; the importance We and the
 * raster position of a t = 1 splat; roulette divisors; and every pdf_fwd /
 * pdf_rev ratio of the MIS walk. Not differentiated (held fixed, as
 * path.h explains): the triangles hit, the lobes, the light and triangle
 * chosen, the envmap pixel, visibility and roulette decisions; all enter
 * the topology hash.
 */
#include <string.h>

#include "render/integrators/path_internal.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* The strategy handed to the estimator through path__ctx.arg. */
typedef struct pbd__strategy {
  int s, t;
  double rough_min; /* absolute directions at scattering vertices rougher than this (>= 1: none) */
} pbd__strategy;

/* bdpt_sphere_dir in duals: the world direction of spherical coordinates
 * (v1, v2), and J = 2 pi^2 sin(pi v2). */
static adv3 pbd__sphere_dir(ad_arena *A, ad v1, ad v2, ad *OUT_jac) {
  ad phi = ad_mul_s(A, v1, 2.0 * M_PI), theta = ad_mul_s(A, v2, M_PI);
  ad st = ad_sin(A, theta);
  *OUT_jac = ad_mul_s(A, ad_fabs(A, st), 2.0 * M_PI * M_PI);
  adv3 w;
  w.x = ad_mul(A, st, ad_cos(A, phi));
  w.y = ad_mul(A, st, ad_sin(A, phi));
  w.z = ad_cos(A, theta);
  return w;
}

/* ---------------------------------------------------------------------------
 * The camera: direction density and importance (camera.c's formulas).
 */

/* Camera-space unit direction of world direction w. */
static adv3 pbd__cam_local(path__ctx *c, adv3 w) {
  const camera *cam = &c->sc->cam;
  return adv3_normalize(c->A, path__mat_vec(c->A, (const double (*)[4])cam->to_world.inv, w));
}

/* camera_pdf_dir: 1 / (A cos^3 theta) inside the image, with A = 4 tan_x tan_y. */
static ad pbd__cam_pdf_dir(path__ctx *c, adv3 w) {
  ad_arena *A = c->A;
  const camera *cam = &c->sc->cam;
  adv3 d = pbd__cam_local(c, w);
  if (!(d.z.v > 0.0)) return ad_const(A, 0.0);
  double x = d.x.v / d.z.v, y = d.y.v / d.z.v;
  if (fabs(x) > cam->tan_half_x || fabs(y) > cam->tan_half_y) return ad_const(A, 0.0);
  double a = 4.0 * cam->tan_half_x * cam->tan_half_y;
  ad den = ad_mul(A, ad_mul(A, ad_mul_s(A, d.z, a), d.z), d.z);
  return ad_s_div(A, 1.0, den);
}

/* camera_we: We = W H / (A cos^4 theta) and the raster point of direction
 * w, rx = (1 - x / tan_x) W / 2 with x = d_x / d_z (likewise ry); 0 when w
 * misses the film. */
static ad pbd__cam_we(path__ctx *c, adv3 w, ad *OUT_rx, ad *OUT_ry) {
  ad_arena *A = c->A;
  const camera *cam = &c->sc->cam;
  adv3 d = pbd__cam_local(c, w);
  if (!(d.z.v > 0.0)) return ad_const(A, 0.0);
  ad x = ad_div(A, d.x, d.z), y = ad_div(A, d.y, d.z);
  ad px = ad_mul_s(A, ad_mul_s(A, ad_s_sub(A, 1.0, ad_div_s(A, x, cam->tan_half_x)), 0.5),
                   cam->width);
  ad py = ad_mul_s(A, ad_mul_s(A, ad_s_sub(A, 1.0, ad_div_s(A, y, cam->tan_half_y)), 0.5),
                   cam->height);
  if (!(px.v >= 0.0 && px.v < cam->width && py.v >= 0.0 && py.v < cam->height))
    return ad_const(A, 0.0);
  *OUT_rx = px;
  *OUT_ry = py;
  double a = 4.0 * cam->tan_half_x * cam->tan_half_y;
  ad cos2 = ad_sqr(A, d.z);
  return ad_s_div(A, (double)cam->width * cam->height, ad_mul(A, ad_mul_s(A, cos2, a), cos2));
}

/* ---------------------------------------------------------------------------
 * Emission sampling (light.c's light_sample_le, light_ad.h) in duals.
 */

/* light_sample_le in duals (light_ad.h), its choices noted in the topology. */
typedef light_le_sample_ad pbd__le;
static int pbd__sample_le(path__ctx *c, const light *l, ad u1, ad u2, ad u3, ad u4,
                          pbd__le *out) {
  int ok = light_sample_le_ad(c->A, l, c->sc, u1, u2, u3, u4, out);
  path__light_topo(c, out->tri, out->cell);
  return ok;
}

/* The solid-angle density of light_pdf_le for emission from p (normal n)
 * along the unit travel direction w. */
static ad pbd__pdf_le_dir(path__ctx *c, const light *l, adv3 p, vec3 n, adv3 w) {
  return light_pdf_le_dir_ad(c->A, l, c->sc, p, n, w);
}

/* ---------------------------------------------------------------------------
 * The steps shared with integrator_bdpt.c (bdpt_generic.h), in duals: vertex
 * queries, f cos, the densities of the MIS walk and the MIS weight.
 */

#define R_DUAL 1
#include "render/real.h"
#define BDPT_VERTEX path__bdv
#define BDPT_HIT path__hit
#define BDPT_CTX path__ctx *c
#define BDPT_C c
#define BDPT_SC (c->sc)
#define BDPT_ARENA ad_arena *A = c->A;
#define BDPT_CAM_PDF_DIR(w) pbd__cam_pdf_dir(c, (w))
#define BDPT_PDF_LE_DIR(l, p, n, w) pbd__pdf_le_dir(c, (l), (p), (n), (w))
#define BDPT_PDF_LI(l, ref, w, p, n) path__pdf_li(c, (l), (ref), (w), (p), (n))
/* Russian roulette's q in duals: rgb_max of the throughput (times the
 * radiance compression), or of its ratio to y_1's (rgb_div: a zero
 * denominator gives 0). */
static ad pbd__rr_q(ad_arena *A, transport_mode mode, adrgb beta, adrgb b1, double eta_scale) {
  ad thr;
  if (mode == TRANSPORT_RADIANCE) {
    thr = ad_mul_s(A, ad_fmax(A, beta.r, ad_fmax(A, beta.g, beta.b)), eta_scale);
  } else {
    ad r = b1.r.v != 0.0 ? ad_div(A, beta.r, b1.r) : ad_const(A, 0.0);
    ad g = b1.g.v != 0.0 ? ad_div(A, beta.g, b1.g) : ad_const(A, 0.0);
    ad b = b1.b.v != 0.0 ? ad_div(A, beta.b, b1.b) : ad_const(A, 0.0);
    thr = ad_fmax(A, r, ad_fmax(A, g, b));
  }
  return ad_fmin(A, ad_const(A, 0.95), thr);
}

/* The vertex of an escaped ray: beyond the scene (a constant). */
static adv3 pbd__far_point(path__ctx *c, adv3 org, adv3 dir) {
  vec3 o = path__val(org);
  const scene *sc = c->sc;
  return path__cv(c->A, v3_fma(o, path__val(dir), 2.0 * sc->radius + v3_len(v3_sub(o, sc->center))));
}

#define BDPT_WALK_CTX path__ctx *w
#define BDPT_WALK_PROLOGUE \
  path__ctx *c = w;        \
  ad_arena *A = c->A;      \
  (void)c, (void)A;
#define BDPT_W_INTERSECT(org, dir, tmin, hit) path__intersect(w, (org), (dir), (tmin), (hit))
#define BDPT_W_DRAW(diff) path__draw(w, (diff))
#define BDPT_W_TOPO(x) path__topo(w, (x))
#define BDPT_W_FAR_POINT(org, dir) pbd__far_point(w, (org), (dir))
#define BDPT_W_ROUGH(h)                                                  \
  (((const pbd__strategy *)w->arg)->rough_min < 1.0 &&                  \
   bsdf_is_rough((h)->bsdf, ((const pbd__strategy *)w->arg)->rough_min))
#define BDPT_W_ABSOLUTE(rough, n) (rough)
#define BDPT_W_SPHERE_DIR(u1, u2, J) pbd__sphere_dir(A, (u1), (u2), (J))
#define BDPT_W_PDF_REV(bs, h, wo_l) bsdf_pdf_ad(A, (h)->bsdf, (h)->tu, (h)->tv, (bs).wi, (wo_l))
#define BDPT_W_RR_Q(mode, beta, beta1, eta) pbd__rr_q(A, (mode), (beta), (beta1), (eta))
#define BDPT_W_SET_LOBE(v, flags) ((v)->lobe = path__lobe_flag(flags))
#define BDPT_W_LE pbd__le
#define BDPT_W_SAMPLE_LE(l, u1, u2, u3, u4, les) pbd__sample_le(w, (l), (u1), (u2), (u3), (u4), (les))
/* The s = 1 connection's three numbers: the connect triple of this t
 * (the ones of smaller t are drawn too, unused). */
static int pbd__numbers(path__ctx *c, int t, ad u[3]) {
  path__use_stream(c, LMC_STREAM_CONNECT);
  for (int k = 0; k < BDPT_DIMS_CONNECT * (t - 2); k++) path__draw(c, 0);
  u[0] = path__draw(c, 0), u[1] = path__draw(c, 1), u[2] = path__draw(c, 1);
  return 1;
}

/* Lobes of the non-delta part of a connection vertex's BSDF. */
static unsigned pbd__connect_lobes(const path__bdv *v) {
  return path__lobe_flag(bsdf_flags(v->hit.bsdf) & ~BSDF_DELTA);
}

#define BDPT_JOIN_CTX path__ctx *j
#define BDPT_JOIN_PROLOGUE \
  path__ctx *c = j;        \
  ad_arena *A = c->A;      \
  (void)c;
#define BDPT_J_SEGMENT_BLOCKED(a, dir, b) \
  path__blocked(j, path__val(a), path__val(dir), path__val(b), 0)
#define BDPT_J_BLOCKED(p, wi, lp, dist) \
  path__blocked(j, path__val(p), path__val(wi), (lp), isinf(dist))
#define BDPT_J_CAMERA_WE(dir, rx, ry) pbd__cam_we(j, (dir), (rx), (ry))
#define BDPT_J_NUMBERS(t, u) pbd__numbers(j, (t), (u))
#define BDPT_J_LI path__li
#define BDPT_J_SAMPLE_LI(l, ref, u1, u2, ls) path__sample_li(j, (l), (ref), (u1), (u2), (ls))
#define BDPT_J_LI_POINT(ls) ((ls).pd)
#define BDPT_J_TOPO(x) path__topo(j, (x))
#define BDPT_J_EMIT(l) path__emit_flag(l)
#define BDPT_J_EMIT_AREA PATH_EMIT_AREA
#define BDPT_J_LOBES(v) pbd__connect_lobes(v)
#define BDPT_MEDIA_CODE 0
#include "render/integrators/bdpt_generic.h"

/* ---------------------------------------------------------------------------
 * The camera subpath (the walk and the light subpath are bdpt_generic.h's).
 */

/* The camera subpath (bdpt_camera_subpath) from the film position (u0, u1). */
static int pbd__camera_subpath(path__ctx *c, ad u0, ad u1, int max_vertices, path__bdv *path,
                               ad *OUT_rx, ad *OUT_ry) {
  bdpt__camera_vertex(c, &path[0]);
  if (max_vertices < 2) return 1;
  adv3 org, dir;
  path__camera_ray(c, u0, u1, OUT_rx, OUT_ry, &org, &dir);
  return bdpt__camera_walk(c, org, dir, max_vertices, path);
}


/* ---------------------------------------------------------------------------
 * One strategy (bdpt_connect).
 */


/* Traces the strategy's two subpaths; returns 0 when they are not whole
 * (the strategy contributes nothing). */
static int pbd__subpaths(path__ctx *c, int s, int t, path__bdv *cam, path__bdv *lp, ad *OUT_rx,
                         ad *OUT_ry) {
  ad_arena *A = c->A;
  /* The camera subpath: t vertices (t = 1: the pinhole alone, no numbers). */
  int nc = 1;
  if (t >= 2) {
    path__use_stream(c, LMC_STREAM_CAMERA);
    ad u0 = path__draw(c, 1), u1 = path__draw(c, 1);
    nc = pbd__camera_subpath(c, u0, u1, t, cam, OUT_rx, OUT_ry);
  } else {
    pbd__camera_subpath(c, ad_const(A, 0.0), ad_const(A, 0.0), 1, cam, NULL, NULL);
  }
  path__topo(c, nc);
  if (nc < t) return 0;
  /* The light subpath: s vertices (s <= 1 needs none). */
  if (s >= 2) {
    path__use_stream(c, LMC_STREAM_LIGHT);
    int nl = bdpt__light_walk(c, s, lp);
    path__topo(c, nl);
    if (nl < s) return 0;
  }
  return 1;
}

static void pbd__estimate(path__ctx *c, adrgb *OUT_L, ad *OUT_rx, ad *OUT_ry) {
  ad_arena *A = c->A;
  const render_settings *rs = c->rs;
  const pbd__strategy *st = c->arg;
  int s = st->s, t = st->t;
  path__bdv *cam = c->ps->bd_cam, *lp = c->ps->bd_light;
  adrgb zero = adrgb_const(A, rgb_zero());
  *OUT_L = zero;
  *OUT_rx = *OUT_ry = ad_const(A, 0.0);

  /* A strategy BDPT uses, with a length inside [mindepth, maxdepth]. */
  int max_cam, max_light;
  bdpt_subpath_limits(rs, &max_cam, &max_light);
  int length = s + t - 1;
  if (t < 1 || s < 0 || length < 1 || (s == 1 && t == 1)) return;
  if (t > max_cam || (s >= 2 && s > max_light)) return;
  if ((rs->maxdepth >= 0 && length > rs->maxdepth) || (rs->mindepth > 0 && length < rs->mindepth))
    return;
  if (!pbd__subpaths(c, s, t, cam, lp, OUT_rx, OUT_ry)) return;
  /* An escaped camera ray is only an emitter (s = 0). */
  if (t > 1 && s != 0 && cam[t - 1].type == BDPT_VERTEX_LIGHT) return;

  /* The lobes sampled inside both subpaths (the connection vertices' own
   * lobes are added by the join). */
  bdpt__join J;
  J.L = zero;
  J.stage = 0;
  J.emit = J.lobes = 0;
  J.has_sampled = 0;
  for (int i = 1; i < t - 1; i++) J.lobes |= cam[i].lobe;
  for (int i = 1; i < s - 1; i++) J.lobes |= lp[i].lobe;
  if (s == 0)
    bdpt__join_emitter(c, cam, t, &J);
  else if (t == 1)
    bdpt__join_camera(c, cam, lp, s, &J, OUT_rx, OUT_ry);
  else if (s == 1)
    bdpt__join_light(c, cam, t, &J);
  else
    bdpt__join_vertices(c, cam, t, lp, s, &J);
  path__topo(c, J.stage);
  if (path__rgb_black(J.L)) {
    *OUT_L = zero;
    return;
  }

  /* The MIS weight over all strategies of this path (its temporaries are
   * dropped). */
  size_t mark = ad_arena_mark(A);
  const path__bdv *samp = J.has_sampled ? &J.sampled : NULL;
  ad w = ad_arena_rewind_keep(A, mark, bdpt__mis_weight(c, cam, t, lp, s, samp, NULL));
  *OUT_L = adrgb_scale(A, J.L, w);
  /* Absolute directions: the value in their measure. */
  if (st->rough_min < 1.0) {
    ad jac = ad_const(A, 1.0);
    for (int j = 1; j <= t - 2; j++) jac = ad_mul(A, jac, cam[j].jac);
    for (int j = 1; j <= s - 2; j++) jac = ad_mul(A, jac, lp[j].jac);
    c->jac = jac.v;
    *OUT_L = adrgb_scale(A, *OUT_L, jac);
  }
  if (!path__rgb_black(*OUT_L)) {
    c->flags |= J.emit | J.lobes;
    c->length = length;
  }
}

lmc_status path_eval_bdpt(const scene *sc, const render_settings *rs, lmc_sampler *smp, int s,
                          int t, int want_grad, path_scratch *ps, path_eval *OUT_eval,
                          int64_t *rays) {
  pbd__strategy st = {s, t, 2.0};
  path__run(sc, rs, smp, want_grad, ps, OUT_eval, rays, pbd__estimate, &st);
  return LMC_OK;
}

lmc_status path_eval_bdpt_abs(const scene *sc, const render_settings *rs, lmc_sampler *smp, int s,
                              int t, double rough_min, int want_grad, path_scratch *ps,
                              path_eval *OUT_eval, int64_t *rays) {
  pbd__strategy st = {s, t, rough_min};
  path__run(sc, rs, smp, want_grad, ps, OUT_eval, rays, pbd__estimate, &st);
  return LMC_OK;
}
