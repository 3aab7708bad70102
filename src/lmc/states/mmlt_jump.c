/*
 * mmlt_jump.c: the reversible jump between strategies of the mmlt states
 * (mmlt_jump.h says what it does and why it is exact).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/states/mmlt_jump.h"
#include "lmc/states/mmlt_states.h"
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

/* Walks the state u's strategy (s, t) again into X_0 .. X_k, as
 * mc_mmlt_contribution makes it (for s = 1 the light vertex its connect
 * numbers sample). Returns 0 when the walk does not make a full path. */
static int mmj__path(const mc_target *T, const double *u, int s, int t, bdpt_vertex *X,
                     bdpt_vertex *cam, bdpt_vertex *lp) {
  const mc_mmlt_states *st = T->ctx;
  const scene *sc = st->s;
  int k = st->length;
  mmj__vec v = {{mmj__next, mmj__stream, NULL}, T, u, LMC_STREAM_CAMERA, {0}, 0};
  render_counters cnt = {0};
  double rx = -st->margin + sampler_next(&v.base) * (sc->cam.width + 2.0 * st->margin);
  double ry = -st->margin + sampler_next(&v.base) * (sc->cam.height + 2.0 * st->margin);
  if (bdpt_camera_subpath(sc, &st->rs, &v.base, rx, ry, t, cam, &cnt) < t) return 0;
  for (int i = 0; i < t; i++) X[i] = cam[i];
  if (s >= 2) {
    sampler_use_stream(&v.base, LMC_STREAM_LIGHT);
    if (bdpt_light_subpath(sc, &st->rs, &v.base, s, lp, &cnt) < s) return 0;
    for (int j = 0; j < s; j++) X[k - j] = lp[j];
  } else if (s == 1) {
    const double *uc = u + mc_target_stream_offset(T, LMC_STREAM_CONNECT) + 1;
    double pmf, ur;
    int li = scene_sample_light(sc, uc[0], &pmf, &ur);
    light_li_sample ls;
    if (li < 0 || !light_sample_li(&sc->lights[li], sc, cam[t - 1].p, uc[1], uc[2], &ls)) return 0;
    bdpt_vertex *y = &X[k];
    memset(y, 0, sizeof *y);
    y->type = BDPT_VERTEX_LIGHT;
    y->light = li;
    y->p = ls.p;
    y->n = sc->lights[li].type == LIGHT_AREA ? ls.n : v3(0.0, 0.0, 0.0);
    y->dir = v3_neg(ls.wi);
    y->hit.mesh = sc->lights[li].type == LIGHT_AREA ? sc->lights[li].mesh : -1;
    y->hit.prim = ls.tri;
  }
  /* The connection's ends scatter through smooth lobes (ps_from_bdpt's rule). */
  if (s > 0 && t >= 1) X[t - 1].delta = X[t].delta = 0;
  return !v.past;
}

/* The numbers of strategy (s, t) for the path X into y (every number X
 * does not fix already a fresh uniform there). Returns 0 when a subpath
 * cannot be inverted. */
