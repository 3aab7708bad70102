/*
 * mut_perturb.c: the lens, multi-chain and caustic perturbations of
 * path-space MLT (Veach 1997, section 11.4.3), their transition densities
 * and acceptance ratios; mut_perturb.h states the moves and the densities.
 * Mitsuba 0.6's perturbations (src/libbidir) were read for the method's
 * facts (the default sizes, Veach's caustic scaling, the forms each move
 * applies to); the code here is lmc's own, on pathspace.h's caches.
 *
 * Retracing a chain: each new vertex is the surface the ray hits (bdpt's
 * walk, one vertex at a time, so that its records are bdpt's), and its
 * next direction is x's: through a delta lobe of the same kind
 * (reflection or transmission) chosen at the new vertex (ps's rule that
 * lmc's delta models pick their lobe by u_lobe against a threshold), or at
 * a chain's D start the given direction.
 */
#include "lmc/path/mut_perturb.h"

#include <math.h>
#include <string.h>

#define MP_PI 3.14159265358979323846

void mut_perturb_init(mut_perturb *mp, const ps_context *ctx) {
  const camera *cam = &ctx->sc->cam;
  memset(mp, 0, sizeof *mp);
  mp->ctx = ctx;
  mp->r1 = 0.1;
  mp->r2 = sqrt(0.05 * cam->width * cam->height / MP_PI);
  if (mp->r2 < 2.0 * mp->r1) mp->r2 = 2.0 * mp->r1;
  /* Radians per pixel: the smaller of the two axes' (Mitsuba's heuristic:
   * every pixel subtends about the same angle). */
  double ax = 2.0 * atan(cam->tan_half_x) / cam->width;
  double ay = 2.0 * atan(cam->tan_half_y) / cam->height;
  double rad = ax < ay ? ax : ay;
  mp->theta1 = rad * mp->r1;
  mp->theta2 = rad * mp->r2;
  mp->mc_theta1 = 0.0001 * MP_PI / 180.0;
  mp->mc_theta2 = 0.1 * MP_PI / 180.0;
  mp->test_jac_power = 1.0;
}

/* ---- Sizes ------------------------------------------------------------------ */

double mut_perturb_log_sample(double lo, double hi, double u) { return hi * exp(log(lo / hi) * u); }

double mut_perturb_log_pdf(double lo, double hi, double t) {
  if (!(t > lo && t < hi)) return 0.0;
  return 1.0 / (t * log(hi / lo));
}

/* The angle between unit vectors, accurate for tiny angles. */
static double mp__angle(vec3 a, vec3 b) {
  double h = 0.5 * v3_len(v3_sub(a, b));
  return 2.0 * asin(h < 1.0 ? h : 1.0);
}

/* w turned by theta, at azimuth phi around it. */
static vec3 mp__turn(vec3 w, double theta, double phi) {
  frame f = frame_from_z(w);
  vec3 l = v3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
  return v3_normalize(frame_to_world(&f, l));
}

/* ---- Forms ------------------------------------------------------------------ */

int mut_perturb_glossy(const mut_perturb *mp, const ps_path *x, int i) {
  return ps_glossy(mp->ctx, x, i);
}

int mut_perturb_chains(const mut_perturb *mp, const ps_path *x, int *OUT_ends) {
  int k = x->k, n = 0, i = 1;
  while (i < k) {
    while (i < k && (x->x[i].delta || mut_perturb_glossy(mp, x, i))) i++;
    if (i >= k) return 0; /* the emitter reached through S and G vertices */
    OUT_ends[n++] = i;
    if (ps_connectible(x, i + 1)) return n;
    i++;
  }
  return 0;
}

int mut_perturb_caustic_m(const mut_perturb *mp, const ps_path *x) {
  int k = x->k;
  if (k < 2 || !ps_connectible(x, 1)) return 0;
  int m = 2;
  while (m < k && (!ps_connectible(x, m) || ps_glossy(mp->ctx, x, m))) m++;
  return x->x[m].inf ? 0 : m;
}

int mut_perturb_applies(const mut_perturb *mp, mut_perturb_kind kind, const ps_path *x) {
  int ends[MUT_PERTURB_MAX_CHAINS];
  switch (kind) {
  case MUT_PERTURB_LENS:
    return mut_perturb_chains(mp, x, ends) == 1;
  case MUT_PERTURB_MULTICHAIN:
    return mut_perturb_chains(mp, x, ends) >= 2;
  case MUT_PERTURB_CAUSTIC:
    return mut_perturb_caustic_m(mp, x) > 0;
  }
  return 0;
}

