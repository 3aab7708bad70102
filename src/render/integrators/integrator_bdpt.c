/*
 * integrator_bdpt.c: bidirectional path tracing (Veach and Guibas 1995;
 * Veach 1997, chapter 10) with multiple importance sampling over all
 * strategies, power heuristic.
 *
 * A camera subpath z_0 (the pinhole) ... z_{t-1} and a light subpath
 * y_0 (on a light) ... y_{s-1} are traced once per pixel sample; every
 * prefix pair (s, t) then makes one full path:
 *   s = 0        z_{t-1} is itself on an emitter (area light, or the ray
 *                escaped to the infinite lights);
 *   s = 1        next-event estimation: a fresh light sample joined to
 *                z_{t-1} (scene_sample_light + light_sample_li);
 *   t = 1        light tracing: y_{s-1} joined to the pinhole and splatted
 *                at the raster point camera_we returns;
 *   s, t >= 2    y_{s-1} and z_{t-1} joined by a shadow ray.
 * (s = 1, t = 1) is not used: lights seen directly come from s = 0.
 *
 * Contributions. With beta the subpath throughputs (products of BSDF
 * sample weights over the emission or camera densities) and f_s the BSDF
 * including the shading cosine,
 *   C(s,t) = beta_y f_s(y_{s-2} -> y_{s-1} -> z_{t-1}) G f_s(y_{s-1} -> z_{t-1} -> z_{t-2}) beta_z,
 *   G = 1 / |y_{s-1} - z_{t-1}|^2 (visibility tested by a shadow ray).
 * For t = 1 the camera factor is We cos_cam / d^2 with We = camera_we
 * (normalised per pixel, see camera.h); the driver scales splats by
 * W H / samples.
 *
 * Light subpaths carry importance (TRANSPORT_IMPORTANCE) and Veach's
 * shading-normal correction (thesis section 5.3; pbrt's
 * CorrectShadingNormal): at a light-subpath vertex with wo towards the
 * light and wi onward, f is multiplied by
 *   |wo . n_s| |wi . n_g| / (|wo . n_g| |wi . n_s|),
 * so that both subpaths estimate the same integrand as pt_li. Mitsuba's
 * rule that a direction is used only when it lies on the same side of the
 * geometric and the shading surface applies to every direction at every
 * scattering vertex, on both subpaths and at connections (as in pt_li).
 *
 * MIS weights. Each vertex keeps pdf_fwd (its density under its own
 * subpath's sampling) and pdf_rev (its density when sampled from the other
 * end), per unit area; vertices at infinity (escaped rays, infinite and
 * directional lights) use solid angle, and the vertex after them is
 * sampled with the planar density 1/(pi r^2) |cos| of light_sample_le's
 * disk. The power-heuristic weight is
 *   w(s,t) = 1 / (1 + sum_{s' != s} (p_{s'} / p_s)^2),
 * and the ratios p_{s'}/p_s follow from a walk outwards from the
 * connection, multiplying pdf_rev / pdf_fwd of one vertex per step (pbrt's
 * MISWeight, with zero densities of delta lobes read as one, so the delta
 * factors cancel). The four vertices next to the connection get their
 * pdf_rev recomputed for the joined path. A strategy s' is skipped when
 * its connection would touch a vertex that scattered through a delta lobe,
 * when s' = 0 and the light is a delta light, and when s' = 1 and t' = 1.
 * Infinite lights are one emitter for the s = 0 strategy: their densities
 * are summed over all infinite lights (each weighted by its selection
 * probability). Russian roulette is not part of the densities.
 *
 * The steps that path_bdpt.c's differentiable strategy shares (vertex
 * queries, f cos, the densities of the MIS walk and the MIS weight) are
 * written once, in bdpt_generic.h.
 *
 * Random numbers: the layout of integrator.h (camera, light and connect
 * streams, a fixed number per vertex). Russian roulette, as pt_li, from
 * rrdepth segments on with survival min(0.95, max(throughput)): on the
 * camera subpath the throughput includes the eta^2 of refractions; on the
 * light subpath it is the product of the BSDF weights only (the emitted
 * power is not a probability).
 */
#include "render/integrators/integrator.h"
#include "render/warp.h"

#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ---------------------------------------------------------------------------
 * The steps shared with path_bdpt.c (bdpt_generic.h), in doubles.
 */

/* The emission density of direction w from point p (normal n) of light l. */
static double bdpt__pdf_le_dir(const scene *sc, const light *l, vec3 p, vec3 n, vec3 w) {
  double pdf_pos, pdf_dir;
  light_pdf_le(l, sc, p, n, w, &pdf_pos, &pdf_dir);
  return pdf_dir;
}

