/*
 * bdpt_states.c: the bdpt states as a labelled mc_target (see
 * bdpt_states.h for the model).
 *
 * Per-label evaluation (eval_label) traces just the strategy's two
 * subpaths, t camera and s light vertices (for s = 1 the light sample of
 * the connect triple of camera vertex t, skipped to: the 3 (t - 2) numbers
 * before it belong to other strategies), with the label's absolute
 * directions.
 * The whole sample (eval_all) is bdpt_li's loop, every strategy of a
 * length in [kmin, kmax] recorded apart; for a current state of label l
 * the scattering vertices of l's subpaths read absolute directions and the
 * rest BSDF-relative ones (the numbers l leaves free), all in the large
 * step's measure.
 */
#include "lmc/states/bdpt_states.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/driver/space.h"
#include "lmc/states/states.h"
#include "render/integrators/integrator.h"
#include "render/integrators/path.h"

typedef mc_states_scratch bs__scratch;

int mc_bdpt_states_length(const mc_bdpt_states *ctx, int label) {
  if (label < 0 || label >= ctx->n_labels) return 0;
  return ctx->strat[label].s + ctx->strat[label].t - 1;
}

/* Value and f of a contribution c at (rx, ry); non-finite ones are
 * dropped (and counted). */
static void bs__value(mc_value *v, rgb c, double rx, double ry, render_counters *cnt) {
  mc_states_value(v, c, rx, ry, &cnt->nan_samples);
}

/* The raster point of the film numbers (u0, u1): uniform over the film
 * grown by the filter radius. */
static void bs__raster(const mc_bdpt_states *st, double u0, double u1, double *rx, double *ry) {
  double r = st->margin;
  *rx = -r + u0 * (st->s->cam.width + 2.0 * r);
  *ry = -r + u1 * (st->s->cam.height + 2.0 * r);
}

/* The product of the jac of strategy (s, t)'s scattering vertices. */
static double bs__jacobian(const bdpt_vertex *cam, int t, const bdpt_vertex *lp, int s) {
  double jac = 1.0;
  for (int j = 1; j <= t - 2; j++) jac *= cam[j].jac;
  for (int j = 1; j <= s - 2; j++) jac *= lp[j].jac;
  return jac;
}

/* ---- The gradient (path_eval_bdpt_abs through a film adapter) ----------- */

/* With OUT_hess (eval_hess), also the Hessian of f over the label's
 * differentiated coordinates, from path_eval's Hessian of the luminance:
 * d^2 f / du_a du_b = scale m_a m_b d^2 lum / du'_a du'_b, with m the
 * adapter's chain-rule factor of each coordinate (the film's two, else 1). */
