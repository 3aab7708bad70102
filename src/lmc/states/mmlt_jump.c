/*
 * mmlt_jump.c: the reversible jump between strategies of the mmlt states
 * (mmlt_jump.h says what it does and why it is exact).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/states/bdpt_states.h"
#include "lmc/states/mmlt_jump.h"
#include "lmc/states/mmlt_states.h"
#include "lmc/states/states.h"
#include "render/warp.h"

enum { MMJ_N = BDPT_MAX_VERTICES + 1 };

/* A sampler over a state's coordinates, stream by stream (a number past a
 * stream's block marks the replay as incomplete). */
typedef struct mmj__vec {
  lmc_sampler base;
  const mc_target *t;
  const double *u;
  int stream, pos[LMC_STREAM_COUNT];
  int past;
} mmj__vec;

static double mmj__next(lmc_sampler *self) {
  mmj__vec *v = (mmj__vec *)self;
  int k = v->stream, p = v->pos[k]++;
  if (p >= v->t->stream_dim[k]) {
    v->past = 1;
    return 0.5;
  }
  return v->u[mc_target_stream_offset(v->t, k) + p];
}

static void mmj__stream(lmc_sampler *self, int stream) { ((mmj__vec *)self)->stream = stream; }

/* What the moves need of the two state spaces: the scene, the walks'
 * settings, the film's margin, and how a strategy reads its numbers. */
typedef struct mmj__space {
  const scene *sc;
  const render_settings *rs;
  double margin;
  double rough_min; /* bdpt states: absolute directions above it (the mmlt states walk with
                       no bdpt_param: BSDF sampling everywhere) */
} mmj__space;

static mmj__space mmj__space_of(const mc_mmlt_jump *j) {
  if (j->bs) return (mmj__space){j->bs->s, &j->bs->rs, j->bs->margin, j->bs->rough_min};
  const mc_mmlt_states *st = j->target->ctx;
  return (mmj__space){st->s, &st->rs, st->margin, 1.0};
}

/* The first of the three connect numbers strategy (s = 1, t) reads. */
static int mmj__connect_at(const mc_mmlt_jump *j, int t) {
  int c0 = mc_target_stream_offset(j->target, LMC_STREAM_CONNECT);
  return j->bs ? c0 + BDPT_DIMS_CONNECT * (t - 2) : c0 + 1;
}

/* Walks the state u's strategy (s, t) again into X_0 .. X_k, k = s + t -
 * 1, as the states' f makes it (for s = 1 the light vertex its connect
 * numbers sample; on the bdpt states the strategy's rough vertices read
 * absolute directions), its subpaths into cam and lp, the camera's raster
 * point into *OUT_rx, *OUT_ry. Returns 0 when the walk does not make a
 * full path. */
static int mmj__path(const mc_mmlt_jump *j, const double *u, int s, int t, bdpt_vertex *X,
                     bdpt_vertex *cam, bdpt_vertex *lp, double *OUT_rx, double *OUT_ry) {
  const mc_target *T = j->target;
  mmj__space S = mmj__space_of(j);
  const scene *sc = S.sc;
  int k = s + t - 1;
  mmj__vec v = {{mmj__next, mmj__stream, NULL}, T, u, LMC_STREAM_CAMERA, {0}, 0};
  render_counters cnt = {0};
  double rx = 0.0, ry = 0.0; /* (the bdpt states' t = 1 reads no film numbers) */
  if (!j->bs || t >= 2) {
    rx = -S.margin + sampler_next(&v.base) * (sc->cam.width + 2.0 * S.margin);
    ry = -S.margin + sampler_next(&v.base) * (sc->cam.height + 2.0 * S.margin);
  }
  *OUT_rx = rx, *OUT_ry = ry;
  bdpt_param pc = {t - 1, S.rough_min}, pl = {s - 1, S.rough_min};
  const bdpt_param *ppc = j->bs ? &pc : NULL, *ppl = j->bs ? &pl : NULL;
  if (bdpt_camera_subpath_p(sc, S.rs, &v.base, rx, ry, t, ppc, cam, &cnt) < t) return 0;
  for (int i = 0; i < t; i++) X[i] = cam[i];
  if (s >= 2) {
    sampler_use_stream(&v.base, LMC_STREAM_LIGHT);
    if (bdpt_light_subpath_p(sc, S.rs, &v.base, s, ppl, lp, &cnt) < s) return 0;
    for (int i = 0; i < s; i++) X[k - i] = lp[i];
  } else if (s == 1) {
    if (!bdpt_connect_vertex(sc, cam[t - 1].p, u + mmj__connect_at(j, t), &X[k])) return 0;
  }
  /* The connection's ends scatter through smooth lobes (ps_from_bdpt's rule). */
  if (s > 0 && t >= 1) X[t - 1].delta = X[t].delta = 0;
  return !v.past;
}

