/*
 * pathspace.c: a whole path as a state of path-space MLT (Veach 1997,
 * chapter 11; Veach and Guibas 1997): its factors, geometry terms and
 * densities from the geometry, and its contribution f. pathspace.h states
 * the measure, the indexing and the rules for delta vertices.
 *
 * Every density is bdpt's (bdpt_vertex_pdf, _pdf_light, _pdf_light_origin:
 * the functions BDPT's MIS weights use), except at delta vertices, whose
 * lobe probabilities BDPT never needs (its MIS walk reads them as one) and
 * which are found here by sampling the lobes (ps_delta_lobe).
 */
#include "lmc/path/pathspace.h"

#include <limits.h>
#include <string.h>

#include "render/bsdf/bsdf_model.h"

void ps_context_init(ps_context *ctx, const scene *sc, const render_settings *rs) {
  memset(ctx, 0, sizeof *ctx);
  ctx->sc = sc;
  ctx->rs = *rs;
  ctx->rs.rrdepth = INT_MAX;
  ctx->kmin = rs->mindepth > 1 ? rs->mindepth : 1;
  ctx->kmax = PS_MAX_VERTICES - 1;
  if (rs->maxdepth >= 0 && rs->maxdepth < ctx->kmax) ctx->kmax = rs->maxdepth;
  for (int i = 0; i < sc->n_lights; i++)
    if (sc->lights[i].type == LIGHT_AREA || light_is_infinite(&sc->lights[i]))
      ctx->can_hit_emitter = 1;
  ctx->glossy_rough = 0.1;
}

int ps_glossy_vertex(const ps_context *ctx, const bdpt_vertex *v) {
  if (v->type != BDPT_VERTEX_SURFACE) return 0;
  const bsdf *b = v->hit.bsdf;
  if (!b || b->masked || !(ctx->glossy_rough > 0.0)) return 0;
  return b->model->chain && !bsdf_is_rough(b, ctx->glossy_rough);
}

int ps_glossy(const ps_context *ctx, const ps_path *p, int i) {
  if (i < 1 || i >= p->k || p->x[i].delta) return 0;
  return ps_glossy_vertex(ctx, &p->x[i].v);
}

/* ---- Vertex queries -------------------------------------------------------- */

/* The light a path's last vertex stands on, or -1 when it is not a finite
 * emitter. */
static int ps__light(const ps_context *ctx, const bdpt_vertex *v) {
  if (v->light < 0) return -1;
  if (v->type == BDPT_VERTEX_SURFACE) return v->light;
  if (v->type != BDPT_VERTEX_LIGHT) return -1;
  const light *l = &ctx->sc->lights[v->light];
  if (light_is_infinite(l) || l->type == LIGHT_DIRECTIONAL) return -1;
  return v->light;
}

/* An endpoint of the infinite lights (constant, envmap, sunsky; not
 * directional): a direction; its emission is that of every infinite light
 * together (bdpt's escaped camera ray, light -1, or one light's sample). */
static int ps__infinite(const ps_context *ctx, const bdpt_vertex *v) {
  if (v->type != BDPT_VERTEX_LIGHT) return 0;
  return v->light < 0 || light_is_infinite(&ctx->sc->lights[v->light]);
}

/* A directional light's endpoint: a direction too (its own, fixed), its
 * emission the light's irradiance (the Dirac in direction reduced). */
static int ps__directional(const ps_context *ctx, const bdpt_vertex *v) {
  return v->type == BDPT_VERTEX_LIGHT && v->light >= 0 &&
         ctx->sc->lights[v->light].type == LIGHT_DIRECTIONAL;
}

int ps_vertex_fits(const ps_context *ctx, const bdpt_vertex *v, int index, int k) {
  if (index == 0) return v->type == BDPT_VERTEX_CAMERA;
  if (index == k)
    return ps__light(ctx, v) >= 0 || ps__infinite(ctx, v) || ps__directional(ctx, v);
  return v->type == BDPT_VERTEX_SURFACE;
}

/* A BSDF all of whose lobes are deltas (a mask's pass-through does not
 * count: a masked model is mixed). */
static int ps__pure_delta(const bsdf *b) { return b && bsdf_is_delta(b) && !b->masked; }

int ps_connectible(const ps_path *p, int i) {
  const ps_vertex *x = &p->x[i];
  if (i == 0 || i == p->k) return 1;
  return x->v.type == BDPT_VERTEX_SURFACE && !x->delta;
}

