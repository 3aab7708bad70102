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
#include "lmc/integrators/integrator_lmc.h"

#include <math.h>
#include <omp.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/kernels/gcache.h"
#include "lmc/kernels/lmc_kernel.h"
#include "lmc/driver/method.h"
#include "lmc/states/states.h"
#include "render/dist.h"

#define LMC_CACHE_DOUBLES (16 * 1024 * 1024) /* stage-1 records of all chains: 128 MB */
#define LMC_ANCHORS 256                      /* independence proposal anchors */
#define LMC_CACHE_PER_DIM 256                /* entries kept per tree (lookup cost: brute force in high dimensions) */
#define LMC_CACHE_PER_LABEL 3000             /* labelled states: entries per label (the paper's implementation's size) */
#define LMC_INDEP_SIGMA 0.01                 /* its Gaussian width per coordinate */
#define LMC_STALL_STEPS 10000                /* a chain this long without acceptance is stalled */

/* One family of chains: the space's family and what adapts to it. */
typedef struct lmc__family {
  const mc_space_family *sf; /* borrowed from the space */
  const mc_target *target;   /* &sf->target */
  lmc_kernel_params kp;
  gcache *cache;             /* merged and frozen (cache mode, stage 2) */
  lmc_indep indep;           /* read-only in stage 2 */
} lmc__family;

typedef struct lmc_run lmc_run;

struct lmc_run {
  render_settings rs;    /* the chains' settings */
  mcmc_settings ms;      /* the driver's */
  lmc_settings ls;       /* lmc's own (its flags) */
  const mc_space *space; /* borrowed */
  int n_fam;
  lmc__family *fam;
  int n;                 /* chains */
  int *chain_fam;        /* per chain: its family */
  lmc_mala *mala;        /* per chain */
  lmc_cwalk *cwalk;      /* per chain: stage 2 of --adapt cache on labelled states */
  int cwalk_on;          /* stage 2 runs the cached walk (no gradients) */
  gcache **rec;          /* per chain, stage 1 */
  int stage1;            /* cache mode, stage 1 running */
  int64_t stage1_mutations;
  double stage1_seconds, build_seconds;
  int64_t stage1_grad_evals; /* gradient evaluations when stage 2 began */
};

static void lmc_run_destroy(lmc_run *run);
static const lmc_opt_table lmc__options; /* lmc's flags (below) */

/* One lmc family per family of the space. */
static lmc_status lmc_run_create(lmc_run **OUT_run, const mc_method_setup *setup, lmc_error *err) {
  *OUT_run = NULL;
  const mc_space *sp = setup->space;
  lmc_run *run = calloc(1, sizeof *run);
  if (run) run->fam = calloc((size_t)(sp->n_fam > 0 ? sp->n_fam : 1), sizeof *run->fam);
  if (!run || !run->fam) {
    free(run);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "lmc: out of memory");
  }
  run->rs = *setup->rs;
  run->ms = *setup->ms;
  lmc_status st = lmc_opt_read(&lmc__options, setup->rs, &run->ls, err);
  if (st) {
    free(run->fam), free(run);
    return st;
  }
  run->space = sp;
  run->n_fam = sp->n_fam;
  run->stage1 = run->ls.adapt == LMC_ADAPT_CACHE && run->ls.cache_fraction > 0.0;
  for (int g = 0; g < sp->n_fam; g++) {
    lmc__family *F = &run->fam[g];
    F->sf = &sp->fam[g];
    F->target = &F->sf->target;
    F->kp = lmc_kernel_params_from_settings(&run->ls, run->ms.sigma);
    /* The coordinates that pick a light triangle: a smaller step for the
     * chain's Kelemen step and a factor c^2 on MALA's preconditioner
     * (lmc_kernel.h). */
    F->kp.scale = F->target->step_scale;
    F->indep = (lmc_indep){NULL, LMC_INDEP_SIGMA, F->kp.s1, F->kp.s2};
  }
  *OUT_run = run;
  return LMC_OK;
}

