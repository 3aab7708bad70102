/*
 * integrator_h2mc.c: `--integrator h2mc`, Hessian-Hamiltonian Monte Carlo
 * rendering (Li, Lehtinen, Ramamoorthi, Jakob and Durand 2015), on the
 * MCMC driver (method.h). Its chains mix the large step (--largestep),
 * Kelemen's isotropic small step (--iso-prob), on per-length states the
 * technique mutation (--technique-prob of the rest) and H2MC's
 * proposal (h2mc.h: a Gaussian from the second-order model of log f at the
 * state, with the prior --h2mc-sigma) in what is left. Paths of one or two
 * segments take Kelemen's step instead (f is smooth there; a Hessian costs
 * more than it saves). It needs a state space with Hessians (eval_hess):
 * the bdpt states (the default) or mmlt's. H2MC adapts nothing, so every
 * kernel is fixed and the chains are exact.
 */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

#include "lmc/kernels/h2mc.h"
#include "lmc/kernels/lmc_kernel.h"
#include "lmc/driver/method.h"

#define H2MC_MIN_LENGTH 3       /* per-length states: shorter paths take Kelemen's step */

/* h2mc's own settings (its flags, the table below). */
typedef struct h2mc_settings {
  double sigma;    /* the prior's standard deviation (0: h2mc.h's default) */
  double iso_prob; /* Kelemen's isotropic small step's probability */
  int delayed;     /* delayed acceptance (h2mc_params.delayed) */
} h2mc_settings;

static const h2mc_settings h2mc__defaults = {0.0, 0.4, 1};
static const lmc_opt_table h2mc__options; /* (below) */

typedef struct h2mc_run {
  mcmc_settings ms;
  h2mc_settings hs;
  const mc_space *space; /* borrowed */
  lmc_kernel_params kp;  /* the small steps' s1, s2 (as lmc's) */
  int n;
  int *chain_fam;
  h2mc_kernel *h2;       /* per chain */
} h2mc_run;

static void h2mc__destroy(void *r) {
  h2mc_run *run = r;
  if (!run) return;
  for (int i = 0; i < run->n && run->h2; i++) h2mc_kernel_free(&run->h2[i]);
  free(run->h2);
  free(run->chain_fam);
  free(run);
}

static lmc_status h2mc__create(void **OUT_run, const mc_method_setup *setup, lmc_error *err) {
  *OUT_run = NULL;
  for (int g = 0; g < setup->space->n_fam; g++)
    if (!setup->space->fam[g].target.eval_hess)
      return lmc_error_set(err, LMC_EUNSUPPORTED, NULL, 0,
                           "h2mc runs on states with a Hessian, the bdpt states (--states bdpt, "
                           "the default) or mmlt's (--states mmlt): the %s states have none",
                           setup->space->name);
  h2mc_run *run = calloc(1, sizeof *run);
  if (!run) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "h2mc: out of memory");
  run->ms = *setup->ms;
  lmc_status st = lmc_opt_read(&h2mc__options, setup->rs, &run->hs, err);
  if (st) {
    free(run);
    return st;
  }
  run->space = setup->space;
  /* The small step's offsets as lmc's: in (1/1024, --sigma]. */
  run->kp = lmc_kernel_params_default();
  if (setup->ms->sigma > run->kp.s1 && setup->ms->sigma < 0.5) run->kp.s2 = setup->ms->sigma;
  *OUT_run = run;
  return LMC_OK;
}

static lmc_status h2mc__set_chains(void *r, int n, const int *family, lmc_error *err) {
  h2mc_run *run = r;
  run->h2 = calloc((size_t)n, sizeof *run->h2);
  run->chain_fam = calloc((size_t)n, sizeof *run->chain_fam);
  if (!run->h2 || !run->chain_fam) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "h2mc: out of memory");
  h2mc_params hp = h2mc_params_default();
  if (run->hs.sigma > 0.0) hp.sigma = run->hs.sigma;
  hp.delayed = run->hs.delayed;
  for (int i = 0; i < n; i++) {
    run->chain_fam[i] = family[i];
    lmc_status st = h2mc_kernel_init(&run->h2[i], &run->space->fam[family[i]].target, &hp, err);
    run->n = i + 1;
    if (st) return st;
  }
  return LMC_OK;
}

