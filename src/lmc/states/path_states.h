/*
 * path_states.h: the state space `path` (path_states.c): whole light paths
 * for path-space Metropolis light transport, and the moves its chains
 * know (the `coord` of their MC_KERNEL_OWN kernels).
 */
#ifndef LMC_MCMC_PATH_STATES_H
#define LMC_MCMC_PATH_STATES_H

/* The moves of a path chain. */
typedef enum mc_path_move {
  MC_PATH_MOVE_BIDIR = 0,     /* Veach's bidirectional mutation (lmc/path/mut_bidir.h) */
  MC_PATH_MOVE_LENS,          /* the lens perturbation (lmc/path/mut_perturb.h) */
  MC_PATH_MOVE_MULTICHAIN,    /* the multi-chain perturbation */
  MC_PATH_MOVE_CAUSTIC,       /* the caustic perturbation */
  MC_PATH_MOVE_LENSSUB,       /* the lens subpath mutation (lmc/path/mut_lenssub.h) */
  MC_PATH_MOVE_PSS,           /* a primary-sample small step (lmc/path/mut_pss.h); the moves
                                 before it are path space's own, which the fused move of the
                                 primary-sample states draws among (MC_PATH_MOVE_FUSED) */
  MC_PATH_MOVE_MANIFOLD,      /* the manifold perturbation (lmc/path/mut_manifold.h; not yet
                                 among the fused move's) */
  MC_PATH_MOVE_HSLT,          /* HSLT's half-vector perturbation (mut_manifold.h; likewise) */
  MC_PATH_MOVE_COUNT
} mc_path_move;

#define MC_PATH_MOVE_FUSED MC_PATH_MOVE_PSS /* path space's own moves: 0 .. this - 1 */

#endif