#define R_DUAL 0
#include "render/real.h"
#define BDPT_VERTEX bdpt_vertex
#define BDPT_HIT surface_hit
#define BDPT_CTX const scene *scene_
#define BDPT_C scene_
#define BDPT_SC scene_
#define BDPT_ARENA
#define BDPT_CAM_PDF_DIR(w) camera_pdf_dir(&scene_->cam, (w))
#define BDPT_PDF_LE_DIR(l, p, n, w) bdpt__pdf_le_dir(scene_, (l), (p), (n), (w))
#define BDPT_PDF_LI(l, ref, w, p, n) light_pdf_li((l), scene_, (ref), (w), (p), (n))
/* What the walk reads: the scene, the settings, the sampler, the absolute
 * directions' rule (NULL: none) and the counters. */
typedef struct bdpt__walker {
  const scene *sc;
  const render_settings *rs;
  lmc_sampler *smp;
  const bdpt_param *par;
  render_counters *cnt;
  int media; /* through the scene's media (bdpt_li on a scene with media) */
  int med;   /* then the medium the walk starts in */
} bdpt__walker;

static int bdpt__intersect(bdpt__walker *w, vec3 org, vec3 dir, double tmin, surface_hit *h) {
  w->cnt->rays++;
  return scene_intersect(w->sc, org, dir, tmin, INFINITY, h);
}

/* The point standing for an escaped ray's vertex: beyond the scene. */
static vec3 bdpt__far_point(const scene *sc, vec3 org, vec3 dir) {
  return v3_fma(org, dir, 2.0 * sc->radius + v3_len(v3_sub(org, sc->center)));
}

static double bdpt__rr_q(transport_mode mode, rgb beta, rgb beta1, double eta_scale) {
  double thr = mode == TRANSPORT_RADIANCE ? rgb_max(beta) * eta_scale : rgb_max(rgb_div(beta, beta1));
  return fmin(0.95, thr);
}

#define BDPT_WALK_CTX bdpt__walker *w
#define BDPT_WALK_PROLOGUE      \
  const scene *scene_ = w->sc; \
  (void)scene_;
#define BDPT_W_INTERSECT(org, dir, tmin, hit) bdpt__intersect(w, (org), (dir), (tmin), (hit))
#define BDPT_W_DRAW(diff) sampler_next(w->smp)
#define BDPT_W_TOPO(x) ((void)0)
#define BDPT_W_FAR_POINT(org, dir) bdpt__far_point(w->sc, (org), (dir))
#define BDPT_W_ROUGH(h) (w->par && bsdf_is_rough((h)->bsdf, w->par->rough_min))
#define BDPT_W_ABSOLUTE(rough, n) ((rough) && (n) - 1 < w->par->abs_until)
#define BDPT_W_SPHERE_DIR(u1, u2, J) bdpt_sphere_dir((u1), (u2), (J))
#define BDPT_W_PDF_REV(bs, h, wo_l) \
  ((bs).has_pdf_rev ? (bs).pdf_rev : bsdf_pdf((h)->bsdf, (h)->tu, (h)->tv, (bs).wi, (wo_l)))
#define BDPT_W_RR_Q(mode, beta, beta1, eta) bdpt__rr_q((mode), (beta), (beta1), (eta))
#define BDPT_W_SET_LOBE(v, flags) ((void)0)
#define BDPT_W_LE light_le_sample
#define BDPT_W_SAMPLE_LE(l, u1, u2, u3, u4, les) \
  light_sample_le((l), w->sc, (u1), (u2), (u3), (u4), (les))
/* What the connections read: the scene, the counters and the s = 1
 * connection's numbers (NULL: none). */
typedef struct bdpt__joiner {
  const scene *sc;
  render_counters *cnt;
  const double *u_connect;
  int media; /* through the scene's media */
} bdpt__joiner;

static int bdpt__segment_blocked(bdpt__joiner *j, vec3 a, vec3 b) {
  j->cnt->rays++;
  return scene_occluded_segment(j->sc, a, b);
}

static int bdpt__light_blocked(bdpt__joiner *j, vec3 p, vec3 wi, vec3 lp, double dist) {
  j->cnt->rays++;
  return isinf(dist) ? scene_occluded_ray(j->sc, p, wi) : scene_occluded_segment(j->sc, p, lp);
}

static int bdpt__numbers(const bdpt__joiner *j, double u[3]) {
  if (!j->u_connect) return 0;
  for (int k = 0; k < 3; k++) u[k] = j->u_connect[k];
  return 1;
}

#define BDPT_JOIN_CTX bdpt__joiner *j
#define BDPT_JOIN_PROLOGUE      \
  const scene *scene_ = j->sc; \
  (void)scene_;
