/*
 * integrator_mmlt.c: `--integrator mmlt`, multiplexed Metropolis light
 * transport (Hachisuka, Kaplanyan and Dachsbacher 2014), on the MCMC
 * driver (method.h). Its states are one family of chains per path length
 * (mmlt_states.h), each state a strategy (s, t) and its numbers; its
 * chains mix the large step, Kelemen's small step and the technique
 * mutation, which redraws the strategy (mc_kernels_metropolis). With
 * --technique-jump P, a share P of the mutations that are not large steps
 * are reversible jumps (mmlt_jump.h: the path kept, its strategy changed,
 * Bitterli et al. 2017), and with --path-mutations P a share P are path-space
 * perturbations of the state's path fused into its numbers (mmlt_jump.h),
 * both taken from the small steps' share. The families'
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
  double jump_prob;    /* --technique-jump */
  double perturb_prob; /* --path-mutations */
} mmlt_settings;

static const mmlt_settings mmlt__defaults = {0.0, 0.0};
static const lmc_opt_table mmlt__options; /* (below) */

typedef struct mmlt_run {
  mmlt_settings ms;
  const mc_space *space; /* borrowed */
  int n;
  mc_mmlt_jump *jump;    /* per chain: the strategy jumps (NULL: none) */
  mc_mmlt_jump *perturb; /* per chain: the fused path perturbations (NULL: none) */
} mmlt_run;

static void mmlt__destroy(void *r) {
  mmlt_run *run = r;
  if (!run) return;
  for (int i = 0; i < run->n; i++) {
    if (run->jump) mc_mmlt_jump_free(&run->jump[i]);
    if (run->perturb) mc_mmlt_jump_free(&run->perturb[i]);
  }
  free(run->jump);
  free(run->perturb);
  free(run);
}

static lmc_status mmlt__create(void **OUT_run, const mc_method_setup *setup, lmc_error *err) {
  *OUT_run = NULL;
  mmlt_run *run = calloc(1, sizeof *run);
  if (!run) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "mmlt: out of memory");
  lmc_status st = lmc_opt_read(&mmlt__options, setup->rs, &run->ms, err);
  int moves = run->ms.jump_prob > 0.0 || run->ms.perturb_prob > 0.0;
  if (!st && moves && strcmp(setup->space->name, "mmlt") != 0)
    st = lmc_error_set(err, LMC_EUNSUPPORTED, NULL, 0,
                       "--technique-jump and --path-mutations run on the mmlt states (the "
                       "default of mmlt), not the %s states",
                       setup->space->name);
  if (!st && run->ms.jump_prob + run->ms.perturb_prob + setup->ms->technique_prob > 1.0)
    st = lmc_error_set(err, LMC_EINVAL, NULL, 0,
                       "--technique-jump %g, --path-mutations %g and --technique-prob %g share "
                       "the mutations that are not large steps: together at most 1",
                       run->ms.jump_prob, run->ms.perturb_prob, setup->ms->technique_prob);
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
  if (run->ms.jump_prob > 0.0) run->jump = calloc((size_t)n, sizeof *run->jump);
  if (run->ms.perturb_prob > 0.0) run->perturb = calloc((size_t)n, sizeof *run->perturb);
  if ((run->ms.jump_prob > 0.0 && !run->jump) || (run->ms.perturb_prob > 0.0 && !run->perturb))
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "mmlt: out of memory");
  for (int i = 0; i < n; i++) {
    const mc_target *T = &run->space->fam[family[i]].target;
    lmc_status st = run->jump ? mc_mmlt_jump_init(&run->jump[i], T, 0, err) : LMC_OK;
    if (!st && run->perturb) st = mc_mmlt_jump_init(&run->perturb[i], T, 1, err);
    run->n = i + 1;
    if (st) return st;
  }
  return LMC_OK;
}

