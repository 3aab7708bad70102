/*
 * integrator_lmc.h: `--integrator lmc`, Langevin Monte Carlo rendering
 * (Luan, Zhao, Bala and Gkioulekas 2020), as a client of the MCMC driver
 * (mcmc.c) and the chain framework (chain.h).
 *
 * The states (--states, space.h). `bdpt` (the default): one family over
 * every length, a state being a BDPT sample's numbers and the strategy
 * that carries it (bdpt_states.h). `mmlt`: the multiplexed bidirectional
 * states of mmlt, one family of chains per path length, the state space of
 * the LMC paper's own implementation (mmlt_states.h). `pt`: a path
 * tracer's numbers (pt_states.c). Each space's target gives f with its
 * gradient on request: the same states and values pssmlt and mmlt run on.
 *
 * Each chain mixes the large step (--largestep), Kelemen's isotropic
 * small step (--iso-prob), for mmlt states the technique mutation
 * (--technique-prob, as mmlt), and LMC's preconditioned MALA step
 * (lmc_kernel.h; the rest). Both small steps are scaled down on the
 * coordinates that pick a light triangle (mc_light_u1_scale and
 * mc_pt_step_scale, as mmlt and pssmlt); for MALA that is a constant
 * factor c^2 of the preconditioner, with the gradient, its truncation and
 * Adam taken in the rescaled coordinates. With --adapt cache and
 * --cache-indep P > 0 the cache's independence proposal joins them (in
 * stage 1, where there is no cache yet, its slot makes a Kelemen step). It
 * is off by default: on ring-caustics (pt states) it accepted 0 of 51291 proposals in
 * a 60 s render (a Gaussian of 0.01 around a cached state in 20 to 65
 * coordinates, the rest uniform, almost never lands on a path of similar
 * contribution) and cost 7% of the time.
 *
 * --adapt cache runs in two stages. Stage 1 takes --cache-fraction of the
 * budget (of the time under --time, of the mutations under --spp): the
 * chains run plain MALA (M = I, a fixed kernel) while they compute online
 * Adam moments of their gradients and record states with them; Adam's M
 * is not used in stage 1, so its image is unbiased and KEPT. Then the
 * per-chain records are merged per family (path length) and frozen into
 * k-d trees, the chains restart from the bootstrap's starting states (the
 * driver's job) and stage 2 renders with the frozen, state-dependent
 * preconditioner, a fixed kernel given the cache. The image is the sum
 * over both stages.
 *
 * The driver runs lmc through its table mc_method_lmc (method.h):
 * kernels per chain, stage 1's end as the hook after a round (its return 1
 * restarts the chains from their starting states; splats and mutation
 * counts carry on), and its statistics lines.
 */
#ifndef LMC_MCMC_INTEGRATOR_LMC_H
#define LMC_MCMC_INTEGRATOR_LMC_H

#include <stdint.h>

#include "lmc/driver/method.h"

#define LMC_MALA_MIN_LENGTH 3  /* mmlt states: shorter paths take no MALA step (Kelemen's instead) */

#endif