#define BDPT_J_SEGMENT_BLOCKED(a, dir, b) bdpt__segment_blocked(j, (a), (b))
#define BDPT_J_BLOCKED(p, wi, lp, dist) bdpt__light_blocked(j, (p), (wi), (lp), (dist))
#define BDPT_J_CAMERA_WE(dir, rx, ry) camera_we(&j->sc->cam, (dir), (rx), (ry))
#define BDPT_J_NUMBERS(t, u) bdpt__numbers(j, (u))
#define BDPT_J_LI light_li_sample
#define BDPT_J_SAMPLE_LI(l, ref, u1, u2, ls) light_sample_li((l), j->sc, (ref), (u1), (u2), (ls))
#define BDPT_J_LI_POINT(ls) ((ls).p)
#define BDPT_J_TOPO(x) ((void)0)
#define BDPT_J_EMIT(l) 0u
#define BDPT_J_EMIT_AREA 0u
#define BDPT_J_LOBES(v) 0u
#define BDPT_MEDIA_CODE 1
#include "render/integrators/bdpt_generic.h"

/* ---------------------------------------------------------------------------
 * The sphere map of absolute directions (bdpt_param).
 */

vec3 bdpt_sphere_dir(double v1, double v2, double *OUT_jac) {
  double phi = 2.0 * M_PI * v1, theta = M_PI * v2;
  double st = sin(theta);
  if (OUT_jac) *OUT_jac = 2.0 * M_PI * M_PI * fabs(st);
  return v3(st * cos(phi), st * sin(phi), cos(theta));
}

void bdpt_sphere_coords(vec3 w, double *OUT_v1, double *OUT_v2, double *OUT_jac) {
  double phi = atan2(w.y, w.x);
  if (phi < 0.0) phi += 2.0 * M_PI;
  double v1 = phi / (2.0 * M_PI);
  double theta = acos(w.z < -1.0 ? -1.0 : w.z > 1.0 ? 1.0 : w.z);
  double v2 = theta / M_PI;
  *OUT_v1 = v1 < 1.0 ? v1 : 0.0;
  *OUT_v2 = v2 < 1.0 ? v2 : nextafter(1.0, 0.0);
  if (OUT_jac) *OUT_jac = 2.0 * M_PI * M_PI * sin(theta);
}

/* ---------------------------------------------------------------------------
 * The subpaths (their walk, bdpt__walk, is bdpt_generic.h's).
 */

void bdpt_subpath_limits(const render_settings *rs, int *OUT_max_camera, int *OUT_max_light) {
  int maxdepth = BDPT_MAX_VERTICES - 1;
  if (rs->maxdepth >= 0 && rs->maxdepth < maxdepth) maxdepth = rs->maxdepth;
  *OUT_max_camera = maxdepth + 1;
  *OUT_max_light = maxdepth;
}

int bdpt_camera_subpath(const scene *sc, const render_settings *rs, lmc_sampler *smp, double rx,
                        double ry, int max_vertices, bdpt_vertex *OUT_path, render_counters *cnt) {
  return bdpt_camera_subpath_p(sc, rs, smp, rx, ry, max_vertices, NULL, OUT_path, cnt);
}

int bdpt_camera_subpath_p(const scene *sc, const render_settings *rs, lmc_sampler *smp, double rx,
                          double ry, int max_vertices, const bdpt_param *par,
                          bdpt_vertex *OUT_path, render_counters *cnt) {
  if (max_vertices > BDPT_MAX_VERTICES) max_vertices = BDPT_MAX_VERTICES;
  if (max_vertices < 1) return 0;
  bdpt__walker w = {sc, rs, smp, par, cnt, render_media_on(sc, rs), 0};
  bdpt__camera_vertex(&w, &OUT_path[0]);
  vec3 org, dir;
  camera_generate_ray(&sc->cam, rx, ry, &org, &dir);
  return bdpt__camera_walk(&w, org, dir, max_vertices, OUT_path);
}

int bdpt_light_subpath(const scene *sc, const render_settings *rs, lmc_sampler *smp,
                       int max_vertices, bdpt_vertex *OUT_path, render_counters *cnt) {
  return bdpt_light_subpath_p(sc, rs, smp, max_vertices, NULL, OUT_path, cnt);
}

int bdpt_light_subpath_p(const scene *sc, const render_settings *rs, lmc_sampler *smp,
                         int max_vertices, const bdpt_param *par, bdpt_vertex *OUT_path,
                         render_counters *cnt) {
  bdpt__walker w = {sc, rs, smp, par, cnt, render_media_on(sc, rs), 0};
  return bdpt__light_walk(&w, max_vertices, OUT_path);
}

/* ---------------------------------------------------------------------------
 * The inverses of the subpaths (inverse path sampling).
 */

/* The light endpoint's light (y: a light vertex, or a surface on an area
 * light, as the end of a camera walk) and the triangle of its point. The
 * infinite lights together (light -1, an escaped camera ray) resolve to
 * one of them with probability in proportion to its share of the density
 * of the direction: dens(l) is that light's (emission or direct sampling). */
