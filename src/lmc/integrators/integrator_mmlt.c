/*
 * integrator_mmlt.c: `--integrator mmlt`, multiplexed Metropolis light
 * transport (Hachisuka, Kaplanyan and Dachsbacher 2014), on the MCMC
 * driver (method.h). Its states are one family of chains per path length
 * (mmlt_states.h), each state a strategy (s, t) and its numbers; its
 * chains mix the large step, Kelemen's small step and the technique
 * mutation, which redraws the strategy (mc_kernels_metropolis). With
 * --technique-jump P, a share P of the mutations that are not large steps
 * are reversible jumps (mmlt_jump.h: the path kept, its strategy changed,
 * Bitterli et al. 2017), taken from the small steps' share. The families'
 * shares of the mutations follow their b (the driver's allocation), as a
 * single multiplexed chain's would.
 */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/driver/method.h"
#include "lmc/states/mmlt_jump.h"

typedef struct mmlt_settings {
  double jump_prob; /* --technique-jump */
} mmlt_settings;

static const mmlt_settings mmlt__defaults = {0.0};
static const lmc_opt_table mmlt__options; /* (below) */

typedef struct mmlt_run {
  mmlt_settings ms;
  const mc_space *space; /* borrowed */
  int n;
  mc_mmlt_jump *jump;    /* per chain (NULL: no jumps) */
} mmlt_run;

static void mmlt__destroy(void *r) {
  mmlt_run *run = r;
  if (!run) return;
  for (int i = 0; i < run->n && run->jump; i++) mc_mmlt_jump_free(&run->jump[i]);
  free(run->jump);
  free(run);
}

static lmc_status mmlt__create(void **OUT_run, const mc_method_setup *setup, lmc_error *err) {
  *OUT_run = NULL;
  mmlt_run *run = calloc(1, sizeof *run);
  if (!run) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "mmlt: out of memory");
  lmc_status st = lmc_opt_read(&mmlt__options, setup->rs, &run->ms, err);
  if (!st && run->ms.jump_prob > 0.0 && strcmp(setup->space->name, "mmlt") != 0)
    st = lmc_error_set(err, LMC_EUNSUPPORTED, NULL, 0,
                       "--technique-jump runs on the mmlt states (the default of mmlt), not the "
                       "%s states",
                       setup->space->name);
  if (!st && run->ms.jump_prob + setup->ms->technique_prob > 1.0)
    st = lmc_error_set(err, LMC_EINVAL, NULL, 0,
                       "--technique-jump %g and --technique-prob %g share the mutations that are "
                       "not large steps: together at most 1",
                       run->ms.jump_prob, setup->ms->technique_prob);
  if (st) {
    free(run);
    return st;
  }
  run->space = setup->space;
  *OUT_run = run;
  return LMC_OK;
}

static lmc_status mmlt__set_chains(void *r, int n, const int *family, lmc_error *err) {
  mmlt_run *run = r;
  if (!(run->ms.jump_prob > 0.0)) return LMC_OK;
  run->jump = calloc((size_t)n, sizeof *run->jump);
  if (!run->jump) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "mmlt: out of memory");
  for (int i = 0; i < n; i++) {
    lmc_status st = mc_mmlt_jump_init(&run->jump[i], &run->space->fam[family[i]].target, err);
    run->n = i + 1;
    if (st) return st;
  }
  return LMC_OK;
}

static int mmlt__chain_kernels(void *r, const mc_method_setup *setup, int i,
                               const mc_space_family *F, mc_kernel *k, double *p) {
  mmlt_run *run = r;
  int n = mc_kernels_metropolis(setup->ms, F, k, p);
  if (!run || !run->jump || F->technique < 0) return n;
  /* The jump's share of the non-large mutations, from the small step's. */
  double jump = run->ms.jump_prob * (1.0 - setup->ms->largestep);
  p[1] = p[1] - jump > 0.0 ? p[1] - jump : 0.0;
  k[n] = mc_mmlt_jump_kernel(&run->jump[i]);
  p[n] = jump;
  return n + 1;
}

static void mmlt__share_stats(void *r) {
  mmlt_run *run = r;
  _Static_assert(sizeof(mc_mmlt_jump_stats) % sizeof(int64_t) == 0, "int64_t counters only");
  if (run && run->n > 0)
    mc_share_counters(&run->jump[0].st, run->n, sizeof *run->jump, sizeof(mc_mmlt_jump_stats));
}

static void mmlt__report(void *r, mc_chain *const *chains, int n, double chain_seconds,
                         const mc_counts *counts) {
  (void)counts;
  mmlt_run *run = r;
  if (!run || run->n == 0) return;
  mc_mmlt_jump_stats t = {0};
  for (int i = 0; i < run->n; i++) {
    t.proposed += run->jump[i].st.proposed, t.lone += run->jump[i].st.lone;
    t.refused += run->jump[i].st.refused, t.mismatch += run->jump[i].st.mismatch;
    t.inversions += run->jump[i].st.inversions;
  }
  int64_t acc = 0;
  for (int c = 0; c < n; c++)
    for (int q = 0; q < chains[c]->n_kernels; q++)
      if (chains[c]->kernels[q].name && !strcmp(chains[c]->kernels[q].name, "jump"))
        acc += chains[c]->stats[q].accepted;
  double pr = t.proposed > 0 ? (double)t.proposed : 1.0;
  fprintf(stderr,
          "mmlt: technique jumps: %lld proposed, %.1f%% accepted, %.2f%% with no other strategy, "
          "%.3f%% refused (a re-split its walks cannot reach), %.3f%% walked elsewhere; "
          "%lld subpaths inverted (%.4g/s)\n",
          (long long)t.proposed, 100.0 * (double)acc / pr, 100.0 * (double)t.lone / pr,
          100.0 * (double)t.refused / pr, 100.0 * (double)t.mismatch / pr,
          (long long)t.inversions, (double)t.inversions / (chain_seconds > 1e-9 ? chain_seconds : 1e-9));
}

static const lmc_opt mmlt__opts[] = {
    {"technique-jump", LMC_OPT_DOUBLE, offsetof(mmlt_settings, jump_prob), 0, 0, 1, NULL, NULL, 0,
     "P", "0",
     "share of the mutations that are not large steps made reversible jumps: the path kept, "
     "its strategy redrawn by the MIS weights and its numbers found by inverting the subpaths "
     "(mmlt states; exact)",
     NULL},
};

static const lmc_opt_table mmlt__options = {"MMLT (--integrator mmlt)", mmlt__opts, 1,
                                            &mmlt__defaults, sizeof(mmlt_settings)};

const mc_method mc_method_mmlt = {
    .name = "mmlt",
    .default_states = MCMC_STATES_MMLT,
    .opts = &mmlt__options,
    .create = mmlt__create,
    .destroy = mmlt__destroy,
    .set_chains = mmlt__set_chains,
    .chain_kernels = mmlt__chain_kernels,
    .share_stats = mmlt__share_stats,
    .report = mmlt__report,
};
