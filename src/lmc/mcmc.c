/*
 * mcmc.c: the primary-sample-space MCMC integrators and their driver.
 *
 * pssmlt (Kelemen, Szirmay-Kalos, Antal and Csonka 2002): the state is the
 * camera stream of pt_li; its first two coordinates pick the raster point
 * uniformly over the film grown by the filter radius r (so border pixels
 * get what filter importance sampling gives them in pt), the rest drive
 * the path tracer with next-event estimation. The contribution of a state
 * is A L(u), A = (W + 2r)(H + 2r), an estimate of the whole image; the
 * target is f = luminance of it.
 *
 * mmlt (Hachisuka, Kaplanyan and Dachsbacher 2014, "Multiplexed Metropolis
 * Light Transport"): one family of chains per path length k (segments).
 * A state has the camera and light streams of BDPT plus the connect stream,
 * whose first coordinate chooses the strategy (s, t) with s + t = k + 1
 * uniformly among the n_k valid ones (n_1 = 1: the emitter seen directly,
 * (0, 2); n_k = k + 1 for k >= 2, (1, 1) is never used); the next three
 * coordinates are the light sample of s = 1. The contribution is n_k times
 * the strategy's MIS-weighted estimate (A L for t >= 2; the light-tracing
 * splat as it is for t = 1), so its expectation over the strategy coordinate
 * is the BDPT estimate of length k. Kernels: large step, Kelemen's small
 * step and the technique mutation (chain.h). The small step of the two
 * light-position coordinates (emission and the s = 1 light sample) is
 * scaled down by the area lights' triangle count (mc_light_u1_scale):
 * without it, light-tracing states on a tessellated light almost never
 * accepted a small step. pssmlt (and lmc, integrator_lmc.h) scale the
 * same way the light-position number of next-event estimation at every
 * bounce (mc_pt_step_scale).
 *
 * The driver and the integrators (method.h). This file is the driver: the
 * state spaces (--states: pssmlt's pt states, mmlt's per-length states,
 * the bdpt states of bdpt_states.h) with their targets and step scales,
 * the direct pass, bootstrap, chains, rounds, splats and statistics. The
 * integrators are tables found by name (methods.c): pssmlt and mmlt take
 * the driver's targets and kernels (integrator_pssmlt.c), lmc and h2mc
 * bring targets with gradients and Hessians in the same layouts and their
 * own kernels (integrator_lmc.c).
 *
 * Normalisation. For a family g with target f_g, b_g = E[f_g(u)] over
 * uniform u is estimated by the bootstrap (for mmlt's families from
 * eval_expect, the expectation over the technique coordinate, on samples
 * independent of those that pick the starting states: same mean, far less
 * variance); the family's n_g chains each make
 * m mutations, and its image is b_g / (n_g m) times the sum of its splats
 * value / f (expected-value splatting, chain.c). Families add.
 *
 * Refining b with the large steps (Kelemen et al. 2002 do the same; pssmlt
 * and lmc on pssmlt's states only, see mcmc__refine_b). A large step
 * proposes a fresh uniform state y, so f_g(y) is one more independent
 * sample of exactly what the bootstrap averages (for mmlt, the large step
 * of a length-k chain samples b_k too, but with a far heavier tail than
 * eval_expect's samples, so mmlt's families keep the bootstrap's b). The
 * chains tally sum f(y), sum f(y)^2 and the count of their large-step
 * proposals (chain.h, mc_kernel_stats), and the image uses
 * b_g = (bootstrap sum + large-step
 * sum) / (bootstrap count + large-step count), reduced in chain order so
 * that under --spp the image stays bit-identical for any --threads. The
 * splats are therefore kept apart from b: pssmlt and lmc multiply the film
 * by b at the end (film.splat_scale); mmlt keeps one splat buffer per
 * length and sums b_k times it into the film at every snapshot and at the
 * end (when those buffers would exceed MCMC_FAMILY_FILM_BYTES, it falls
 * back to the bootstrap's b_k, baked into the splats as they are made).
 * Bias: b_g is an unbiased estimate of b_g, but the image is b_g times the
 * normalised splat histogram, and the large-step proposals that refine b_g
 * also drive the chains, so the two factors are (weakly) correlated: like
 * every ratio estimator the product has an O(1/N) bias, N the number of
 * samples of b_g, far below its O(1/sqrt N) noise (and the bootstrap-only
 * b has the same caveat through the starting states).
 *
 * Bootstrap (bootstrap.h). Sample j of family g is the large step drawn
 * from the stream (seed, hash(g, j)). --bootstrap N draws exactly N per
 * family, all in b_g. Otherwise a pilot of MCMC_BOOT_BATCH per family,
 * then a main phase in batches shared among the families by Neyman
 * allocation (in proportion to sigma_g / sqrt(c_g), c_g the rays per
 * sample: on ring-caustics about half the samples of an even split for
 * the same error), at most MCMC_BOOT_CAP samples in all. Under --time it
 * runs for a tenth of the time left, on the pilot's shares, and b_g is the
 * mean of all its samples; under --spp it runs a planning and an
 * estimating stream side by side until the estimating stream's standard
 * error, by the planning stream's figures, is 1% of sum_g b_g
 * (--bootstrap-error), and b_g is the estimating stream's mean. Either
 * way the number of samples behind b_g does not depend on their values,
 * so b_g is exactly unbiased (the earlier rule, pooled samples and a stop
 * once their running error fell below 1%, came out low under heavy
 * tails). All samples serve the starting states: they are chosen by
 * systematic resampling in proportion to f, so chains start in the
 * stationary distribution (no burn-in, no start-up bias, up to the
 * bootstrap's finite size).
 *
 * Allocation (mmlt, and lmc on mmlt's states). A family's share of the
 * mutations should follow b_g, as it does in Hachisuka et al.'s single
 * multiplexed chain. Chains are shared in proportion to b_g, but at least
 * MCMC_MIN_CHAINS per family, so a length with a tiny b (on ring-caustics
 * lengths 6-8 hold 0.03% of b) would otherwise get 16 full chains' worth of
 * its costliest mutations. Each family's chains therefore make m_g of every
 * round's MCMC_ROUND mutations, m_g = MCMC_ROUND (b_g / n_g) / max_h (b_h / n_h)
 * rounded, at least 1; its buffer is normalised by its own count (any
 * count is unbiased: a family's image is b_g times its chains' normalised
 * histogram). --allocate even gives every chain MCMC_ROUND (the old rule).
 *
 * Determinism. The number of chains is fixed (--chains, default MCMC_CHAINS, shared among
 * the mmlt families in proportion to b_g, at least MCMC_MIN_CHAINS each), not tied to
 * threads. Each chain owns its random stream seeded from (seed, family,
 * chain). Chains advance in rounds of MCMC_ROUND mutations each; a round's
 * splats are recorded per chain and then added to the film in chain order
 * (each thread adds the records falling in its band of rows), so under
 * --spp the image is bit-identical for any --threads. Under --time the
 * rounds continue until the clock says stop: the chains of a family make the
 * same number of mutations (the budget is split across chains by rounds).
 * A stop request (Ctrl-C) or the time limit abandons the round in flight;
 * the film always holds whole rounds and is correctly normalised.
 *
 * --direct separate (the default, as in Mitsuba's pssmlt and in the LMC
 * paper's implementation): pt renders paths of length <= 2 first (with
 * --spp samples per pixel, or the scene's directSamples, or 15% of
 * --time), into the same film, and MCMC only paths of length >= 3.
 * --direct mcmc leaves every path to MCMC.
 */
#include "lmc/mcmc.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/bdpt_states.h"
#include "lmc/bootstrap.h"
#include "lmc/chain.h"
#include "lmc/method.h"
#include "lmc/states.h"

#define MCMC_CHAINS 256
#define MCMC_MIN_CHAINS 16 /* per mmlt family: one stuck chain must not carry a whole length */
#define MCMC_MMLT_SIGMA 0.05 /* mmlt's default small-step scale (see mcmc_render_run) */
#define MCMC_GAUSS_SIGMA 0.01 /* --small-step gauss: default standard deviation (the LMC
                                 paper's implementation's perturbStdDev) */