static int mmj__numbers(mc_mmlt_jump *j, rng *r, const bdpt_vertex *X, int s, int t, double *y) {
  const mc_target *T = j->target;
  const mc_mmlt_states *st = T->ctx;
  const scene *sc = st->s;
  int k = st->length, n = st->n_strategies;
  bdpt_vertex *cam = j->v + 2 * MMJ_N, *lp = j->v + 3 * MMJ_N;
  double *uc = y + mc_target_stream_offset(T, LMC_STREAM_CAMERA);
  double *ul = y + mc_target_stream_offset(T, LMC_STREAM_LIGHT);
  double *ux = y + mc_target_stream_offset(T, LMC_STREAM_CONNECT);
  /* The technique coordinate: uniform in t's interval. */
  ux[0] = warp_uniform_in((double)(t - 1) / n, (double)t / n, rng_uniform(r));
  bdpt_resplit(sc, X, k, s, t, cam, lp);
  double buf[2 + BDPT_DIMS_LIGHT_START + BDPT_DIMS_PER_VERTEX * MMJ_N];
  if (t >= 2) {
    double rx, ry;
    j->st.inversions++;
    if (!bdpt_invert_camera_subpath(sc, &st->rs, NULL, cam, t, r, &rx, &ry, buf)) return 0;
    /* The film grown by the filter's radius, as the states sample it. */
    uc[0] = (rx + st->margin) / (sc->cam.width + 2.0 * st->margin);
    uc[1] = (ry + st->margin) / (sc->cam.height + 2.0 * st->margin);
    if (!(uc[0] >= 0.0 && uc[0] < 1.0 && uc[1] >= 0.0 && uc[1] < 1.0)) return 0;
    int m = BDPT_DIMS_PER_VERTEX * (t - 1);
    if (2 + m > T->stream_dim[LMC_STREAM_CAMERA]) return 0;
    memcpy(uc + 2, buf, (size_t)m * sizeof *buf);
  }
  if (s >= 2) {
    j->st.inversions++;
    if (!bdpt_invert_light_subpath(sc, &st->rs, NULL, lp, s, r, buf)) return 0;
    int m = BDPT_DIMS_LIGHT_START + BDPT_DIMS_PER_VERTEX * (s - 1);
    if (m > T->stream_dim[LMC_STREAM_LIGHT]) return 0;
    memcpy(ul, buf, (size_t)m * sizeof *buf);
  } else if (s == 1) {
    j->st.inversions++;
    if (!bdpt_invert_connect(sc, &cam[t - 1], &X[k], r, ux + 1)) return 0;
  }
  return 1;
}

/* What both moves do first: count the proposal, fill y with fresh
 * uniforms (the numbers the new path will not fix), and walk the state x's
 * path again into j->v (its strategy into *OUT_t). The walk is a function
 * of x's numbers: when they are those of the last walk (x stayed since
 * this kernel's last proposal from it), its path is still in j->v. Returns
 * 0 when x has no path to move (f = 0, or its walk reads past its
 * blocks). */
static int mmj__begin(mc_mmlt_jump *j, rng *r, const mc_state *x, double *OUT_y, int *OUT_t) {
  const mc_target *T = j->target;
  const mc_mmlt_states *st = T->ctx;
  int k = st->length, n = st->n_strategies;
  j->st.proposed++;
  for (int i = 0; i < x->dim; i++) OUT_y[i] = rng_uniform(r);
  if (!(x->v.f > 0.0)) return 0;
  int idx = (int)(x->u[mc_target_stream_offset(T, LMC_STREAM_CONNECT)] * n);
  if (idx >= n) idx = n - 1;
  *OUT_t = k == 1 ? 2 : idx + 1;
  size_t bytes = (size_t)x->dim * sizeof *x->u;
  if (j->walked_ok && !memcmp(j->walked_u, x->u, bytes)) {
    j->st.reused++;
    return 1;
  }
  j->walked_ok =
      mmj__path(T, x->u, k + 1 - *OUT_t, *OUT_t, j->v, j->v + 2 * MMJ_N, j->v + 3 * MMJ_N);
  if (j->walked_ok) memcpy(j->walked_u, x->u, bytes);
  return j->walked_ok;
}

/* A strategy t' != skip (0: none skipped) of weight w[t'] > 0, drawn with
 * probability w[t'] / sum (sum: the weights but skip's); the last one with
 * weight where rounding leaves the draw past them all. */
static int mmj__draw(rng *r, const double *w, int k, int skip, double sum) {
  double pick = rng_uniform(r) * sum, acc = 0.0;
  int last = -1;
  for (int tp = 1; tp <= k + 1; tp++) {
    if (tp == skip || !(w[tp] > 0.0)) continue;
    acc += w[tp];
    last = tp;
    if (pick < acc) return tp;
  }
  return last;
}