int ps_unhittable(const ps_context *ctx, const ps_path *p, int i) {
  const bdpt_vertex *v = &p->x[i].v;
  if (i == 0) return 1;
  return v->type == BDPT_VERTEX_LIGHT && v->light >= 0 &&
         light_is_delta(&ctx->sc->lights[v->light]);
}

/* Unit direction from vertex a to vertex b of p (against the light's
 * travel when b is at infinity). */
vec3 ps_dir(const ps_path *p, int a, int b) {
  if (p->x[b].inf) return v3_neg(p->x[b].v.dir);
  if (p->x[a].inf) return p->x[a].v.dir;
  return v3_normalize(v3_sub(p->x[b].v.p, p->x[a].v.p));
}

int ps_edge_blocked(const ps_context *ctx, const ps_path *p, int a) {
  const scene *sc = ctx->sc;
  if (p->x[a + 1].inf) return scene_occluded_ray(sc, p->x[a].v.p, v3_neg(p->x[a + 1].v.dir));
  return scene_occluded_segment(sc, p->x[a].v.p, p->x[a + 1].v.p);
}

/* |cos| at vertex i of the unit direction w: the optical axis' at the
 * pinhole, 1 at a point or spot light, the geometric normal's elsewhere. */
static double ps__cos(const ps_context *ctx, const ps_path *p, int i, vec3 w) {
  const bdpt_vertex *v = &p->x[i].v;
  if (v->type == BDPT_VERTEX_CAMERA) return fabs(v3_dot(ctx->sc->cam.forward, w));
  if (v3_len2(v->n) == 0.0) return 1.0;
  return fabs(v3_dot(v->n, w));
}

/* Mitsuba's side rule: w on the same side of the geometric and the
 * shading surface. */
static int ps__side_ok(const surface_hit *h, vec3 w) {
  return v3_dot(w, h->ng) * frame_to_local(&h->sh, w).z > 0.0;
}

int ps_delta_lobe(const bdpt_vertex *v, vec3 wo, vec3 wi, transport_mode mode, rgb *OUT_f,
                  double *OUT_prob, int *OUT_trans, double *OUT_eta) {
  const surface_hit *h = &v->hit;
  vec3 wo_l = frame_to_local(&h->sh, wo), wi_l = frame_to_local(&h->sh, wi);
  /* Each delta model of lmc picks its lobe by u_lobe against a threshold:
   * 0 chooses the first lobe, a number below one the last. */
  static const double u_lobes[2] = {0.0, 1.0 - 1e-9};
  for (int j = 0; j < 2; j++) {
    bsdf_sample bs;
    if (!bsdf_sample_f(h->bsdf, h->tu, h->tv, wo_l, u_lobes[j], 0.5, 0.5, mode, &bs)) continue;
    if (!(bs.flags & BSDF_DELTA) || !(bs.pdf > 0.0)) continue;
    if (v3_len2(v3_sub(v3_normalize(bs.wi), wi_l)) > 1e-10) continue;
    *OUT_f = bs.f;
    *OUT_prob = bs.pdf;
    *OUT_trans = (bs.flags & BSDF_TRANSMISSION) != 0;
    if (OUT_eta) *OUT_eta = bs.eta;
    return 1;
  }
  return 0;
}

/* ---- Factors of f ------------------------------------------------------------ */

/* Le of the last vertex towards x_{k-1}. */
static rgb ps__emitted(const ps_context *ctx, const ps_path *p) {
  int k = p->k;
  const bdpt_vertex *v = &p->x[k].v;
  if (p->x[k].inf && ps__directional(ctx, v)) return ctx->sc->lights[v->light].value;
  if (p->x[k].inf) {
    /* Every infinite light's radiance from that direction. */
    rgb le = rgb_zero();
    for (int j = 0; j < ctx->sc->n_infinite; j++)
      le = rgb_add(le, light_le_infinite(&ctx->sc->lights[ctx->sc->infinite_lights[j]],
                                         v3_neg(v->dir)));
    return le;
  }
  int li = ps__light(ctx, v);
  if (li < 0) return rgb_zero();
  const light *l = &ctx->sc->lights[li];
  if (l->type == LIGHT_AREA) return light_le_area(l, v->n, ps_dir(p, k, k - 1));
  /* Point and spot lights: the intensity towards x_{k-1}. */
  light_li_sample ls;
  if (!light_sample_li(l, ctx->sc, p->x[k - 1].v.p, 0.5, 0.5, &ls)) return rgb_zero();
  return rgb_scale(ls.li, ls.dist * ls.dist);
}

