/*
 * integrator_pssmlt.c: `--integrator pssmlt`, primary-sample-space
 * Metropolis light transport (Kelemen, Szirmay-Kalos, Antal and Csonka
 * 2002), on the MCMC driver (method.h). Its chains mix the large step
 * (--largestep) and Kelemen's small step (--sigma, --small-step), and the
 * technique mutation on states with a strategy coordinate
 * (kernel_mix.h). It runs on the bdpt states by default (one
 * family over every length, a BDPT sample and one of its strategies,
 * bdpt_states.h), as the LMC paper's implementation runs it; --states pt
 * gives Kelemen et al.'s original path-tracer states.
 */
#include "lmc/driver/method.h"

static int pssmlt__chain_kernels(void *run, const mc_method_setup *setup, int i,
                                 const mc_space_family *F, mc_kernel *k, double *p) {
  (void)run, (void)i;
  mc_mix_params mp = mc_mix_params_from(setup->ms, F);
  return mc_kernels_metropolis(&mp, NULL, NULL, k, p);
}

const mc_method mc_method_pssmlt = {
    .name = "pssmlt",
    .default_states = MCMC_STATES_BDPT,
    .media_states = 1u << MCMC_STATES_BDPT | 1u << MCMC_STATES_MMLT | 1u << MCMC_STATES_PT,
    .chain_kernels = pssmlt__chain_kernels,
};
