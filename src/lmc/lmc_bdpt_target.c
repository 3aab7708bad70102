/*
 * lmc_bdpt_target.c: the multiplexed bidirectional state of mmlt (mcmc.c)
 * as an mc_target with gradients: one target per path length k, its
 * strategy (s, t) chosen by the first connect coordinate, evaluated by
 * path_eval_bdpt (render/path.h) so that a state has the exact gradient of
 * its MIS-weighted contribution.
 *
 * The layout is mmlt's, so a state means the same path here and there:
 *   camera stream   film position over the film grown by the filter radius
 *                   r (rx = -r + u0 (W + 2r)), then the camera subpath;
 *   light stream    the light subpath;
 *   connect stream  0: the strategy, uniform over the n_k valid ones;
 *                   1 .. 3: the light sample of s = 1.
 * path_eval_bdpt reads BDPT's own layout (integrator.h): raster position
 * u0 W and the s = 1 light sample at connect positions 3 (t - 2) .. + 2.
 * A sampler adapter translates: it hands path_eval_bdpt the film numbers
 * (-r + u (W + 2r)) / W (outside [0, 1) near the border, which the camera
 * accepts) and, for s = 1, the state's connect numbers 1 .. 3 in the slots
 * of its t (the slots before, which it draws and ignores, get a constant).
 * The gradient is mapped back coordinate by coordinate, with the chain
 * rule factor (W + 2r) / W on the two film numbers.
 *
 * f = n_k times the strategy's contribution, as mmlt: A = (W + 2r)(H + 2r)
 * times it for t >= 2 (a radiance estimate at a uniform raster point), the
 * light-tracing splat itself for t = 1.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/integrator_lmc.h"
#include "lmc/states.h"
#include "render/path.h"

typedef struct lmc_bdpt_scratch {
  path_scratch *ps;
  render_counters cnt; /* the plain evaluation's rays */
  bdpt_vertex cam[BDPT_MAX_VERTICES], lp[BDPT_MAX_VERTICES];
  int64_t rays;
  int64_t grad_evals, hess_evals;
  int64_t nan_samples;
} lmc_bdpt_scratch;

static void *lmc__bdpt_scratch_create(const mc_target *t) {
  (void)t;
  lmc_bdpt_scratch *sc = calloc(1, sizeof *sc);
  if (!sc) return NULL;
  lmc_error err;
  if (path_scratch_create(&sc->ps, &err) != LMC_OK) {
    free(sc);
    return NULL;
  }
  return sc;
}

static void lmc__bdpt_scratch_destroy(void *scratch) {
  lmc_bdpt_scratch *sc = scratch;
  if (!sc) return;
  path_scratch_destroy(sc->ps);
  free(sc);
}

static int64_t lmc__bdpt_scratch_rays(const void *scratch) {
  const lmc_bdpt_scratch *sc = scratch;
  return sc->rays + sc->cnt.rays;
}

int64_t lmc_bdpt_scratch_grad_evals(const void *scratch) {
  return scratch ? ((const lmc_bdpt_scratch *)scratch)->grad_evals : 0;
}

int64_t lmc_bdpt_scratch_hess_evals(const void *scratch) {
  return scratch ? ((const lmc_bdpt_scratch *)scratch)->hess_evals : 0;
}

int64_t lmc_bdpt_scratch_nan_samples(const void *scratch) {
  return scratch ? ((const lmc_bdpt_scratch *)scratch)->nan_samples : 0;
}

/* The adapter from BDPT's layout to the state's (see above). */
typedef struct lmc__adapter {
  lmc_sampler base;
  lmc_sampler *inner;
  int stream;         /* current stream */
  int pos[LMC_STREAM_COUNT];
  int skip;           /* connect slots path_eval_bdpt draws before its own: 3 (t - 2) */
  double fx, fy, r, W, H; /* film mapping */
} lmc__adapter;