static void lmc_run_destroy(lmc_run *run) {
  if (!run) return;
  for (int i = 0; i < run->n; i++) {
    lmc_mala_free(&run->mala[i]);
    if (run->cwalk) lmc_cwalk_free(&run->cwalk[i]);
    if (run->rec) gcache_destroy(run->rec[i]);
  }
  free(run->mala);
  free(run->cwalk);
  free(run->rec);
  free(run->chain_fam);
  for (int g = 0; g < run->n_fam; g++) {
    gcache_destroy(run->fam[g].cache);
  }
  free(run->fam);
  free(run);
}

/* Gradient evaluations made in a chain's scratch. */
static int64_t lmc__grad_evals(const lmc_run *run, const mc_chain *c) {
  mc_counts n = {0};
  mc_space_counts(run->fam[0].sf, c->scratch, &n);
  mc_space_counts(run->fam[0].sf, c->scratch_alt, &n);
  return n.grad_evals;
}

/* A cache (stage-1 record or merged) of `capacity` doubles for family F:
 * keyed by label for labelled targets (lmc_mala_set_target), else by
 * dimension. */
static lmc_status lmc__record_create(const lmc__family *F, int64_t capacity, gcache **OUT_c,
                                     lmc_error *err) {
  const mc_target *T = F->target;
  if (!T->label_coords) return gcache_create(OUT_c, T->dim, capacity, err);
  int *len = malloc((size_t)T->n_labels * sizeof(int)), *idx = malloc((size_t)T->dim * sizeof(int));
  if (!len || !idx) {
    free(len), free(idx);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "lmc: out of memory");
  }
  for (int l = 0; l < T->n_labels; l++) {
    len[l] = T->label_coords(T, l, idx);
    if (len[l] < 1) len[l] = 1;
  }
  lmc_status st = gcache_create_keyed(OUT_c, T->n_labels, len, capacity, err);
  free(len), free(idx);
  return st;
}

/* An empty frozen cache: M = I everywhere (a valid stage-2 kernel). */
static gcache *lmc__empty_cache(const lmc__family *F) {
  gcache *c = NULL;
  lmc_error err;
  if (lmc__record_create(F, 0, &c, &err) != LMC_OK) return NULL;
  if (gcache_freeze(c, 0, 0, &err) != LMC_OK) {
    gcache_destroy(c);
    return NULL;
  }
  return c;
}

/* Allocates per-chain state for n chains; chain i belongs to family[i]. */
static lmc_status lmc_run_set_chains(lmc_run *run, int n, const int *family, lmc_error *err) {
  run->mala = calloc((size_t)n, sizeof *run->mala);
  run->cwalk = calloc((size_t)n, sizeof *run->cwalk);
  run->rec = calloc((size_t)n, sizeof *run->rec);
  run->chain_fam = calloc((size_t)n, sizeof *run->chain_fam);
  if (!run->mala || !run->cwalk || !run->rec || !run->chain_fam)
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "lmc: out of memory");
  run->n = n;
  if (!run->stage1 && run->ls.adapt == LMC_ADAPT_CACHE) {
    /* --cache-fraction 0: stage 2 with empty caches. */
    for (int g = 0; g < run->n_fam; g++)
      if (!(run->fam[g].cache = lmc__empty_cache(&run->fam[g])))
        return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "lmc: out of memory");
  }
  for (int i = 0; i < n; i++) {
    int g = family[i] >= 0 && family[i] < run->n_fam ? family[i] : 0;
    lmc__family *F = &run->fam[g];
    run->chain_fam[i] = g;
    lmc_status st = lmc_mala_init(&run->mala[i], F->target->dim, &F->kp, err);
    if (st) return st;
    if (F->target->label_coords) lmc_mala_set_target(&run->mala[i], F->target);
    if (run->stage1) {
      st = lmc__record_create(F, LMC_CACHE_DOUBLES / n, &run->rec[i], err);
      if (st) return st;
      lmc_mala_set_record(&run->mala[i], run->rec[i]);
    } else if (run->ls.adapt == LMC_ADAPT_CACHE) {
      lmc_mala_begin_stage2(&run->mala[i], F->cache);
      if (!run->ls.cache_gradient && F->target->label_coords) {
        lmc_cwalk_params cp = lmc_cwalk_params_from_settings(&run->ls);
        st = lmc_cwalk_init(&run->cwalk[i], F->target, F->cache, &cp, err);
        if (st) return st;
        run->cwalk_on = 1;
      }
    }
  }
  return LMC_OK;
}

