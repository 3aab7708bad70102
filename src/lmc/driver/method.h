/*
 * method.h: an MCMC integrator as a plugin of the driver (mcmc.c).
 *
 * The driver owns what every MCMC integrator shares: the direct pass, the
 * state space (space.h: created from --states or the integrator's default,
 * its families and their targets), the bootstrap and b, the chains'
 * starting states, rounds, budgets, splatting, snapshots, the shared
 * statistics lines and Ctrl-C. It names no integrator and no state space.
 * An integrator is a table of functions, mc_method, found by name
 * (registry.c); it is a leaf: it chooses its kernels and their
 * probabilities for each chain, keeps what they adapt, and reports its own
 * statistics. A chain's state and the kernels' insides stay the
 * integrator's and the chain framework's (chain.h).
 *
 * The driver calls, in order: create (once the space exists), set_chains,
 * chain_kernels per chain, per round round_limit before and after_round
 * after, report, destroy. chain_kernels is called again when the
 * --largestep-scale schedule begins and after a restart (after_round's
 * return 1: every chain restarts from its starting state, splats and
 * counts kept, note_restart_chain first); it must then give the same mix
 * (the driver scales the large step's probability itself). Every function
 * pointer but name and chain_kernels may be NULL. Over several MPI ranks
 * every rank calls them all, the same way (mcmc_chain_here below); report
 * only on rank 0, whose view of per-chain state the integrator keeps
 * itself is its own chains'.
 */
#ifndef LMC_MCMC_METHOD_H
#define LMC_MCMC_METHOD_H

#include <stdint.h>

#include "lmc/kernels/chain.h"
#include "lmc/kernels/kernel_mix.h"
#include "lmc/driver/space.h"
#include "render/error.h"
#include "render/options.h"
#include "render/scene.h"
#include "render/settings.h"

/* The driver's settings: its flags (mcmc.c's table), read from
 * render_settings.params when a render starts. */
typedef struct mcmc_settings {
  int states;             /* --states: MCMC_STATES_* (space.h; DEFAULT: the integrator's) */
  double largestep;       /* --largestep: the large step's probability */
  double largestep_scale; /* --largestep-scale: it times this after a tenth of the budget */
  int small_gauss;        /* --small-step gauss: Gaussian small steps instead of Kelemen's */
  double technique_prob;  /* --technique-prob: the technique mutation's share of the rest */
  double jump_prob;       /* --technique-jump: the space's reversible jumps' share of the rest */
  double path_prob;       /* --path-mutations: the space's fused path mutations' share */
  double sigma;           /* --sigma: the small step's scale; an integrator sees it resolved
                             (the space's default, or 0.01 for gauss, when not given) */
  int chains;             /* --chains */
  int64_t bootstrap;      /* --bootstrap: paths that estimate b (0: adaptive) */
  double bootstrap_error; /* --bootstrap-error: b's target relative standard error */
  int direct_separate;    /* --direct separate: pt renders the paths of <= 2 segments */
  int64_t direct_spp;     /* --direct-spp: that pass's samples per pixel (0: --spp) */
  int even;               /* --allocate even: every chain the same mutations */
} mcmc_settings;

/* What the driver tells an integrator at create. */
typedef struct mc_method_setup {
  const scene *s;            /* borrowed */
  const render_settings *rs; /* the chains' settings: mindepth as the chains see it, and the
                                plugins' own (lmc_opt_read) */
  const mcmc_settings *ms;   /* the driver's, sigma resolved */
  const mc_space *space;     /* borrowed: the families and their targets */
} mc_method_setup;