static int bs__eval_grad(const mc_target *t, bs__scratch *sc, lmc_sampler *smp, int ss, int tt,
                         mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok, int *OUT_hn,
                         int *OUT_hidx, double *OUT_hess, int *OUT_hess_ok) {
  const mc_bdpt_states *st = t->ctx;
  /* path_eval_bdpt_abs reads the raster position as u0 W, u1 H: the
   * adapter maps the state's film numbers (states.h). */
  path_scratch *ps = mc_states_scratch_path(sc);
  if (!ps) return -1;
  mc_film_adapter a;
  mc_film_adapter_init(&a, smp, LMC_STREAM_CAMERA, 0, st->margin, st->s->cam.width,
                       st->s->cam.height);
  path_eval pe;
  if (OUT_hess_ok) *OUT_hess_ok = 0;
  if (path_eval_bdpt_abs(st->s, &st->rs, &a.base, ss, tt, st->rough_min,
                         OUT_hess ? PATH_WANT_HESS : PATH_WANT_GRAD, ps, &pe,
                         &sc->rays_d) != LMC_OK)
    return -1;
  sc->counts.grad_evals++;
  sc->counts.hess_evals += OUT_hess != NULL;
  double scale = tt == 1 ? 1.0 : st->area;
  bs__value(OUT_value, rgb_scale(pe.value, scale), pe.rx, pe.ry, &sc->cnt);
  OUT_value->f_large = pe.jac > 0.0 ? OUT_value->f / pe.jac : 0.0;

  /* The gradient of f per coordinate of the state. */
  memset(OUT_grad, 0, (size_t)t->dim * sizeof(double));
  if (!(OUT_value->f > 0.0) || !pe.grad_ok) return 0;
  int ok = 0;
  for (int i = 0; i < pe.n_coords; i++) {
    const path_coord *pc = &pe.coords[i];
    if (!pc->diff || pc->stream < 0 || pc->stream >= LMC_STREAM_COUNT) continue;
    if (pc->pos >= t->stream_dim[pc->stream]) continue;
    double d = pc->dlum * scale * mc_film_adapter_factor(&a, pc->stream, pc->pos);
    if (!isfinite(d)) return 0; /* no usable gradient at this state */
    OUT_grad[mc_target_stream_offset(t, pc->stream) + pc->pos] += d;
    ok = 1;
  }
  *OUT_grad_ok = ok;
  if (!OUT_hess || !ok || !pe.hess_ok || pe.n_diff > MC_HESS_MAX) return 0;

  /* The Hessian: each tangent slot's coordinate and factor, then the
   * slots kept (inside their stream's block) in slot order. */
  int coord[MC_HESS_MAX], nd = pe.n_diff;
  double m[MC_HESS_MAX];
  for (int j = 0; j < nd; j++) coord[j] = -1;
  for (int i = 0; i < pe.n_coords; i++) {
    const path_coord *pc = &pe.coords[i];
    if (pc->var < 0 || pc->var >= nd || pc->stream < 0 || pc->stream >= LMC_STREAM_COUNT) continue;
    if (pc->pos >= t->stream_dim[pc->stream]) continue;
    coord[pc->var] = mc_target_stream_offset(t, pc->stream) + pc->pos;
    m[pc->var] = mc_film_adapter_factor(&a, pc->stream, pc->pos);
  }
  if (!mc_states_hessian(&pe, nd, coord, m, scale, OUT_hn, OUT_hidx, OUT_hess)) return 0;
  if (OUT_hess_ok) *OUT_hess_ok = 1;
  return 0;
}

/* ---- The target ------------------------------------------------------------- */

static int bs__eval_label(const mc_target *t, void *scratch, lmc_sampler *smp, int label,
                          mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok) {
  const mc_bdpt_states *st = t->ctx;
  bs__scratch *sc = scratch;
  if (OUT_grad_ok) *OUT_grad_ok = 0;
  memset(OUT_value, 0, sizeof *OUT_value);
  if (label < 0 || label >= st->n_labels) return -1;
  int ss = st->strat[label].s, tt = st->strat[label].t;
  if (OUT_grad && st->media) return -1; /* no gradients through media yet */
  if (OUT_grad)
    return bs__eval_grad(t, sc, smp, ss, tt, OUT_value, OUT_grad, OUT_grad_ok, NULL, NULL, NULL,
                         NULL);
  const scene *s = st->s;

  /* The light sample of s = 1: the connect triple of camera vertex t. */
  double uc[BDPT_DIMS_CONNECT] = {0.0, 0.0, 0.0};
  if (ss == 1) {
    sampler_use_stream(smp, LMC_STREAM_CONNECT);
    sampler_skip(smp, BDPT_DIMS_CONNECT * (tt - 2));
    for (int i = 0; i < BDPT_DIMS_CONNECT; i++) uc[i] = sampler_next(smp);
  }
  /* The two subpaths, just long enough for (s, t), in the label's own
   * coordinates. */
  double rx = 0.0, ry = 0.0;
  if (tt >= 2) {
    sampler_use_stream(smp, LMC_STREAM_CAMERA);
    double u0 = sampler_next(smp), u1 = sampler_next(smp);
    bs__raster(st, u0, u1, &rx, &ry);
  }
  bdpt_param pc = {tt - 1, st->rough_min}, pl = {ss - 1, st->rough_min};
  int nc = bdpt_camera_subpath_p(s, &st->rs, smp, rx, ry, tt, &pc, sc->cam, &sc->cnt);
  if (nc < tt) return 0;
  if (ss >= 2) {
    sampler_use_stream(smp, LMC_STREAM_LIGHT);
    int nl = bdpt_light_subpath_p(s, &st->rs, smp, ss, &pl, sc->lp, &sc->cnt);
    if (nl < ss) return 0;
  }
  mc_bdpt_states_value(st, sc->cam, tt, sc->lp, ss, uc, rx, ry, OUT_value, &sc->cnt);
  return 0;
}