/* The kernels and probabilities of chain i into k[MC_MAX_KERNELS], p[]:
 * the driver's mix (kernel_mix.h) with MALA in what the large step,
 * Kelemen's isotropic step (--iso-prob), the technique mutation and the
 * cache's independence proposal leave. */
static int lmc_run_chain_kernels(lmc_run *run, int i, mc_kernel *OUT_k, double *OUT_p) {
  lmc__family *F = &run->fam[run->chain_fam[i]];
  mc_mix_params mp = mc_mix_params_from(&run->ms, F->sf);
  mp.s1 = F->kp.s1, mp.s2 = F->kp.s2;
  mp.small = run->ls.iso_prob;
  mp.extra = run->ls.adapt == LMC_ADAPT_CACHE ? run->ls.cache_indep : 0.0;
  /* Paths of one or two segments (emitters seen directly, direct light on
   * a surface) get Kelemen's step instead of MALA: f is smooth there, and a
   * gradient costs more than the few more mutations it saves. */
  mp.min_length = LMC_MALA_MIN_LENGTH;
  /* Stage 2 of --adapt cache on labelled states: the cached walk in
   * MALA's slot (no gradients), unless --cache-gradient on. */
  mc_kernel own = run->cwalk_on && run->cwalk[i].cache ? lmc_cwalk_kernel(&run->cwalk[i])
                                                       : lmc_mala_kernel(&run->mala[i]);
  mc_kernel indep = lmc_indep_kernel(&F->indep);
  return mc_kernels_metropolis(&mp, &own, &indep, OUT_k, OUT_p);
}

/* Over several MPI ranks (dist.h) each rank's chains recorded their own
 * stage 1: the records of every chain another rank ran are copied into
 * this rank's (empty) record of it, so that every rank merges every
 * chain's records in chain order and freezes the cache one process would. */
static void lmc__share_records(lmc_run *run) {
  if (!dist_active()) return;
  int64_t *at = calloc((size_t)run->n + 1, sizeof *at);
  if (!at) dist_abort(1);
  for (int i = 0; i < run->n; i++) {
    int64_t n = 0;
    if (mcmc_chain_here(i) && run->rec[i]) gcache_records(run->rec[i], &n);
    at[i + 1] = n;
  }
  dist_allsum_i64(at + 1, (size_t)run->n);
  for (int i = 0; i < run->n; i++) at[i + 1] += at[i];
  double *buf = calloc((size_t)(at[run->n] > 0 ? at[run->n] : 1), sizeof *buf);
  if (!buf) dist_abort(1);
  for (int i = 0; i < run->n; i++) {
    int64_t n = 0;
    const double *r = mcmc_chain_here(i) && run->rec[i] ? gcache_records(run->rec[i], &n) : NULL;
    if (n > 0) memcpy(buf + at[i], r, (size_t)n * sizeof *buf);
  }
  dist_allsum(buf, (size_t)at[run->n]);
  for (int i = 0; i < run->n; i++)
    if (!mcmc_chain_here(i) && run->rec[i]) gcache_add_records(run->rec[i], buf + at[i], at[i + 1] - at[i]);
  free(buf);
  free(at);
}