static double lmc__adapter_next(lmc_sampler *self) {
  lmc__adapter *a = (lmc__adapter *)self;
  int p = a->pos[a->stream]++;
  if (a->stream == LMC_STREAM_CONNECT && p < a->skip) return 0.5; /* drawn and unused */
  double u = sampler_next(a->inner);
  if (a->stream == LMC_STREAM_CAMERA && p < 2)
    return p == 0 ? (-a->r + u * (a->W + 2.0 * a->r)) / a->W : (-a->r + u * (a->H + 2.0 * a->r)) / a->H;
  return u;
}

static void lmc__adapter_use_stream(lmc_sampler *self, int stream) {
  lmc__adapter *a = (lmc__adapter *)self;
  a->stream = stream;
  sampler_use_stream(a->inner, stream);
}

/* Sets the value of a state from its contribution c; returns f. */
static double lmc__set_value(lmc_bdpt_scratch *sc, mc_value *v, rgb c, double rx, double ry) {
  if (!rgb_isfinite(c)) {
    sc->nan_samples++;
    c = rgb_zero();
  }
  double f = rgb_luminance(c);
  if (!(f > 0.0) || !isfinite(f)) {
    c = rgb_zero();
    f = 0.0;
  }
  v->value = c;
  v->f = f;
  v->rx = rx;
  v->ry = ry;
  return f;
}

/* The state's strategy (s, t) from its technique coordinate (connect 0). */
static void lmc__strategy(const lmc_bdpt_target *st, double u_tech, int *OUT_s, int *OUT_t) {
  int n = st->n_strategies, k = st->length;
  int idx = (int)(u_tech * n);
  if (idx >= n) idx = n - 1;
  *OUT_t = k == 1 ? 2 : idx + 1;
  *OUT_s = k + 1 - *OUT_t;
}

/* f with its gradient (want PATH_WANT_GRAD) or also its Hessian
 * (PATH_WANT_HESS) over the state's coordinates: d f / du = scale m dlum,
 * d^2 f / du_a du_b = scale m_a m_b d^2 lum, with m the adapter's chain-rule
 * factor of a coordinate (the film's two, else 1). */