void mc_bdpt_states_value(const mc_bdpt_states *st, const bdpt_vertex *cam, int tt,
                          const bdpt_vertex *lp, int ss, const double *uc, double rx, double ry,
                          mc_value *OUT_value, render_counters *cnt) {
  double prx = rx, pry = ry;
  rgb c = bdpt_connect(st->s, cam, tt, lp, ss, uc, &prx, &pry, NULL, cnt);
  if (tt != 1) c = rgb_scale(c, st->area);
  bs__value(OUT_value, c, prx, pry, cnt);
  /* The density in the label's coordinates. */
  double jac = st->rough_min < 1.0 ? bs__jacobian(cam, tt, lp, ss) : 1.0;
  OUT_value->f *= jac;
  OUT_value->value = rgb_scale(OUT_value->value, jac);
  if (!(OUT_value->f > 0.0) || !isfinite(OUT_value->f)) {
    OUT_value->f = OUT_value->f_large = 0.0;
    OUT_value->value = rgb_zero();
  }
}

static int bs__eval_all(const mc_target *t, void *scratch, lmc_sampler *smp, int from_label,
                        mc_contrib *OUT) {
  const mc_bdpt_states *st = t->ctx;
  bs__scratch *sc = scratch;
  const scene *s = st->s;
  /* Both subpaths as long as the longest length needs; a current state's
   * label's scattering vertices read their absolute directions. */
  bdpt_param pc = {0, st->rough_min}, pl = {0, st->rough_min};
  if (from_label >= 0 && from_label < st->n_labels) {
    pc.abs_until = st->strat[from_label].t - 1;
    pl.abs_until = st->strat[from_label].s - 1;
  }
  sampler_use_stream(smp, LMC_STREAM_CAMERA);
  double u0 = sampler_next(smp), u1 = sampler_next(smp), rx, ry;
  bs__raster(st, u0, u1, &rx, &ry);
  int nc = bdpt_camera_subpath_p(s, &st->rs, smp, rx, ry, st->kmax + 1, &pc, sc->cam, &sc->cnt);
  sampler_use_stream(smp, LMC_STREAM_LIGHT);
  int nl = bdpt_light_subpath_p(s, &st->rs, smp, st->kmax, &pl, sc->lp, &sc->cnt);
  sampler_use_stream(smp, LMC_STREAM_CONNECT);

  /* Every strategy of a length in [kmin, kmax], as bdpt_li. */
  int n = 0, stride = st->kmax + 2;
  for (int tt = 1; tt <= nc; tt++) {
    double uc[BDPT_DIMS_CONNECT] = {0.0, 0.0, 0.0};
    if (tt >= 2)
      for (int k = 0; k < BDPT_DIMS_CONNECT; k++) uc[k] = sampler_next(smp);
    for (int ss = 0; ss + tt - 1 <= st->kmax; ss++) {
      if (ss >= 2 && ss > nl) break;
      int label = st->label_of[ss * stride + tt];
      if (label < 0) continue;
      double prx = rx, pry = ry;
      rgb c = bdpt_connect(s, sc->cam, tt, sc->lp, ss, uc, &prx, &pry, NULL, &sc->cnt);
      if (rgb_is_black(c)) continue;
      if (tt != 1) c = rgb_scale(c, st->area);
      bs__value(&OUT[n].v, c, prx, pry, &sc->cnt);
      if (!(OUT[n].v.f > 0.0)) continue;
      OUT[n++].label = label;
    }
  }
  return n;
}

