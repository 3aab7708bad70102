/*
 * mmlt_states.c: the mmlt states (--states mmlt), the multiplexed
 * bidirectional states of Hachisuka, Kaplanyan and Dachsbacher 2014
 * ("Multiplexed Metropolis Light Transport"): one family of chains per
 * path length k (segments). A state has the camera and light streams of
 * BDPT plus the connect stream, whose first coordinate chooses the
 * strategy (s, t) with s + t = k + 1 uniformly among the n_k valid ones
 * (n_1 = 1: the emitter seen directly, (0, 2); n_k = k + 1 for k >= 2,
 * (1, 1) is never used); the next three coordinates are the light sample
 * of s = 1:
 *   camera stream   film position over the film grown by the filter radius
 *                   r (rx = -r + u0 (W + 2r)), then the camera subpath;
 *   light stream    the light subpath;
 *   connect stream  0: the strategy; 1 .. 3: the light sample of s = 1.
 * f = n_k times the strategy's MIS-weighted contribution: A = (W + 2r)(H + 2r)
 * times it for t >= 2 (a radiance estimate at a uniform raster point), the
 * light-tracing splat itself for t = 1; its expectation over the strategy
 * coordinate is the BDPT estimate of length k.
 *
 * Derivatives. Without them, f is mc_mmlt_contribution (states.c, plain
 * numbers); with them, path_eval_bdpt (render/integrators/path.h), which reads BDPT's
 * own layout (integrator.h): raster position u0 W and the s = 1 light
 * sample at connect positions 3 (t - 2) .. + 2. A sampler adapter
 * translates: it hands path_eval_bdpt the film numbers (-r + u (W + 2r)) / W
 * (outside [0, 1) near the border, which the camera accepts) and, for
 * s = 1, the state's connect numbers 1 .. 3 in the slots of its t (the
 * slots before, which it draws and ignores, get a constant). The gradient
 * and the Hessian are mapped back coordinate by coordinate, with the chain
 * rule factor (W + 2r) / W on the two film numbers.
 *
 * Media: on a scene with participating media (unless rs.no_media) the
 * subpaths and the connection run through them (states.c), each vertex's
 * numbers led by its flight's BDPT_DIMS_MEDIA; f alone there (no
 * gradients yet: eval with one fails, no eval_hess).
 *
 * Step scales: the light-position numbers u1 of the light stream
 * (emission) and of the connect stream (the light sample of s = 1) pick an
 * area light's triangle (mc_light_u1_scale). The small step's default
 * scale on these states is MC_MMLT_SIGMA.
 *
 * Normalisation (estimate_b). Every independent BDPT sample (the bdpt
 * states' eval_all, bdpt_states.h) holds one estimate of every length's
 * b_k at once: the sum of the MIS-weighted contributions of that length's
 * strategies. Drawn together, each length gets every sample at the cost of
 * one sample of the longest, instead of a share of the bootstrap's
 * (Neyman allocation starved the long lengths, whose heavy-tailed b_k then
 * read low in a typical short render). Samples come in blocks of
 * MMLT_SHARED_BLOCK, each block from its own streams and summed by one
 * thread in order, the block sums added in block order: the estimate does
 * not depend on the threads. The number of blocks depends on the clock
 * (--time) or on a pilot of MMLT_SHARED_PILOT blocks alone (--spp), never
 * on the samples it averages, so each b_k is unbiased. The families' own
 * bootstrap samples only pick the chains' starting states, and b is not
 * refined with the large steps (a large step of length k samples b_k too,
 * but with a far heavier tail than a whole BDPT sample's).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>
#include <stdio.h>

#include "lmc/states/bdpt_states.h"
#include "lmc/states/mmlt_states.h"
#include "lmc/driver/space.h"
#include "lmc/states/states.h"
#include "render/dist.h"
#include "render/integrators/path.h"

typedef mc_states_scratch mms__scratch;

/* Sets the value of a state from its contribution c; returns f. */
static double mms__set_value(mms__scratch *sc, mc_value *v, rgb c, double rx, double ry) {
  return mc_states_value(v, c, rx, ry, &sc->counts.nan_samples);
}