static int lmc__bdpt_eval_d(const mc_target *t, lmc_bdpt_scratch *sc, lmc_sampler *smp, int want,
                            mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok, int *OUT_hn,
                            int *OUT_hidx, double *OUT_hess, int *OUT_hess_ok) {
  const lmc_bdpt_target *st = t->ctx;
  int n = st->n_strategies;
  *OUT_grad_ok = 0;
  if (OUT_hess_ok) *OUT_hess_ok = 0;

  /* The strategy. */
  sampler_use_stream(smp, LMC_STREAM_CONNECT);
  int ss, tt;
  lmc__strategy(st, sampler_next(smp), &ss, &tt);

  /* The path, through the adapter. */
  lmc__adapter a;
  memset(&a, 0, sizeof a);
  a.base.next = lmc__adapter_next;
  a.base.use_stream = lmc__adapter_use_stream;
  a.inner = smp;
  a.stream = LMC_STREAM_CONNECT;
  a.pos[LMC_STREAM_CONNECT] = 0;
  a.skip = ss == 1 ? BDPT_DIMS_CONNECT * (tt - 2) : 0;
  a.r = st->margin;
  a.W = st->s->cam.width;
  a.H = st->s->cam.height;
  path_eval pe;
  if (path_eval_bdpt(st->s, &st->rs, &a.base, ss, tt, want, sc->ps, &pe, &sc->rays) != LMC_OK)
    return -1;
  sc->grad_evals++;
  sc->hess_evals += want == PATH_WANT_HESS;

  double scale = tt == 1 ? (double)n : st->area * n;
  double f = lmc__set_value(sc, OUT_value, rgb_scale(pe.value, scale), pe.rx, pe.ry);

  /* Each differentiated coordinate's index in the state (-1: none) and
   * chain-rule factor. */
  memset(OUT_grad, 0, (size_t)t->dim * sizeof(double));
  if (!(f > 0.0) || !pe.grad_ok) return 0;
  int off_conn = mc_target_stream_offset(t, LMC_STREAM_CONNECT);
  int ok = 0;
  int coord[MC_HESS_MAX];
  double m[MC_HESS_MAX];
  int nd = pe.n_diff <= MC_HESS_MAX ? pe.n_diff : 0;
  for (int j = 0; j < nd; j++) coord[j] = -1;
  for (int i = 0; i < pe.n_coords; i++) {
    const path_coord *pc = &pe.coords[i];
    if (!pc->diff || pc->stream < 0 || pc->stream >= LMC_STREAM_COUNT) continue;
    double mi = 1.0;
    int idx_u;
    if (pc->stream == LMC_STREAM_CONNECT) {
      if (pc->pos < a.skip) continue;
      idx_u = off_conn + 1 + (pc->pos - a.skip);
      if (idx_u >= off_conn + t->stream_dim[LMC_STREAM_CONNECT]) continue;
    } else {
      if (pc->pos >= t->stream_dim[pc->stream]) continue;
      idx_u = mc_target_stream_offset(t, pc->stream) + pc->pos;
      if (pc->stream == LMC_STREAM_CAMERA && pc->pos < 2)
        mi = pc->pos == 0 ? (a.W + 2.0 * a.r) / a.W : (a.H + 2.0 * a.r) / a.H;
    }
    double d = pc->dlum * scale * mi;
    if (!isfinite(d)) return 0; /* no usable gradient at this state */
    OUT_grad[idx_u] += d;
    ok = 1;
    if (pc->var >= 0 && pc->var < nd) coord[pc->var] = idx_u, m[pc->var] = mi;
  }
  *OUT_grad_ok = ok;
  if (want != PATH_WANT_HESS || !ok || !pe.hess_ok || pe.n_diff > MC_HESS_MAX) return 0;

  /* The Hessian over the slots kept, in slot order. */
  int keep[MC_HESS_MAX], hn = 0;
  for (int j = 0; j < nd; j++)
    if (coord[j] >= 0) keep[hn] = j, OUT_hidx[hn++] = coord[j];
  int q = 0;
  for (int x = 0; x < hn; x++)
    for (int y = x; y < hn; y++) {
      int ja = keep[x], jb = keep[y];
      double h = pe.hlum[(size_t)ja * nd - (size_t)ja * (size_t)(ja - 1) / 2 + (size_t)(jb - ja)];
      h *= scale * m[ja] * m[jb];
      if (!isfinite(h)) return 0;
      OUT_hess[q++] = h;
    }
  *OUT_hn = hn;
  *OUT_hess_ok = 1;
  return 0;
}

static int lmc__bdpt_eval(const mc_target *t, void *scratch, lmc_sampler *smp, mc_value *OUT_value,
                          double *OUT_grad, int *OUT_grad_ok) {
  const lmc_bdpt_target *st = t->ctx;
  lmc_bdpt_scratch *sc = scratch;
  if (OUT_grad_ok) *OUT_grad_ok = 0;
  if (!OUT_grad) {
    /* f alone: mmlt's plain-double evaluation (the same number as
     * path_eval_bdpt's up to rounding, and about twice as fast). */
    double rx, ry;
    rgb c = mc_mmlt_contribution(st->s, &st->rs, st->length, st->n_strategies, st->margin,
                                   st->area, smp, sc->cam, sc->lp, &sc->cnt, &rx, &ry);
    lmc__set_value(sc, OUT_value, c, rx, ry);
    return 0;
  }
  int ok;
  int rc = lmc__bdpt_eval_d(t, sc, smp, PATH_WANT_GRAD, OUT_value, OUT_grad, &ok, NULL, NULL,
                            NULL, NULL);
  if (OUT_grad_ok) *OUT_grad_ok = ok;
  return rc;
}

/* eval_hess (target.h); the label is ignored (the target has none). */
static int lmc__bdpt_eval_hess(const mc_target *t, void *scratch, lmc_sampler *smp, int label,
                               mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok,
                               int *OUT_hn, int *OUT_hidx, double *OUT_hess, int *OUT_hess_ok) {
  (void)label;
  return lmc__bdpt_eval_d(t, scratch, smp, PATH_WANT_HESS, OUT_value, OUT_grad, OUT_grad_ok,
                          OUT_hn, OUT_hidx, OUT_hess, OUT_hess_ok);
}