static int bdpt__invert_which_light(const scene *sc, const bdpt_vertex *y, vec3 w, int emission,
                                    double r, int *OUT_li, int64_t *OUT_tri) {
  *OUT_tri = -1;
  if (y->type == BDPT_VERTEX_SURFACE) {
    *OUT_li = y->hit.light;
    *OUT_tri = y->hit.prim;
    return *OUT_li >= 0;
  }
  if (y->type != BDPT_VERTEX_LIGHT) return 0;
  if (y->light >= 0) {
    *OUT_li = y->light;
    if (sc->lights[y->light].type == LIGHT_AREA) *OUT_tri = y->hit.prim;
    return 1;
  }
  double dens[64], total = 0.0;
  int idx[64], m = 0;
  for (int i = 0; i < sc->n_lights && m < 64; i++) {
    const light *l = &sc->lights[i];
    if (!light_is_infinite(l)) continue;
    double d, pos;
    if (emission)
      light_pdf_le(l, sc, y->p, v3(0.0, 0.0, 0.0), w, &pos, &d);
    else
      d = light_pdf_li(l, sc, v3(0.0, 0.0, 0.0), w, y->p, v3(0.0, 0.0, 0.0));
    dens[m] = scene_light_pmf(sc, i) * d;
    idx[m++] = i;
    total += dens[m - 1];
  }
  if (!(total > 0.0)) return 0;
  double acc = 0.0, t = r * total;
  for (int k = 0; k < m; k++) {
    acc += dens[k];
    if (t < acc || k == m - 1) {
      *OUT_li = idx[k];
      return dens[k] > 0.0;
    }
  }
  return 0;
}

/* The numbers of the walk's step at surface vertex path[i] (i >= 1) to
 * path[i + 1], and the walk's throughput after it (*beta, *eta_scale; beta1
 * the throughput at y_1 of a light walk): the BSDF's numbers by
 * bsdf_invert (or the absolute direction's coordinates), the roulette
 * number uniform below its survival probability. 0 when the walk cannot
 * take that step. */
static int bdpt__invert_step(const scene *sc, const render_settings *rs, const bdpt_param *par,
                             transport_mode mode, const bdpt_vertex *path, int i, rgb beta1,
                             rgb *beta, double *eta_scale, rng *g, double u[4]) {
  const bdpt_vertex *v = &path[i];
  const surface_hit *h = &v->hit;
  if (v->type != BDPT_VERTEX_SURFACE || !h->bsdf) return 0;
  vec3 wi = bdpt__dir_to(sc, v, &path[i + 1]), wo_l, wi_l;
  if (!bdpt__side_ok(h, v->wo, &wo_l) || !bdpt__side_ok(h, wi, &wi_l)) return 0;
  double r[4] = {rng_uniform(g), rng_uniform(g), rng_uniform(g), rng_uniform(g)};
  int rough = par && bsdf_is_rough(h->bsdf, par->rough_min);
  rgb weight;
  int flags;
  double eta = 1.0;
  if (rough && i < par->abs_until) {
    /* The walk reads the direction's spherical coordinates. */
    u[0] = r[0];
    bdpt_sphere_coords(wi, &u[1], &u[2], NULL);
    double pdf;
    rgb f = bsdf_eval_pdf(h->bsdf, h->tu, h->tv, wo_l, wi_l, mode, &pdf);
    if (!(pdf > 0.0) || !isfinite(pdf)) return 0;
    weight = rgb_scale(f, fabs(wi_l.z) / pdf);
    int trans = wi_l.z * wo_l.z < 0.0;
    flags = trans ? BSDF_TRANSMISSION : BSDF_REFLECTION;
    if (trans) eta = wi_l.z < 0.0 ? h->bsdf->eta : 1.0 / h->bsdf->eta;
  } else {
    bsdf_sample bs;
    if (!bsdf_invert(h->bsdf, h->tu, h->tv, wo_l, wi_l, v->delta, r, u) ||
        !bsdf_sample_f(h->bsdf, h->tu, h->tv, wo_l, u[0], u[1], u[2], mode, &bs))
      return 0;
    weight = bs.weight, flags = bs.flags, eta = bs.eta;
  }
  if (!rgb_isfinite(weight) || rgb_is_black(weight)) return 0;
  if (mode == TRANSPORT_IMPORTANCE) weight = rgb_scale(weight, bdpt__shading_correction(h, v->wo, wi));
  *beta = rgb_mul(*beta, weight);
  if (mode == TRANSPORT_RADIANCE && (flags & BSDF_TRANSMISSION)) *eta_scale *= eta * eta;
  if (rgb_is_black(*beta)) return 0;
  u[3] = r[3];
  if (i >= rs->rrdepth) {
    double q = bdpt__rr_q(mode, *beta, beta1, *eta_scale);
    if (!(q > 0.0)) return 0;
    u[3] = warp_uniform_in(0.0, q, r[3]);
    *beta = rgb_scale(*beta, 1.0 / q);
  }
  return 1;
}