/* The numbers of strategy (s, t) for the path X of length k = s + t - 1
 * into y (every number X does not fix already a fresh uniform there; on
 * the mmlt states the technique coordinate uniform in t's interval, on
 * the bdpt states the strategy's rough vertices absolute). Returns 0 when
 * a subpath cannot be inverted. */
static int mmj__numbers(mc_mmlt_jump *j, rng *r, const bdpt_vertex *X, int s, int t, double *y) {
  const mc_target *T = j->target;
  mmj__space S = mmj__space_of(j);
  const scene *sc = S.sc;
  int k = s + t - 1;
  bdpt_vertex *cam = j->v + 2 * MMJ_N, *lp = j->v + 3 * MMJ_N;
  double *uc = y + mc_target_stream_offset(T, LMC_STREAM_CAMERA);
  double *ul = y + mc_target_stream_offset(T, LMC_STREAM_LIGHT);
  if (!j->bs) {
    int n = ((const mc_mmlt_states *)T->ctx)->n_strategies;
    y[mc_target_stream_offset(T, LMC_STREAM_CONNECT)] =
        warp_uniform_in((double)(t - 1) / n, (double)t / n, rng_uniform(r));
  }
  bdpt_resplit(sc, X, k, s, t, cam, lp);
  bdpt_param pc = {t - 1, S.rough_min}, pl = {s - 1, S.rough_min};
  const bdpt_param *ppc = j->bs ? &pc : NULL, *ppl = j->bs ? &pl : NULL;
  double buf[2 + BDPT_DIMS_LIGHT_START + BDPT_DIMS_PER_VERTEX * MMJ_N];
  if (t >= 2) {
    double rx, ry;
    j->st.inversions++;
    if (!bdpt_invert_camera_subpath(sc, S.rs, ppc, cam, t, r, &rx, &ry, buf)) return 0;
    /* The film grown by the filter's radius, as the states sample it. */
    uc[0] = (rx + S.margin) / (sc->cam.width + 2.0 * S.margin);
    uc[1] = (ry + S.margin) / (sc->cam.height + 2.0 * S.margin);
    if (!(uc[0] >= 0.0 && uc[0] < 1.0 && uc[1] >= 0.0 && uc[1] < 1.0)) return 0;
    int m = BDPT_DIMS_PER_VERTEX * (t - 1);
    if (2 + m > T->stream_dim[LMC_STREAM_CAMERA]) return 0;
    memcpy(uc + 2, buf, (size_t)m * sizeof *buf);
  }
  if (s >= 2) {
    j->st.inversions++;
    if (!bdpt_invert_light_subpath(sc, S.rs, ppl, lp, s, r, buf)) return 0;
    int m = BDPT_DIMS_LIGHT_START + BDPT_DIMS_PER_VERTEX * (s - 1);
    if (m > T->stream_dim[LMC_STREAM_LIGHT]) return 0;
    memcpy(ul, buf, (size_t)m * sizeof *buf);
  } else if (s == 1) {
    j->st.inversions++;
    if (!bdpt_invert_connect(sc, &cam[t - 1], &X[k], r, y + mmj__connect_at(j, t))) return 0;
  }
  return 1;
}

/* The label of strategy (s, t) on the bdpt states (-1: not one). */
static int mmj__label(const mc_bdpt_states *bs, int s, int t) {
  return s >= 0 && t >= 1 && s + t - 1 <= bs->kmax ? bs->label_of[s * (bs->kmax + 2) + t] : -1;
}