typedef struct mc_method {
  const char *name;          /* --integrator NAME */
  int default_states;        /* MCMC_STATES_*: the space without --states */
  unsigned media_states;     /* 1u << MCMC_STATES_*: the states on which it renders a scene's
                                participating media (without the inverse path sampler's
                                moves); on others the chains and the direct pass see the media
                                as empty space, after render_media_note's warning */
  const lmc_opt_table *opts; /* its own flags (NULL: none) */
  lmc_status (*create)(void **OUT_run, const mc_method_setup *setup, lmc_error *err);
  void (*destroy)(void *run);
  /* n chains; chain i belongs to family[i] of the space. */
  lmc_status (*set_chains)(void *run, int n, const int *family, lmc_error *err);
  /* Chain i's kernels and probabilities into k[] and p[] (room for
   * MC_MAX_KERNELS); returns their count. run is NULL when create is. */
  int (*chain_kernels)(void *run, const mc_method_setup *setup, int i, const mc_space_family *F,
                       mc_kernel *k, double *p);
  /* The most mutations per chain the next round may make (INT64_MAX: no limit). */
  int64_t (*round_limit)(void *run, int64_t done, int64_t budget);
  /* After a round (done / budget mutations per chain, budget INT64_MAX
   * under --time; elapsed seconds of the render and of the chains, the
   * same on every rank): 1 restarts the chains. It must decide from its
   * arguments alone, so that every rank decides the same. */
  int (*after_round)(void *run, int64_t done, int64_t budget, double elapsed,
                     double chains_elapsed);
  void (*note_restart_chain)(void *run, const mc_chain *c);
  /* Over several MPI ranks, once the chains have run: every rank calls it
   * (collective, render/dist.h) to sum into every rank what report counts
   * per chain beyond mc_chain's counters; a chain's own counters are
   * non-zero only on the rank that stepped it, so dist_allsum_i64 over
   * all chains' gives the totals. */
  void (*share_stats)(void *run);
  /* Statistics lines (stderr) after the driver's, on rank 0; counts: the
   * scene targets' counters (evaluations with gradients and Hessians) of
   * every chain, summed over the ranks. */
  void (*report)(void *run, mc_chain *const *chains, int n, double chain_seconds,
                 const mc_counts *counts);
} mc_method;

/* Whether chain i runs in this process. Over several MPI ranks
 * (render/dist.h) every rank holds every chain, started from the same
 * state, but steps only its own (i modulo the ranks); the driver shares
 * the chains' statistics (mc_chain's counters) before after_round's
 * restart, snapshots and the report. What an integrator keeps per chain
 * beyond those is its own to share (integrator_lmc.c: stage 1's records).
 * Under one process every chain is here. */
int mcmc_chain_here(int i);

/* For share_stats: n counter structs of `size` bytes (int64_t counters
 * only) at first, first + stride, ..., each summed over the ranks into
 * every rank (a chain's counters are non-zero only where it runs).
 * Collective; nothing in one process. */
void mc_share_counters(void *first, int n, size_t stride, size_t size);

/* The integrators built on the driver, by --integrator name (NULL: none). */
const mc_method *mc_method_find(const char *name);

/* Adds an integrator defined outside src/lmc (borrowed: m must outlive
 * its use), found by name from then on. Call it before rendering, from one
 * thread; at most 8. Fails on a name already taken. */
lmc_status mc_method_register(const mc_method *m, lmc_error *err);

/* The numbers of a chain's mix (kernels/kernel_mix.h) for family F from
 * the driver's flags: the large step with probability ms->largestep, the
 * small step (Kelemen's with offsets in (1/1024, ms->sigma], or
 * --small-step gauss of scale ms->sigma) and, on a family with a technique
 * coordinate, the technique mutation (--technique-prob of the rest, 0.1).
 * An integrator with a proposal of its own sets small, extra and
 * min_length (and its own s1, s2) before calling mc_kernels_metropolis. */
static inline mc_mix_params mc_mix_params_from(const mcmc_settings *ms, const mc_space_family *F) {
  mc_mix_params mp = {0};
  mp.large = ms->largestep;
  mp.technique = ms->technique_prob;
  mp.coord = F->technique;
  mp.gauss = ms->small_gauss;
  mp.sigma = ms->sigma;
  mp.s1 = 1.0 / 1024.0;
  mp.s2 = ms->sigma;
  mp.length = F->length;
  return mp;
}

#endif