/* The state's strategy (s, t) from its technique coordinate (connect 0). */
static void mms__strategy(const mc_mmlt_states *st, double u_tech, int *OUT_s, int *OUT_t) {
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
static int mms__eval_d(const mc_target *t, mms__scratch *sc, lmc_sampler *smp, int want,
                            mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok, int *OUT_hn,
                            int *OUT_hidx, double *OUT_hess, int *OUT_hess_ok) {
  const mc_mmlt_states *st = t->ctx;
  int n = st->n_strategies;
  *OUT_grad_ok = 0;
  if (OUT_hess_ok) *OUT_hess_ok = 0;

  /* The strategy. */
  sampler_use_stream(smp, LMC_STREAM_CONNECT);
  int ss, tt;
  mms__strategy(st, sampler_next(smp), &ss, &tt);

  /* The path, through the adapter. */
  mc_film_adapter a;
  mc_film_adapter_init(&a, smp, LMC_STREAM_CONNECT, ss == 1 ? BDPT_DIMS_CONNECT * (tt - 2) : 0,
                       st->margin, st->s->cam.width, st->s->cam.height);
  path_scratch *ps = mc_states_scratch_path(sc);
  if (!ps) return -1;
  path_eval pe;
  if (path_eval_bdpt(st->s, &st->rs, &a.base, ss, tt, want, ps, &pe, &sc->rays_d) != LMC_OK)
    return -1;
  sc->counts.grad_evals++;
  sc->counts.hess_evals += want == PATH_WANT_HESS;

  double scale = tt == 1 ? (double)n : st->area * n;
  double f = mms__set_value(sc, OUT_value, rgb_scale(pe.value, scale), pe.rx, pe.ry);

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
    double mi = mc_film_adapter_factor(&a, pc->stream, pc->pos);
    int idx_u;
    if (pc->stream == LMC_STREAM_CONNECT) {
      if (pc->pos < a.skip) continue;
      idx_u = off_conn + 1 + (pc->pos - a.skip);
      if (idx_u >= off_conn + t->stream_dim[LMC_STREAM_CONNECT]) continue;
    } else {
      if (pc->pos >= t->stream_dim[pc->stream]) continue;
      idx_u = mc_target_stream_offset(t, pc->stream) + pc->pos;
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
  if (!mc_states_hessian(&pe, nd, coord, m, scale, OUT_hn, OUT_hidx, OUT_hess)) return 0;
  *OUT_hess_ok = 1;
  return 0;
}

static int mms__eval(const mc_target *t, void *scratch, lmc_sampler *smp, mc_value *OUT_value,
                          double *OUT_grad, int *OUT_grad_ok) {
  const mc_mmlt_states *st = t->ctx;
  mms__scratch *sc = scratch;
  if (OUT_grad_ok) *OUT_grad_ok = 0;
  if (!OUT_grad) {
    /* f alone: mmlt's plain-double evaluation (the same number as
     * path_eval_bdpt's up to rounding, and about twice as fast). */
    double rx, ry;
    rgb c = mc_mmlt_contribution(st->s, &st->rs, st->length, st->n_strategies, st->margin,
                                   st->area, smp, sc->cam, sc->lp, &sc->cnt, &rx, &ry);
    mms__set_value(sc, OUT_value, c, rx, ry);
    return 0;
  }
  if (st->media) return -1; /* no gradients through media yet */
  int ok;
  int rc = mms__eval_d(t, sc, smp, PATH_WANT_GRAD, OUT_value, OUT_grad, &ok, NULL, NULL,
                            NULL, NULL);
  if (OUT_grad_ok) *OUT_grad_ok = ok;
  return rc;
}

/* eval_hess (target.h); the label is ignored (the target has none). */
static int mms__eval_hess(const mc_target *t, void *scratch, lmc_sampler *smp, int label,
                               mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok,
                               int *OUT_hn, int *OUT_hidx, double *OUT_hess, int *OUT_hess_ok) {
  (void)label;
  return mms__eval_d(t, scratch, smp, PATH_WANT_HESS, OUT_value, OUT_grad, OUT_grad_ok,
                          OUT_hn, OUT_hidx, OUT_hess, OUT_hess_ok);
}

/* local_coords (target.h): the coordinates strategy (s, t) reads, the
 * technique coordinate excluded: the film position and the numbers of the
 * t - 1 camera-subpath surface vertices, the emitter's and those of the
 * s - 1 light-subpath surface vertices, and for s = 1 the light sample
 * (integrator.h's layout); a function of the technique coordinate alone. */
static int mms__local_coords(const mc_target *t, const double *u, int label, int *OUT_idx) {
  (void)label;
  const mc_mmlt_states *st = t->ctx;
  int off_conn = mc_target_stream_offset(t, LMC_STREAM_CONNECT);
  int ss, tt;
  mms__strategy(st, u[off_conn], &ss, &tt);
  int n = 0;
  int nc = 2 + st->per_vertex * (tt - 1);
  if (nc > t->stream_dim[LMC_STREAM_CAMERA]) nc = t->stream_dim[LMC_STREAM_CAMERA];
  for (int i = 0; i < nc; i++) OUT_idx[n++] = i;
  if (ss > 0) {
    int off_l = mc_target_stream_offset(t, LMC_STREAM_LIGHT);
    int nl = BDPT_DIMS_LIGHT_START + st->per_vertex * (ss - 1);
    if (nl > t->stream_dim[LMC_STREAM_LIGHT]) nl = t->stream_dim[LMC_STREAM_LIGHT];
    for (int i = 0; i < nl; i++) OUT_idx[n++] = off_l + i;
  }
  if (ss == 1)
    for (int i = 1; i < t->stream_dim[LMC_STREAM_CONNECT]; i++) OUT_idx[n++] = off_conn + i;
  return n;
}

static double mms__expect(const mc_target *t, void *scratch, lmc_sampler *smp) {
  const mc_mmlt_states *st = t->ctx;
  mms__scratch *sc = scratch;
  return mc_mmlt_expected(st->s, &st->rs, st->length, st->margin, st->area, smp, sc->cam, sc->lp,
                            &sc->cnt);
}

lmc_status mc_mmlt_states_init(mc_target *OUT_target, mc_mmlt_states *ctx, const scene *s,
                               const render_settings *rs, int length, lmc_error *err) {
  memset(OUT_target, 0, sizeof *OUT_target);
  memset(ctx, 0, sizeof *ctx);
  double r = s->filter.radius, W = s->cam.width, H = s->cam.height;
  ctx->s = s;
  ctx->rs = *rs;
  ctx->rs.mindepth = -1; /* the family's length is what counts */
  ctx->length = length;
  ctx->n_strategies = length == 1 ? 1 : length + 1;
  ctx->margin = r;
  ctx->area = (W + 2.0 * r) * (H + 2.0 * r);
  ctx->media = render_media_on(s, rs);
  ctx->per_vertex = BDPT_DIMS_PER_VERTEX + (ctx->media ? BDPT_DIMS_MEDIA : 0);
  mc_target *T = OUT_target;
  T->stream_dim[LMC_STREAM_CAMERA] = 2 + ctx->per_vertex * (length + 1);
  T->stream_dim[LMC_STREAM_LIGHT] = BDPT_DIMS_LIGHT_START + ctx->per_vertex * (length + 1);
  T->stream_dim[LMC_STREAM_CONNECT] = 1 + BDPT_DIMS_CONNECT;
  T->dim = T->stream_dim[0] + T->stream_dim[1] + T->stream_dim[2];
  T->ctx = ctx;
  T->eval = mms__eval;
  T->eval_expect = mms__expect;
  if (!ctx->media) T->eval_hess = mms__eval_hess;
  T->local_coords = mms__local_coords;
  mc_states_use_scratch(T);
  /* The light-position coordinates u1 of the light stream (emission) and
   * of the connect stream (the light sample of s = 1). */
  ctx->step_scale = malloc((size_t)T->dim * sizeof(double));
  if (!ctx->step_scale) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the mmlt states");
  double u1_scale = mc_light_u1_scale(s);
  for (int i = 0; i < T->dim; i++) ctx->step_scale[i] = 1.0;
  ctx->step_scale[mc_target_stream_offset(T, LMC_STREAM_LIGHT) + 1] = u1_scale;
  ctx->step_scale[mc_target_stream_offset(T, LMC_STREAM_CONNECT) + 2] = u1_scale;
  T->step_scale = ctx->step_scale;
  return LMC_OK;
}

void mc_mmlt_states_free(mc_mmlt_states *ctx) {
  if (!ctx) return;
  free(ctx->step_scale);
  ctx->step_scale = NULL;
}

/* ---------------------------------------------------------------------------
 * b_k of every length from whole BDPT samples (estimate_b, see above).
 */
#define MMLT_SHARED_BLOCK 1024
#define MMLT_SHARED_PILOT 8
#define MMLT_SHARED_SEQ 0x3c6ef372fe94f82bull

typedef struct mms__shared {
  int n_len;          /* lengths kmin .. kmin + n_len - 1; column n_len: all lengths */
  int64_t blocks, cap;
  double *sum, *sum2; /* [block][length] */
} mms__shared;

/* Draws blocks [from, to) of the shared samples: over several ranks each
 * draws its share and the sums are gathered exactly (dist.h), so every
 * rank holds every block. */
static void mms__shared_draw(const mc_target *T, const mc_bdpt_states *ctx, int kmin,
                             uint64_t seed, int nthreads, mms__shared *sb, int64_t from,
                             int64_t to, render_counters *cnt) {
  const int w = sb->n_len + 1;
  int64_t lo, hi;
  dist_block(from, to, &lo, &hi);
  for (int64_t k = from * w; k < to * w; k++) sb->sum[k] = sb->sum2[k] = 0.0;
#pragma omp parallel num_threads(nthreads)
  {
    void *sc = T->scratch_create(T);
    mc_contrib *cb = malloc((size_t)T->n_labels * sizeof *cb);
    double *f = malloc((size_t)sb->n_len * sizeof *f);
    int tid = omp_get_thread_num();
#pragma omp for schedule(dynamic, 1)
    for (int64_t blk = lo; blk < hi; blk++) {
      double *s1 = sb->sum + blk * w, *s2 = sb->sum2 + blk * w;
      if (!sc || !cb || !f) continue;
      for (int j = 0; j < MMLT_SHARED_BLOCK; j++) {
        lmc_indep_sampler smp;
        indep_sampler_init(&smp, seed, rng_hash64(MMLT_SHARED_SEQ ^ (uint64_t)(blk * MMLT_SHARED_BLOCK + j)));
        int n = T->eval_all(T, sc, &smp.base, -1, cb);
        for (int k = 0; k < sb->n_len; k++) f[k] = 0.0;
        for (int q = 0; q < n; q++) {
          int k = mc_bdpt_states_length(ctx, cb[q].label) - kmin;
          double v = cb[q].v.f;
          if (k >= 0 && k < sb->n_len && v > 0.0 && isfinite(v)) f[k] += v;
        }
        double tot = 0.0;
        for (int k = 0; k < sb->n_len; k++) s1[k] += f[k], s2[k] += f[k] * f[k], tot += f[k];
        s1[sb->n_len] += tot, s2[sb->n_len] += tot * tot;
      }
    }
    if (sc) {
      int64_t rays = T->scratch_rays(sc);
#pragma omp atomic
      cnt[tid].rays += rays;
    }
    T->scratch_destroy(sc);
    free(cb), free(f);
  }
  dist_allsum(sb->sum + from * w, (size_t)((to - from) * w));
  dist_allsum(sb->sum2 + from * w, (size_t)((to - from) * w));
}

typedef struct mms__space {
  const scene *s;
  render_settings rs;
  int n_fam;
  mc_mmlt_states *ctx;     /* per family */
  mc_space_family *fam;
} mms__space;

/* estimate_b (space.h): b_k of the lengths kmin .. kmin + n_fam - 1 from
 * whole BDPT samples; under --spp a pilot plans the count for a standard
 * error of rq->rel_err of sum_k b_k, and its blocks stay out of the
 * estimate (they decided its size). */
static int64_t mms__estimate_b(const mc_space *sp, mc_boot *boot, const mc_space_b_request *rq,
                               render_counters *cnt) {
  const mms__space *M = sp->ctx;
  int n_fam = sp->n_fam, kmin = sp->kmin;
  if (n_fam == 0) return 0;
  mc_target T;
  mc_bdpt_states ctx;
  lmc_error err;
  if (mc_bdpt_states_init(&T, &ctx, M->s, &M->rs, 2.0, kmin, kmin + n_fam - 1, &err) != LMC_OK)
    return -1;
  mms__shared sb = {n_fam, 0, 0, NULL, NULL};
  double t0 = omp_get_wtime();
  int64_t cap = (rq->cap + MMLT_SHARED_BLOCK - 1) / MMLT_SHARED_BLOCK;
  int64_t fixed = rq->fixed;
  int64_t want = fixed > 0 ? (fixed + MMLT_SHARED_BLOCK - 1) / MMLT_SHARED_BLOCK : cap;
  int status = 0;
  /* Four blocks per thread of every rank (the same on every rank). */
  const int64_t batch = 4 * (int64_t)dist_size() * (int64_t)dist_max((double)rq->nthreads);
  for (;;) {
    /* The next batch: the pilot, then batches of blocks for every thread. */
    int64_t to = sb.blocks == 0 ? (fixed > 0 ? want : MMLT_SHARED_PILOT)
                                : sb.blocks + batch;
    if (to > want) to = want;
    if (to <= sb.blocks) break;
    if (to > sb.cap) {
      int64_t c = sb.cap ? 2 * sb.cap : 64;
      while (c < to) c *= 2;
      double *a = realloc(sb.sum, (size_t)(c * (n_fam + 1)) * sizeof(double));
      if (!a) { status = -1; break; }
      sb.sum = a;
      double *b = realloc(sb.sum2, (size_t)(c * (n_fam + 1)) * sizeof(double));
      if (!b) { status = -1; break; }
      sb.sum2 = b;
      sb.cap = c;
    }
    mms__shared_draw(&T, &ctx, kmin, rq->seed, rq->nthreads, &sb, sb.blocks, to, cnt);
    int first = sb.blocks == 0;
    sb.blocks = to;
    if (fixed > 0) break;
    /* (Over several ranks the first to see the time or a stop decides.) */
    if (dist_any(render_stop_signal() ||
                 (isfinite(rq->seconds) && omp_get_wtime() - t0 >= rq->seconds)))
      break;
    if (!isfinite(rq->seconds) && first) {
      /* Plan the count from the pilot alone: the standard error of
       * sum_k b_k is sigma / sqrt(N). */
      double s1 = 0.0, s2 = 0.0, n = (double)sb.blocks * MMLT_SHARED_BLOCK;
      for (int64_t blk = 0; blk < sb.blocks; blk++)
        s1 += sb.sum[blk * (n_fam + 1) + n_fam], s2 += sb.sum2[blk * (n_fam + 1) + n_fam];
      double mean = s1 / n, var = fmax(0.0, s2 / n - mean * mean);
      double need = mean > 0.0 ? var / (rq->rel_err * rq->rel_err * mean * mean) : 0.0;
      want = MMLT_SHARED_PILOT + (int64_t)ceil(need / MMLT_SHARED_BLOCK);
      if (want > cap) want = cap;
      if (want < 2 * MMLT_SHARED_PILOT) want = 2 * MMLT_SHARED_PILOT;
    }
  }
  /* The estimate: every block but the planning pilot's under --spp. */
  int64_t b0 = (fixed > 0 || isfinite(rq->seconds)) ? 0 : MMLT_SHARED_PILOT;
  if (b0 >= sb.blocks) b0 = 0;
  double n = (double)(sb.blocks - b0) * MMLT_SHARED_BLOCK;
  for (int g = 0; g < n_fam && status == 0; g++) {
    double s1 = 0.0, s2 = 0.0;
    for (int64_t blk = b0; blk < sb.blocks; blk++)
      s1 += sb.sum[blk * (n_fam + 1) + g], s2 += sb.sum2[blk * (n_fam + 1) + g];
    mc_boot *B = &boot[g];
    B->s = s1, B->s2 = s2, B->n_est = (int64_t)n;
    B->b = n > 0.0 ? s1 / n : 0.0;
    double var = n > 1.0 ? fmax(0.0, (s2 - n * B->b * B->b) / (n - 1.0)) : 0.0;
    B->b_var = n > 0.0 ? var / n : 0.0;
  }
  free(sb.sum), free(sb.sum2);
  mc_bdpt_states_free(&ctx);
  return status ? -1 : (int64_t)n;
}

/* ---------------------------------------------------------------------------
 * The space: one family per length.
 */

static int mms__length_of(const mc_space_family *F, int label, int last) {
  (void)label, (void)last;
  return F->length;
}

static void mms__destroy(mc_space *sp) {
  mms__space *M = sp->ctx;
  if (!M) return;
  for (int g = 0; g < M->n_fam; g++) mc_mmlt_states_free(&M->ctx[g]);
  free(M->ctx);
  free(M->fam);
  free(M);
}

lmc_status mc_space_mmlt_create(mc_space *OUT, const scene *s, const render_settings *rs,
                                lmc_error *err) {
  int kmax = rs->maxdepth >= 0 ? rs->maxdepth : MC_MMLT_UNBOUNDED;
  if (kmax > BDPT_MAX_VERTICES - 2) kmax = BDPT_MAX_VERTICES - 2;
  int kmin = rs->mindepth > 1 ? rs->mindepth : 1;
  if (kmax - kmin + 1 > MC_MMLT_MAX_FAMILIES) kmax = kmin + MC_MMLT_MAX_FAMILIES - 1;
  if (rs->maxdepth < 0 && !rs->quiet)
    fprintf(stderr, "lmc: %s renders paths of at most %d segments (set --maxdepth)\n",
            rs->integrator, kmax);
  int n_fam = kmax >= kmin ? kmax - kmin + 1 : 0;
  mms__space *M = calloc(1, sizeof *M);
  if (M) {
    M->ctx = calloc((size_t)(n_fam > 0 ? n_fam : 1), sizeof *M->ctx);
    M->fam = calloc((size_t)(n_fam > 0 ? n_fam : 1), sizeof *M->fam);
  }
  OUT->ctx = M;
  OUT->destroy = mms__destroy;
  if (!M || !M->ctx || !M->fam) {
    mms__destroy(OUT);
    OUT->ctx = NULL;
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the mmlt states");
  }
  M->s = s;
  M->rs = *rs;
  for (int g = 0; g < n_fam; g++) {
    mc_space_family *F = &M->fam[g];
    M->n_fam = g + 1;
    lmc_status st = mc_mmlt_states_init(&F->target, &M->ctx[g], s, rs, kmin + g, err);
    if (st) return st; /* (the caller frees the space) */
    F->length = kmin + g;
    F->technique = M->ctx[g].n_strategies > 1 ? mc_target_stream_offset(&F->target, LMC_STREAM_CONNECT) : -1;
    F->length_of = mms__length_of;
  }
  OUT->name = "mmlt";
  OUT->n_fam = n_fam;
  OUT->fam = M->fam;
  OUT->kmin = kmin;
  OUT->kmax = kmax;
  OUT->sigma = MC_MMLT_SIGMA;
  OUT->pool_large = 0;
  OUT->b_note = "whole BDPT samples, every length";
  OUT->estimate_b = mms__estimate_b;
  OUT->moves = &mc_strategy_moves;
  return LMC_OK;
}
