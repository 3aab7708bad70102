/*
 * integrator_mmlt.c: `--integrator mmlt`, multiplexed Metropolis light
 * transport (Hachisuka, Kaplanyan and Dachsbacher 2014), on the MCMC
 * driver (method.h) and by default the mmlt states (mmlt_states.h: one
 * family of chains per path length, each state a strategy (s, t) and its
 * numbers). Its chains mix the large step, Kelemen's small step and the
 * technique mutation, which redraws the strategy (kernel_mix.h).
 * The families' shares of the mutations follow their b (the driver's
 * allocation), as a single multiplexed chain's would. The states' own
 * moves, reversible jumps between strategies (--technique-jump) and
 * path-space mutations fused in (--path-mutations), are the driver's to
 * add (mmlt_moves.c), for this and every other integrator on these states.
 */
#include "lmc/driver/method.h"

static int mmlt__chain_kernels(void *run, const mc_method_setup *setup, int i,
                               const mc_space_family *F, mc_kernel *k, double *p) {
  (void)run, (void)i;
  mc_mix_params mp = mc_mix_params_from(setup->ms, F);
  return mc_kernels_metropolis(&mp, NULL, NULL, k, p);
}

const mc_method mc_method_mmlt = {
    .name = "mmlt",
    .default_states = MCMC_STATES_MMLT,
    .media_states = 1u << MCMC_STATES_BDPT | 1u << MCMC_STATES_MMLT | 1u << MCMC_STATES_PT,
    .chain_kernels = mmlt__chain_kernels,
};