/* The walk from path[1] on: steps 1 .. n - 2, then the last vertex's
 * numbers, which shape nothing here, drawn from g. */
static int bdpt__invert_walk(const scene *sc, const render_settings *rs, const bdpt_param *par,
                             transport_mode mode, const bdpt_vertex *path, int n, rgb beta,
                             rng *g, double *OUT_u) {
  rgb beta1 = beta;
  double eta_scale = 1.0;
  for (int i = 1; i < n - 1; i++)
    if (!bdpt__invert_step(sc, rs, par, mode, path, i, beta1, &beta, &eta_scale, g,
                           OUT_u + BDPT_DIMS_PER_VERTEX * (i - 1)))
      return 0;
  for (int k = 0; k < BDPT_DIMS_PER_VERTEX; k++)
    OUT_u[BDPT_DIMS_PER_VERTEX * (n - 2) + k] = rng_uniform(g);
  return 1;
}

int bdpt_invert_camera_subpath(const scene *sc, const render_settings *rs, const bdpt_param *par,
                               const bdpt_vertex *path, int n, rng *g, double *OUT_rx,
                               double *OUT_ry, double *OUT_u) {
  if (n < 2 || path[0].type != BDPT_VERTEX_CAMERA) return 0;
  if (!camera_raster(&sc->cam, bdpt__dir_to(sc, &path[0], &path[1]), OUT_rx, OUT_ry)) return 0;
  return bdpt__invert_walk(sc, rs, par, TRANSPORT_RADIANCE, path, n, rgb_gray(1.0), g, OUT_u);
}

int bdpt_invert_light_subpath(const scene *sc, const render_settings *rs, const bdpt_param *par,
                              const bdpt_vertex *path, int n, rng *g, double *OUT_u) {
  if (n < 2) return 0;
  const bdpt_vertex *y0 = &path[0];
  /* The emitted ray: from y0 towards y1, or for a light at infinity along
   * its travel from the disk point whose ray passes through y1. */
  vec3 p = y0->p, dir;
  int far = y0->type == BDPT_VERTEX_LIGHT &&
            (y0->light < 0 || light_is_infinite(&sc->lights[y0->light]) ||
             sc->lights[y0->light].type == LIGHT_DIRECTIONAL);
  if (far) {
    dir = y0->dir;
    p = v3_fma(path[1].p, dir, -(v3_dot(v3_sub(path[1].p, sc->center), dir) + sc->radius));
  } else {
    dir = v3_normalize(v3_sub(path[1].p, y0->p));
  }
  int li;
  int64_t tri;
  if (!bdpt__invert_which_light(sc, y0, dir, 1, rng_uniform(g), &li, &tri)) return 0;
  const light *l = &sc->lights[li];
  OUT_u[0] = distrib1d_invert_discrete(&sc->light_select, li, rng_uniform(g));
  double r[4] = {rng_uniform(g), rng_uniform(g), rng_uniform(g), rng_uniform(g)};
  if (!(OUT_u[0] >= 0.0) || !light_invert_le(l, sc, p, dir, tri, r, OUT_u + 1)) return 0;
  /* The walk's first throughput, from the same numbers. */
  light_le_sample les;
  double pmf = scene_light_pmf(sc, li);
  if (!light_sample_le(l, sc, OUT_u[1], OUT_u[2], OUT_u[3], OUT_u[4], &les) ||
      !(les.pdf_pos > 0.0 && les.pdf_dir > 0.0 && pmf > 0.0))
    return 0;
  double cos0 = l->type == LIGHT_AREA ? fabs(v3_dot(les.n, les.dir)) : 1.0;
  rgb beta = rgb_scale(les.le, cos0 / (les.pdf_dir * pmf * les.pdf_pos));
  return bdpt__invert_walk(sc, rs, par, TRANSPORT_IMPORTANCE, path, n, beta, g,
                           OUT_u + BDPT_DIMS_LIGHT_START);
}

int bdpt_invert_connect(const scene *sc, const bdpt_vertex *ref, const bdpt_vertex *y, rng *g,
                        double OUT_u[BDPT_DIMS_CONNECT]) {
  vec3 wi = bdpt__dir_to(sc, ref, y);
  int li;
  int64_t tri;
  if (!bdpt__invert_which_light(sc, y, wi, 0, rng_uniform(g), &li, &tri)) return 0;
  OUT_u[0] = distrib1d_invert_discrete(&sc->light_select, li, rng_uniform(g));
  double r[2] = {rng_uniform(g), rng_uniform(g)};
  return OUT_u[0] >= 0.0 && light_invert_li(&sc->lights[li], sc, ref->p, wi, y->p, tri, r, OUT_u + 1);
}

