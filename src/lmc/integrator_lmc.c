/*
 * integrator_lmc.c: the LMC integrator's state over a render: per-chain
 * kernels, the two stages of --adapt cache, and the statistics (see
 * integrator_lmc.h for the model and the driver's protocol).
 *
 * Stage 1 records into one gcache per chain (no locks; each chain is
 * driven by one thread at a time) holding LMC_CACHE_DOUBLES / n doubles;
 * at the switch the per-chain caches are merged into one, frozen, and the
 * per-chain ones freed.
 */
#include "lmc/integrator_lmc.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/gcache.h"
#include "lmc/lmc_kernel.h"
#include "lmc/mcmc.h"

#define LMC_CACHE_DOUBLES (16 * 1024 * 1024) /* stage-1 records of all chains: 128 MB */
#define LMC_ANCHORS 256                      /* independence proposal anchors */
#define LMC_CACHE_PER_DIM 2048               /* entries kept per tree (lookup cost) */
#define LMC_INDEP_SIGMA 0.01                 /* its Gaussian width per coordinate */
#define LMC_STALL_STEPS 10000                /* a chain this long without acceptance is stalled */

struct lmc_run {
  lmc_scene_target tctx;
  mc_target target;
  render_settings rs;
  lmc_kernel_params kp;
  double *step_scale;    /* the target's and the kernels' step scale (owned; mcmc_pt_step_scale) */
  int n;                 /* chains */
  lmc_mala *mala;        /* per chain */
  gcache **rec;          /* per chain, stage 1 */
  gcache *cache;         /* merged and frozen */
  lmc_indep indep;       /* shared, read-only in stage 2 */
  int stage1;            /* cache mode, stage 1 running */
  int64_t stage1_mutations;
  double stage1_seconds, build_seconds;
  double chains_start;   /* omp_get_wtime() when the chains were set up */
};

lmc_status lmc_run_create(lmc_run **OUT_run, const scene *s, const render_settings *rs,
                          int unbounded, lmc_error *err) {
  *OUT_run = NULL;
  lmc_run *run = calloc(1, sizeof *run);
  if (!run) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "lmc: out of memory");
  run->rs = *rs;
  lmc_target_init(&run->target, &run->tctx, s, rs, unbounded);
  run->kp = lmc_kernel_params_from_settings(rs);
  /* The light-position numbers of next-event estimation, as pssmlt: a
   * smaller step for the chain's Kelemen step and a factor c^2 on MALA's
   * preconditioner (lmc_kernel.h). */
  run->step_scale = malloc((size_t)run->target.dim * sizeof(double));
  if (!run->step_scale) {
    free(run);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "lmc: out of memory");
  }
  mcmc_pt_step_scale(s, run->target.dim, run->step_scale);
  run->target.step_scale = run->step_scale;
  run->kp.scale = run->step_scale;
  run->indep = (lmc_indep){NULL, LMC_INDEP_SIGMA, run->kp.s1, run->kp.s2};
  run->stage1 = rs->adapt == LMC_ADAPT_CACHE && rs->cache_fraction > 0.0;
  *OUT_run = run;
  return LMC_OK;
}

void lmc_run_destroy(lmc_run *run) {
  if (!run) return;
  for (int i = 0; i < run->n; i++) {
    lmc_mala_free(&run->mala[i]);
    if (run->rec) gcache_destroy(run->rec[i]);
  }
  free(run->mala);
  free(run->rec);
  gcache_destroy(run->cache);
  free(run->step_scale);
  free(run);
}

const mc_target *lmc_run_target(const lmc_run *run) { return &run->target; }
int lmc_run_in_stage1(const lmc_run *run) { return run->stage1; }
int64_t lmc_run_stage1_mutations(const lmc_run *run) { return run->stage1_mutations; }