static int mmlt__chain_kernels(void *r, const mc_method_setup *setup, int i,
                               const mc_space_family *F, mc_kernel *k, double *p) {
  mmlt_run *run = r;
  int n = mc_kernels_metropolis(setup->ms, F, k, p);
  if (!run) return n;
  /* The moves' shares of the non-large mutations, from the small step's
   * (the jumps only where there is a strategy to change). */
  double rest = 1.0 - setup->ms->largestep;
  if (run->jump && F->technique >= 0) {
    double jump = run->ms.jump_prob * rest;
    p[1] = p[1] - jump > 0.0 ? p[1] - jump : 0.0;
    k[n] = mc_mmlt_jump_kernel(&run->jump[i]);
    p[n++] = jump;
  }
  if (run->perturb) {
    double pert = run->ms.perturb_prob * rest;
    p[1] = p[1] - pert > 0.0 ? p[1] - pert : 0.0;
    k[n] = mc_mmlt_jump_kernel(&run->perturb[i]);
    p[n++] = pert;
  }
  return n;
}

static void mmlt__share_stats(void *r) {
  mmlt_run *run = r;
  _Static_assert(sizeof(mc_mmlt_jump_stats) % sizeof(int64_t) == 0, "int64_t counters only");
  if (!run || run->n == 0) return;
  if (run->jump)
    mc_share_counters(&run->jump[0].st, run->n, sizeof *run->jump, sizeof(mc_mmlt_jump_stats));
  if (run->perturb)
    mc_share_counters(&run->perturb[0].st, run->n, sizeof *run->perturb,
                      sizeof(mc_mmlt_jump_stats));
}

/* One kind of move's statistics line. */
static void mmlt__report_moves(const mmlt_run *run, const mc_mmlt_jump *mv, const char *kname,
                               const char *what, mc_chain *const *chains, int n,
                               double chain_seconds) {
  mc_mmlt_jump_stats t = {0};
  for (int i = 0; i < run->n; i++) {
    t.proposed += mv[i].st.proposed, t.lone += mv[i].st.lone;
    t.refused += mv[i].st.refused, t.mismatch += mv[i].st.mismatch;
    t.inversions += mv[i].st.inversions;
  }
  int64_t acc = 0;
  for (int c = 0; c < n; c++)
    for (int q = 0; q < chains[c]->n_kernels; q++)
      if (chains[c]->kernels[q].name && !strcmp(chains[c]->kernels[q].name, kname))
        acc += chains[c]->stats[q].accepted;
  double pr = t.proposed > 0 ? (double)t.proposed : 1.0;
  fprintf(stderr,
          "mmlt: %s: %lld proposed, %.1f%% accepted, %.2f%% with no move to make, "
          "%.3f%% refused (a path its walks cannot reach), %.3f%% walked elsewhere; "
          "%lld subpaths inverted (%.4g/s)\n",
          what, (long long)t.proposed, 100.0 * (double)acc / pr, 100.0 * (double)t.lone / pr,
          100.0 * (double)t.refused / pr, 100.0 * (double)t.mismatch / pr,
          (long long)t.inversions,
          (double)t.inversions / (chain_seconds > 1e-9 ? chain_seconds : 1e-9));
}

static void mmlt__report(void *r, mc_chain *const *chains, int n, double chain_seconds,
                         const mc_counts *counts) {
  (void)counts;
  mmlt_run *run = r;
  if (!run || run->n == 0) return;
  if (run->jump)
    mmlt__report_moves(run, run->jump, "jump", "technique jumps", chains, n, chain_seconds);
  if (run->perturb)
    mmlt__report_moves(run, run->perturb, "perturb", "path perturbations (fused)", chains, n,
                       chain_seconds);
}

static const lmc_opt mmlt__opts[] = {
    {"technique-jump", LMC_OPT_DOUBLE, offsetof(mmlt_settings, jump_prob), 0, 0, 1, NULL, NULL, 0,
     "P", "0",
     "share of the mutations that are not large steps made reversible jumps: the path kept, "
     "its strategy redrawn by the MIS weights and its numbers found by inverting the subpaths "
     "(mmlt states; exact)",
     NULL},
    {"path-mutations", LMC_OPT_DOUBLE, offsetof(mmlt_settings, perturb_prob), 0, 0, 1, NULL,
     NULL, 0, "P", "0",
     "share of the mutations that are not large steps made path-space perturbations of the "
     "state's path (lens, multi-chain, caustic), mapped back to a strategy's numbers (mmlt "
     "states; exact)",
     NULL},
};

static const lmc_opt_table mmlt__options = {"MMLT (--integrator mmlt)", mmlt__opts, 2,
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