/* Ends stage 1: merge per family, freeze, switch every chain's kernel to
 * its family's cache. */
static void lmc__end_stage1(lmc_run *run, int64_t done, double chains_elapsed) {
  double t0 = omp_get_wtime();
  lmc_error err;
  run->stage1 = 0;
  run->stage1_mutations = done;
  run->stage1_seconds = chains_elapsed;
  lmc__share_records(run);
  for (int g = 0; g < run->n_fam; g++) {
    lmc__family *F = &run->fam[g];
    int dim = F->target->dim;
    int64_t total = 0;
    int max_len = dim;
    for (int i = 0; i < run->n; i++)
      if (run->chain_fam[i] == g) total += gcache_size(run->rec[i]) * (3 * max_len + 2);
    if (lmc__record_create(F, total, &F->cache, &err) == LMC_OK) {
      for (int i = 0; i < run->n; i++)
        if (run->chain_fam[i] == g) gcache_merge(F->cache, run->rec[i]);
      int64_t per_key = F->target->label_coords ? LMC_CACHE_PER_LABEL : LMC_CACHE_PER_DIM;
      if (gcache_freeze(F->cache, LMC_ANCHORS, per_key, &err) != LMC_OK) {
        gcache_destroy(F->cache);
        F->cache = NULL;
      }
    }
    /* Out of memory: an empty frozen cache still gives a valid (isotropic) kernel. */
    if (!F->cache) F->cache = lmc__empty_cache(F);
    F->indep.cache = F->cache;
  }
  run->cwalk_on = !run->ls.cache_gradient;
  for (int i = 0; i < run->n; i++) {
    gcache_destroy(run->rec[i]);
    run->rec[i] = NULL;
    const lmc__family *F = &run->fam[run->chain_fam[i]];
    if (run->cwalk_on && F->target->label_coords) {
      lmc_cwalk_params cp = lmc_cwalk_params_from_settings(&run->ls);
      if (lmc_cwalk_init(&run->cwalk[i], F->target, F->cache, &cp, &err) != LMC_OK)
        run->cwalk_on = 0; /* out of memory: the gradient-evaluating stage 2 */
    }
    lmc_mala_begin_stage2(&run->mala[i], run->fam[run->chain_fam[i]].cache);
    /* Statistics count stage 2 only (the recorded count stays). */
    int64_t recorded = run->mala[i].st.recorded, full = run->mala[i].st.record_full;
    memset(&run->mala[i].st, 0, sizeof run->mala[i].st);
    run->mala[i].st.recorded = recorded, run->mala[i].st.record_full = full;
  }
  run->build_seconds = omp_get_wtime() - t0;
}

/* Stage 1's share of an --spp budget, in mutations per chain. */
static int64_t lmc__stage1_budget(const lmc_run *run, int64_t budget) {
  return (int64_t)ceil(run->ls.cache_fraction * (double)budget);
}

/* The most mutations per chain the next round may make: stage 1 ends on
 * its share of an --spp budget exactly (INT64_MAX: no limit). */
static int64_t lmc_run_round_limit(const lmc_run *run, int64_t done, int64_t budget) {
  if (!run->stage1 || budget == INT64_MAX) return INT64_MAX;
  int64_t left = lmc__stage1_budget(run, budget) - done;
  return left > 1 ? left : 1;
}

/* After a round: 1 when stage 1 ended now (the driver then restarts the
 * chains from their starting states; splats and counts carry on). */
static int lmc_run_after_round(lmc_run *run, int64_t done, int64_t budget, double elapsed,
                               double chains_elapsed) {
  if (!run->stage1) return 0;
  int end;
  /* Under --time, stage 1 gets its share of the time the chains have
   * (what the bootstrap left of the budget). */
  double chain_time = run->rs.time_limit - (elapsed - chains_elapsed);
  if (run->rs.time_limit > 0.0 && budget == INT64_MAX)
    end = chains_elapsed >= run->ls.cache_fraction * chain_time;
  else
    end = done >= lmc__stage1_budget(run, budget);
  if (!end) return 0;
  lmc__end_stage1(run, done, chains_elapsed);
  return 1;
}