lmc_status lmc_run_set_chains(lmc_run *run, int n, lmc_error *err) {
  run->mala = calloc((size_t)n, sizeof *run->mala);
  run->rec = calloc((size_t)n, sizeof *run->rec);
  if (!run->mala || !run->rec) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "lmc: out of memory");
  run->n = n;
  run->chains_start = omp_get_wtime();
  for (int i = 0; i < n; i++) {
    lmc_status st = lmc_mala_init(&run->mala[i], run->target.dim, &run->kp, err);
    if (st) return st;
    if (run->stage1) {
      st = gcache_create(&run->rec[i], run->target.dim, LMC_CACHE_DOUBLES / n, err);
      if (st) return st;
      lmc_mala_set_record(&run->mala[i], run->rec[i]);
    }
  }
  if (!run->stage1 && run->rs.adapt == LMC_ADAPT_CACHE) {
    /* --cache-fraction 0: stage 2 with an empty cache (M = I everywhere). */
    lmc_status st = gcache_create(&run->cache, run->target.dim, 0, err);
    if (!st) st = gcache_freeze(run->cache, 0, 0, err);
    if (st) return st;
    for (int i = 0; i < n; i++) lmc_mala_begin_stage2(&run->mala[i], run->cache);
  }
  return LMC_OK;
}

int lmc_run_chain_kernels(lmc_run *run, int i, mc_kernel *OUT_k, double *OUT_p) {
  double large = run->rs.largestep, iso = run->rs.iso_prob;
  double indep = run->rs.adapt == LMC_ADAPT_CACHE ? LMC_INDEP_PROB : 0.0;
  OUT_k[0] = mc_kernel_large();
  OUT_k[1] = mc_kernel_small(run->kp.s1, run->kp.s2);
  OUT_k[2] = lmc_mala_kernel(&run->mala[i]);
  OUT_p[0] = large;
  OUT_p[1] = iso;
  OUT_p[2] = fmax(0.0, 1.0 - large - iso - indep);
  if (indep == 0.0) return 3;
  OUT_k[3] = lmc_indep_kernel(&run->indep);
  OUT_p[3] = indep;
  return 4;
}

/* Ends stage 1: merge, freeze, switch every chain's kernel to the cache. */
static void lmc__end_stage1(lmc_run *run, int64_t done) {
  double t0 = omp_get_wtime();
  int64_t total = 0;
  for (int i = 0; i < run->n; i++) total += gcache_size(run->rec[i]) * (3 * run->target.dim + 2);
  lmc_error err;
  run->stage1 = 0;
  run->stage1_mutations = done;
  run->stage1_seconds = omp_get_wtime() - run->chains_start;
  if (gcache_create(&run->cache, run->target.dim, total, &err) == LMC_OK) {
    for (int i = 0; i < run->n; i++) gcache_merge(run->cache, run->rec[i]);
    if (gcache_freeze(run->cache, LMC_ANCHORS, LMC_CACHE_PER_DIM, &err) != LMC_OK) {
      gcache_destroy(run->cache);
      run->cache = NULL;
    }
  }
  if (!run->cache) {
    /* Out of memory: an empty frozen cache still gives a valid (isotropic) kernel. */
    if (gcache_create(&run->cache, run->target.dim, 0, &err) == LMC_OK)
      gcache_freeze(run->cache, 0, 0, &err);
  }
  for (int i = 0; i < run->n; i++) {
    gcache_destroy(run->rec[i]);
    run->rec[i] = NULL;
    lmc_mala_begin_stage2(&run->mala[i], run->cache);
    /* Statistics count stage 2 only (the recorded count stays). */
    int64_t recorded = run->mala[i].st.recorded, full = run->mala[i].st.record_full;
    memset(&run->mala[i].st, 0, sizeof run->mala[i].st);
    run->mala[i].st.recorded = recorded, run->mala[i].st.record_full = full;
  }
  run->indep.cache = run->cache;
  run->build_seconds = omp_get_wtime() - t0;
}

/* Stage 1's share of an --spp budget, in mutations per chain. */
static int64_t lmc__stage1_budget(const lmc_run *run, int64_t budget) {
  return (int64_t)ceil(run->rs.cache_fraction * (double)budget);
}

int64_t lmc_run_round_limit(const lmc_run *run, int64_t done, int64_t budget) {
  if (!run->stage1 || budget == INT64_MAX) return INT64_MAX;
  int64_t left = lmc__stage1_budget(run, budget) - done;
  return left > 1 ? left : 1;
}