/* local_coords (target.h): the coordinates strategy (s, t) reads, the
 * technique coordinate excluded: the film position and the numbers of the
 * t - 1 camera-subpath surface vertices, the emitter's and those of the
 * s - 1 light-subpath surface vertices, and for s = 1 the light sample
 * (integrator.h's layout); a function of the technique coordinate alone. */
static int lmc__bdpt_local_coords(const mc_target *t, const double *u, int label, int *OUT_idx) {
  (void)label;
  const lmc_bdpt_target *st = t->ctx;
  int off_conn = mc_target_stream_offset(t, LMC_STREAM_CONNECT);
  int ss, tt;
  lmc__strategy(st, u[off_conn], &ss, &tt);
  int n = 0;
  int nc = 2 + BDPT_DIMS_PER_VERTEX * (tt - 1);
  if (nc > t->stream_dim[LMC_STREAM_CAMERA]) nc = t->stream_dim[LMC_STREAM_CAMERA];
  for (int i = 0; i < nc; i++) OUT_idx[n++] = i;
  if (ss > 0) {
    int off_l = mc_target_stream_offset(t, LMC_STREAM_LIGHT);
    int nl = BDPT_DIMS_LIGHT_START + BDPT_DIMS_PER_VERTEX * (ss - 1);
    if (nl > t->stream_dim[LMC_STREAM_LIGHT]) nl = t->stream_dim[LMC_STREAM_LIGHT];
    for (int i = 0; i < nl; i++) OUT_idx[n++] = off_l + i;
  }
  if (ss == 1)
    for (int i = 1; i < t->stream_dim[LMC_STREAM_CONNECT]; i++) OUT_idx[n++] = off_conn + i;
  return n;
}

static double lmc__bdpt_expect(const mc_target *t, void *scratch, lmc_sampler *smp) {
  const lmc_bdpt_target *st = t->ctx;
  lmc_bdpt_scratch *sc = scratch;
  return mc_mmlt_expected(st->s, &st->rs, st->length, st->margin, st->area, smp, sc->cam, sc->lp,
                            &sc->cnt);
}

void lmc_bdpt_target_init(mc_target *OUT_target, lmc_bdpt_target *ctx, const scene *s,
                          const render_settings *rs, int length) {
  memset(OUT_target, 0, sizeof *OUT_target);
  double r = s->filter.radius, W = s->cam.width, H = s->cam.height;
  ctx->s = s;
  ctx->rs = *rs;
  ctx->rs.mindepth = -1; /* the family's length is what counts */
  ctx->length = length;
  ctx->n_strategies = length == 1 ? 1 : length + 1;
  ctx->margin = r;
  ctx->area = (W + 2.0 * r) * (H + 2.0 * r);
  OUT_target->stream_dim[LMC_STREAM_CAMERA] = 2 + BDPT_DIMS_PER_VERTEX * (length + 1);
  OUT_target->stream_dim[LMC_STREAM_LIGHT] = BDPT_DIMS_LIGHT_START + BDPT_DIMS_PER_VERTEX * (length + 1);
  OUT_target->stream_dim[LMC_STREAM_CONNECT] = 1 + BDPT_DIMS_CONNECT;
  OUT_target->dim = OUT_target->stream_dim[0] + OUT_target->stream_dim[1] + OUT_target->stream_dim[2];
  OUT_target->ctx = ctx;
  OUT_target->eval = lmc__bdpt_eval;
  OUT_target->eval_expect = lmc__bdpt_expect;
  OUT_target->eval_hess = lmc__bdpt_eval_hess;
  OUT_target->local_coords = lmc__bdpt_local_coords;
  OUT_target->scratch_create = lmc__bdpt_scratch_create;
  OUT_target->scratch_destroy = lmc__bdpt_scratch_destroy;
  OUT_target->scratch_rays = lmc__bdpt_scratch_rays;
}