/* Adds the gradient evaluations chain c made in stage 1 to stage 1's
 * count, so that the report can give stage 2's own. */
static void lmc_run_note_stage1_chain(lmc_run *run, const mc_chain *c) {
  run->stage1_grad_evals += lmc__grad_evals(run, c);
}

/* Steps of the chains since they were last started (stage 2 of the cache). */
static double lmc__steps(mc_chain *const *chains, int n) {
  double s = 0.0;
  for (int i = 0; i < n; i++) s += (double)chains[i]->steps;
  return s;
}

/* The LMC statistics (stderr). */
/* The path length a statistics key of lmc_kernel.h stands for (label + 1
 * on labelled targets, else 1 + the deepest differentiated coordinate;
 * 0 the fallback), MAXL - 1 for the last key and what the space cannot say. */
enum { MAXL = 32 };
static int lmc__key_length(const lmc_run *run, const mc_space_family *SF, int fallback, int key) {
  (void)run;
  if (SF->length > 0) return SF->length < MAXL ? SF->length : MAXL - 1;
  if (fallback) return 0;
  int len = -1;
  if (key > 0 && key < LMC_STAT_KEYS - 1 && SF->length_of)
    len = SF->target.n_labels > 0 ? SF->length_of(SF, key - 1, -1) : SF->length_of(SF, -1, key - 1);
  else if (key == 0 && SF->target.n_labels == 0 && SF->length_of)
    len = 1;
  return len >= 0 && len < MAXL ? len : MAXL - 1;
}

/* Every chain's kernel counters and stage 1's gradient evaluations summed
 * over the ranks (method.h). */
static void lmc_run_share_stats(lmc_run *run) {
  _Static_assert(sizeof(lmc_mala_stats) % sizeof(int64_t) == 0, "int64_t only");
  _Static_assert(sizeof(lmc_cwalk_stats) % sizeof(int64_t) == 0, "int64_t only");
  if (run->n <= 0) return;
  mc_share_counters(&run->mala[0].st, run->n, sizeof *run->mala, sizeof(lmc_mala_stats));
  if (run->cwalk)
    mc_share_counters(&run->cwalk[0].st, run->n, sizeof *run->cwalk, sizeof(lmc_cwalk_stats));
  mc_share_counters(&run->stage1_grad_evals, 1, sizeof(int64_t), sizeof(int64_t));
}