int bdpt_connect_vertex(const scene *sc, vec3 ref, const double u[BDPT_DIMS_CONNECT],
                        bdpt_vertex *OUT_y) {
  double pmf, ur;
  int li = scene_sample_light(sc, u[0], &pmf, &ur);
  light_li_sample ls;
  if (li < 0 || !light_sample_li(&sc->lights[li], sc, ref, u[1], u[2], &ls)) return 0;
  memset(OUT_y, 0, sizeof *OUT_y);
  OUT_y->type = BDPT_VERTEX_LIGHT;
  OUT_y->light = li;
  OUT_y->p = ls.p;
  OUT_y->n = sc->lights[li].type == LIGHT_AREA ? ls.n : v3(0.0, 0.0, 0.0);
  OUT_y->dir = v3_neg(ls.wi);
  OUT_y->hit.mesh = sc->lights[li].type == LIGHT_AREA ? sc->lights[li].mesh : -1;
  OUT_y->hit.prim = ls.tri;
  return 1;
}

int bdpt_draw_strategy(const double *w, int k, int skip, double sum, double u) {
  double pick = u * sum, acc = 0.0;
  int last = -1;
  for (int t = 1; t <= k + 1; t++) {
    if (t == skip || !(w[t] > 0.0)) continue;
    acc += w[t];
    last = t;
    if (pick < acc) return t;
  }
  return last;
}

void bdpt_resplit(const scene *sc, const bdpt_vertex *x, int k, int s, int t,
                  bdpt_vertex *OUT_cam, bdpt_vertex *OUT_lp) {
  for (int i = 0; i < t; i++) {
    OUT_cam[i] = x[i];
    if (i > 0 && x[i].type == BDPT_VERTEX_SURFACE) OUT_cam[i].wo = bdpt__dir_to(sc, &x[i], &x[i - 1]);
  }
  for (int j = 0; j < s; j++) {
    OUT_lp[j] = x[k - j];
    if (j > 0 && x[k - j].type == BDPT_VERTEX_SURFACE)
      OUT_lp[j].wo = bdpt__dir_to(sc, &x[k - j], &x[k - j + 1]);
  }
  /* An area light the camera walk hit, as the light endpoint the light
   * walk and the s = 1 connection make (the MIS weights read it so). */
  if (s >= 1 && x[k].type == BDPT_VERTEX_SURFACE && x[k].hit.light >= 0) {
    bdpt_vertex *y = &OUT_lp[0];
    y->type = BDPT_VERTEX_LIGHT;
    y->light = x[k].hit.light;
    y->n = x[k].hit.ng;
    y->dir = y->wo = v3(0.0, 0.0, 0.0);
    y->delta = 0;
  }
}

/* ---------------------------------------------------------------------------
 * MIS weights.
 */

double bdpt_mis_weight(const scene *sc, const bdpt_vertex *cam, int t, const bdpt_vertex *lp,
                       int s, const bdpt_vertex *sampled) {
  return bdpt__mis_weight(sc, cam, t, lp, s, sampled, NULL);
}

void bdpt_path_pdfs(const scene *sc, bdpt_vertex *cam, int t, bdpt_vertex *lp, int s) {
  int n = s + t;
  if (n < 2 || t < 1) return;
  /* The full path from the light end: F[i] = lp[i] (i < s), cam[n-1-i] after. */
  bdpt_vertex *f[2 * BDPT_MAX_VERTICES];
  for (int i = 0; i < s; i++) f[i] = &lp[i];
  for (int j = 0; j < t; j++) f[s + j] = &cam[t - 1 - j];
  for (int i = 0; i < n; i++) {
    /* Density from the light side (sampled by F[i-1], reached from F[i-2]). */
    double from_light;
    if (i == 0)
      from_light = bdpt__pdf_light_origin(sc, f[0], f[1]);
    else if (i == 1)
      from_light = bdpt__pdf_light(sc, f[0], f[1]);
    else
      from_light = f[i - 1]->delta ? 0.0 : bdpt__pdf(sc, f[i - 1], f[i - 2], f[i]);
    /* Density from the camera side. */
    double from_cam;
    if (i == n - 1)
      from_cam = 1.0;
    else if (i == n - 2)
      from_cam = bdpt__pdf(sc, f[n - 1], NULL, f[i]);
    else
      from_cam = f[i + 1]->delta ? 0.0 : bdpt__pdf(sc, f[i + 1], f[i + 2], f[i]);
    if (i < s) {
      f[i]->pdf_fwd = from_light;
      f[i]->pdf_rev = from_cam;
    } else {
      f[i]->pdf_fwd = from_cam;
      f[i]->pdf_rev = from_light;
    }
  }
}