/* The label (s, t)'s coordinates from the large step's (bdpt_states.h):
 * the rough scattering vertices z_1 .. z_{t-2}, y_1 .. y_{s-2} get the
 * spherical coordinates of their direction and a fresh lobe number; the
 * Jacobian is the product of their pdf J. */
static double bs__relabel(const mc_target *t, void *scratch, int label, double *u, rng *r) {
  const mc_bdpt_states *st = t->ctx;
  const bs__scratch *sc = scratch;
  int ss = st->strat[label].s, tt = st->strat[label].t;
  double jac = 1.0;
  int cam0 = mc_target_stream_offset(t, LMC_STREAM_CAMERA) + 2;
  for (int j = 1; j <= tt - 2; j++) {
    const bdpt_vertex *v = &sc->cam[j];
    if (!v->rough) continue;
    int i = cam0 + st->per_vertex * (j - 1) + st->dir_at;
    u[i - 1] = rng_uniform(r), u[i] = v->sph[0], u[i + 1] = v->sph[1];
    jac *= v->jac;
  }
  int lp0 = mc_target_stream_offset(t, LMC_STREAM_LIGHT) + BDPT_DIMS_LIGHT_START;
  for (int j = 1; j <= ss - 2; j++) {
    const bdpt_vertex *v = &sc->lp[j];
    if (!v->rough) continue;
    int i = lp0 + st->per_vertex * (j - 1) + st->dir_at;
    u[i - 1] = rng_uniform(r), u[i] = v->sph[0], u[i + 1] = v->sph[1];
    jac *= v->jac;
  }
  return jac;
}

/* eval_hess (target.h): bs__eval_grad with the Hessian. */
static int bs__eval_hess(const mc_target *t, void *scratch, lmc_sampler *smp, int label,
                         mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok, int *OUT_hn,
                         int *OUT_hidx, double *OUT_hess, int *OUT_hess_ok) {
  const mc_bdpt_states *st = t->ctx;
  *OUT_grad_ok = *OUT_hess_ok = 0;
  *OUT_hn = 0;
  memset(OUT_value, 0, sizeof *OUT_value);
  if (label < 0 || label >= st->n_labels) return -1;
  return bs__eval_grad(t, scratch, smp, st->strat[label].s, st->strat[label].t, OUT_value,
                       OUT_grad, OUT_grad_ok, OUT_hn, OUT_hidx, OUT_hess, OUT_hess_ok);
}

/* The continuous numbers of strategy (s, t), in this order: the film
 * position (t >= 2); the direction of each scattering camera vertex z_1
 * .. z_{t-2}; the emission's position and direction (s >= 2) and the
 * direction of each scattering light vertex y_1 .. y_{s-2}; the point on
 * the light of s = 1. */
static int bs__label_coords(const mc_target *t, int label, int *OUT_idx) {
  const mc_bdpt_states *st = t->ctx;
  if (label < 0 || label >= st->n_labels) return 0;
  int ss = st->strat[label].s, tt = st->strat[label].t, n = 0;
  int c0 = mc_target_stream_offset(t, LMC_STREAM_CAMERA);
  if (tt >= 2) OUT_idx[n++] = c0, OUT_idx[n++] = c0 + 1;
  for (int j = 1; j <= tt - 2; j++) {
    int i = c0 + 2 + st->per_vertex * (j - 1) + st->dir_at;
    OUT_idx[n++] = i, OUT_idx[n++] = i + 1;
  }
  int l0 = mc_target_stream_offset(t, LMC_STREAM_LIGHT);
  if (ss >= 2) {
    for (int k = 1; k < BDPT_DIMS_LIGHT_START; k++) OUT_idx[n++] = l0 + k;
    for (int j = 1; j <= ss - 2; j++) {
      int i = l0 + BDPT_DIMS_LIGHT_START + st->per_vertex * (j - 1) + st->dir_at;
      OUT_idx[n++] = i, OUT_idx[n++] = i + 1;
    }
  }
  if (ss == 1) {
    int i = mc_target_stream_offset(t, LMC_STREAM_CONNECT) + BDPT_DIMS_CONNECT * (tt - 2);
    OUT_idx[n++] = i + 1, OUT_idx[n++] = i + 2;
  }
  return n;
}