#define MCMC_LARGESTEP_SCALE_AFTER 0.1 /* --largestep-scale applies after this share of
                                          the chains' budget (the paper's LS_RATIO) */
#define MCMC_ROUND 64
#define MCMC_BOOT_BATCH 8192
#define MCMC_BOOT_CAP (1 << 22) /* bootstrap samples in all, over the families */
#define MCMC_EXPECT_SEQ 0x5eed0fb0075a3e11ull /* eval_expect's bootstrap streams: (seed, seq ^ this) */
#define MCMC_MAX_FAMILIES 64
#define MCMC_FAMILY_FILM_BYTES ((int64_t)512 << 20) /* mmlt's per-length splat buffers, at most */
#define MCMC_UNBOUNDED_PT 128  /* pt bounces kept in the state when maxdepth is -1 */
#define MCMC_UNBOUNDED_MMLT 24 /* mmlt's longest path when maxdepth is -1 */
#define MCMC_UNBOUNDED_BDPT (BDPT_MAX_VERTICES - 2) /* the bdpt states' (subpaths of 63 vertices) */

int mcmc_is_integrator(const char *name) {
  return mc_method_find(name) != NULL;
}

/* --- scene targets ----------------------------------------------------------- */

typedef struct mcmc_scene_target {
  const scene *s;
  render_settings rs; /* mindepth/maxdepth as the MCMC part renders them */
  int length;         /* mmlt: path length k of this family */
  int n_strategies;   /* mmlt: n_k */
  double margin;      /* filter radius r */
  double area;        /* (W + 2r)(H + 2r) */
} mcmc_scene_target;

typedef struct mcmc_scratch {
  render_counters cnt;
  bdpt_vertex cam[BDPT_MAX_VERTICES], lp[BDPT_MAX_VERTICES];
} mcmc_scratch;

static void *mcmc__scratch_create(const mc_target *t) {
  (void)t;
  return calloc(1, sizeof(mcmc_scratch));
}
static void mcmc__scratch_destroy(void *scratch) { free(scratch); }
static int64_t mcmc__scratch_rays(const void *scratch) {
  return ((const mcmc_scratch *)scratch)->cnt.rays;
}

/* Sets value, f and raster position from an RGB contribution. */
static void mcmc__value(mc_value *v, rgb c, double rx, double ry, render_counters *cnt) {
  v->rx = rx;
  v->ry = ry;
  if (!rgb_isfinite(c)) {
    cnt->nan_samples++;
    c = rgb_zero();
  }
  double f = rgb_luminance(c);
  if (!(f > 0.0)) {
    f = 0.0;
    c = rgb_zero();
  }
  v->value = c;
  v->f = f;
}

static void mcmc__raster(const mcmc_scene_target *st, lmc_sampler *smp, double *rx, double *ry) {
  double r = st->margin;
  double u0 = sampler_next(smp), u1 = sampler_next(smp);
  *rx = -r + u0 * (st->s->cam.width + 2.0 * r);
  *ry = -r + u1 * (st->s->cam.height + 2.0 * r);
}

static int mcmc__pssmlt_eval(const mc_target *t, void *scratch, lmc_sampler *smp,
                             mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok) {
  const mcmc_scene_target *st = t->ctx;
  mcmc_scratch *sc = scratch;
  (void)OUT_grad;
  if (OUT_grad_ok) *OUT_grad_ok = 0;
  sampler_use_stream(smp, LMC_STREAM_CAMERA);
  double rx, ry;
  mcmc__raster(st, smp, &rx, &ry);
  vec3 org, dir;
  camera_generate_ray(&st->s->cam, rx, ry, &org, &dir);
  rgb L = pt_li(st->s, &st->rs, smp, org, dir, &sc->cnt);
  mcmc__value(OUT_value, rgb_scale(L, st->area), rx, ry, &sc->cnt);
  return 0;
}

static double mcmc__mmlt_expect(const mc_target *t, void *scratch, lmc_sampler *smp) {
  const mcmc_scene_target *st = t->ctx;
  mcmc_scratch *sc = scratch;
  return mc_mmlt_expected(st->s, &st->rs, st->length, st->margin, st->area, smp, sc->cam, sc->lp,
                            &sc->cnt);
}

static int mcmc__mmlt_eval(const mc_target *t, void *scratch, lmc_sampler *smp,
                           mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok) {
  const mcmc_scene_target *st = t->ctx;
  mcmc_scratch *sc = scratch;
  (void)OUT_grad;
  if (OUT_grad_ok) *OUT_grad_ok = 0;
  double rx, ry;
  rgb c = mc_mmlt_contribution(st->s, &st->rs, st->length, st->n_strategies, st->margin,
                                 st->area, smp, sc->cam, sc->lp, &sc->cnt, &rx, &ry);
  mcmc__value(OUT_value, c, rx, ry, &sc->cnt);
  return 0;
}

/* --- splat records ----------------------------------------------------------- */

typedef struct mcmc_splat {
  double rx, ry;
  rgb v;
} mcmc_splat;

typedef struct mcmc_chain_slot {
  mc_chain *chain;
  int family;
  double scale;     /* b_g / n_g */
  uint64_t start_seq; /* bootstrap sample the chain started from */
  mcmc_splat *rec;  /* this round's splats */
  int n_rec, cap_rec;
  int rec_failed;   /* a splat was dropped: no memory to grow rec */
} mcmc_chain_slot;

static void mcmc__record(void *ctx, const mc_value *v, double weight) {
  mcmc_chain_slot *sl = ctx;
  if (sl->n_rec == sl->cap_rec) {
    /* A labelled large step splats every strategy of its sample: grow
     * (rarely: the buffer keeps its size across rounds). */
    mcmc_splat *r = realloc(sl->rec, 2 * (size_t)sl->cap_rec * sizeof *r);
    if (!r) {
      sl->rec_failed = 1;
      return;
    }
    sl->rec = r;
    sl->cap_rec *= 2;
  }
  mcmc_splat *r = &sl->rec[sl->n_rec++];
  r->rx = v->rx;
  r->ry = v->ry;
  r->v = rgb_scale(v->value, weight * sl->scale);
}

/* Adds record r to rows [y_lo, y_hi) of splat, a film's splat array or a
 * buffer of its size (film_splat's rule). */
static void mcmc__splat_rows(const film *f, double *splat, const film_filter *filter,
                             const mcmc_splat *r, int y_lo, int y_hi) {
  if (!rgb_isfinite(r->v)) return;
  int x0 = (int)floor(r->rx - 0.5 - filter->radius), x1 = (int)ceil(r->rx - 0.5 + filter->radius);
  int y0 = (int)floor(r->ry - 0.5 - filter->radius), y1 = (int)ceil(r->ry - 0.5 + filter->radius);
  if (x0 < 0) x0 = 0;
  if (y0 < y_lo) y0 = y_lo;
  if (x1 > f->width - 1) x1 = f->width - 1;
  if (y1 > y_hi - 1) y1 = y_hi - 1;
  for (int y = y0; y <= y1; y++) {
    for (int x = x0; x <= x1; x++) {
      double w = filter_eval(filter, (x + 0.5) - r->rx, (y + 0.5) - r->ry);
      if (w == 0.0) continue;
      double *s = splat + 3 * ((int64_t)y * f->width + x);
      s[0] += w * r->v.r;
      s[1] += w * r->v.g;
      s[2] += w * r->v.b;
    }
  }
}

/* --- the driver ------------------------------------------------------------------ */