static void lmc_run_report(const lmc_run *run, mc_chain *const *chains, int n, double chain_seconds,
                           const mc_counts *counts) {
  static const char *mode[] = {"none", "adam (biased)", "diminish", "cache"};
  int adapt = run->ls.adapt >= 0 && run->ls.adapt <= 3 ? (int)run->ls.adapt : 0;
  const lmc__family *F0 = &run->fam[0];
  fprintf(stderr,
          "lmc: adapt %s, %s states, step %g (range x%g), precond clamp [%g, %g], grad bound %g, "
          "iso %g, light-triangle step scale %g\n",
          mode[adapt], run->space->name, F0->kp.step, F0->kp.step_range, F0->kp.lo, F0->kp.hi,
          F0->kp.grad_bound, run->ls.iso_prob, mc_step_scale_min(F0->target));
  /* The caches. */
  if (run->ls.adapt == LMC_ADAPT_CACHE) {
    int trees = 0;
    int64_t entries = 0;
    double bytes = 0.0;
    for (int g = 0; g < run->n_fam; g++) {
      const gcache *c = run->fam[g].cache;
      if (!c) continue;
      for (int d = 1; d <= gcache_max_dim(c); d++) trees += gcache_size_dim(c, d) > 0;
      entries += gcache_size(c);
      bytes += (double)gcache_bytes(c);
    }
    int64_t cw_pr = 0, cw_ac = 0, s2_lookups = 0, s2_hits = 0;
    int64_t s2_grads = counts->grad_evals - run->stage1_grad_evals;
    for (int i = 0; i < run->n; i++) {
      if (run->cwalk_on) {
        s2_lookups += run->cwalk[i].st.lookups, s2_hits += run->cwalk[i].st.hits;
        cw_pr += run->cwalk[i].st.proposed, cw_ac += run->cwalk[i].st.accepted;
      }
      s2_lookups += run->mala[i].st.lookups, s2_hits += run->mala[i].st.lookup_hits;
    }
    double s2_rate = lmc__steps(chains, n) /
                     fmax(1e-9, chain_seconds - run->stage1_seconds - run->build_seconds);
    char what[96];
    if (run->cwalk_on)
      snprintf(what, sizeof what, "cached walk (no gradients), proposed %lld, accepted %lld (%.1f%%)",
               (long long)cw_pr, (long long)cw_ac, 100.0 * (double)cw_ac / fmax(1.0, (double)cw_pr));
    else
      snprintf(what, sizeof what, "Langevin proposals with the cached M");
    fprintf(stderr,
            "lmc: stage 2: %s, %.4g mutations/s, %lld lookups (%.1f%% with neighbours), %lld "
            "gradient evaluations\n",
            what, s2_rate, (long long)s2_lookups,
            100.0 * (double)s2_hits / fmax(1.0, (double)s2_lookups), (long long)s2_grads);
    fprintf(stderr,
            "lmc: cache: stage 1 %.2f s, %lld mutations per chain (M = I, image kept); %lld entries "
            "in %d trees over %d families, %.1f MB, built in %.3f s\n",
            run->stage1_seconds, (long long)run->stage1_mutations, (long long)entries, trees,
            run->n_fam, bytes / 1048576.0, run->build_seconds);
  }
  /* Per proposal type and path length (of the state proposed from). */
  int64_t pr[2][MAXL] = {{0}}, ac[2][MAXL] = {{0}};
  int64_t stalled = 0, grad_evals = counts->grad_evals;
  for (int i = 0; i < run->n; i++) {
    const lmc_mala_stats *st = &run->mala[i].st;
    const mc_space_family *SF = run->fam[run->chain_fam[i]].sf;
    for (int t = 0; t < 2; t++)
      for (int k = 0; k < LMC_STAT_KEYS; k++) {
        if (!st->key_proposed[t][k]) continue;
        int len = lmc__key_length(run, SF, t, k);
        pr[t][len] += st->key_proposed[t][k];
        ac[t][len] += st->key_accepted[t][k];
      }
    if (st->max_streak >= LMC_STALL_STEPS) stalled++;
  }
  int64_t regrad = 0, screened = 0, passed = 0;
  for (int i = 0; i < n; i++) {
    regrad += chains[i]->regrad;
    screened += chains[i]->screened;
    passed += chains[i]->screen_passed;
  }
  if (screened)
    fprintf(stderr, "lmc: delayed acceptance: %lld first tests, %.1f%% passed (evaluated with the gradient)\n",
            (long long)screened, 100.0 * (double)passed / (double)screened);
  for (int len = 0; len < MAXL; len++)
    if (pr[0][len])
      fprintf(stderr, "lmc: mala       length %-3d%s proposed %lld, accepted %lld (%.1f%%)\n", len,
              len == MAXL - 1 ? "+" : " ", (long long)pr[0][len], (long long)ac[0][len],
              100.0 * (double)ac[0][len] / (double)pr[0][len]);
  int64_t fpr = 0, fac = 0;
  for (int len = 0; len < MAXL; len++) fpr += pr[1][len], fac += ac[1][len];
  if (fpr)
    fprintf(stderr, "lmc: mala fallback (no gradient, Kelemen step) proposed %lld, accepted %lld (%.1f%%)\n",
            (long long)fpr, (long long)fac, 100.0 * (double)fac / (double)fpr);
  fprintf(stderr, "lmc: %lld gradient evaluations (%.4g/s; %lld states re-evaluated for their gradient); %lld of %d chains stalled (%d+ steps without an accepted move)\n",
          (long long)grad_evals, (double)grad_evals / fmax(chain_seconds, 1e-9), (long long)regrad,
          (long long)stalled, run->n, LMC_STALL_STEPS);
}