/* What both moves do first: count the proposal, fill y with fresh
 * uniforms (the numbers the new path will not fix), and walk the state x's
 * path again into j->walked_x (its strategy into *OUT_s, *OUT_t: on the
 * mmlt states from the technique coordinate, on the bdpt states the
 * label). The walk is a function of x's numbers and label: when they are
 * those of the last walk (x stayed since this kernel's last proposal from
 * it) or of this kernel's last proposal (walked by propose, and
 * accepted), that path is used. Returns 0 when x has no path
 * to move (f = 0, or its walk reads past its blocks), 2 when its path was
 * kept, 1 when walked. */
static int mmj__begin(mc_mmlt_jump *j, rng *r, const mc_state *x, double *OUT_y, int *OUT_s,
                      int *OUT_t) {
  const mc_target *T = j->target;
  j->st.proposed++;
  j->y_ok = 0;
  for (int i = 0; i < x->dim; i++) OUT_y[i] = rng_uniform(r);
  if (!(x->v.f > 0.0)) return 0;
  if (j->bs) {
    if (x->label < 0 || x->label >= j->bs->n_labels) return 0;
    *OUT_s = j->bs->strat[x->label].s, *OUT_t = j->bs->strat[x->label].t;
  } else {
    const mc_mmlt_states *st = T->ctx;
    int k = st->length, n = st->n_strategies;
    int idx = (int)(x->u[mc_target_stream_offset(T, LMC_STREAM_CONNECT)] * n);
    if (idx >= n) idx = n - 1;
    *OUT_t = k == 1 ? 2 : idx + 1;
    *OUT_s = k + 1 - *OUT_t;
  }
  size_t bytes = (size_t)x->dim * sizeof *x->u;
  if (j->walked_ok && j->walked_label == x->label && !memcmp(j->walked_u, x->u, bytes)) {
    j->st.reused++;
    return 2;
  }
  if (j->pend_ok && j->pend_label == x->label && !memcmp(j->pend_u, x->u, bytes)) {
    /* The last proposal, accepted: its walk becomes the state's. */
    bdpt_vertex *tx = j->walked_x;
    double *tu = j->walked_u;
    j->walked_x = j->pend_x, j->walked_u = j->pend_u, j->walked_label = j->pend_label;
    j->pend_x = tx, j->pend_u = tu;
    j->walked_ok = 1, j->pend_ok = 0, j->px_ok = 0;
    j->st.reused++;
    return 2;
  }
  j->px_ok = 0;
  double rx, ry;
  j->walked_ok = mmj__path(j, x->u, *OUT_s, *OUT_t, j->walked_x, j->v + 2 * MMJ_N,
                           j->v + 3 * MMJ_N, &rx, &ry);
  if (j->walked_ok) memcpy(j->walked_u, x->u, bytes), j->walked_label = x->label;
  return j->walked_ok;
}

/* Walks the proposal y (strategy (s, t), label) into j->pend_x and
 * evaluates it there as the target does (mc_bdpt_states_value, or the
 * mmlt states' mc_mmlt_connect), for the chain (mc_kernel.value) and for
 * this kernel's next proposal should y be accepted. */
static void mmj__eval_proposal(mc_mmlt_jump *j, const double *y, int s, int t, int label) {
  const mc_target *T = j->target;
  mmj__space S = mmj__space_of(j);
  bdpt_vertex *cam = j->v + 2 * MMJ_N, *lp = j->v + 3 * MMJ_N;
  double rx, ry;
  j->y_ok = j->pend_ok = 0;
  if ((j->bs && label < 0) || !mmj__path(j, y, s, t, j->pend_x, cam, lp, &rx, &ry)) return;
  memcpy(j->pend_u, y, (size_t)T->dim * sizeof *y);
  j->pend_label = label, j->pend_ok = 1;
  const double zero[BDPT_DIMS_CONNECT] = {0.0, 0.0, 0.0};
  const double *uc = s == 1 ? y + mmj__connect_at(j, t) : zero;
  render_counters cnt = {0};
  if (j->bs) {
    mc_bdpt_states_value(j->bs, cam, t, lp, s, uc, rx, ry, &j->yv, &cnt);
  } else {
    const mc_mmlt_states *st = T->ctx;
    rgb c = mc_mmlt_connect(S.sc, cam, t, lp, s, uc, st->n_strategies, st->area, &cnt, &rx, &ry);
    int64_t nan = 0;
    mc_states_value(&j->yv, c, rx, ry, &nan);
  }
  j->y_ok = 1;
}