/* f_s at surface vertex i: f(w_cam, w_light) |w_light . n_s| / |w_light . n_g|. */
static rgb ps__scatter_factor(const ps_path *p, int i) {
  const ps_vertex *x = &p->x[i];
  vec3 wc = ps_dir(p, i, i - 1), wl = ps_dir(p, i, i + 1);
  double cg = fabs(v3_dot(wl, x->v.n));
  if (!(cg > 0.0)) return rgb_zero();
  if (x->delta) {
    const surface_hit *h = &x->v.hit;
    rgb f;
    double prob;
    int trans;
    if (!ps__side_ok(h, wc) || !ps__side_ok(h, wl)) return rgb_zero();
    if (!ps_delta_lobe(&x->v, wc, wl, TRANSPORT_RADIANCE, &f, &prob, &trans, NULL))
      return rgb_zero();
    return rgb_scale(f, fabs(frame_to_local(&h->sh, wl).z) / cg);
  }
  bdpt_vertex tmp = x->v;
  tmp.wo = wc;
  return rgb_scale(bdpt_vertex_f_cos(&tmp, wl, TRANSPORT_RADIANCE), 1.0 / cg);
}

/* Vertex i's factor of f; at the pinhole also the raster point. */
static rgb ps__factor(const ps_context *ctx, ps_path *p, int i) {
  if (i == 0) {
    double rx = -1.0, ry = -1.0;
    double we = camera_we(&ctx->sc->cam, ps_dir(p, 0, 1), &rx, &ry);
    p->rx = rx, p->ry = ry;
    return rgb_gray(we);
  }
  if (i == p->k) return ps__emitted(ctx, p);
  return ps__scatter_factor(p, i);
}

/* G(x_i, x_{i+1}); towards a direction at infinity |cos| at x_i alone
 * (its measure is solid angle). */
static double ps__geometry(const ps_context *ctx, const ps_path *p, int i) {
  if (p->x[i + 1].inf) return ps__cos(ctx, p, i, ps_dir(p, i, i + 1));
  vec3 d = v3_sub(p->x[i + 1].v.p, p->x[i].v.p);
  double d2 = v3_len2(d);
  if (!(d2 > 0.0)) return 0.0;
  vec3 w = v3_scale(d, 1.0 / sqrt(d2));
  return ps__cos(ctx, p, i, w) * ps__cos(ctx, p, i + 1, w) / d2;
}

/* ---- Densities ------------------------------------------------------------------ */

/* A solid-angle density at vertex a of the direction to b, per unit area at
 * b (unchanged when b is a direction at infinity). */
static double ps__to_area(const ps_context *ctx, const ps_path *p, double pdf_sa, int a, int b) {
  if (p->x[b].inf) return pdf_sa;
  vec3 d = v3_sub(p->x[b].v.p, p->x[a].v.p);
  double d2 = v3_len2(d);
  if (!(d2 > 0.0)) return 0.0;
  return pdf_sa * ps__cos(ctx, p, b, v3_scale(d, 1.0 / sqrt(d2))) / d2;
}

/* Density of vertex `to` sampled through the delta lobe of vertex s that
 * was reached from `from`, in the reduced measure of f (pathspace.h: the
 * lobe's Dirac in the direction towards the light). From the light side
 * the walk's Dirac is in the direction towards the camera, w_c = wi, so a
 * refraction's density carries |dw_l / dw_c| = eta^2 |cos w_c| / |cos w_l|
 * (the radiance invariant eta^2 cos dw, eta = eta_c / eta_l the sample's
 * relative index); a reflection's Jacobian is 1. */
static double ps__delta_density(const ps_context *ctx, const ps_path *p, int s, int from, int to,
                                int light_side, int with_prob) {
  const surface_hit *h = &p->x[s].v.hit;
  vec3 wo = ps_dir(p, s, from), wi = ps_dir(p, s, to);
  if (!ps__side_ok(h, wo) || !ps__side_ok(h, wi)) return 0.0;
  rgb f;
  double prob, eta = 1.0, jac = 1.0;
  int trans;
  transport_mode mode = light_side ? TRANSPORT_IMPORTANCE : TRANSPORT_RADIANCE;
  if (!ps_delta_lobe(&p->x[s].v, wo, wi, mode, &f, &prob, &trans, &eta)) return 0.0;
  if (light_side && trans) {
    double cl = fabs(frame_to_local(&h->sh, wo).z), cc = fabs(frame_to_local(&h->sh, wi).z);
    if (!(cl > 0.0)) return 0.0;
    jac = eta * eta * cc / cl;
  }
  return ps__to_area(ctx, p, (with_prob ? prob : 1.0) * jac, s, to);
}