/* ---- Retracing ---------------------------------------------------------------- */

/* The walk's numbers: a delta lobe's direction does not read them, and the
 * walk stops before scattering at the new vertex. */
typedef struct mp__smp {
  lmc_sampler base;
} mp__smp;

static double mp__half(lmc_sampler *s) {
  (void)s;
  return 0.5;
}

static void mp__stream(lmc_sampler *s, int stream) { (void)s, (void)stream; }

int mut_perturb_transmits(const ps_path *x, int i) {
  vec3 n = x->x[i].v.n;
  return v3_dot(ps_dir(x, i, i - 1), n) * v3_dot(ps_dir(x, i, i + 1), n) < 0.0;
}

int mut_perturb_forced_dir(const bdpt_vertex *v, vec3 wo, int trans, transport_mode mode,
                           vec3 *OUT_dir) {
  const surface_hit *h = &v->hit;
  vec3 wo_l = frame_to_local(&h->sh, wo);
  if (!(v3_dot(wo, h->ng) * wo_l.z > 0.0)) return 0;
  static const double u_lobes[2] = {0.0, 1.0 - 1e-9};
  for (int j = 0; j < 2; j++) {
    bsdf_sample bs;
    if (!bsdf_sample_f(h->bsdf, h->tu, h->tv, wo_l, u_lobes[j], 0.5, 0.5, mode, &bs)) continue;
    if (!(bs.flags & BSDF_DELTA) || !(bs.pdf > 0.0)) continue;
    if (((bs.flags & BSDF_TRANSMISSION) != 0) != trans) continue;
    vec3 wi = v3_normalize(frame_to_world(&h->sh, bs.wi));
    if (!(v3_dot(wi, h->ng) * frame_to_local(&h->sh, wi).z > 0.0)) return 0;
    *OUT_dir = wi;
    return 1;
  }
  return 0;
}

/* The type of the vertex bdpt's walk records from `from` along dir into
 * *OUT; -1 when it records none. */
static int mp__next(const ps_context *ctx, const bdpt_vertex *from, vec3 dir, transport_mode mode,
                    bdpt_vertex *OUT, int64_t *rays) {
  bdpt_vertex tmp[2];
  tmp[0] = *from;
  mp__smp smp = {{mp__half, mp__stream, NULL}};
  render_counters cnt;
  memset(&cnt, 0, sizeof cnt);
  int n = bdpt_continue_subpath(ctx->sc, &ctx->rs, &smp.base, mode, from->p, dir, 1.0, tmp, 1, 2,
                                &cnt);
  if (rays) *rays += cnt.rays;
  if (n != 2) return -1;
  *OUT = tmp[1];
  return (int)OUT->type;
}

int mut_perturb_trace(const ps_context *ctx, const bdpt_vertex *from, vec3 dir,
                      transport_mode mode, bdpt_vertex *OUT, int64_t *rays) {
  bdpt_vertex v;
  if (mp__next(ctx, from, dir, mode, &v, rays) != BDPT_VERTEX_SURFACE) return 0;
  *OUT = v;
  OUT->delta = 0;
  return 1;
}

int mut_perturb_trace_sky(const ps_context *ctx, const bdpt_vertex *from, vec3 dir,
                          bdpt_vertex *OUT, int64_t *rays) {
  bdpt_vertex v;
  if (mp__next(ctx, from, dir, TRANSPORT_RADIANCE, &v, rays) != BDPT_VERTEX_LIGHT) return 0;
  *OUT = v;
  return 1;
}

int mut_perturb_first_hit(const ps_context *ctx, double rx, double ry, bdpt_vertex *OUT_pinhole,
                          bdpt_vertex *OUT_hit, int64_t *rays) {
  bdpt_vertex tmp[2];
  mp__smp smp = {{mp__half, mp__stream, NULL}};
  render_counters cnt;
  memset(&cnt, 0, sizeof cnt);
  int n = bdpt_camera_subpath(ctx->sc, &ctx->rs, &smp.base, rx, ry, 2, tmp, &cnt);
  if (rays) *rays += cnt.rays;
  if (n != 2 || tmp[1].type != BDPT_VERTEX_SURFACE) return 0;
  *OUT_pinhole = tmp[0];
  *OUT_hit = tmp[1];
  OUT_hit->delta = 0;
  return 1;
}

/* y's vertices lo .. hi have x's kinds (S or D); then the edge from y_a
 * to y_{a+1} unblocked (else f(y) = 0), and f(y). */
