/*
 * integrator_mlt.c: `--integrator mlt`, path-space Metropolis light
 * transport (Veach and Guibas 1997; Veach 1997, chapter 11), on the MCMC
 * driver (method.h) and the path states (path_states.c): chains of whole
 * light paths moved by Veach's bidirectional mutation (lmc/path/mut_bidir.h),
 * which deletes a subpath (possibly the whole path) and regenerates it from
 * both ends. As Veach's, direct light is rendered apart by default
 * (--direct separate). The perturbations (lens, caustic, multi-chain) are
 * to come.
 */
#include "lmc/driver/method.h"
#include "lmc/states/path_states.h"

static int mlt__chain_kernels(void *run, const mc_method_setup *setup, int i,
                              const mc_space_family *F, mc_kernel *k, double *p) {
  (void)run, (void)setup, (void)i, (void)F;
  k[0] = (mc_kernel){.name = "bidir", .kind = MC_KERNEL_OWN, .coord = MC_PATH_MOVE_BIDIR};
  p[0] = 1.0;
  return 1;
}

const mc_method mc_method_mlt = {
    .name = "mlt",
    .default_states = MCMC_STATES_PATH,
    .chain_kernels = mlt__chain_kernels,
};