lmc_status mc_bdpt_states_init(mc_target *OUT_target, mc_bdpt_states *ctx, const scene *s,
                               const render_settings *rs, double rough_min, int kmin, int kmax,
                               lmc_error *err) {
  memset(OUT_target, 0, sizeof *OUT_target);
  memset(ctx, 0, sizeof *ctx);
  if (kmin < 1) kmin = 1;
  if (kmax > BDPT_MAX_VERTICES - 2) kmax = BDPT_MAX_VERTICES - 2;
  if (kmax < kmin)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "bdpt states: no length in [%d, %d]", kmin, kmax);
  ctx->s = s;
  ctx->rs = *rs;
  ctx->rs.mindepth = -1;
  ctx->rs.maxdepth = kmax;
  ctx->margin = s->filter.radius;
  ctx->area = (s->cam.width + 2.0 * ctx->margin) * (s->cam.height + 2.0 * ctx->margin);
  ctx->rough_min = rough_min;
  ctx->kmin = kmin, ctx->kmax = kmax;
  ctx->media = render_media_on(s, rs);
  ctx->per_vertex = BDPT_DIMS_PER_VERTEX + (ctx->media ? BDPT_DIMS_MEDIA : 0);
  ctx->dir_at = (ctx->media ? BDPT_DIMS_MEDIA : 0) + 1;

  /* The labels: length k has t = 1 .. k + 1, s = k + 1 - t, without
   * (1, 1); length 1 has (0, 2) alone (bdpt_connect's rules). */
  int stride = kmax + 2;
  /* One block: strat, then label_of (shorts after the 4-byte-aligned pairs). */
  size_t cells = (size_t)stride * (size_t)stride;
  ctx->strat = malloc(cells * (sizeof *ctx->strat + sizeof *ctx->label_of));
  ctx->label_of = ctx->strat ? (short *)(ctx->strat + cells) : NULL;
  if (!ctx->strat) {
    mc_bdpt_states_free(ctx);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the strategies");
  }
  for (int i = 0; i < stride * stride; i++) ctx->label_of[i] = -1;
  int n = 0;
  for (int k = kmin; k <= kmax; k++)
    for (int tt = 1; tt <= k + 1; tt++) {
      int ss = k + 1 - tt;
      if ((ss == 1 && tt == 1) || (k == 1 && tt != 2)) continue;
      ctx->strat[n] = (mc_strategy){ss, tt};
      ctx->label_of[ss * stride + tt] = (short)n++;
    }
  ctx->n_labels = n;

  mc_target *T = OUT_target;
  T->stream_dim[LMC_STREAM_CAMERA] = 2 + ctx->per_vertex * (kmax + 1);
  T->stream_dim[LMC_STREAM_LIGHT] = BDPT_DIMS_LIGHT_START + ctx->per_vertex * (kmax + 1);
  T->stream_dim[LMC_STREAM_CONNECT] = BDPT_DIMS_CONNECT * (kmax + 1);
  T->dim = T->stream_dim[0] + T->stream_dim[1] + T->stream_dim[2];
  T->ctx = ctx;
  mc_states_use_scratch(T);
  T->n_labels = n;
  T->eval_label = bs__eval_label;
  T->eval_all = bs__eval_all;
  if (ctx->rough_min < 1.0) T->relabel = bs__relabel;
  T->label_coords = bs__label_coords;
  if (!ctx->media) T->eval_hess = bs__eval_hess;

  /* The light-position numbers u1 of the emission and of every connect
   * triple pick an area light's triangle (mc_light_u1_scale). */
  ctx->step_scale = malloc((size_t)T->dim * sizeof(double));
  if (!ctx->step_scale) {
    mc_bdpt_states_free(ctx);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the strategies");
  }
  double u1_scale = mc_light_u1_scale(s);
  for (int i = 0; i < T->dim; i++) ctx->step_scale[i] = 1.0;
  ctx->step_scale[mc_target_stream_offset(T, LMC_STREAM_LIGHT) + 1] = u1_scale;
  int c0 = mc_target_stream_offset(T, LMC_STREAM_CONNECT);
  for (int i = 1; i < T->stream_dim[LMC_STREAM_CONNECT]; i += BDPT_DIMS_CONNECT)
    ctx->step_scale[c0 + i] = u1_scale;
  T->step_scale = ctx->step_scale;
  return LMC_OK;
}