/* The MIS weights w[t] (t = 1 .. k + 1) of the strategies of the path X of
 * length k that the states have (length 1 has (0, 2) alone, unless its
 * light cannot be hit); on the bdpt states a strategy without a label has
 * weight 0. */
static void mmj__weights(const mc_mmlt_jump *j, const bdpt_vertex *X, int k, double *w) {
  mmj__space S = mmj__space_of(j);
  bdpt_mis_weights(S.sc, X, k, j->v + 2 * MMJ_N, w);
  if (j->bs)
    for (int t = 1; t <= k + 1; t++)
      if (mmj__label(j->bs, k + 1 - t, t) < 0) w[t] = 0.0;
}

static double mmj__propose(void *self, rng *r, const mc_state *x, double *OUT_y) {
  mc_mmlt_jump *j = self;
  int s0, t;
  j->label_to = x->label;
  if (!mmj__begin(j, r, x, OUT_y, &s0, &t)) return -INFINITY;
  const bdpt_vertex *X = j->walked_x;
  int k = s0 + t - 1;

  /* Every strategy's weight; t' != t drawn with w_t' / (W - w_t). */
  double w[MMJ_N + 1], sum = 0.0;
  mmj__weights(j, X, k, w);
  for (int tp = 1; tp <= k + 1; tp++) sum += w[tp];
  double rest = sum - w[t];
  if (!(w[t] > 0.0) || !(rest > 0.0)) {
    j->st.lone++;
    return -INFINITY;
  }
  int t2 = bdpt_draw_strategy(w, k, t, rest, rng_uniform(r));
  if (!mmj__numbers(j, r, X, k + 1 - t2, t2, OUT_y)) {
    j->st.refused++;
    return -INFINITY;
  }
  if (j->bs) j->label_to = mmj__label(j->bs, k + 1 - t2, t2);
  mmj__eval_proposal(j, OUT_y, k + 1 - t2, t2, j->label_to);
  j->log_rest_to = log(sum - w[t2]);
  j->rx = x->v.rx, j->ry = x->v.ry;
  return -log(x->v.f) - log(rest);
}

static double mmj__log_density(void *self, const mc_state *from, const double *to_u) {
  (void)to_u;
  mc_mmlt_jump *j = self;
  /* The same path seen from the same raster point, or a walk that went elsewhere. */
  const mc_mmlt_states *st = j->target->ctx;
  double tol = 1e-6 * (st->s->cam.width + st->s->cam.height);
  if (!(fabs(from->v.rx - j->rx) <= tol && fabs(from->v.ry - j->ry) <= tol)) {
    j->st.mismatch++;
    return -INFINITY;
  }
  return -log(from->v.f) - j->log_rest_to;
}

/* Whether path move kind applies to P (the bidirectional mutation always
 * does; test_kind: that kind alone). */
static int mmj__applies(const mc_mmlt_jump *j, int kind, const ps_path *P) {
  if (j->test_kind >= 0 && kind != j->test_kind) return 0;
  switch ((mc_path_move)kind) {
  case MC_PATH_MOVE_BIDIR: return 1;
  case MC_PATH_MOVE_LENSSUB: return mut_lenssub_m(&j->ctx, P) > 0;
  case MC_PATH_MOVE_LENS: return mut_perturb_applies(&j->mp, MUT_PERTURB_LENS, P);
  case MC_PATH_MOVE_MULTICHAIN: return mut_perturb_applies(&j->mp, MUT_PERTURB_MULTICHAIN, P);
  case MC_PATH_MOVE_CAUSTIC: return mut_perturb_applies(&j->mp, MUT_PERTURB_CAUSTIC, P);
  default: return 0;
  }
}