double ps_forced_density(const ps_context *ctx, const ps_path *p, int s, int from, int to,
                         int light_side) {
  return ps__delta_density(ctx, p, s, from, to, light_side, 0);
}

double ps_area_jacobian(const ps_context *ctx, const ps_path *p, int a, int b) {
  return ps__to_area(ctx, p, 1.0, a, b);
}

double ps_density_cam(const ps_context *ctx, const ps_path *p, int i) {
  if (i == 0) return 1.0;
  if (ps_unhittable(ctx, p, i)) return 0.0;
  const scene *sc = ctx->sc;
  if (i == 1) return bdpt_vertex_pdf(sc, &p->x[0].v, NULL, &p->x[1].v);
  if (p->x[i - 1].delta) return ps__delta_density(ctx, p, i - 1, i - 2, i, 0, 1);
  return bdpt_vertex_pdf(sc, &p->x[i - 1].v, &p->x[i - 2].v, &p->x[i].v);
}

double ps_density_light(const ps_context *ctx, const ps_path *p, int i) {
  int k = p->k;
  const scene *sc = ctx->sc;
  if (i == 0) return 0.0;
  if (i == k) return bdpt_vertex_pdf_light_origin(sc, &p->x[k].v, &p->x[k - 1].v);
  if (i == k - 1) return bdpt_vertex_pdf_light(sc, &p->x[k].v, &p->x[i].v);
  if (p->x[i + 1].delta) return ps__delta_density(ctx, p, i + 1, i + 2, i, 1, 1);
  return bdpt_vertex_pdf(sc, &p->x[i + 1].v, &p->x[i + 2].v, &p->x[i].v);
}

/* ---- The path ----------------------------------------------------------------- */

void ps_update(const ps_context *ctx, ps_path *p, int lo, int hi) {
  if (lo < 0) lo = 0;
  if (hi > p->k) hi = p->k;
  /* The delta and infinity flags first: the densities of neighbours read
   * them. */
  for (int i = lo; i <= hi; i++) {
    const bdpt_vertex *v = &p->x[i].v;
    const bsdf *b = v->type == BDPT_VERTEX_SURFACE ? v->hit.bsdf : NULL;
    p->x[i].delta = i > 0 && i < p->k && b &&
                    (ps__pure_delta(b) || (v->delta && (bsdf_flags(b) & BSDF_DELTA)));
    p->x[i].inf = i == p->k && (ps__infinite(ctx, v) || ps__directional(ctx, v));
  }
  for (int i = lo; i <= hi; i++) {
    ps_vertex *x = &p->x[i];
    x->fac = ps__factor(ctx, p, i);
    x->g = i < p->k ? ps__geometry(ctx, p, i) : 0.0;
    x->pdf_cam = ps_density_cam(ctx, p, i);
    x->pdf_light = ps_density_light(ctx, p, i);
  }
}

void ps_total(ps_path *p) {
  rgb f = rgb_gray(1.0);
  for (int i = 0; i <= p->k; i++) {
    f = rgb_mul(f, p->x[i].fac);
    if (i < p->k) f = rgb_scale(f, p->x[i].g);
  }
  if (!rgb_isfinite(f)) f = rgb_zero();
  p->f = f;
  p->lum = rgb_luminance(f);
}

void ps_eval(const ps_context *ctx, ps_path *p) {
  ps_update(ctx, p, 0, p->k);
  ps_total(p);
}

int ps_from_bdpt(const ps_context *ctx, const bdpt_vertex *cam, int t, const bdpt_vertex *lp,
                 int s, ps_path *OUT_p) {
  int n = s + t;
  if (t < 1 || n < 2 || n > PS_MAX_VERTICES) return 0;
  OUT_p->k = n - 1;
  for (int i = 0; i < t; i++) OUT_p->x[i].v = cam[i];
  for (int j = 0; j < s; j++) OUT_p->x[n - 1 - j].v = lp[j];
  for (int i = 0; i < n; i++)
    if (!ps_vertex_fits(ctx, &OUT_p->x[i].v, i, n - 1)) return 0;
  /* The connection's two ends scatter through smooth lobes; the subpaths'
   * own scatterings keep the lobe their walk chose. */
  if (s > 0) OUT_p->x[t - 1].v.delta = OUT_p->x[t].v.delta = 0;
  ps_eval(ctx, OUT_p);
  return 1;
}
