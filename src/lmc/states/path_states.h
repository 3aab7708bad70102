/*
 * path_states.h: the state space `path` (path_states.c): whole light paths
 * for path-space Metropolis light transport, and the moves its chains
 * know (the `coord` of their MC_KERNEL_OWN kernels).
 */
#ifndef LMC_MCMC_PATH_STATES_H
#define LMC_MCMC_PATH_STATES_H

/* The moves of a path chain. */
typedef enum mc_path_move {
  MC_PATH_MOVE_BIDIR = 0 /* Veach's bidirectional mutation (lmc/path/mut_bidir.h) */
} mc_path_move;

#endif
