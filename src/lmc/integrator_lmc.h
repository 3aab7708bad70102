/*
 * integrator_lmc.h: `--integrator lmc`, Langevin Monte Carlo rendering
 * (Luan, Zhao, Bala and Gkioulekas 2020), as a client of the MCMC driver
 * (mcmc.c) and the chain framework (chain.h).
 *
 * The states (--lmc-states). `mmlt` (the default): the chains live in the
 * multiplexed bidirectional states of mmlt (mcmc.c), one family of chains
 * per path length k, a state being the strategy (s, t) and its camera,
 * light and connect streams; the target (lmc_bdpt_target.c) is
 * path_eval_bdpt with the gradient of its MIS-weighted contribution. This
 * is the state space of the LMC paper's own implementation. `pt`: the
 * unidirectional path of path_eval_pt (pt_li's estimator with next-event
 * estimation) over the camera stream (lmc_target.c), pssmlt's states, with
 * f = W H lum(L).
 *
 * Each chain mixes the large step (--largestep), Kelemen's isotropic
 * small step (--iso-prob), for mmlt states the technique mutation
 * (LMC_TECHNIQUE_PROB, as mmlt), and LMC's preconditioned MALA step
 * (lmc_kernel.h; the rest). Both small steps are scaled down on the
 * coordinates that pick a light triangle (mcmc_light_u1_scale and
 * mcmc_pt_step_scale, as mmlt and pssmlt); for MALA that is a constant
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
 * The driver calls, in order: lmc_run_create (the targets: one, or one per
 * length for mmlt states; lmc_run_n_families, lmc_run_family_target), lmc_run_set_chains,
 * lmc_run_chain_kernels per chain, lmc_run_round_limit before and
 * lmc_run_after_round after every round
 * (a return of 1 means stage 1 just ended: restart the chains from their
 * starting states; splats and mutation counts carry on), lmc_run_report,
 * lmc_run_destroy.
 */
#ifndef LMC_MCMC_INTEGRATOR_LMC_H
#define LMC_MCMC_INTEGRATOR_LMC_H

#include <stdint.h>

#include "lmc/chain.h"
#include "render/scene.h"
#include "render/settings.h"

#define LMC_INDEP_PROB 0.0 /* --adapt cache: share of the independence proposal (off: see above) */
#define LMC_TECHNIQUE_PROB 0.1 /* mmlt states: share of the technique mutation */
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

/* ---- The run ------------------------------------------------------------- */

typedef struct lmc_run lmc_run;

/* pt states (rs->lmc_states): one family, `unbounded` bounces kept in the
 * state when maxdepth is -1. mmlt states: one family per length
 * kmin .. kmax. */
lmc_status lmc_run_create(lmc_run **OUT_run, const scene *s, const render_settings *rs,
                          int unbounded, int kmin, int kmax, lmc_error *err);
void lmc_run_destroy(lmc_run *run);
/* The families' targets (owned by run). */
int lmc_run_n_families(const lmc_run *run);
const mc_target *lmc_run_family_target(const lmc_run *run, int g);
/* Path length of family g (0 for pt states: all lengths). */
int lmc_run_family_length(const lmc_run *run, int g);
/* Allocates per-chain state for n chains; chain i belongs to family[i]. */
lmc_status lmc_run_set_chains(lmc_run *run, int n, const int *family, lmc_error *err);
/* Non-finite contributions dropped in a chain's scratch. */
int64_t lmc_run_scratch_nan_samples(const lmc_run *run, const void *scratch);
/* The kernels and probabilities of chain i into k[MC_MAX_KERNELS], p[]. */
int lmc_run_chain_kernels(lmc_run *run, int i, mc_kernel *OUT_k, double *OUT_p);
/* After a round: done / budget mutations per chain (budget INT64_MAX under
 * --time), seconds since the render began. Returns 1 when stage 1 ended
 * now (see above), 0 otherwise. */
int lmc_run_after_round(lmc_run *run, int64_t done, int64_t budget, double elapsed);
/* Adds the gradient evaluations chain c has made so far to stage 1's
 * count (call for every chain when stage 1 has ended, before stage 2's
 * first round), so that the report can give stage 2's own. */
void lmc_run_note_stage1_chain(lmc_run *run, const mc_chain *c);
/* The most mutations per chain the next round may make (stage 1 ends on
 * its share of an --spp budget exactly; INT64_MAX: no limit). */
int64_t lmc_run_round_limit(const lmc_run *run, int64_t done, int64_t budget);
/* 1 while stage 1 (cache building) runs. */
int lmc_run_in_stage1(const lmc_run *run);
/* Mutations per chain spent in stage 1. */
int64_t lmc_run_stage1_mutations(const lmc_run *run);
/* Prints the LMC statistics (stderr) for the chains. */
void lmc_run_report(const lmc_run *run, mc_chain *const *chains, int n, double chain_seconds);

#endif
