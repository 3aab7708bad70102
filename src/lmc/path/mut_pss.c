/*
 * mut_pss.c: a primary-sample small step of a path (mut_pss.h says what it
 * does and why it is exact).
 */
#include "lmc/path/mut_pss.h"

#include <math.h>
#include <string.h>

#include "render/integrators/integrator.h"

enum { PSS_N = BDPT_MAX_VERTICES + 1 };
enum { PSS_CAM = BDPT_DIMS_PER_VERTEX * PSS_N, PSS_LIGHT = BDPT_DIMS_LIGHT_START + PSS_CAM };

/* A strategy's numbers: the film position, the camera and light streams,
 * the light sample of s = 1. */
typedef struct pss__numbers {
  double film[2], cam[PSS_CAM], light[PSS_LIGHT], conn[BDPT_DIMS_CONNECT];
  int n_cam, n_light;
} pss__numbers;

/* A sampler over the camera and light numbers (a number past them marks
 * the walk as reading elsewhere). */
typedef struct pss__smp {
  lmc_sampler base;
  const pss__numbers *u;
  int stream, pos[2], past;
} pss__smp;

static double pss__next(lmc_sampler *self) {
  pss__smp *s = (pss__smp *)self;
  int lt = s->stream == LMC_STREAM_LIGHT, p = s->pos[lt]++;
  if (p >= (lt ? s->u->n_light : s->u->n_cam)) {
    s->past = 1;
    return 0.5;
  }
  return lt ? s->u->light[p] : s->u->cam[p];
}

static void pss__stream(lmc_sampler *self, int stream) { ((pss__smp *)self)->stream = stream; }

void mut_pss_init(mut_pss *m, const ps_context *ctx, double u1_scale) {
  memset(m, 0, sizeof *m);
  m->ctx = ctx;
  m->s1 = 1.0 / 1024.0, m->s2 = 1.0 / 64.0;
  m->u1_scale = u1_scale;
  m->test_power = 1.0;
}

/* Kelemen's small step of u, wrapped into [0, 1). */
static double pss__step(const mut_pss *m, double u, double scale, rng *r) {
  double off = scale * m->s2 * exp(-log(m->s2 / m->s1) * rng_uniform(r));
  double v = rng_uniform(r) < 0.5 ? u + off : u - off;
  v -= floor(v);
  return v < 1.0 ? v : 0.0;
}

/* Walks strategy (s, t) from its numbers into cam and lp (for s = 1 the
 * light vertex its numbers sample in lp[0]); its MIS-weighted
 * contribution into *OUT_c and the raster point. Returns 0 when the walk
 * does not make the strategy's vertices from exactly these numbers. */
static int pss__walk(const mut_pss *m, const pss__numbers *u, int s, int t, bdpt_vertex *cam,
                     bdpt_vertex *lp, rgb *OUT_c, double *OUT_rx, double *OUT_ry,
                     int64_t *rays) {
  const scene *sc = m->ctx->sc;
  const render_settings *rs = &m->ctx->rs;
  pss__smp smp = {{pss__next, pss__stream, NULL}, u, LMC_STREAM_CAMERA, {0, 0}, 0};
  render_counters cnt = {0};
  double rx = u->film[0] * sc->cam.width, ry = u->film[1] * sc->cam.height;
  int ok = bdpt_camera_subpath(sc, rs, &smp.base, rx, ry, t, cam, &cnt) == t;
  if (ok && s >= 2) {
    sampler_use_stream(&smp.base, LMC_STREAM_LIGHT);
    ok = bdpt_light_subpath(sc, rs, &smp.base, s, lp, &cnt) == s;
  } else if (ok && s == 1) {
    ok = bdpt_connect_vertex(sc, cam[t - 1].p, u->conn, &lp[0]);
  }
  *OUT_c = rgb_zero();
  *OUT_rx = rx, *OUT_ry = ry;
  if (ok && !smp.past)
    *OUT_c = bdpt_connect(sc, cam, t, lp, s, u->conn, OUT_rx, OUT_ry, NULL, &cnt);
  if (rays) *rays += cnt.rays;
  return ok && !smp.past;
}

/* Whether the walked subpaths lie on the path X of length k (to rounding);
 * an end at infinity (inf_end: an escaped ray, a directional light) is
 * its direction, its point being only a far one. */
static int pss__same(const bdpt_vertex *X, int k, int inf_end, const bdpt_vertex *cam, int t,
                     const bdpt_vertex *lp) {
  for (int i = 0; i <= k; i++) {
    const bdpt_vertex *v = i < t ? &cam[i] : &lp[k - i];
    int dir = i == k && inf_end;
    vec3 p = dir ? v->dir : v->p, q = dir ? X[i].dir : X[i].p;
    double d = fabs(p.x - q.x) + fabs(p.y - q.y) + fabs(p.z - q.z);
    double sz = dir ? 0.0 : fabs(q.x) + fabs(q.y) + fabs(q.z);
    if (!(d <= 1e-6 * (1.0 + sz))) return 0;
  }
  return 1;
}