/* The number of path moves that apply to P. */
static int mmj__n_applies(const mc_mmlt_jump *j, const ps_path *P) {
  int n = 0;
  for (int q = 0; q < MC_PATH_MOVE_FUSED; q++) n += mmj__applies(j, q, P);
  return n;
}

/* One of path-space MLT's moves of P into Y, drawn uniformly among those
 * that apply to P, as the mlt integrator draws them, with its ratio f(y)
 * T(y -> x) / (f(x) T(x -> y)) times the selection's, n(x) / n(y) for the
 * numbers n of moves that apply (0 when the move does not apply to y),
 * into *OUT_ratio. The path space has the state's length alone, so a
 * bidirectional mutation adds as many edges as it deletes and a lens
 * subpath mutation keeps its subpath's length. Returns 0 when there is no
 * proposal. */
static int mmj__path_move(mc_mmlt_jump *j, rng *r, const ps_path *P, ps_path *Y,
                          double *OUT_ratio) {
  int n_x = mmj__n_applies(j, P), pick = (int)(rng_uniform(r) * n_x), kind = -1, ok;
  int64_t rays = 0;
  *OUT_ratio = 0.0;
  if (n_x == 0) return 0;
  if (pick >= n_x) pick = n_x - 1;
  for (int q = 0; q < MC_PATH_MOVE_FUSED && kind < 0; q++)
    if (mmj__applies(j, q, P) && pick-- == 0) kind = q;
  j->st.kinds[kind]++;
  if (kind == MC_PATH_MOVE_BIDIR) {
    mut_bidir_record rec;
    ok = mut_bidir_propose(&j->mb, r, P, Y, &rec, OUT_ratio) == MUT_BIDIR_OK;
  } else if (kind == MC_PATH_MOVE_LENSSUB) {
    ok = mut_lenssub_propose(&j->ml, r, P, Y, OUT_ratio, &rays);
  } else {
    mut_perturb_kind pk = kind == MC_PATH_MOVE_LENS         ? MUT_PERTURB_LENS
                          : kind == MC_PATH_MOVE_MULTICHAIN ? MUT_PERTURB_MULTICHAIN
                                                            : MUT_PERTURB_CAUSTIC;
    ok = mut_perturb_propose(&j->mp, pk, r, P, Y, OUT_ratio, &rays, NULL);
  }
  if (!ok || !(*OUT_ratio > 0.0)) return 0;
  int n_y = mmj__applies(j, kind, Y) ? mmj__n_applies(j, Y) : 0;
  *OUT_ratio = n_y > 0 ? *OUT_ratio * n_x / n_y : 0.0;
  return *OUT_ratio > 0.0;
}

/* The fused move: the state's path moved in path space by one of
 * path-space MLT's moves (mmj__path_move), then a strategy for the new
 * path drawn by its MIS weights and its numbers found by the inverses. The
 * ratio is the path move's own f(y) T(y -> x) / (f(x) T(x -> y))
 * (mmlt_jump.h). */