typedef struct mcmc_family {
  mc_target target;
  mcmc_scene_target st;
  mc_boot bt;         /* the bootstrap's samples and estimate of b (bootstrap.h) */
  double b_ref, b_ref_var; /* b refined with the chains' large steps, and its variance */
  int64_t n_large;    /* large-step proposals counted in b_ref */
  double *splat;      /* mmlt: this length's splats, not yet times b (owned; 3 per pixel) */
  int n_chains, first_chain;
  int m_round;        /* mutations per chain in a full round (1 .. MCMC_ROUND; see Allocation) */
  int64_t done;       /* mutations per chain of this family so far */
  double *step_scale; /* mmlt, pssmlt: the target's per-coordinate small-step factors (owned) */
  mc_bdpt_states bst; /* --states bdpt: the labelled target's context (bdpt_states.h) */
  int no_pool;        /* b is not refined with the large steps (mmlt's states, see mcmc__refine_b) */
  mc_kernel kdef[MC_MAX_KERNELS]; /* the driver's default kernel mix (method.h) */
  double pdef[MC_MAX_KERNELS];
  int nkdef;
} mcmc_family;

static uint64_t mcmc__boot_seq(int g, int64_t j) {
  return rng_hash64(((uint64_t)(g + 1) << 44) ^ (uint64_t)j);
}
static uint64_t mcmc__chain_seq(int g, int i) {
  return rng_hash64(((uint64_t)(g + 1) << 44) ^ (1ull << 43) ^ (uint64_t)i);
}

/* mc_boot_draw_fn over the families: draws bootstrap samples
 * [bt.n, to[g]) of every family g in parallel (each sample from its own
 * stream, so the values do not depend on threads); the cost is rays. */
typedef struct mcmc_boot_ctx {
  mcmc_family *fam;
  uint64_t seed;
  int nthreads;
  render_counters *cnt;
} mcmc_boot_ctx;

static void mcmc__bootstrap_draw(void *ctx, mc_boot *boot, int n_fam, const int64_t *to) {
  mcmc_boot_ctx *C = ctx;
  for (int g = 0; g < n_fam; g++) {
    mcmc_family *F = &C->fam[g];
    mc_boot *B = &boot[g];
    int64_t from = B->n;
    const uint64_t seed = C->seed;
#pragma omp parallel num_threads(C->nthreads)
    {
      /* The target's own scratch (lmc's target has another kind). */
      void *sc = F->target.scratch_create(&F->target);
      int tid = omp_get_thread_num();
#pragma omp for schedule(dynamic, 256)
      for (int64_t j = from; j < to[g]; j++) {
        B->f[j] = sc ? mc_eval_independent(&F->target, sc, seed, mcmc__boot_seq(g, j), NULL) : 0.0;
        if (B->has_fe) {
          /* An independent sample for b (the one above picks starting states). */
          lmc_indep_sampler smp;
          indep_sampler_init(&smp, seed, mcmc__boot_seq(g, j) ^ MCMC_EXPECT_SEQ);
          double v = sc ? F->target.eval_expect(&F->target, sc, &smp.base) : 0.0;
          B->fe[j] = v >= 0.0 && isfinite(v) ? v : 0.0;
        }
      }
      if (sc) {
        int64_t rays = F->target.scratch_rays(sc);
#pragma omp atomic
        C->cnt[tid].rays += rays;
#pragma omp atomic
        B->cost += (double)rays;
      }
      F->target.scratch_destroy(sc);
    }
  }
}

/* --- mmlt's b_k from whole BDPT samples -------------------------------------
 *
 * Every independent BDPT sample (the bdpt states' eval_all, bdpt_states.h)
 * holds one estimate of every length's b_k at once: the sum of the MIS-
 * weighted contributions of that length's strategies, which is what mmlt's
 * eval_expect averages family by family. Drawn together, each length gets
 * every sample at the cost of one sample of the longest, instead of a share
 * of the bootstrap's (Neyman allocation starved the long lengths, whose
 * heavy-tailed b_k then read low in a typical short render). Samples come
 * in blocks of MCMC_SHARED_BLOCK, each block from its own streams and
 * summed by one thread in order, the block sums added in block order: the
 * estimate does not depend on the threads. The number of blocks depends on
 * the clock (--time) or on a pilot of MCMC_SHARED_PILOT blocks alone
 * (--spp), never on the samples it averages, so each b_k is unbiased. */
#define MCMC_SHARED_BLOCK 1024
#define MCMC_SHARED_PILOT 8
#define MCMC_SHARED_SEQ 0x3c6ef372fe94f82bull

typedef struct mcmc_shared_b {
  int n_len;          /* lengths kmin .. kmin + n_len - 1; column n_len: all lengths */
  int64_t blocks, cap;
  double *sum, *sum2; /* [block][length] */
} mcmc_shared_b;