/* ---- The flags and the method table (method.h) ------------------------ */

static const char *const lmc__adapts[] = {"none", "adam", "diminish", "cache", NULL};
static const int lmc__adapt_values[] = {LMC_ADAPT_NONE, LMC_ADAPT_ADAM, LMC_ADAPT_DIMINISH,
                                        LMC_ADAPT_CACHE};
static const char *const lmc__on_off[] = {"on", "off", NULL}; /* (stores 1 for off) */

static const lmc_opt lmc__opts[] = {
    {"adapt", LMC_OPT_CHOICE, offsetof(lmc_settings, adapt), 0, 0, 0, lmc__adapts,
     lmc__adapt_values, 0, NULL, NULL,
     "the preconditioner's adaptation: none, adam (biased), diminish or cache", NULL},
    {"step", LMC_OPT_DOUBLE, offsetof(lmc_settings, step), 0, 1e-12, 1, NULL, NULL, 0, "S",
     NULL, "Langevin step s: y ~ N(x + s/2 M g, s M)", NULL},
    {"step-range", LMC_OPT_DOUBLE, offsetof(lmc_settings, step_range), 0, 1, 1e6, NULL, NULL, 0,
     "R", NULL, "each Langevin step draws s log-uniformly from [S/R, S R]", NULL},
    {"adam-eps", LMC_OPT_DOUBLE, offsetof(lmc_settings, adam_eps), 0, 0, 1e6, NULL, NULL, 0, "E",
     NULL, "M = clamp(1 / (E + sqrt(v)), LO, HI)", NULL},
    {"precond-clamp", LMC_OPT_PAIR, offsetof(lmc_settings, precond_lo),
     offsetof(lmc_settings, precond_hi), 1e-300, 1e300, NULL, NULL, 0, "LO,HI", NULL,
     "the clamp of M", NULL},
    {"grad-bound", LMC_OPT_DOUBLE, offsetof(lmc_settings, grad_bound), 0, 1e-9, 1e300, NULL,
     NULL, 0, "B", NULL, "truncate |grad log f| to B", NULL},
    {"cache-fraction", LMC_OPT_DOUBLE, offsetof(lmc_settings, cache_fraction), 0, 0, 0.99, NULL,
     NULL, 0, "F", NULL, "--adapt cache: share of the budget for stage 1", NULL},
    {"iso-prob", LMC_OPT_DOUBLE, offsetof(lmc_settings, iso_prob), 0, 0, 1, NULL, NULL, 0, "P",
     NULL, "probability of Kelemen's isotropic small step (lmc, h2mc)", NULL},
    {"cache-gradient", LMC_OPT_CHOICE, offsetof(lmc_settings, cache_gradient), 0, 0, 0,
     lmc_opt_off_on, NULL, 0, NULL, NULL,
     "--adapt cache, bdpt states: stage 2 evaluates gradients (MALA with the cached M) instead of "
     "the cached walk", NULL},
    {"cache-step", LMC_OPT_DOUBLE, offsetof(lmc_settings, cache_step), 0, 1e-9, 0.5, NULL, NULL,
     0, "S", "0.005", "the cached walk: cov = 1 / (1 / (S^2 (M + 1)) + 1 / P^2)", NULL},
    {"cache-prior", LMC_OPT_DOUBLE, offsetof(lmc_settings, cache_prior), 0, 1e-9, 0.5, NULL,
     NULL, 0, "P", "0.005", "its prior standard deviation, the width where no entry is near", NULL},
    {"cache-radius", LMC_OPT_DOUBLE, offsetof(lmc_settings, cache_radius), 0, 1e-9, 1, NULL,
     NULL, 0, "R", "0.01", "its neighbours lie within R sqrt(n)", NULL},
    {"cache-k", LMC_OPT_INT, offsetof(lmc_settings, cache_k), 0, 1, 32, NULL, NULL, 0, "K", "5",
     "its neighbours", NULL},
    {"cache-drift", LMC_OPT_CHOICE, offsetof(lmc_settings, cache_no_drift), 0, 0, 0, lmc__on_off,
     NULL, 0, NULL, NULL, "drift from the cached first moment", NULL},
    {"cache-indep", LMC_OPT_DOUBLE, offsetof(lmc_settings, cache_indep), 0, 0, 0.5, NULL, NULL,
     0, "P", NULL,
     "--adapt cache: probability of the cache's independence proposal (a Gaussian around a cached "
     "state; on ring-caustics it accepted none of 51291)", NULL},
    {"delayed", LMC_OPT_CHOICE, offsetof(lmc_settings, delayed), 0, 0, 0, lmc_opt_off_on, NULL, 0,
     NULL, NULL, "Langevin proposals first tested without their gradient (delayed acceptance, exact)", NULL},
};