void bdpt_mis_weights(const scene *sc, const bdpt_vertex *x, int k, bdpt_vertex *scratch,
                      double *OUT_w) {
  for (int t = 0; t <= k + 1; t++) OUT_w[t] = 0.0;
  if (k < 1 || k + 1 > 2 * BDPT_MAX_VERTICES) return;
  /* Every vertex's densities from either side, once: the split (k, 1). */
  bdpt_vertex *cam = scratch, *lp = scratch + 1;
  bdpt_resplit(sc, x, k, k, 1, cam, lp);
  bdpt_path_pdfs(sc, cam, 1, lp, k);
  /* fc[i], fl[i]: x_i sampled from the camera side and from the light side
   * (zero read as one, as the ratio walk does); d[i]: its delta flag. */
  double fc[2 * BDPT_MAX_VERTICES], fl[2 * BDPT_MAX_VERTICES];
  int d[2 * BDPT_MAX_VERTICES];
  for (int i = 0; i <= k; i++) {
    const bdpt_vertex *v = i == 0 ? &cam[0] : &lp[k - i];
    fc[i] = bdpt__remap0(i == 0 ? v->pdf_fwd : v->pdf_rev);
    fl[i] = bdpt__remap0(i == 0 ? v->pdf_rev : v->pdf_fwd);
    d[i] = v->delta;
  }
  /* Strategy t joins x_{t-1} and x_t (t = k + 1: the camera walk ends on
   * the emitter): possible unless a delta vertex is at the joint, and
   * (1, 1) is not used. Its density relative to t = 1's: the product of
   * fc / fl over x_1 .. x_{t-1}, as logs. */
  double lr[2 * BDPT_MAX_VERTICES + 1];
  int ok[2 * BDPT_MAX_VERTICES + 1];
  lr[1] = 0.0;
  for (int t = 2; t <= k + 1; t++) lr[t] = lr[t - 1] + log(fc[t - 1]) - log(fl[t - 1]);
  for (int t = 1; t <= k + 1; t++) {
    if (t <= k)
      ok[t] = !d[t - 1] && !d[t] && !(t == 1 && k == 1);
    else
      ok[t] = !d[k] && !bdpt__is_delta_light(sc, &lp[0]);
  }
  /* The power heuristic: w_t = 1 / sum_j (p_j / p_t)^2 over the possible j. */
  for (int t = 1; t <= k + 1; t++) {
    if (!ok[t]) continue;
    double sum = 0.0;
    for (int j = 1; j <= k + 1; j++)
      if (ok[j]) sum += exp(2.0 * (lr[j] - lr[t]));
    OUT_w[t] = 1.0 / sum;
  }
}

/* ---------------------------------------------------------------------------
 * The densities and the walk for other samplers of whole paths (integrator.h).
 */

double bdpt_vertex_pdf(const scene *sc, const bdpt_vertex *v, const bdpt_vertex *prev,
                       const bdpt_vertex *next) {
  return bdpt__pdf(sc, v, prev, next);
}

double bdpt_vertex_pdf_light(const scene *sc, const bdpt_vertex *v, const bdpt_vertex *next) {
  return bdpt__pdf_light(sc, v, next);
}

double bdpt_vertex_pdf_light_origin(const scene *sc, const bdpt_vertex *v,
                                    const bdpt_vertex *next) {
  return bdpt__pdf_light_origin(sc, v, next);
}

rgb bdpt_vertex_f_cos(const bdpt_vertex *v, vec3 wi, transport_mode mode) {
  return bdpt__f_cos(v, wi, mode);
}

int bdpt_continue_subpath(const scene *sc, const render_settings *rs, lmc_sampler *smp,
                          transport_mode mode, vec3 org, vec3 dir, double pdf_dir,
                          bdpt_vertex *path, int n, int max_vertices, render_counters *cnt) {
  if (max_vertices > BDPT_MAX_VERTICES) max_vertices = BDPT_MAX_VERTICES;
  if (n < 1 || n >= max_vertices) return n;
  bdpt__walker w = {sc, rs, smp, NULL, cnt, 0, 0};
  double tmin = scene_ray_eps(sc, org);
  return bdpt__walk(&w, mode, org, dir, tmin, rgb_gray(1.0), pdf_dir, 0, path, n, max_vertices);
}

/* ---------------------------------------------------------------------------
 * One strategy.
 */

