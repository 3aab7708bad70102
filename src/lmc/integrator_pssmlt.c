/*
 * integrator_pssmlt.c: `--integrator pssmlt` (Kelemen, Szirmay-Kalos,
 * Antal and Csonka 2002) and `--integrator mmlt` (Hachisuka, Kaplanyan and
 * Dachsbacher 2014) on the MCMC driver (method.h). Both take the driver's
 * targets and its default kernels (the large step, Kelemen's small step
 * and, on mmlt's per-length states, the technique mutation); they differ
 * in the state space they run on without --states: pssmlt on the bdpt
 * states (one family over every length), mmlt on its per-length families.
 * The state spaces themselves are described in mcmc.c.
 */
#include "lmc/method.h"

const mc_method mc_method_pssmlt = {.name = "pssmlt", .default_states = MCMC_STATES_BDPT};

const mc_method mc_method_mmlt = {.name = "mmlt", .default_states = MCMC_STATES_MMLT};