static double mmj__propose_perturb(void *self, rng *r, const mc_state *x, double *OUT_y) {
  mc_mmlt_jump *j = self;
  int s0, t;
  bdpt_vertex *Xy = j->v + MMJ_N;
  j->label_to = x->label;
  int begun = mmj__begin(j, r, x, OUT_y, &s0, &t);
  if (!begun) return -INFINITY;
  int k = s0 + t - 1;
  ps_path *P = j->px, *Y = j->py;
  double ratio = 0.0;
  /* The state's path in path space, kept with its walk. (On the mmlt
   * states the path space has the family's length alone.) */
  if (begun != 2 || !j->px_ok) j->px_ok = ps_from_bdpt(&j->ctx, j->walked_x, k + 1, NULL, 0, P);
  if (!j->px_ok || !(P->lum > 0.0) ||
      !mmj__path_move(j, r, P, Y, &ratio) || !(ratio > 0.0) || Y->k < j->ctx.kmin ||
      Y->k > j->ctx.kmax) {
    j->st.lone++;
    return -INFINITY;
  }
  /* The new path's strategy, by its MIS weights. */
  int ky = Y->k;
  double w[MMJ_N + 1], sum = 0.0;
  for (int i = 0; i <= ky; i++) Xy[i] = Y->x[i].v;
  mmj__weights(j, Xy, ky, w);
  for (int tp = 1; tp <= ky + 1; tp++) sum += w[tp];
  if (!(sum > 0.0)) {
    j->st.lone++;
    return -INFINITY;
  }
  int t2 = bdpt_draw_strategy(w, ky, 0, sum, rng_uniform(r));
  if (!mmj__numbers(j, r, Xy, ky + 1 - t2, t2, OUT_y)) {
    j->st.refused++;
    return -INFINITY;
  }
  if (j->bs) j->label_to = mmj__label(j->bs, ky + 1 - t2, t2);
  mmj__eval_proposal(j, OUT_y, ky + 1 - t2, t2, j->label_to);
  j->log_rest_to = 0.0;
  j->rx = Y->rx, j->ry = Y->ry;
  return -log(x->v.f) - log(ratio);
}

lmc_status mc_mmlt_jump_init(mc_mmlt_jump *j, const mc_target *mmlt_target, int perturb,
                             lmc_error *err) {
  memset(j, 0, sizeof *j);
  j->target = mmlt_target;
  j->perturb = perturb;
  j->test_kind = -1;
  size_t nu = (size_t)(mmlt_target->dim > 0 ? mmlt_target->dim : 1);
  j->v = malloc(5 * MMJ_N * sizeof *j->v);
  j->walked_u = malloc(2 * nu * sizeof *j->walked_u);
  j->walked_x = j->v, j->pend_x = j->v ? j->v + 4 * MMJ_N : NULL;
  j->u_block = j->walked_u, j->pend_u = j->walked_u ? j->walked_u + nu : NULL;
  /* The bdpt states are the labelled target these moves know. */
  if (mmlt_target->n_labels > 0) j->bs = mmlt_target->ctx;
  if (perturb) {
    mmj__space S = mmj__space_of(j);
    ps_context_init(&j->ctx, S.sc, S.rs);
    if (j->bs) {
      j->ctx.kmin = j->bs->kmin, j->ctx.kmax = j->bs->kmax;
    } else {
      /* The family's paths all have its length: so have the moves'. */
      j->ctx.kmin = j->ctx.kmax = ((const mc_mmlt_states *)mmlt_target->ctx)->length;
    }
    mut_perturb_init(&j->mp, &j->ctx);
    mut_bidir_init(&j->mb, &j->ctx);
    mut_lenssub_init(&j->ml, &j->ctx);
    j->px = malloc(sizeof *j->px);
    j->py = malloc(sizeof *j->py);
  }
  if (!j->v || !j->walked_u || (perturb && (!j->px || !j->py))) {
    mc_mmlt_jump_free(j);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the mmlt moves");
  }
  return LMC_OK;
}

void mc_mmlt_jump_free(mc_mmlt_jump *j) {
  if (!j) return;
  free(j->v);
  free(j->u_block);
  free(j->px);
  free(j->py);
  j->v = NULL;
  j->walked_u = j->pend_u = j->u_block = NULL;
  j->walked_x = j->pend_x = NULL;
  j->px = j->py = NULL;
}

static int mmj__label_to(void *self) { return ((const mc_mmlt_jump *)self)->label_to; }

static int mmj__value(void *self, mc_value *OUT) {
  const mc_mmlt_jump *j = self;
  if (j->y_ok) *OUT = j->yv;
  return j->y_ok;
}

mc_kernel mc_mmlt_jump_kernel(mc_mmlt_jump *j) {
  mc_kernel k;
  memset(&k, 0, sizeof k);
  k.name = j->perturb ? "path" : "jump";
  k.kind = MC_KERNEL_FULL;
  k.self = j;
  k.propose = j->perturb ? mmj__propose_perturb : mmj__propose;
  k.log_density = mmj__log_density;
  if (j->bs) k.label = mmj__label_to;
  k.value = mmj__value;
  return k;
}