void mc_bdpt_states_free(mc_bdpt_states *ctx) {
  if (!ctx) return;
  free(ctx->strat); /* with label_of */
  free(ctx->step_scale);
  ctx->strat = NULL;
  ctx->label_of = NULL;
  ctx->step_scale = NULL;
}

/* ---------------------------------------------------------------------------
 * The space: one family over the lengths kmin .. kmax, and its flag.
 */

/* The space's own settings (its flag table). */
typedef struct bs__settings {
  double rough_min; /* --roughness-threshold */
} bs__settings;

static const bs__settings bs__defaults = {0.3};

static const lmc_opt bs__opts[] = {
    {"roughness-threshold", LMC_OPT_DOUBLE, offsetof(bs__settings, rough_min), 0, 0, 1e6, NULL,
     NULL, 0, "R", NULL,
     "directions at BSDFs rougher than R are moved as absolute world directions (1: never)",
     "roughnessthreshold"},
};

const lmc_opt_table mc_space_bdpt_options = {"The bdpt states (--states bdpt)", bs__opts, 1,
                                             &bs__defaults, sizeof bs__defaults};

typedef struct bs__space {
  mc_bdpt_states ctx;
  mc_space_family fam;
} bs__space;

static int bs__length_of(const mc_space_family *F, int label, int last) {
  (void)last;
  const mc_bdpt_states *ctx = F->target.ctx;
  return label >= 0 && label < ctx->n_labels ? mc_bdpt_states_length(ctx, label) : -1;
}

static void bs__space_destroy(mc_space *sp) {
  bs__space *B = sp->ctx;
  if (B) mc_bdpt_states_free(&B->ctx);
  free(B);
}

lmc_status mc_space_bdpt_create(mc_space *OUT, const scene *s, const render_settings *rs,
                                lmc_error *err) {
  int kmax = rs->maxdepth >= 0 ? rs->maxdepth : MC_BDPT_UNBOUNDED;
  if (kmax > MC_BDPT_UNBOUNDED) kmax = MC_BDPT_UNBOUNDED;
  int kmin = rs->mindepth > 1 ? rs->mindepth : 1;
  if (rs->maxdepth < 0 && !rs->quiet)
    fprintf(stderr, "lmc: %s renders paths of at most %d segments (set --maxdepth)\n",
            rs->integrator, kmax);
  bs__settings bs;
  lmc_status st = lmc_opt_read(&mc_space_bdpt_options, rs, &bs, err);
  if (st) return st;
  bs__space *B = calloc(1, sizeof *B);
  if (!B) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the bdpt states");
  OUT->ctx = B;
  OUT->destroy = bs__space_destroy;
  st = mc_bdpt_states_init(&B->fam.target, &B->ctx, s, rs, bs.rough_min, kmin, kmax, err);
  if (st) return st; /* (the caller frees the space) */
  B->fam.length = 0;
  B->fam.technique = -1;
  B->fam.length_of = bs__length_of;
  OUT->name = "bdpt";
  OUT->n_fam = 1;
  OUT->fam = &B->fam;
  OUT->kmin = kmin;
  OUT->kmax = kmax;
  OUT->pool_large = 1;
  OUT->moves = &mc_strategy_moves;
  return LMC_OK;
}