static const lmc_opt_table lmc__options = {"LMC (--integrator lmc)", lmc__opts,
                                           (int)(sizeof lmc__opts / sizeof lmc__opts[0]),
                                           &lmc_settings_defaults, sizeof(lmc_settings)};

static lmc_status lmc__m_create(void **OUT_run, const mc_method_setup *setup, lmc_error *err) {
  lmc_run *run = NULL;
  lmc_status st = lmc_run_create(&run, setup, err);
  *OUT_run = run;
  return st;
}
static void lmc__m_destroy(void *run) { lmc_run_destroy(run); }
static lmc_status lmc__m_set_chains(void *run, int n, const int *family, lmc_error *err) {
  return lmc_run_set_chains(run, n, family, err);
}
static int lmc__m_chain_kernels(void *run, const mc_method_setup *setup, int i,
                                const mc_space_family *F, mc_kernel *k, double *p) {
  (void)setup, (void)F; /* (the run knows chain i's family) */
  return lmc_run_chain_kernels(run, i, k, p);
}
static int64_t lmc__m_round_limit(void *run, int64_t done, int64_t budget) {
  return lmc_run_round_limit(run, done, budget);
}
static int lmc__m_after_round(void *run, int64_t done, int64_t budget, double elapsed,
                              double chains_elapsed) {
  return lmc_run_after_round(run, done, budget, elapsed, chains_elapsed);
}
static void lmc__m_note_restart(void *run, const mc_chain *c) { lmc_run_note_stage1_chain(run, c); }
static void lmc__m_share_stats(void *run) { lmc_run_share_stats(run); }
static void lmc__m_report(void *run, mc_chain *const *chains, int n, double chain_seconds,
                          const mc_counts *counts) {
  lmc_run_report(run, chains, n, chain_seconds, counts);
}

const mc_method mc_method_lmc = {
    .name = "lmc",
    .default_states = MCMC_STATES_BDPT,
    .media_states = 1u << MCMC_STATES_PT, /* gradients through media: the pt states' so far */
    .opts = &lmc__options,
    .create = lmc__m_create,
    .destroy = lmc__m_destroy,
    .set_chains = lmc__m_set_chains,
    .chain_kernels = lmc__m_chain_kernels,
    .round_limit = lmc__m_round_limit,
    .after_round = lmc__m_after_round,
    .note_restart_chain = lmc__m_note_restart,
    .share_stats = lmc__m_share_stats,
    .report = lmc__m_report,
};