/* Draws blocks [from, to) of the shared samples. */
static void mcmc__shared_draw(const mc_target *T, const mc_bdpt_states *ctx, int kmin,
                              uint64_t seed, int nthreads, mcmc_shared_b *sb, int64_t from,
                              int64_t to, render_counters *cnt) {
#pragma omp parallel num_threads(nthreads)
  {
    void *sc = T->scratch_create(T);
    mc_contrib *cb = malloc((size_t)T->n_labels * sizeof *cb);
    double *f = malloc((size_t)sb->n_len * sizeof *f);
    int tid = omp_get_thread_num();
#pragma omp for schedule(dynamic, 1)
    for (int64_t blk = from; blk < to; blk++) {
      int w = sb->n_len + 1;
      double *s1 = sb->sum + blk * w, *s2 = sb->sum2 + blk * w;
      for (int k = 0; k < w; k++) s1[k] = s2[k] = 0.0;
      if (!sc || !cb || !f) continue;
      for (int j = 0; j < MCMC_SHARED_BLOCK; j++) {
        lmc_indep_sampler smp;
        indep_sampler_init(&smp, seed, rng_hash64(MCMC_SHARED_SEQ ^ (uint64_t)(blk * MCMC_SHARED_BLOCK + j)));
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
}

/* b_k of the lengths kmin .. kmin + n_fam - 1 (fam[g] has length kmin + g)
 * from whole BDPT samples, into fam[g].bt.b, b_var, n_est, s, s2; seconds:
 * the time for them (INFINITY under --spp: then a pilot plans the count for
 * a standard error of rel_err of sum_k b_k); fixed > 0: exactly that many
 * samples. Returns 0, or -1 when out of memory. */
static int mcmc__shared_b(const scene *s, const render_settings *rs, mcmc_family *fam, int n_fam,
                          int kmin, int64_t fixed, double seconds, double rel_err, int nthreads,
                          render_counters *cnt) {
  render_settings brs = *rs;
  brs.rough_min = 2.0;
  mc_target T;
  mc_bdpt_states ctx;
  lmc_error err;
  if (mc_bdpt_states_init(&T, &ctx, s, &brs, kmin, kmin + n_fam - 1, &err) != LMC_OK) return -1;
  mcmc_shared_b sb = {n_fam, 0, 0, NULL, NULL};
  double t0 = omp_get_wtime();
  int64_t cap = (MCMC_BOOT_CAP + MCMC_SHARED_BLOCK - 1) / MCMC_SHARED_BLOCK;
  int64_t want = fixed > 0 ? (fixed + MCMC_SHARED_BLOCK - 1) / MCMC_SHARED_BLOCK : cap;
  int status = 0;
  for (;;) {
    /* The next batch: the pilot, then batches of blocks for every thread. */
    int64_t to = sb.blocks == 0 ? (fixed > 0 ? want : MCMC_SHARED_PILOT)
                                : sb.blocks + 4 * (int64_t)nthreads;
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
    mcmc__shared_draw(&T, &ctx, kmin, rs->seed, nthreads, &sb, sb.blocks, to, cnt);
    int first = sb.blocks == 0;
    sb.blocks = to;
    if (fixed > 0) break;
    if (render_stop_signal()) break;
    if (isfinite(seconds)) {
      if (omp_get_wtime() - t0 >= seconds) break;
    } else if (first) {
      /* Plan the count from the pilot alone: the standard error of
       * sum_k b_k is sigma / sqrt(N). The pilot's samples are kept apart
       * from the estimate below (they decided its size). */
      double s1 = 0.0, s2 = 0.0, n = (double)sb.blocks * MCMC_SHARED_BLOCK;
      for (int64_t blk = 0; blk < sb.blocks; blk++)
        s1 += sb.sum[blk * (n_fam + 1) + n_fam], s2 += sb.sum2[blk * (n_fam + 1) + n_fam];
      double mean = s1 / n, var = fmax(0.0, s2 / n - mean * mean);
      double need = mean > 0.0 ? var / (rel_err * rel_err * mean * mean) : 0.0;
      want = MCMC_SHARED_PILOT + (int64_t)ceil(need / MCMC_SHARED_BLOCK);
      if (want > cap) want = cap;
      if (want < 2 * MCMC_SHARED_PILOT) want = 2 * MCMC_SHARED_PILOT;
    }
  }
  /* The estimate: every block but the planning pilot's under --spp. */
  int64_t b0 = (fixed > 0 || isfinite(seconds)) ? 0 : MCMC_SHARED_PILOT;
  if (b0 >= sb.blocks) b0 = 0;
  double n = (double)(sb.blocks - b0) * MCMC_SHARED_BLOCK;
  for (int g = 0; g < n_fam && status == 0; g++) {
    double s1 = 0.0, s2 = 0.0;
    for (int64_t blk = b0; blk < sb.blocks; blk++)
      s1 += sb.sum[blk * (n_fam + 1) + g], s2 += sb.sum2[blk * (n_fam + 1) + g];
    mc_boot *B = &fam[g].bt;
    B->s = s1, B->s2 = s2, B->n_est = (int64_t)n;
    B->b = n > 0.0 ? s1 / n : 0.0;
    double var = n > 1.0 ? fmax(0.0, (s2 - n * B->b * B->b) / (n - 1.0)) : 0.0;
    B->b_var = n > 0.0 ? var / n : 0.0;
  }
  free(sb.sum), free(sb.sum2);
  mc_bdpt_states_free(&ctx);
  return status;
}

/* Mean and variance of the mean of n samples with sums s, s2. */
static void mcmc__mean_var(double s, double s2, double n, double *OUT_mean, double *OUT_var) {
  double mean = n > 0.0 ? s / n : 0.0;
  double var = n > 1.0 ? fmax(0.0, (s2 - n * mean * mean) / (n - 1.0)) : 0.0;
  *OUT_mean = mean;
  *OUT_var = n > 0.0 ? var / n : 0.0;
}

/* b_ref of every family with chains: the bootstrap's samples pooled with
 * its chains' large-step tallies, added in chain order (deterministic).
 * Both are unbiased samples of b_g, so the pooled mean is unbiased. A
 * family whose target has eval_expect (mmlt's and lmc's multiplexed
 * lengths) keeps its bootstrap b alone: there the bootstrap's samples are
 * the expectation over the technique coordinate, its large steps one
 * strategy's value, whose tail is far heavier (on ring-caustics-glass one
 * large step of length 10 took that length's b from 46 to 3657, and the
 * render's relative MSE from 0.04 to 4.2; on the torus pooling lowered b
 * in each of four runs looked at: unbiased, but a typical run darker).
 * (An inverse-variance weighting of the two means was tried and dropped:
 * with heavy tails a low estimate comes with a low estimated variance,
 * and on ring-caustics it pulled the long lengths' b far down.) Returns
 * the sum of b_ref over the families and its variance in OUT_var. */
static double mcmc__refine_b(mcmc_family *fam, int n_fam, const mcmc_chain_slot *slots,
                             double *OUT_var) {
  double b = 0.0, v = 0.0;
  for (int g = 0; g < n_fam; g++) {
    mcmc_family *F = &fam[g];
    double s = 0.0, s2 = 0.0;
    int64_t nl = 0;
    for (int i = 0; i < F->n_chains && !F->no_pool; i++) {
      const mc_chain *c = slots[F->first_chain + i].chain;
      for (int q = 0; q < c->n_kernels; q++) {
        if (c->kernels[q].kind != MC_KERNEL_LARGE) continue;
        s += c->stats[q].f_sum;
        s2 += c->stats[q].f_sum2;
        nl += c->stats[q].proposed;
      }
    }
    mcmc__mean_var(F->bt.s + s, F->bt.s2 + s2, (double)(F->bt.n_est + nl), &F->b_ref,
                   &F->b_ref_var);
    F->n_large = nl;
    b += F->b_ref;
    v += F->b_ref_var;
  }
  *OUT_var = v;
  return b;
}

/* How the splats meet b (see Normalisation above). */
typedef enum mcmc_norm {
  MCMC_NORM_BOOT = 0, /* bootstrap b baked into each splat (mmlt without buffer memory) */
  MCMC_NORM_SCALE,    /* one family: refined b in film.splat_scale */
  MCMC_NORM_BUFFERS   /* mmlt: per-length buffers, summed times refined b_k */
} mcmc_norm;

/* Puts the chains' image (done mutations per chain) into the film with the
 * refined b: one family through splat_scale; per-length buffers, when
 * compose is set, by summing b_k times each buffer into the film's splats. */
static void mcmc__publish(film *out, mcmc_family *fam, int n_fam, const mcmc_chain_slot *slots,
                          mcmc_norm norm, int64_t done, int compose) {
  if (done <= 0) return;
  double v;
  if (norm != MCMC_NORM_BOOT) mcmc__refine_b(fam, n_fam, slots, &v);
  if (norm != MCMC_NORM_BUFFERS) {
    out->splat_scale = (norm == MCMC_NORM_SCALE ? fam[0].b_ref : 1.0) / (double)done;
    return;
  }
  /* Per-length buffers: each normalised by its own chains' mutations. */
  out->splat_scale = 1.0;
  if (!compose) return;
  int64_t n = 3 * (int64_t)out->width * out->height;
  memset(out->splat, 0, (size_t)n * sizeof(double));
  for (int g = 0; g < n_fam; g++) {
    if (!fam[g].splat || fam[g].done <= 0) continue;
    double b = fam[g].b_ref / (double)fam[g].done;
    for (int64_t i = 0; i < n; i++) out->splat[i] += b * fam[g].splat[i];
  }
}

/* Mutations a chain of family F makes in a round of m (m for a family at
 * the full rate, else in proportion, rounded up and at least one). Rounded
 * up, the rounds of a --spp render add up to at least its budget (the
 * number of rounds is the budget over the families' full-round weight,
 * rounded up); rounded to the nearest, a short last round could leave a
 * render a few mutations short. */
static int64_t mcmc__family_steps(const mcmc_family *F, int64_t m) {
  if (F->m_round >= MCMC_ROUND) return m;
  int64_t k = (m * F->m_round + MCMC_ROUND - 1) / MCMC_ROUND;
  return k < 1 ? 1 : k;
}

/* Mutations the chains of every family have made so far. */
static int64_t mcmc__mutations(const mcmc_family *fam, int n_fam) {
  int64_t n = 0;
  for (int g = 0; g < n_fam; g++) n += fam[g].done * fam[g].n_chains;
  return n;
}

/* Scales the probability of c's large step (kernel 0) by `scale`, at most
 * to 1, and the other kernels' together by what is left. */
static void mcmc__scale_large(mc_chain *c, double scale) {
  double p[MC_MAX_KERNELS], prev = 0.0;
  for (int q = 0; q < c->n_kernels; q++) p[q] = c->cdf[q] - prev, prev = c->cdf[q];
  if (c->kernels[0].kind != MC_KERNEL_LARGE || !(p[0] < 1.0)) return;
  double pl = fmin(1.0, p[0] * scale), rest = (1.0 - pl) / (1.0 - p[0]);
  p[0] = pl;
  for (int q = 1; q < c->n_kernels; q++) p[q] *= rest;
  mc_chain_set_probs(c, p);
}

static void mcmc__free_slots(mcmc_chain_slot *slots, int n) {
  if (!slots) return;
  for (int i = 0; i < n; i++) {
    mc_chain_destroy(slots[i].chain);
    free(slots[i].rec);
  }
  free(slots);
}

lmc_status mcmc_render_run(const scene *s, const render_settings *rs, film *out,
                           render_stats *st, lmc_error *err) {
  memset(st, 0, sizeof *st);
  /* The integrator (method.h): its table, and its run once created. */
  const mc_method *M = mc_method_find(rs->integrator);
  void *mrun = NULL;
  if (!M)
    return lmc_error_set(err, LMC_EUNSUPPORTED, NULL, 0,
                         "integrator %s is not built on this framework yet", rs->integrator);
  /* The state space (--states, else the integrator's). */
  int states = rs->mcmc_states != MCMC_STATES_DEFAULT ? rs->mcmc_states : M->default_states;
  int bdpt_states = states == MCMC_STATES_BDPT;
  /* Families per path length: mmlt's states. */
  int multiplexed = states == MCMC_STATES_MMLT;
  /* The integrator's own targets replace the driver's (with their own step scales). */
  int own_targets = M->family_target != NULL;
  render_settings lrs_states = *rs;
  lrs_states.lmc_states = states == MCMC_STATES_PT     ? LMC_STATES_PT
                          : states == MCMC_STATES_MMLT ? LMC_STATES_MMLT
                                                       : LMC_STATES_BDPT;
  rs = &lrs_states;
  const int W = s->cam.width, H = s->cam.height;
  const int nthreads = rs->threads > 0 ? rs->threads : omp_get_max_threads();
  const int timed = rs->time_limit > 0.0;
  const int by_spp = !timed || (rs->set & SET_SPP);
  double t0 = omp_get_wtime();
  lmc_status status;

  /* Kelemen's s2: --sigma, else 1/64 (pssmlt, lmc) or MCMC_MMLT_SIGMA (mmlt:
   * on ring-caustics at 20 s, once the light-position steps were scaled
   * (mc_light_u1_scale), 0.05 gave relative MSE 0.10 against 0.17 - 0.28
   * for 1/64, 0.03, 0.1 and 0.2, one run each). */
  const double sigma = (rs->set & SET_SIGMA)  ? rs->sigma
                       : rs->small_gauss      ? MCMC_GAUSS_SIGMA
                       : !multiplexed         ? rs->sigma
                                              : MCMC_MMLT_SIGMA;

  /* One progress line over the phases: direct light, bootstrap, chains. */
  progress bar;
  progress_init(&bar, rs->integrator, rs->quiet);

  /* Direct lighting by pt first, when asked (--direct separate). */
  render_settings mrs = *rs;
  if (rs->direct_separate) {
    progress_phase(&bar, "direct light", 0.0);
    render_settings prs = *rs;
    snprintf(prs.integrator, sizeof prs.integrator, "pt");
    prs.maxdepth = rs->maxdepth >= 0 && rs->maxdepth < 2 ? rs->maxdepth : 2;
    prs.snapshot = 0.0;
    prs.snapshot_fn = NULL;
    if (rs->direct_spp > 0) prs.spp = rs->direct_spp;
    if (timed) {
      prs.time_limit = 0.15 * rs->time_limit;
      if (!(rs->set & SET_SPP)) prs.set &= ~(unsigned)SET_SPP;
    }
    prs.quiet = 1;
    render_stats pst;
    status = render_run(s, &prs, out, &pst, err);
    if (status) {
      progress_end(&bar);
      return status;
    }
    st->rays += pst.rays;
    st->nan_samples += pst.nan_samples;
    if (pst.interrupted) {
      progress_end(&bar);
      st->interrupted = 1;
      st->seconds = omp_get_wtime() - t0;
      return LMC_OK;
    }
    mrs.mindepth = rs->mindepth > 3 ? rs->mindepth : 3;
  } else {
    status = film_init(out, W, H, err);
    if (status) return status;
  }
  if (rs->direct_separate && rs->maxdepth >= 0 && rs->maxdepth < 3) {
    progress_end(&bar);
    st->seconds = omp_get_wtime() - t0;
    return LMC_OK;
  }

  /* The families: one for pssmlt, one per path length for mmlt. */
  mcmc_family fam[MCMC_MAX_FAMILIES];
  memset(fam, 0, sizeof fam);
  int n_fam = 0;
  double margin = s->filter.radius, area = (W + 2.0 * margin) * (H + 2.0 * margin);
  int kmin = 1, kmax = 0;
  if (multiplexed) {
    kmax = rs->maxdepth >= 0 ? rs->maxdepth : MCMC_UNBOUNDED_MMLT;
    if (kmax > MCMC_MAX_FAMILIES) kmax = MCMC_MAX_FAMILIES;
    if (kmax > BDPT_MAX_VERTICES - 2) kmax = BDPT_MAX_VERTICES - 2;
    kmin = mrs.mindepth > 1 ? mrs.mindepth : 1;
    if (kmax - kmin + 1 > MCMC_MAX_FAMILIES) kmax = kmin + MCMC_MAX_FAMILIES - 1;
    if (rs->maxdepth < 0 && !rs->quiet)
      fprintf(stderr, "lmc: %s renders paths of at most %d segments (set --maxdepth)\n",
              rs->integrator, kmax);
  }
  if (bdpt_states) {
    /* One family over every length (see mcmc__bdpt_eval_label). */
    kmax = rs->maxdepth >= 0 ? rs->maxdepth : MCMC_UNBOUNDED_BDPT;
    if (kmax > BDPT_MAX_VERTICES - 2) kmax = BDPT_MAX_VERTICES - 2;
    kmin = mrs.mindepth > 1 ? mrs.mindepth : 1;
    if (rs->maxdepth < 0 && !rs->quiet)
      fprintf(stderr, "lmc: %s renders paths of at most %d segments (set --maxdepth)\n",
              rs->integrator, kmax);
    mcmc_family *F = &fam[n_fam++];
    F->st = (mcmc_scene_target){s, mrs, 0, 1, margin, area};
    status = mc_bdpt_states_init(&F->target, &F->bst, s, &mrs, kmin, kmax, err);
    if (status) {
      progress_end(&bar);
      film_free(out);
      return status;
    }
  } else if (!multiplexed) {
    int bounces = rs->maxdepth >= 0 ? rs->maxdepth : MCMC_UNBOUNDED_PT;
    mcmc_family *F = &fam[n_fam++];
    F->st = (mcmc_scene_target){s, mrs, 0, 1, margin, area};
    F->target.stream_dim[LMC_STREAM_CAMERA] = PT_DIMS_CAMERA + PT_DIMS_PER_BOUNCE * (bounces + 1);
  } else {
    for (int k = kmin; k <= kmax && n_fam < MCMC_MAX_FAMILIES; k++) {
      mcmc_family *F = &fam[n_fam++];
      F->st = (mcmc_scene_target){s, mrs, k, k == 1 ? 1 : k + 1, margin, area};
      F->st.rs.mindepth = -1;
      F->target.stream_dim[LMC_STREAM_CAMERA] = 2 + BDPT_DIMS_PER_VERTEX * (k + 1);
      F->target.stream_dim[LMC_STREAM_LIGHT] = BDPT_DIMS_LIGHT_START + BDPT_DIMS_PER_VERTEX * (k + 1);
      F->target.stream_dim[LMC_STREAM_CONNECT] = 1 + BDPT_DIMS_CONNECT;
    }
  }
  for (int g = 0; g < n_fam && !bdpt_states; g++) {
    mc_target *T = &fam[g].target;
    T->ctx = &fam[g].st;
    T->dim = T->stream_dim[0] + T->stream_dim[1] + T->stream_dim[2];
    T->eval = multiplexed ? mcmc__mmlt_eval : mcmc__pssmlt_eval;
    T->eval_expect = multiplexed ? mcmc__mmlt_expect : NULL;
    T->scratch_create = mcmc__scratch_create;
    T->scratch_destroy = mcmc__scratch_destroy;
    T->scratch_rays = mcmc__scratch_rays;
  }

  render_counters *cnt = calloc((size_t)nthreads, sizeof *cnt);
  mcmc_chain_slot *slots = NULL;
  int n_slots = 0;
  render_settings lrs = mrs;
  lrs.sigma = sigma;
  if (M->create) {
    mc_method_setup setup = {s, &lrs, states, kmin, kmax, n_fam};
    status = M->create(&mrun, &setup, err);
    if (status) goto done;
  }
  if (own_targets) /* (e.g. lmc's: the same layouts, with gradients) */
    for (int g = 0; g < n_fam; g++) fam[g].target = *M->family_target(mrun, g);
  /* The bootstrap keeps eval_expect's samples apart where the target has it. */
  int cap = 1; /* 0: out of memory */
  /* (mmlt's states estimate b from whole BDPT samples instead, below: their
   * bootstrap samples pick starting states only) */
  for (int g = 0; g < n_fam; g++) fam[g].bt.has_fe = 0;
  int64_t shared_paths = 0;
  if (bdpt_states) {
    /* (bdpt_states.c sets its own step scale) */
  } else if (!own_targets && !multiplexed) {
    /* The pt states: next-event estimation's light-position number u1 of
     * every bounce (lmc's run sets the same on its own target). */
    mc_target *T = &fam[0].target;
    fam[0].step_scale = malloc((size_t)T->dim * sizeof(double));
    if (fam[0].step_scale) {
      mc_pt_step_scale(s, T->dim, fam[0].step_scale);
      T->step_scale = fam[0].step_scale;
    } else {
      cap = 0;
    }
  }
  if (!own_targets && multiplexed) {
    /* mmlt's states: the light-position coordinates u1 of the light stream (emission) and
     * of the connect stream (the light sample of s = 1): see
     * mc_light_u1_scale. */
    double u1_scale = mc_light_u1_scale(s);
    for (int g = 0; g < n_fam; g++) {
      mc_target *T = &fam[g].target;
      fam[g].step_scale = malloc((size_t)T->dim * sizeof(double));
      if (!fam[g].step_scale) {
        cap = 0;
        continue;
      }
      for (int i = 0; i < T->dim; i++) fam[g].step_scale[i] = 1.0;
      fam[g].step_scale[mc_target_stream_offset(T, LMC_STREAM_LIGHT) + 1] = u1_scale;
      fam[g].step_scale[mc_target_stream_offset(T, LMC_STREAM_CONNECT) + 2] = u1_scale;
      T->step_scale = fam[g].step_scale;
    }
  }
  if (!cnt || cap == 0) {
    status = lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the bootstrap");
    goto done;
  }

  /* Bootstrap (bootstrap.h): the pilot (or all of --bootstrap N), then the
   * main phase planned from it, in at most a tenth of the time left (after
   * --direct separate's pt pass), at most MCMC_BOOT_CAP samples in all. */
  {
    const double t_boot = omp_get_wtime();
    progress_phase(&bar, "bootstrap", timed ? (t_boot - t0) / rs->time_limit : 0.0);
    mc_boot_params bp = {
        /* mmlt's states: a pilot per family for the starting states alone */
        .fixed = multiplexed ? MCMC_BOOT_BATCH : rs->bootstrap > 0 ? rs->bootstrap : 0,
        .batch = MCMC_BOOT_BATCH,
        .cap_total = MCMC_BOOT_CAP,
        .rel_err = rs->bootstrap_error,
        .seconds = timed ? 0.1 * (rs->time_limit - (t_boot - t0)) : INFINITY,
        .stop = render_stop_signal,
    };
    mc_boot *boot = malloc((size_t)n_fam * sizeof(mc_boot));
    int failed = !boot;
    if (boot) {
      for (int g = 0; g < n_fam; g++) boot[g] = fam[g].bt;
      mcmc_boot_ctx bc = {fam, rs->seed, nthreads, cnt};
      failed = mc_boot_run(boot, n_fam, &bp, mcmc__bootstrap_draw, &bc);
      for (int g = 0; g < n_fam; g++) fam[g].bt = boot[g];
      free(boot);
    }
    /* mmlt's states: b_k from whole BDPT samples (mcmc__shared_b) in the
     * rest of the bootstrap's time; the families' own samples only pick
     * the starting states. */
    if (!failed && multiplexed) {
      double left = timed ? bp.seconds - (omp_get_wtime() - t_boot) : INFINITY;
      failed = mcmc__shared_b(s, &mrs, fam, n_fam, kmin, rs->bootstrap > 0 ? rs->bootstrap : 0,
                              timed ? fmax(left, 0.0) : INFINITY, rs->bootstrap_error, nthreads,
                              cnt) != 0;
      shared_paths = fam[0].bt.n_est;
    }
    if (failed) {
      status = lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the bootstrap");
      goto done;
    }
  }
  for (int g = 0; g < n_fam; g++) {
    fam[g].b_ref = fam[g].bt.b;
    fam[g].b_ref_var = fam[g].bt.b_var;
    fam[g].n_large = 0;
    fam[g].no_pool = multiplexed;
  }
  double b_total = 0.0, b_var = 0.0;
  for (int g = 0; g < n_fam; g++) b_total += fam[g].bt.b, b_var += fam[g].bt.b_var;
  st->mcmc_b_boot = st->mcmc_b = b_total;
  st->mcmc_boot_paths = 0;
  for (int g = 0; g < n_fam; g++) st->mcmc_boot_paths += fam[g].bt.n;
  st->mcmc_boot_paths += shared_paths;
  st->mcmc_b_boot_se = st->mcmc_b_se = sqrt(b_var);

  /* Chains: MCMC_CHAINS shared in proportion to b_g (at least MCMC_MIN_CHAINS per
   * family that has any contribution). */
  for (int g = 0; g < n_fam; g++) {
    if (!(fam[g].bt.b > 0.0)) continue;
    int n_chains = rs->chains > 0 ? rs->chains : MCMC_CHAINS;
    int nc = (int)floor(n_chains * fam[g].bt.b / b_total + 0.5);
    fam[g].n_chains = nc < MCMC_MIN_CHAINS ? MCMC_MIN_CHAINS : nc;
    fam[g].first_chain = n_slots;
    n_slots += fam[g].n_chains;
  }
  if (n_slots == 0) {
    /* No bootstrap path carried light: the chains' part of the image is
     * black (all of it, or all but pt's direct light). */
    if (!rs->quiet)
      fprintf(stderr, "lmc: %s's bootstrap found no light on paths of %d or more segments (%lld "
              "paths): %s\n", rs->integrator, mrs.mindepth > 1 ? mrs.mindepth : 1,
              (long long)st->mcmc_boot_paths,
              rs->direct_separate ? "the image is --direct separate's path-traced pass alone"
                                  : "the image is black");
    goto finish;
  }

  /* Where the splats go (see Normalisation above). */
  mcmc_norm norm = n_fam == 1 ? MCMC_NORM_SCALE : MCMC_NORM_BUFFERS;
  if (norm == MCMC_NORM_BUFFERS) {
    int n_active = 0;
    for (int g = 0; g < n_fam; g++) n_active += fam[g].n_chains > 0;
    if ((int64_t)n_active * 3 * W * H * (int64_t)sizeof(double) > MCMC_FAMILY_FILM_BYTES)
      norm = MCMC_NORM_BOOT;
    for (int g = 0; g < n_fam && norm == MCMC_NORM_BUFFERS; g++) {
      if (fam[g].n_chains == 0) continue;
      fam[g].splat = calloc(3 * (size_t)W * (size_t)H, sizeof(double));
      if (!fam[g].splat) norm = MCMC_NORM_BOOT;
    }
    if (norm == MCMC_NORM_BOOT) {
      for (int g = 0; g < n_fam; g++) free(fam[g].splat), fam[g].splat = NULL;
      if (!rs->quiet)
        fprintf(stderr, "lmc: no memory for per-length splat buffers; b from the bootstrap only\n");
    }
  }
  /* Mutations per round (see Allocation above): in proportion to b_g per
   * family, so a family held at MCMC_MIN_CHAINS chains makes fewer
   * mutations per chain. Per-length buffers only: the other two
   * normalisations share one mutation count. */
  {
    double top = 0.0;
    for (int g = 0; g < n_fam; g++)
      if (fam[g].n_chains > 0) top = fmax(top, fam[g].bt.b / fam[g].n_chains);
    for (int g = 0; g < n_fam; g++) {
      fam[g].m_round = MCMC_ROUND;
      fam[g].done = 0;
      if (norm != MCMC_NORM_BUFFERS || rs->mcmc_even || fam[g].n_chains == 0) continue;
      double w = fam[g].bt.b / fam[g].n_chains / top;
      int m = (int)floor(MCMC_ROUND * w + 0.5);
      fam[g].m_round = m < 1 ? 1 : m > MCMC_ROUND ? MCMC_ROUND : m;
    }
  }
  slots = calloc((size_t)n_slots, sizeof *slots);
  if (!slots) {
    status = lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the chains");
    goto done;
  }
  if (M->set_chains) {
    int *family = malloc((size_t)n_slots * sizeof *family);
    if (!family) {
      status = lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the chains");
      goto done;
    }
    for (int g = 0; g < n_fam; g++)
      for (int i = 0; i < fam[g].n_chains; i++) family[fam[g].first_chain + i] = g;
    status = M->set_chains(mrun, n_slots, family, err);
    free(family);
    if (status) goto done;
  }
  for (int g = 0; g < n_fam; g++) {
    mcmc_family *F = &fam[g];
    if (F->n_chains == 0) continue;
    mc_kernel k[MC_MAX_KERNELS] = {mc_kernel_large(),
                                   rs->small_gauss ? mc_kernel_small_gauss(sigma)
                                                   : mc_kernel_small(1.0 / 1024.0, sigma),
                                   mc_kernel_technique(0)};
    double large = rs->largestep;
    double p[MC_MAX_KERNELS] = {large, 1.0 - large, 0.0};
    int nk = 2;
    if (multiplexed && F->st.n_strategies > 1) {
      /* The technique coordinate is the first of the connect stream. */
      k[2] = mc_kernel_technique(mc_target_stream_offset(&F->target, LMC_STREAM_CONNECT));
      p[1] = 0.9 * (1.0 - large);
      p[2] = 0.1 * (1.0 - large);
      nk = 3;
    }
    memcpy(F->kdef, k, sizeof k), memcpy(F->pdef, p, sizeof p);
    F->nkdef = nk;
    if (!(sigma > (rs->small_gauss ? 0.0 : 1.0 / 1024.0) && sigma < 0.5)) {
      status = lmc_error_set(err, LMC_EINVAL, NULL, 0,
                             rs->small_gauss ? "--sigma must lie in (0, 1/2)"
                                             : "--sigma must lie in (1/1024, 1/2)");
      goto done;
    }

    /* Starting states by systematic resampling of the bootstrap in
     * proportion to f. */
    rng pick;
    rng_seed(&pick, rs->seed, mcmc__chain_seq(g, -1));
    double u0 = rng_uniform(&pick), acc = 0.0, total = 0.0;
    for (int64_t q = 0; q < F->bt.n; q++) total += F->bt.f[q]; /* (b may come from fe) */
    int64_t j = 0;
    for (int i = 0; i < F->n_chains; i++) {
      mcmc_chain_slot *sl = &slots[F->first_chain + i];
      sl->family = g;
      sl->scale = (norm == MCMC_NORM_BOOT ? F->bt.b : 1.0) / F->n_chains;
      mc_kernel ki[MC_MAX_KERNELS];
      double pi[MC_MAX_KERNELS];
      memcpy(ki, k, sizeof ki), memcpy(pi, p, sizeof pi);
      int nki = M->chain_kernels ? M->chain_kernels(mrun, F->first_chain + i, ki, pi, nk) : nk;
      status = mc_chain_create(&sl->chain, &F->target, ki, pi, nki, err);
      if (status) goto done;
      sl->cap_rec = 2 * MCMC_ROUND;
      sl->rec = malloc((size_t)sl->cap_rec * sizeof(mcmc_splat));
      if (!sl->rec) {
        status = lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the splats");
        goto done;
      }
      double target = (i + u0) / F->n_chains * total;
      while (j < F->bt.n - 1 && acc + F->bt.f[j] <= target) acc += F->bt.f[j++];
      while (j < F->bt.n - 1 && !(F->bt.f[j] > 0.0)) j++;
      sl->chain->target = &F->target;
      sl->start_seq = mcmc__boot_seq(g, j);
      mc_chain_start(sl->chain, rs->seed, sl->start_seq, mcmc__chain_seq(g, i));
    }
  }
  for (int g = 0; g < n_fam; g++) {
    mc_boot_free(&fam[g].bt);
  }

  /* Chains in rounds. Every chain makes MCMC_ROUND mutations per round. */
  {
    int64_t per_chain = INT64_MAX;
    if (by_spp) {
      /* The budget in full-round mutations: sum_g n_g m_g / MCMC_ROUND chains' worth. */
      int64_t total = rs->spp * (int64_t)W * H, weight = 0;
      for (int g = 0; g < n_fam; g++) weight += (int64_t)fam[g].n_chains * fam[g].m_round;
      per_chain = (total * MCMC_ROUND + weight - 1) / weight;
    }
    double t_chain0 = omp_get_wtime(), next_snapshot = rs->snapshot;
    /* Under --spp the ETA is the chains' own (the bar's clock restarts). */
    if (!timed) bar.start = t_chain0;
    progress_phase(&bar, "chains", timed ? (t_chain0 - t0) / rs->time_limit : 0.0);
    int64_t done_per_chain = 0;
    volatile int stop = 0;
    /* --largestep-scale: from MCMC_LARGESTEP_SCALE_AFTER of the chains'
     * budget on (of their mutations under --spp, of their time under --time). */
    int ls_pending = rs->largestep_scale != 1.0;
    while (done_per_chain < per_chain && !stop) {
      int64_t m = per_chain - done_per_chain < MCMC_ROUND ? per_chain - done_per_chain : MCMC_ROUND;
      if (M->round_limit) {
        int64_t lim = M->round_limit(mrun, done_per_chain, per_chain);
        if (m > lim) m = lim;
      }
      volatile int abandon = 0;
#pragma omp parallel num_threads(nthreads)
      {
        int tid = omp_get_thread_num();
        /* Advance every chain by m mutations, recording its splats. */
#pragma omp for schedule(dynamic, 1)
        for (int i = 0; i < n_slots; i++) {
          mcmc_chain_slot *sl = &slots[i];
          sl->n_rec = 0;
          if (abandon) continue;
          int64_t r0 = mc_chain_rays(sl->chain);
          int64_t mg = mcmc__family_steps(&fam[sl->family], m);
          for (int64_t q = 0; q < mg; q++) mc_chain_step(sl->chain, mcmc__record, sl);
          cnt[tid].rays += mc_chain_rays(sl->chain) - r0;
          if (render_stop_signal() || (timed && omp_get_wtime() - t0 >= rs->time_limit)) abandon = 1;
        }
        /* Add the records in chain order, each thread to its band of rows. */
        if (!abandon) {
          int y_lo = (int)((int64_t)H * tid / nthreads), y_hi = (int)((int64_t)H * (tid + 1) / nthreads);
          for (int i = 0; i < n_slots; i++) {
            double *dst = fam[slots[i].family].splat ? fam[slots[i].family].splat : out->splat;
            for (int q = 0; q < slots[i].n_rec; q++)
              mcmc__splat_rows(out, dst, &s->filter, &slots[i].rec[q], y_lo, y_hi);
          }
        }
      }
      if (abandon) {
        /* The round in flight is dropped (its chains moved on, which is
         * harmless: the render ends here). */
        stop = 1;
        break;
      }
      done_per_chain += m;
      for (int g = 0; g < n_fam; g++) fam[g].done += mcmc__family_steps(&fam[g], m);
      if (ls_pending) {
        double share = by_spp ? (double)done_per_chain / (double)per_chain
                              : (omp_get_wtime() - t_chain0) / fmax(1e-9, rs->time_limit - (t_chain0 - t0));
        if (share >= MCMC_LARGESTEP_SCALE_AFTER) {
          for (int i = 0; i < n_slots; i++) mcmc__scale_large(slots[i].chain, rs->largestep_scale);
          ls_pending = 0;
        }
      }
      mcmc__publish(out, fam, n_fam, slots, norm, done_per_chain, 0);
      if (M->after_round && M->after_round(mrun, done_per_chain, per_chain, omp_get_wtime() - t0)) {
        /* The integrator asks for a restart (stage 1 of lmc --adapt cache
         * ended: its chains ran a fixed kernel, so its image stays; they
         * restart from their bootstrap states with the frozen cache, a
         * fixed kernel given the cache). */
        for (int i = 0; i < n_slots; i++) {
          mc_kernel k2[MC_MAX_KERNELS];
          double p2[MC_MAX_KERNELS];
          const mcmc_family *F = &fam[slots[i].family];
          if (M->note_restart_chain) M->note_restart_chain(mrun, slots[i].chain);
          memcpy(k2, F->kdef, sizeof k2), memcpy(p2, F->pdef, sizeof p2);
          int nk2 = M->chain_kernels ? M->chain_kernels(mrun, i, k2, p2, F->nkdef) : F->nkdef;
          if (mc_chain_set_kernels(slots[i].chain, k2, p2, nk2, err) != LMC_OK) {
            status = LMC_EINVAL;
            goto done;
          }
          if (!ls_pending && rs->largestep_scale != 1.0)
            mcmc__scale_large(slots[i].chain, rs->largestep_scale);
          mc_chain_start(slots[i].chain, rs->seed, slots[i].start_seq,
                         mcmc__chain_seq(slots[i].family, n_slots + i));
        }
      }
      double now = omp_get_wtime();
      if (render_stop_signal()) stop = 1;
      if (timed && now - t0 >= rs->time_limit) stop = 2;
      if (rs->snapshot > 0.0 && rs->snapshot_fn && now - t0 >= next_snapshot) {
        mcmc__publish(out, fam, n_fam, slots, norm, done_per_chain, 1);
        rs->snapshot_fn(rs->snapshot_ctx, out, now - t0);
        while (next_snapshot <= now - t0) next_snapshot += rs->snapshot;
      }
      double frac = by_spp ? (double)done_per_chain / (double)per_chain : 0.0;
      if (timed) frac = fmax(frac, (now - t0) / rs->time_limit);
      progress_update_rate(&bar, frac, (double)mcmc__mutations(fam, n_fam) / fmax(now - t_chain0, 1e-9),
                           "mutations/s");
    }
    progress_finish(&bar);
    /* The final image with the refined b (also after an interruption: the
     * film holds whole rounds, and the tallies of the abandoned round are
     * still independent samples of b). */
    mcmc__publish(out, fam, n_fam, slots, norm, done_per_chain, 1);
    if (norm != MCMC_NORM_BOOT) {
      double v = 0.0;
      st->mcmc_b = mcmc__refine_b(fam, n_fam, slots, &v);
      st->mcmc_b_se = sqrt(v);
    }
    if (render_stop_signal()) st->interrupted = 1;
    else if (timed && done_per_chain < per_chain) st->timed_out = 1;
    st->samples = mcmc__mutations(fam, n_fam);
    st->passes = st->samples / ((int64_t)W * H);
    double chain_seconds = omp_get_wtime() - t_chain0;

    /* Statistics: per kernel, per length (mmlt), mutations per second, b. */
    if (!rs->quiet) {
      const char *names[MC_MAX_KERNELS] = {0};
      mc_kernel_stats tot[MC_MAX_KERNELS];
      memset(tot, 0, sizeof tot);
      int nk = 0;
      int64_t overflow = 0;
      for (int i = 0; i < n_slots; i++) {
        mc_chain *c = slots[i].chain;
        overflow += c->overflow;
        for (int q = 0; q < c->n_kernels; q++) {
          if (q >= nk) names[nk++] = c->kernels[q].name;
          tot[q].proposed += c->stats[q].proposed;
          tot[q].accepted += c->stats[q].accepted;
        }
      }
      for (int q = 0; q < nk; q++)
        fprintf(stderr, "lmc: %-10s proposed %lld, accepted %lld (%.1f%%)\n", names[q],
                (long long)tot[q].proposed, (long long)tot[q].accepted,
                100.0 * (double)tot[q].accepted / fmax(1.0, (double)tot[q].proposed));
      if (multiplexed)
        for (int g = 0; g < n_fam; g++) {
          int64_t pr = 0, ac = 0;
          for (int i = 0; i < fam[g].n_chains; i++)
            for (int q = 0; q < slots[fam[g].first_chain + i].chain->n_kernels; q++) {
              pr += slots[fam[g].first_chain + i].chain->stats[q].proposed;
              ac += slots[fam[g].first_chain + i].chain->stats[q].accepted;
            }
          fprintf(stderr,
                  "lmc: length %-3d b %.5g (%.1f%%, %lld paths), "
                  "%d chains, proposed %lld, accepted %.1f%%\n",
                  fam[g].st.length, fam[g].b_ref,
                  100.0 * sqrt(fam[g].b_ref_var) / fmax(fam[g].b_ref, 1e-300),
                  (long long)(fam[g].bt.n_est + fam[g].n_large),
                  fam[g].n_chains, (long long)pr, 100.0 * (double)ac / fmax(1.0, (double)pr));
        }
      int64_t n_boot = 0, n_plan = 0;
      for (int g = 0; g < n_fam; g++) {
        n_boot += fam[g].bt.n_est;
        n_plan += fam[g].bt.n - fam[g].bt.n_est;
      }
      if (multiplexed) {
        /* b from shared whole BDPT samples; the families' own picked the starts */
        n_boot = shared_paths;
        n_plan = 0;
        for (int g = 0; g < n_fam; g++) n_plan += fam[g].bt.n;
      }
      fprintf(stderr,
              "lmc: %d chains, %.4g mutations/s; b = %.6g +- %.2g (%.2f%%, %lld bootstrap paths%s; "
              "%lld more for planning and starting states)\n",
              n_slots, (double)st->samples / fmax(chain_seconds, 1e-9), b_total, sqrt(b_var),
              100.0 * sqrt(b_var) / fmax(b_total, 1e-300), (long long)n_boot,
              multiplexed ? " (whole BDPT samples, every length)" : "", (long long)n_plan);
      double b_ref = 0.0, b_ref_var = 0.0;
      int64_t n_large = 0;
      for (int g = 0; g < n_fam; g++)
        b_ref += fam[g].b_ref, b_ref_var += fam[g].b_ref_var, n_large += fam[g].n_large;
      /* Only pssmlt's families pool their large steps (mcmc__refine_b). */
      if (norm != MCMC_NORM_BOOT && n_large > 0) {
        fprintf(stderr, "lmc: b with large steps = %.6g +- %.2g (%.2f%%, %lld large steps more)\n",
                b_ref, sqrt(b_ref_var), 100.0 * sqrt(b_ref_var) / fmax(b_ref, 1e-300),
                (long long)n_large);
      }
      if (overflow > 0)
        fprintf(stderr, "lmc: %lld coordinates drawn past the state's blocks\n", (long long)overflow);
      if (M->report) {
        mc_chain **chains = malloc((size_t)n_slots * sizeof *chains);
        if (chains) {
          for (int i = 0; i < n_slots; i++) chains[i] = slots[i].chain;
          M->report(mrun, chains, n_slots, chain_seconds);
          free(chains);
        }
      }
    }
  }

finish:
  status = LMC_OK;
  for (int t = 0; t < nthreads; t++) {
    st->rays += cnt[t].rays;
  }
  for (int i = 0; i < n_slots; i++)
    if (slots && slots[i].chain && slots[i].chain->scratch)
      st->nan_samples += M->nan_samples ? M->nan_samples(mrun, slots[i].chain)
                         : bdpt_states       ? mc_bdpt_states_nan_samples(slots[i].chain->scratch) +
                                             mc_bdpt_states_nan_samples(slots[i].chain->scratch_alt)
                                       : ((mcmc_scratch *)slots[i].chain->scratch)->cnt.nan_samples;
done:
  progress_end(&bar);
  mcmc__free_slots(slots, n_slots);
  if (M->destroy) M->destroy(mrun);
  for (int g = 0; g < n_fam; g++)
    mc_boot_free(&fam[g].bt), free(fam[g].step_scale), free(fam[g].splat),
        mc_bdpt_states_free(&fam[g].bst);
  free(cnt);
  st->seconds = omp_get_wtime() - t0;
  if (status) film_free(out);
  return status;
}