static int mp__finish(const mut_perturb *mp, const ps_path *x, ps_path *y, int lo, int hi, int a,
                      int64_t *rays) {
  for (int i = lo; i <= hi; i++)
    if (y->x[i].delta != x->x[i].delta ||
        mut_perturb_glossy(mp, y, i) != mut_perturb_glossy(mp, x, i))
      return 0;
  if (rays) (*rays)++;
  if (ps_edge_blocked(mp->ctx, y, a)) {
    y->f = rgb_zero();
    y->lum = 0.0;
    return 1;
  }
  ps_total(y);
  return 1;
}

int mut_perturb_sample_dir(const bdpt_vertex *v, vec3 wo, transport_mode mode, rng *r,
                           vec3 *OUT_dir) {
  const surface_hit *h = &v->hit;
  vec3 wo_l = frame_to_local(&h->sh, wo);
  if (!r || !(v3_dot(wo, h->ng) * wo_l.z > 0.0)) return 0;
  double u_lobe = rng_uniform(r), u1 = rng_uniform(r), u2 = rng_uniform(r);
  bsdf_sample bs;
  if (!bsdf_sample_f(h->bsdf, h->tu, h->tv, wo_l, u_lobe, u1, u2, mode, &bs)) return 0;
  if ((bs.flags & BSDF_DELTA) || !(bs.pdf > 0.0)) return 0;
  vec3 wi = v3_normalize(frame_to_world(&h->sh, bs.wi));
  if (!(v3_dot(wi, h->ng) * frame_to_local(&h->sh, wi).z > 0.0)) return 0;
  *OUT_dir = wi;
  return 1;
}

/* The direction leaving G vertex v (reached from along wo) of the path
 * being retraced, whose counterpart in x leaves along x_dir: with
 * probability 1/2 a sample of v's BSDF, else x_dir turned by a log-uniform
 * angle on [theta1, theta2] (a local move that keeps the path near x's
 * where a fresh sample of a narrow lobe would lose it); mp__glossy_density
 * is the mixture's density. */
static int mp__glossy_dir(const mut_perturb *mp, const bdpt_vertex *v, vec3 wo, vec3 x_dir,
                          transport_mode mode, rng *r, vec3 *OUT_dir) {
  if (!r) return 0;
  if (rng_uniform(r) < 0.5) return mut_perturb_sample_dir(v, wo, mode, r, OUT_dir);
  double th = mut_perturb_log_sample(mp->theta1, mp->theta2, rng_uniform(r));
  *OUT_dir = mp__turn(x_dir, th, 2.0 * MP_PI * rng_uniform(r));
  return 1;
}

/* The area density of the vertex after a G vertex in the retraced path
 * (mp__glossy_dir): pdf_sampled, the BSDF's, and the turn's from the
 * angle between the two paths' directions times area_jac, the solid-angle
 * to area Jacobian. */
static double mp__glossy_density(const mut_perturb *mp, double pdf_sampled, vec3 dir_a,
                                 vec3 dir_b, double area_jac) {
  double th = mp__angle(dir_a, dir_b);
  double turn = th > 0.0 ? mut_perturb_log_pdf(mp->theta1, mp->theta2, th) / (2.0 * MP_PI * sin(th))
                         : 0.0;
  return 0.5 * pdf_sampled + 0.5 * turn * area_jac;
}

int mut_perturb_lens_generate(const mut_perturb *mp, const ps_path *x, double rx, double ry,
                              const vec3 *dirs, rng *r, ps_path *OUT_y, int64_t *rays) {
  const ps_context *ctx = mp->ctx;
  const scene *sc = ctx->sc;
  int ends[MUT_PERTURB_MAX_CHAINS];
  int nc = mut_perturb_chains(mp, x, ends);
  if (nc == 0 || !(rx >= 0.0 && rx < sc->cam.width && ry >= 0.0 && ry < sc->cam.height)) return 0;
  ps_path *y = OUT_y;
  *y = *x;
  y->rays = 0;
  if (!mut_perturb_first_hit(ctx, rx, ry, &y->x[0].v, &y->x[1].v, rays)) return 0;
  int e = ends[nc - 1], chain = 0;
  for (int i = 1; i < e; i++) {
    vec3 wo = v3_normalize(v3_sub(y->x[i - 1].v.p, y->x[i].v.p)), dir;
    if (x->x[i].delta) {
      if (!mut_perturb_forced_dir(&y->x[i].v, wo, mut_perturb_transmits(x, i),
                                  TRANSPORT_RADIANCE, &dir))
        return 0;
      y->x[i].v.delta = 1;
    } else if (mut_perturb_glossy(mp, x, i)) {
      if (!mp__glossy_dir(mp, &y->x[i].v, wo, ps_dir(x, i, i + 1), TRANSPORT_RADIANCE, r, &dir))
        return 0;
      y->x[i].v.delta = 0;
    } else {
      if (chain >= nc - 1 || ends[chain] != i) return 0;
      dir = dirs[chain++];
      y->x[i].v.delta = 0;
    }
    if (!mut_perturb_trace(ctx, &y->x[i].v, dir, TRANSPORT_RADIANCE, &y->x[i + 1].v, rays)) return 0;
  }
  ps_update(ctx, y, 0, e + 2);
  return mp__finish(mp, x, y, 1, e, e, rays);
}