int lmc_run_after_round(lmc_run *run, int64_t done, int64_t budget, double elapsed) {
  if (!run->stage1) return 0;
  int end;
  /* Under --time, stage 1 gets its share of the time the chains have
   * (what the bootstrap left of the budget). */
  double chains_elapsed = omp_get_wtime() - run->chains_start;
  double chain_time = run->rs.time_limit - (elapsed - chains_elapsed);
  if (run->rs.time_limit > 0.0 && budget == INT64_MAX)
    end = chains_elapsed >= run->rs.cache_fraction * chain_time;
  else
    end = done >= lmc__stage1_budget(run, budget);
  if (!end) return 0;
  lmc__end_stage1(run, done);
  return 1;
}

void lmc_run_report(const lmc_run *run, mc_chain *const *chains, int n, double chain_seconds) {
  static const char *mode[] = {"none", "adam (biased)", "diminish", "cache"};
  int adapt = run->rs.adapt >= 0 && run->rs.adapt <= 3 ? (int)run->rs.adapt : 0;
  fprintf(stderr,
          "lmc: adapt %s, step %g, precond clamp [%g, %g], grad bound %g, iso %g, light-position "
          "step scale %g\n",
          mode[adapt], run->kp.step, run->kp.lo, run->kp.hi, run->kp.grad_bound,
          run->rs.iso_prob, run->target.dim > PT_DIMS_CAMERA + 1 ? run->step_scale[PT_DIMS_CAMERA + 1] : 1.0);
  /* The cache. */
  if (run->rs.adapt == LMC_ADAPT_CACHE && run->cache) {
    int trees = 0;
    for (int d = 1; d <= gcache_max_dim(run->cache); d++) trees += gcache_size_dim(run->cache, d) > 0;
    int64_t lookups = 0, hits = 0;
    for (int i = 0; i < run->n; i++) lookups += run->mala[i].st.lookups, hits += run->mala[i].st.lookup_hits;
    fprintf(stderr,
            "lmc: cache: stage 1 %.2f s, %lld mutations per chain (image discarded); %lld entries "
            "in %d trees, %.1f MB, built in %.3f s, %d anchors; lookups %lld, %.1f%% with neighbours\n",
            run->stage1_seconds, (long long)run->stage1_mutations,
            (long long)gcache_size(run->cache), trees, gcache_bytes(run->cache) / 1048576.0,
            run->build_seconds, gcache_anchor_count(run->cache), (long long)lookups,
            100.0 * (double)hits / fmax(1.0, (double)lookups));
  }
  /* Per proposal type and path length (of the state proposed from). */
  enum { MAXL = 32 };
  int64_t pr[2][MAXL] = {{0}}, ac[2][MAXL] = {{0}};
  int64_t stalled = 0, grad_evals = 0;
  for (int i = 0; i < run->n; i++) {
    const lmc_mala_stats *st = &run->mala[i].st;
    for (int t = 0; t < 2; t++)
      for (int k = 0; k < LMC_STAT_KEYS; k++) {
        int len = t == 0 ? lmc_target_length_of_key(k) : 0;
        if (len >= MAXL) len = MAXL - 1;
        pr[t][len] += st->key_proposed[t][k];
        ac[t][len] += st->key_accepted[t][k];
      }
    if (st->max_streak >= LMC_STALL_STEPS) stalled++;
  }
  int64_t regrad = 0;
  for (int i = 0; i < n; i++) {
    grad_evals += lmc_target_scratch_grad_evals(chains[i]->scratch);
    regrad += chains[i]->regrad;
  }
  for (int len = 0; len < MAXL; len++)
    if (pr[0][len])
      fprintf(stderr, "lmc: mala       length %-3d%s proposed %lld, accepted %lld (%.1f%%)\n", len,
              len == MAXL - 1 ? "+" : " ", (long long)pr[0][len], (long long)ac[0][len],
              100.0 * (double)ac[0][len] / (double)pr[0][len]);
  if (pr[1][0])
    fprintf(stderr, "lmc: mala fallback (no gradient, Kelemen step) proposed %lld, accepted %lld (%.1f%%)\n",
            (long long)pr[1][0], (long long)ac[1][0], 100.0 * (double)ac[1][0] / (double)pr[1][0]);
  fprintf(stderr, "lmc: %.4g gradient evaluations/s (%lld states re-evaluated for their gradient); %lld of %d chains stalled (%d+ steps without an accepted move)\n",
          (double)grad_evals / fmax(chain_seconds, 1e-9), (long long)regrad, (long long)stalled, run->n, LMC_STALL_STEPS);
}
