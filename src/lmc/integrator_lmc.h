/*
 * integrator_lmc.h: `--integrator lmc`, Langevin Monte Carlo rendering
 * (Luan, Zhao, Bala and Gkioulekas 2020), as a client of the MCMC driver
 * (mcmc.c) and the chain framework (chain.h).
 *
 * The states (--states, the driver's, mcmc.c). `bdpt` (the default): one
 * family over every length, a state being a BDPT sample's numbers and the
 * strategy that carries it (bdpt_states.h, with gradients and Hessians).
 * `mmlt`: the multiplexed bidirectional states of mmlt, one family of
 * chains per path length k, a state being the strategy (s, t) and its
 * camera, light and connect streams; the target (lmc_bdpt_target.c) is
 * path_eval_bdpt with the gradient (and Hessian) of its MIS-weighted
 * contribution, the state space of the LMC paper's own implementation.
 * `pt`: the unidirectional path of path_eval_pt (pt_li's estimator with
 * next-event estimation) over the camera stream (lmc_target.c), with
 * f = W H lum(L).
 *
 * Each chain mixes the large step (--largestep), Kelemen's isotropic
 * small step (--iso-prob), for mmlt states the technique mutation
 * (LMC_TECHNIQUE_PROB, as mmlt), and LMC's preconditioned MALA step
 * (lmc_kernel.h; the rest). Both small steps are scaled down on the
 * coordinates that pick a light triangle (mc_light_u1_scale and
 * mc_pt_step_scale, as mmlt and pssmlt); for MALA that is a constant
 * factor c^2 of the preconditioner, with the gradient, its truncation and
 * Adam taken in the rescaled coordinates. With --adapt cache and
 * LMC_INDEP_PROB > 0 the cache's independence proposal joins them (in
 * stage 1, where there is no cache yet, its slot makes a Kelemen step). It
 * is off: on ring-caustics (pt states) it accepted 0 of 51291 proposals in
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
 * The driver runs lmc and h2mc through their tables mc_method_lmc and
 * mc_method_h2mc (method.h): targets per family (one, or one per length
 * on mmlt's states), kernels per chain, stage 1's end as the hook after a
 * round (its return 1 restarts the chains from their starting states;
 * splats and mutation counts carry on), and their statistics lines.
 */
#ifndef LMC_MCMC_INTEGRATOR_LMC_H
#define LMC_MCMC_INTEGRATOR_LMC_H

#include <stdint.h>

#include "lmc/states.h"
#include "lmc/chain.h"
#include "render/scene.h"
#include "render/settings.h"

#define LMC_INDEP_PROB 0.0 /* --adapt cache: share of the independence proposal (off: see above) */
#define LMC_TECHNIQUE_PROB 0.1 /* mmlt states: share of the technique mutation */
#define LMC_UNBOUNDED_PT 16    /* pt states: bounces kept in the state when maxdepth is -1 */
#define LMC_MALA_MIN_LENGTH 3  /* mmlt states: shorter paths take no MALA step (Kelemen's instead) */

/* ---- The scene target (lmc_target.c) ------------------------------------- */

typedef struct lmc_scene_target {
  const scene *s;     /* borrowed */
  render_settings rs;
  double area;        /* W H: 1 / density of the film position */
} lmc_scene_target;

/* Sets up *OUT_target over ctx (both owned by the caller, ctx must outlive
 * the target): camera stream of PT_DIMS_CAMERA + PT_DIMS_PER_BOUNCE
 * (bounces + 1) coordinates, bounces = maxdepth or `unbounded` when -1. */
void lmc_target_init(mc_target *OUT_target, lmc_scene_target *ctx, const scene *s,
                     const render_settings *rs, int unbounded);
/* Gradient evaluations made in a scratch of this target. */
int64_t lmc_target_scratch_grad_evals(const void *scratch);
/* The path length (segments) a state's cache key stands for (pt layout):
 * the deepest differentiated coordinate's bounce + 2, or 1 for the film. */
int lmc_target_length_of_key(int key);

/* ---- The multiplexed bidirectional target (lmc_bdpt_target.c) ---------- */

typedef struct lmc_bdpt_target {
  const scene *s;     /* borrowed */
  render_settings rs; /* mindepth -1: the family's length is what counts */
  int length;         /* k, segments */
  int n_strategies;   /* n_k: 1 for k = 1, else k + 1 */
  double margin;      /* filter radius r */
  double area;        /* (W + 2r)(H + 2r) */
} lmc_bdpt_target;

/* Sets up *OUT_target for paths of `length` segments over ctx (both owned
 * by the caller; ctx must outlive the target), with mmlt's layout. */
void lmc_bdpt_target_init(mc_target *OUT_target, lmc_bdpt_target *ctx, const scene *s,
                          const render_settings *rs, int length);
/* Gradient evaluations and non-finite contributions in a scratch of it. */
int64_t lmc_bdpt_scratch_grad_evals(const void *scratch);
int64_t lmc_bdpt_scratch_nan_samples(const void *scratch);
/* Hessian evaluations (eval_hess) in a scratch of it. */
int64_t lmc_bdpt_scratch_hess_evals(const void *scratch);

#endif