int mut_perturb_caustic_generate(const mut_perturb *mp, const ps_path *x, vec3 dir, rng *r,
                                 ps_path *OUT_y, int64_t *rays) {
  const ps_context *ctx = mp->ctx;
  int m = mut_perturb_caustic_m(mp, x);
  if (m == 0) return 0;
  ps_path *y = OUT_y;
  *y = *x;
  y->rays = 0;
  if (!mut_perturb_trace(ctx, &x->x[m].v, dir, TRANSPORT_IMPORTANCE, &y->x[m - 1].v, rays)) return 0;
  for (int i = m - 1; i >= 2; i--) {
    vec3 wo = v3_normalize(v3_sub(y->x[i + 1].v.p, y->x[i].v.p)), d;
    if (x->x[i].delta) {
      if (!mut_perturb_forced_dir(&y->x[i].v, wo, mut_perturb_transmits(x, i),
                                  TRANSPORT_IMPORTANCE, &d))
        return 0;
      y->x[i].v.delta = 1;
    } else {
      if (!mp__glossy_dir(mp, &y->x[i].v, wo, ps_dir(x, i, i - 1), TRANSPORT_IMPORTANCE, r, &d))
        return 0;
      y->x[i].v.delta = 0;
    }
    if (!mut_perturb_trace(ctx, &y->x[i].v, d, TRANSPORT_IMPORTANCE, &y->x[i - 1].v, rays)) return 0;
  }
  ps_update(ctx, y, 0, m + 1);
  return mp__finish(mp, x, y, 1, m - 1, 0, rays);
}

/* ---- Densities ------------------------------------------------------------------ */

double mut_perturb_caustic_scale(const mut_perturb *mp, const ps_path *x, int m) {
  double le = v3_len(v3_sub(x->x[1].v.p, x->x[0].v.p)), ll = 0.0;
  for (int i = 1; i < m; i++) ll += v3_len(v3_sub(x->x[i + 1].v.p, x->x[i].v.p));
  double s = ll > 0.0 ? le / ll : 0.0, cap = 0.5 * MP_PI / mp->theta2;
  return s < cap ? s : cap;
}

static double mp__lens_density(const mut_perturb *mp, const ps_path *x, const ps_path *y) {
  const ps_context *ctx = mp->ctx;
  const camera *cam = &ctx->sc->cam;
  int ex[MUT_PERTURB_MAX_CHAINS], ey[MUT_PERTURB_MAX_CHAINS];
  int nc = mut_perturb_chains(mp, x, ex);
  if (nc == 0 || mut_perturb_chains(mp, y, ey) != nc || ey[nc - 1] != ex[nc - 1] || y->k != x->k)
    return 0.0;
  double dr = hypot(y->rx - x->rx, y->ry - x->ry);
  double p = mut_perturb_log_pdf(mp->r1, mp->r2, dr) / (2.0 * MP_PI * dr);
  for (int j = 0; j + 1 < nc; j++) {
    int i = ex[j];
    double th = mp__angle(ps_dir(x, i, i + 1), ps_dir(y, i, i + 1));
    p *= mut_perturb_log_pdf(mp->mc_theta1, mp->mc_theta2, th) / (2.0 * MP_PI * sin(th));
  }
  if (!(p > 0.0)) return 0.0;
  double jac = (double)cam->width * cam->height * y->x[1].pdf_cam;
  /* Each vertex after a G vertex has the BSDF's sampling density (pdf_cam), after an S or
   * a chain's start the Jacobian of its forced or turned direction. */
  for (int i = 2; i <= ex[nc - 1]; i++)
    jac *= mut_perturb_glossy(mp, y, i - 1)
               ? mp__glossy_density(mp, y->x[i].pdf_cam, ps_dir(x, i - 1, i), ps_dir(y, i - 1, i),
                                    ps_area_jacobian(ctx, y, i - 1, i))
               : ps_area_jacobian(ctx, y, i - 1, i);
  return p * pow(jac, mp->test_jac_power);
}

