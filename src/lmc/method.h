/*
 * method.h: the interface between the MCMC driver (mcmc.c) and the MCMC
 * integrators. The driver owns everything the integrators have in common:
 * the state spaces (--states: the pt, the bdpt and mmlt's per-length
 * states, their targets and step scales), the direct pass, the bootstrap
 * and b, the chains' starting states, rounds, budgets, splatting,
 * snapshots and the shared statistics lines. An integrator is a table of
 * functions, mc_method; the driver finds it by name (mc_method_find) and
 * names no integrator itself. Helpers that several integrators use (step
 * scales, mmlt's contribution) live below both, in states.h.
 *
 * What an integrator supplies:
 *   - its default state space (default_states), and whether it runs on
 *     the one asked for (create may refuse with a message);
 *   - optionally its own targets, family by family, in place of the
 *     driver's (lmc and h2mc: targets with gradients and Hessians, in the
 *     same layouts); the driver's step scales are then the target's own;
 *   - its kernels per chain (chain_kernels), given the driver's default
 *     mix: the large step (--largestep), Kelemen's small step (--sigma,
 *     --small-step) and on mmlt's states of length > 1 the technique
 *     mutation (9:1 with the small step);
 *   - optional hooks per round (round_limit, after_round: a return of 1
 *     restarts every chain from its starting state with its kernels
 *     asked again, splats and counts kept, note_restart_chain first),
 *     its statistics lines (report) and its count of non-finite
 *     contributions per chain scratch (nan_samples).
 * pssmlt and mmlt take the driver's targets and default kernels and
 * differ in their default states only (integrator_pssmlt.c).
 *
 * The driver calls, in order: create, family_target per family,
 * set_chains, chain_kernels per chain, per round round_limit before and
 * after_round after, report, destroy. All function pointers but name may
 * be NULL (no run state, the driver's targets, default kernels, no hooks).
 */
#ifndef LMC_MCMC_METHOD_H
#define LMC_MCMC_METHOD_H

#include <stdint.h>

#include "lmc/chain.h"
#include "render/error.h"
#include "render/scene.h"
#include "render/settings.h"

/* What the driver tells an integrator at create. */
typedef struct mc_method_setup {
  const scene *s;            /* borrowed */
  const render_settings *rs; /* the chains' settings: rs->mcmc_states and lmc_states resolved,
                                sigma the small step's, mindepth as the chains see it */
  int states;                /* MCMC_STATES_PT, _MMLT or _BDPT */
  int kmin, kmax;            /* path lengths of the state space (mmlt's: one family each) */
  int n_families;            /* the driver's families (1, or kmax - kmin + 1 on mmlt's) */
} mc_method_setup;

typedef struct mc_method {
  const char *name;   /* --integrator NAME */
  int default_states; /* MCMC_STATES_BDPT, _MMLT or _PT: the states without --states */
  lmc_status (*create)(void **OUT_run, const mc_method_setup *setup, lmc_error *err);
  void (*destroy)(void *run);
  /* Family g's target (owned by run), or NULL: the driver's. */
  const mc_target *(*family_target)(void *run, int g);
  /* n chains; chain i belongs to family[i]. */
  lmc_status (*set_chains)(void *run, int n, const int *family, lmc_error *err);
  /* Chain i's kernels and probabilities: k[] and p[] (room for
   * MC_MAX_KERNELS) hold the driver's default mix of nk kernels; returns
   * the count written. */
  int (*chain_kernels)(void *run, int i, mc_kernel *k, double *p, int nk);
  /* The most mutations per chain the next round may make (INT64_MAX: no limit). */
  int64_t (*round_limit)(void *run, int64_t done, int64_t budget);
  /* After a round (done / budget mutations per chain, budget INT64_MAX
   * under --time; elapsed seconds of the render): 1 restarts the chains. */
  int (*after_round)(void *run, int64_t done, int64_t budget, double elapsed);
  void (*note_restart_chain)(void *run, const mc_chain *c);
  /* Statistics lines (stderr) after the driver's. */
  void (*report)(void *run, mc_chain *const *chains, int n, double chain_seconds);
  /* Non-finite contributions dropped in a chain's scratch (NULL: the
   * driver's count for its targets). */
  int64_t (*nan_samples)(void *run, const mc_chain *c);
} mc_method;

/* The integrators built on the driver, by --integrator name (NULL: none). */
const mc_method *mc_method_find(const char *name);

/* The tables (methods.c lists them). */
extern const mc_method mc_method_pssmlt, mc_method_mmlt, mc_method_lmc, mc_method_h2mc;

#endif