/* x's numbers for a strategy drawn by its MIS weights (the Gibbs steps on
 * t and z) in *u, the strategy in *OUT_s, *OUT_t, the subpaths inverted
 * added to *inverted; 0 when there are none. */
static int pss__numbers_of(const mut_pss *m, rng *r, const bdpt_vertex *X, int k,
                           bdpt_vertex *cam, bdpt_vertex *lp, pss__numbers *u, int *OUT_s,
                           int *OUT_t, int64_t *inverted) {
  const scene *sc = m->ctx->sc;
  const render_settings *rs = &m->ctx->rs;
  double w[PSS_N + 1] = {0}, sum = 0.0;
  bdpt_mis_weights(sc, X, k, cam, w);
  for (int tp = 1; tp <= k + 1; tp++) sum += w[tp] > 0.0 ? w[tp] : 0.0;
  if (!(sum > 0.0)) return 0;
  int t = bdpt_draw_strategy(w, k, 0, sum, rng_uniform(r));
  if (t < 1) return 0;
  int s = k + 1 - t;
  *OUT_s = s, *OUT_t = t;
  memset(u, 0, sizeof *u);
  bdpt_resplit(sc, X, k, s, t, cam, lp);
  if (t >= 2) {
    double rx, ry;
    ++*inverted;
    if (!bdpt_invert_camera_subpath(sc, rs, NULL, cam, t, r, &rx, &ry, u->cam)) return 0;
    u->film[0] = rx / sc->cam.width, u->film[1] = ry / sc->cam.height;
    if (!(u->film[0] >= 0.0 && u->film[0] < 1.0 && u->film[1] >= 0.0 && u->film[1] < 1.0))
      return 0;
    u->n_cam = BDPT_DIMS_PER_VERTEX * (t - 1);
  }
  if (s >= 1) ++*inverted;
  if (s >= 2) {
    if (!bdpt_invert_light_subpath(sc, rs, NULL, lp, s, r, u->light)) return 0;
    u->n_light = BDPT_DIMS_LIGHT_START + BDPT_DIMS_PER_VERTEX * (s - 1);
  } else if (s == 1) {
    if (!bdpt_invert_connect(sc, &cam[t - 1], &X[k], r, u->conn)) return 0;
  }
  return 1;
}

int mut_pss_propose(const mut_pss *m, rng *r, const ps_path *x, ps_path *OUT_y,
                    double *OUT_ratio, bdpt_vertex *scratch, int64_t *rays,
                    mut_pss_tally *tally) {
  mut_pss_tally own = {0, 0, 0};
  if (!tally) tally = &own;
  int k = x->k;
  bdpt_vertex *X = scratch, *cam = scratch + PSS_N, *lp = scratch + 2 * PSS_N;
  bdpt_vertex *cam2 = scratch + 3 * PSS_N, *lp2 = scratch + 4 * PSS_N;
  *OUT_ratio = 0.0;
  if (k < 1 || k + 1 > PSS_N || !(x->lum > 0.0)) return 0;
  for (int i = 0; i <= k; i++) X[i] = x->x[i].v;
  pss__numbers u, u2;
  int s = 0, t = 0;
  if (!pss__numbers_of(m, r, X, k, cam, lp, &u, &s, &t, &tally->inverted)) {
    tally->refused++;
    return 0;
  }
  /* x's value in these numbers: its strategy walked again from them. */
  rgb c;
  double rx, ry;
  if (!pss__walk(m, &u, s, t, cam, lp, &c, &rx, &ry, rays) ||
      !pss__same(X, k, x->x[k].inf, cam, t, lp)) {
    tally->elsewhere++;
    return 0;
  }
  double fx = rgb_luminance(c);
  if (!(fx > 0.0) || !isfinite(fx)) {
    tally->elsewhere++;
    return 0;
  }
  /* The small step, and y. */
  u2 = u;
  if (t >= 2)
    for (int i = 0; i < 2; i++) u2.film[i] = pss__step(m, u.film[i], 1.0, r);
  for (int i = 0; i < u.n_cam; i++) u2.cam[i] = pss__step(m, u.cam[i], 1.0, r);
  for (int i = 0; i < u.n_light; i++)
    u2.light[i] = pss__step(m, u.light[i], i == 1 ? m->u1_scale : 1.0, r);
  if (s == 1)
    for (int i = 0; i < BDPT_DIMS_CONNECT; i++)
      u2.conn[i] = pss__step(m, u.conn[i], i == 1 ? m->u1_scale : 1.0, r);
  if (!pss__walk(m, &u2, s, t, cam2, lp2, &c, &rx, &ry, rays)) return 1; /* ratio 0 */
  double fy = rgb_luminance(c);
  if (!(fy > 0.0) || !isfinite(fy)) return 1;
  if (!ps_from_bdpt(m->ctx, cam2, t, s > 0 ? lp2 : NULL, s, OUT_y) || OUT_y->k != k ||
      !(OUT_y->lum > 0.0))
    return 1;
  *OUT_ratio = m->test_power == 1.0 ? fy / fx : pow(fy / fx, m->test_power);
  return 1;
}
