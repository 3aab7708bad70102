/*
 * integrator_mmlt.c: `--integrator mmlt`, multiplexed Metropolis light
 * transport (Hachisuka, Kaplanyan and Dachsbacher 2014), on the MCMC
 * driver (method.h). Its states are one family of chains per path length
 * (mmlt_states.h), each state a strategy (s, t) and its numbers; its
 * chains mix the large step, Kelemen's small step and the technique
 * mutation, which redraws the strategy (mc_kernels_metropolis). The
 * families' shares of the mutations follow their b (the driver's
 * allocation), as a single multiplexed chain's would.
 */
#include "lmc/driver/method.h"

static int mmlt__chain_kernels(void *run, const mc_method_setup *setup, int i,
                               const mc_space_family *F, mc_kernel *k, double *p) {
  (void)run, (void)i;
  return mc_kernels_metropolis(setup->ms, F, k, p);
}

const mc_method mc_method_mmlt = {
    .name = "mmlt",
    .default_states = MCMC_STATES_MMLT,
    .chain_kernels = mmlt__chain_kernels,
};