static int h2mc__chain_kernels(void *r, const mc_method_setup *setup, int i,
                               const mc_space_family *F, mc_kernel *OUT_k, double *OUT_p) {
  (void)setup;
  h2mc_run *run = r;
  /* The driver's mix (kernel_mix.h), H2MC's proposal in what the large
   * step, Kelemen's isotropic step and the technique mutation leave; short
   * paths give H2MC's slot nothing, the mix is renormalised. */
  mc_mix_params mp = mc_mix_params_from(&run->ms, F);
  mp.s1 = run->kp.s1, mp.s2 = run->kp.s2;
  mp.small = run->hs.iso_prob;
  mp.min_length = H2MC_MIN_LENGTH;
  mc_kernel own = h2mc_kernel_make(&run->h2[i]);
  return mc_kernels_metropolis(&mp, &own, NULL, OUT_k, OUT_p);
}

/* Every chain's kernel counters summed over the ranks (method.h). */
static void h2mc__share_stats(void *r) {
  h2mc_run *run = r;
  _Static_assert(sizeof(h2mc_stats) % sizeof(int64_t) == 0, "h2mc_stats holds int64_t only");
  if (run->n > 0) mc_share_counters(&run->h2[0].st, run->n, sizeof *run->h2, sizeof(h2mc_stats));
}

static void h2mc__report(void *r, mc_chain *const *chains, int n, double chain_seconds,
                         const mc_counts *counts) {
  const h2mc_run *run = r;
  fprintf(stderr, "h2mc: %s states, prior sigma %g, L %g, iso %g, light-triangle step scale %g\n",
          run->space->name, run->n > 0 ? run->h2[0].p.sigma : 0.0,
          run->n > 0 ? run->h2[0].p.L : 0.0, run->hs.iso_prob,
          run->space->n_fam > 0 ? mc_step_scale_min(&run->space->fam[0].target) : 1.0);
  int64_t hp = 0, hm = 0, ho = 0, hf = 0, hb = 0;
  for (int i = 0; i < run->n; i++) {
    hp += run->h2[i].st.proposed, hm += run->h2[i].st.model;
    ho += run->h2[i].st.outside, hf += run->h2[i].st.eig_fail, hb += run->h2[i].st.built;
  }
  const mc_counts c = *counts;
  int64_t screened = 0, passed = 0;
  for (int i = 0; i < n; i++) screened += chains[i]->screened, passed += chains[i]->screen_passed;
  if (screened)
    fprintf(stderr, "h2mc: delayed acceptance: %lld first tests (at the current state's model), "
                    "%.1f%% passed (then evaluated with the Hessian)\n",
            (long long)screened, 100.0 * (double)passed / (double)screened);
  fprintf(stderr,
          "h2mc: %lld proposals, %.1f%% from the Hessian's model (the rest the prior alone), "
          "%.1f%% outside the unit cube (rejected unevaluated), %.2f Gaussians built per proposal "
          "(the rest kept), %lld failed eigendecompositions; "
          "%lld Hessian evaluations (%.4g/s), %lld with the gradient alone\n",
          (long long)hp, 100.0 * (double)hm / fmax(1.0, (double)hp),
          100.0 * (double)ho / fmax(1.0, (double)hp), (double)hb / fmax(1.0, (double)hp),
          (long long)hf, (long long)c.hess_evals,
          (double)c.hess_evals / fmax(chain_seconds, 1e-9),
          (long long)(c.grad_evals - c.hess_evals));
}

static const lmc_opt h2mc__opts[] = {
    {"h2mc-sigma", LMC_OPT_DOUBLE, offsetof(h2mc_settings, sigma), 0, 1e-6, 0.5, NULL, NULL, 0,
     "S", "0.01", "the prior's standard deviation on the proposal's offset", NULL},
    {"iso-prob", LMC_OPT_DOUBLE, offsetof(h2mc_settings, iso_prob), 0, 0, 1, NULL, NULL, 0, "P",
     NULL, "probability of Kelemen's isotropic small step (lmc, h2mc)", NULL},
    {"delayed", LMC_OPT_CHOICE, offsetof(h2mc_settings, delayed), 0, 0, 0, lmc_opt_off_on, NULL, 0,
     NULL, NULL,
     "H2MC proposals first tested at the current state's quadratic model, the Hessian at the "
     "proposal only when they pass (delayed acceptance, exact)", NULL},
};

static const lmc_opt_table h2mc__options = {"H2MC (--integrator h2mc)", h2mc__opts, 3,
                                            &h2mc__defaults, sizeof(h2mc_settings)};

const mc_method mc_method_h2mc = {
    .name = "h2mc",
    .default_states = MCMC_STATES_BDPT,
    .opts = &h2mc__options,
    .create = h2mc__create,
    .destroy = h2mc__destroy,
    .set_chains = h2mc__set_chains,
    .chain_kernels = h2mc__chain_kernels,
    .share_stats = h2mc__share_stats,
    .report = h2mc__report,
};