static double mp__caustic_density(const mut_perturb *mp, const ps_path *x, const ps_path *y) {
  const ps_context *ctx = mp->ctx;
  int m = mut_perturb_caustic_m(mp, x);
  if (m == 0 || mut_perturb_caustic_m(mp, y) != m || y->k != x->k) return 0.0;
  double s = mut_perturb_caustic_scale(mp, x, m);
  double th = mp__angle(ps_dir(x, m, m - 1), ps_dir(y, m, m - 1));
  double p = mut_perturb_log_pdf(mp->theta1 * s, mp->theta2 * s, th) / (2.0 * MP_PI * sin(th));
  if (!(p > 0.0)) return 0.0;
  double jac = ps_area_jacobian(ctx, y, m, m - 1);
  /* Each vertex before an S the Jacobian of its forced direction, before a G
   * the BSDF's sampling density from the light side (pdf_light). */
  for (int i = m - 2; i >= 1; i--)
    jac *= y->x[i + 1].delta
               ? ps_forced_density(ctx, y, i + 1, i + 2, i, 1)
               : mp__glossy_density(mp, y->x[i].pdf_light, ps_dir(x, i + 1, i),
                                    ps_dir(y, i + 1, i), ps_area_jacobian(ctx, y, i + 1, i));
  return p * pow(jac, mp->test_jac_power);
}

double mut_perturb_density(const mut_perturb *mp, mut_perturb_kind kind, const ps_path *x,
                           const ps_path *y) {
  if (kind == MUT_PERTURB_CAUSTIC) return mp__caustic_density(mp, x, y);
  return mp__lens_density(mp, x, y);
}

/* ---- The proposal --------------------------------------------------------------- */

int mut_perturb_propose(const mut_perturb *mp, mut_perturb_kind kind, rng *r, const ps_path *x,
                        ps_path *OUT_y, double *OUT_ratio, int64_t *rays,
                        mut_perturb_choice *OUT_choice) {
  *OUT_ratio = 0.0;
  mut_perturb_choice ch = {0.0, 0.0, 0.0, 0.0};
  int ok;
  if (kind == MUT_PERTURB_CAUSTIC) {
    int m = mut_perturb_caustic_m(mp, x);
    if (m == 0) return 0;
    double s = mut_perturb_caustic_scale(mp, x, m);
    ch.size = mut_perturb_log_sample(mp->theta1 * s, mp->theta2 * s, rng_uniform(r));
    ch.phi = 2.0 * MP_PI * rng_uniform(r);
    vec3 w = mp__turn(ps_dir(x, m, m - 1), ch.size, ch.phi);
    if (OUT_choice) *OUT_choice = ch;
    ok = mut_perturb_caustic_generate(mp, x, w, r, OUT_y, rays);
  } else {
    int ends[MUT_PERTURB_MAX_CHAINS];
    int nc = mut_perturb_chains(mp, x, ends);
    if (kind == MUT_PERTURB_LENS ? nc != 1 : nc < 2) return 0;
    ch.size = mut_perturb_log_sample(mp->r1, mp->r2, rng_uniform(r));
    ch.phi = 2.0 * MP_PI * rng_uniform(r);
    vec3 dirs[MUT_PERTURB_MAX_CHAINS];
    for (int j = 0; j + 1 < nc; j++) {
      double th = mut_perturb_log_sample(mp->mc_theta1, mp->mc_theta2, rng_uniform(r));
      double ph = 2.0 * MP_PI * rng_uniform(r);
      dirs[j] = mp__turn(ps_dir(x, ends[j], ends[j] + 1), th, ph);
      if (j == 0) ch.turn = th, ch.turn_phi = ph;
    }
    if (OUT_choice) *OUT_choice = ch;
    ok = mut_perturb_lens_generate(mp, x, x->rx + ch.size * cos(ch.phi),
                                   x->ry + ch.size * sin(ch.phi), dirs, r, OUT_y, rays);
  }
  if (!ok) return 0;
  double t_fwd = mut_perturb_density(mp, kind, x, OUT_y);
  if (!(t_fwd > 0.0)) return 0;
  if (!(OUT_y->lum > 0.0) || !(x->lum > 0.0)) return 1;
  double t_rev = mut_perturb_density(mp, kind, OUT_y, x);
  double ratio = OUT_y->lum * t_rev / (x->lum * t_fwd);
  *OUT_ratio = isfinite(ratio) ? ratio : 0.0;
  return 1;
}