static double mmj__propose(void *self, rng *r, const mc_state *x, double *OUT_y) {
  mc_mmlt_jump *j = self;
  const mc_mmlt_states *st = j->target->ctx;
  int k = st->length, t;
  bdpt_vertex *X = j->v, *cam = j->v + 2 * MMJ_N;
  if (st->n_strategies < 2 || !mmj__begin(j, r, x, OUT_y, &t)) return -INFINITY;

  /* Every strategy's weight; t' != t drawn with w_t' / (W - w_t). */
  double w[MMJ_N + 1], sum = 0.0;
  bdpt_mis_weights(st->s, X, k, cam, w);
  for (int tp = 1; tp <= k + 1; tp++) sum += w[tp];
  double rest = sum - w[t];
  if (!(w[t] > 0.0) || !(rest > 0.0)) {
    j->st.lone++;
    return -INFINITY;
  }
  int t2 = mmj__draw(r, w, k, t, rest);
  if (!mmj__numbers(j, r, X, k + 1 - t2, t2, OUT_y)) {
    j->st.refused++;
    return -INFINITY;
  }
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
  for (int q = 0; q < MC_PATH_MOVE_COUNT; q++) n += mmj__applies(j, q, P);
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
  for (int q = 0; q < MC_PATH_MOVE_COUNT && kind < 0; q++)
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
  const mc_mmlt_states *st = j->target->ctx;
  int k = st->length, t;
  bdpt_vertex *X = j->v, *Xy = j->v + MMJ_N, *cam = j->v + 2 * MMJ_N;
  if (!mmj__begin(j, r, x, OUT_y, &t)) return -INFINITY;
  ps_path *P = j->px, *Y = j->py;
  double ratio = 0.0;
  if (!ps_from_bdpt(&j->ctx, X, k + 1, NULL, 0, P) || !(P->lum > 0.0) ||
      !mmj__path_move(j, r, P, Y, &ratio) || !(ratio > 0.0) || Y->k != k) {
    j->st.lone++;
    return -INFINITY;
  }
  /* The new path's strategy, by its MIS weights. */
  double w[MMJ_N + 1], sum = 0.0;
  for (int i = 0; i <= k; i++) Xy[i] = Y->x[i].v;
  bdpt_mis_weights(st->s, Xy, k, cam, w);
  for (int tp = 1; tp <= k + 1; tp++) sum += w[tp];
  if (!(sum > 0.0)) {
    j->st.lone++;
    return -INFINITY;
  }
  int t2 = mmj__draw(r, w, k, 0, sum);
  if (k == 1) t2 = 2; /* (length 1 has one strategy in these states) */
  if (!mmj__numbers(j, r, Xy, k + 1 - t2, t2, OUT_y)) {
    j->st.refused++;
    return -INFINITY;
  }
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
  j->v = malloc(4 * MMJ_N * sizeof *j->v);
  j->walked_u = malloc((size_t)(mmlt_target->dim > 0 ? mmlt_target->dim : 1) * sizeof *j->walked_u);
  if (perturb) {
    const mc_mmlt_states *st = mmlt_target->ctx;
    ps_context_init(&j->ctx, st->s, &st->rs);
    /* The family's paths all have its length: so have the moves'. */
    j->ctx.kmin = j->ctx.kmax = st->length;
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
  free(j->walked_u);
  free(j->px);
  free(j->py);
  j->v = NULL;
  j->walked_u = NULL;
  j->px = j->py = NULL;
}

mc_kernel mc_mmlt_jump_kernel(mc_mmlt_jump *j) {
  mc_kernel k;
  memset(&k, 0, sizeof k);
  k.name = j->perturb ? "path" : "jump";
  k.kind = MC_KERNEL_FULL;
  k.self = j;
  k.propose = j->perturb ? mmj__propose_perturb : mmj__propose;
  k.log_density = mmj__log_density;
  return k;
}