/* bdpt_connect, through the scene's media when `media` is set. */
static rgb bdpt__connect(const scene *sc, const bdpt_vertex *cam, int t, const bdpt_vertex *lp,
                         int s, const double *u_connect, double *OUT_rx, double *OUT_ry,
                         double *OUT_weight, render_counters *cnt, int media) {
  if (OUT_weight) *OUT_weight = 0.0;
  if (t < 1 || s + t < 2 || (s == 1 && t == 1)) return rgb_zero();
  /* An escaped camera ray is only an emitter (s = 0). */
  if (t > 1 && s != 0 && cam[t - 1].type == BDPT_VERTEX_LIGHT) return rgb_zero();
  bdpt__joiner jn = {sc, cnt, u_connect, media};
  bdpt__join J;
  J.L = rgb_zero();
  J.stage = 0;
  J.emit = J.lobes = 0;
  J.has_sampled = 0;
  J.tconn = rgb_gray(1.0);
  if (s == 0)
    bdpt__join_emitter(&jn, cam, t, &J);
  else if (t == 1)
    bdpt__join_camera(&jn, cam, lp, s, &J, OUT_rx, OUT_ry);
  else if (s == 1)
    bdpt__join_light(&jn, cam, t, &J);
  else
    bdpt__join_vertices(&jn, cam, t, lp, s, &J);
  if (rgb_is_black(J.L)) return rgb_zero();
  double w = bdpt__mis_weight(sc, cam, t, lp, s, J.has_sampled ? &J.sampled : NULL,
                              media ? &J.tconn : NULL);
  if (OUT_weight) *OUT_weight = w;
  return rgb_scale(J.L, w);
}

rgb bdpt_connect(const scene *sc, const bdpt_vertex *cam, int t, const bdpt_vertex *lp, int s,
                 const double *u_connect, double *OUT_rx, double *OUT_ry, double *OUT_weight,
                 render_counters *cnt) {
  return bdpt__connect(sc, cam, t, lp, s, u_connect, OUT_rx, OUT_ry, OUT_weight, cnt,
                       sc->n_media > 0 && t >= 1 && cam[0].media);
}

/* ---------------------------------------------------------------------------
 * The per-pixel-sample driver.
 */

static int bdpt__counts(const render_settings *rs, int length) {
  if (rs->maxdepth >= 0 && length > rs->maxdepth) return 0;
  return rs->mindepth <= 0 || length >= rs->mindepth;
}

void bdpt_subpaths(const scene *sc, const render_settings *rs, lmc_sampler *smp, double rx,
                   double ry, int media, bdpt_vertex *OUT_cam, int *OUT_nc, bdpt_vertex *OUT_lp,
                   int *OUT_nl, render_counters *cnt) {
  int max_cam, max_light;
  bdpt_subpath_limits(rs, &max_cam, &max_light);
  bdpt__walker w = {sc, rs, smp, NULL, cnt, media, 0};
  sampler_use_stream(smp, LMC_STREAM_CAMERA);
  *OUT_nc = 0;
  if (max_cam >= 1) {
    bdpt__camera_vertex(&w, &OUT_cam[0]);
    vec3 org, dir;
    camera_generate_ray(&sc->cam, rx, ry, &org, &dir);
    *OUT_nc = bdpt__camera_walk(&w, org, dir, max_cam, OUT_cam);
  }
  sampler_use_stream(smp, LMC_STREAM_LIGHT);
  *OUT_nl = bdpt__light_walk(&w, max_light, OUT_lp);
  sampler_use_stream(smp, LMC_STREAM_CONNECT);
}

rgb bdpt_li(const scene *s, const render_settings *rs, lmc_sampler *smp, double rx, double ry,
            film *splat, render_counters *cnt) {
  const scene *sc = s;
  bdpt_vertex cam[BDPT_MAX_VERTICES], lp[BDPT_MAX_VERTICES];

  /* The two subpaths, each from its own stream (through the scene's
   * media, when it has some). */
  int media = render_media_on(s, rs), nc, nl;
  bdpt_subpaths(sc, rs, smp, rx, ry, media, cam, &nc, lp, &nl, cnt);

  /* Every strategy (s, t); t = 1 goes to the splat film. */
  rgb L = rgb_zero();
  for (int t = 1; t <= nc; t++) {
    double u[BDPT_DIMS_CONNECT] = {0.0, 0.0, 0.0};
    if (t >= 2)
      for (int k = 0; k < BDPT_DIMS_CONNECT; k++) u[k] = sampler_next(smp);
    int s_max = nl > 1 ? nl : 1;
    for (int st = 0; st <= s_max; st++) {
      int length = st + t - 1;
      if (length < 1 || (st == 1 && t == 1)) continue;
      if (st >= 2 && st > nl) break;
      if (!bdpt__counts(rs, length)) continue;
      double prx = 0.0, pry = 0.0;
      rgb c = bdpt__connect(sc, cam, t, lp, st, u, &prx, &pry, NULL, cnt, media);
      if (rgb_is_black(c)) continue;
      if (t == 1) {
        if (rgb_isfinite(c))
          film_splat(splat, &sc->filter, prx, pry, c);
        else
          cnt->nan_samples++;
      } else {
        L = rgb_add(L, c);
      }
    }
  }
  return L;
}
