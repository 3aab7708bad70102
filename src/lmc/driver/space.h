/*
 * space.h: a state space of the MCMC driver as a plugin.
 *
 * A state space says what a chain's state is and what it is worth: it
 * splits the chains into families (one, or one per path length), and
 * gives each family a target (target.h) that evaluates f and, on request,
 * its gradient and, where the space has one, its Hessian. pssmlt and mmlt
 * evaluate it without derivatives, lmc with its gradient, h2mc with its
 * Hessian: one implementation serves them all. A space also sets the
 * small step's per-coordinate scales (mc_target.step_scale), says which
 * coordinate picks a strategy (for the technique mutation) and may bring
 * its own estimator of the normalisation b (mmlt's states: b of every
 * length from whole BDPT samples).
 *
 * The spaces (registry.c): `pt` (pt_states.c: a path tracer's numbers),
 * `mmlt` (mmlt_states.c: one family per path length, Hachisuka et al.
 * 2014), `bdpt` (bdpt_states.c: one family over every length, a BDPT
 * sample and one of its strategies) and `path` (path_states.c: whole
 * light paths, whose chains are their own: mc_target.chain_kind). The driver (mcmc.c) creates the one
 * --states or the integrator names and never looks inside it.
 */
#ifndef LMC_MCMC_SPACE_H
#define LMC_MCMC_SPACE_H

#include <stdint.h>

#include "lmc/driver/bootstrap.h"
#include "lmc/kernels/chain.h"
#include "lmc/kernels/target.h"
#include "render/error.h"
#include "render/integrators/integrator.h"
#include "render/options.h"
#include "render/scene.h"
#include "render/settings.h"

typedef struct mc_space_family mc_space_family;
struct mc_space_family {
  mc_target target; /* f, its gradient on request, its Hessian where eval_hess is set */
  int length;       /* a per-length family: its paths' length in segments; 0: every length */
  int technique;    /* the coordinate that picks the state's strategy, for the technique
                       mutation (chain.h), or -1: none */
  /* Optional (NULL: unknown): the path length in segments of a state with
   * label `label` (labelled targets; else -1) whose deepest differentiated
   * coordinate is `last` (-1: unknown); -1 when the space cannot say. */
  int (*length_of)(const mc_space_family *F, int label, int last);
};

/* What estimate_b is asked for (see mc_space). */
typedef struct mc_space_b_request {
  int64_t fixed;    /* > 0: exactly this many samples */
  double seconds;   /* under --time: draw for this long (INFINITY: plan by rel_err) */
  double rel_err;   /* the standard error of sum_g b_g to aim for, relative */
  int64_t cap;      /* the most samples */
  uint64_t seed;
  int nthreads;
} mc_space_b_request;

typedef struct mc_space mc_space;

/* A state space's own moves: kernels that know its states (mmlt_jump.h's
 * reversible jump and fused path mutation on the mmlt and bdpt states), which the
 * driver adds to every chain of whatever integrator runs on the space when
 * --technique-jump or --path-mutations asks. */
typedef struct mc_space_moves {
  /* The moves of n chains, chain i of family[i], taking the shares jump
   * and path (either may be 0) of the mutations that are not large steps. */
  lmc_status (*create)(void **OUT_run, const mc_space *sp, int n, const int *family, double jump,
                       double path, lmc_error *err);
  void (*destroy)(void *run);
  /* Appends chain i's moves to its n kernels k[], p[] (k[0] the large
   * step), the others' probabilities scaled to make room; the new count. */
  int (*add_kernels)(void *run, int i, mc_kernel *k, double *p, int n);
  /* As mc_method's share_stats and report (method.h). */
  void (*share_stats)(void *run);
  void (*report)(void *run, mc_chain *const *chains, int n, double chain_seconds);
} mc_space_moves;

struct mc_space {
  const char *name;      /* --states NAME */
  int n_fam;
  mc_space_family *fam;  /* owned by the space */
  int kmin, kmax;        /* the path lengths its states cover (segments) */
  double sigma;          /* the small step's scale without --sigma (0: the settings' default) */
  int pool_large;        /* 1: b is refined with the chains' large-step samples (mcmc.c) */
  const char *b_note;    /* how estimate_b draws its samples, for the statistics line */
  /* Optional (NULL: the driver's bootstrap estimates b): b of every family,
   * written to boot[g].b, b_var, s, s2 and n_est, from the space's own
   * unbiased estimator; the bootstrap's samples then only pick the chains'
   * starting states. cnt[thread] counts the rays. Returns the samples
   * drawn, or -1 when out of memory. */
  int64_t (*estimate_b)(const mc_space *sp, mc_boot *boot, const mc_space_b_request *rq,
                        render_counters *cnt);
  const mc_space_moves *moves;   /* its own moves (NULL: none) */
  void (*destroy)(mc_space *sp); /* frees what create made (not sp itself) */
  void *ctx;                     /* the space's own data */
};

/* The state spaces' ids (--states). */
typedef enum mcmc_states {
  MCMC_STATES_DEFAULT = 0, /* the integrator's own */
  MCMC_STATES_PT,          /* a unidirectional path tracer's primary samples */
  MCMC_STATES_MMLT,        /* one family of chains per path length (Hachisuka et al. 2014) */
  MCMC_STATES_BDPT,        /* one family over every length: a BDPT sample's numbers and one
                              of its strategies */
  MCMC_STATES_PATH         /* whole light paths, in chains of their own (path-space MLT) */
} mcmc_states;

/* A kind of state space, by --states name. create fills *OUT (zeroed by
 * the caller) for the chains' settings rs (mindepth as the chains see it). */
typedef struct mc_space_type {
  const char *name;
  int id; /* MCMC_STATES_* */
  lmc_status (*create)(mc_space *OUT, const scene *s, const render_settings *rs, lmc_error *err);
  const lmc_opt_table *opts; /* its own flags (NULL: none) */
} mc_space_type;

/* The state spaces (registry.c), by MCMC_STATES_* (NULL: none). */
const mc_space_type *mc_space_find(int id);

/* --states's choices: the spaces' names (NULL-terminated) and their ids. */
extern const char *const mc_space_names[];
extern const int mc_space_ids[];

/* The bdpt states' flags (bdpt_states.c) and the path states'
 * (path_states.c). */
extern const lmc_opt_table mc_space_bdpt_options;
extern const lmc_opt_table mc_space_path_options;

/* The moves of the mmlt and the bdpt states (mmlt_moves.c). */
extern const mc_space_moves mc_strategy_moves;

/* Frees what sp holds (accepts NULL and a space never created). */
void mc_space_free(mc_space *sp);

/* Sums the counters of a chain scratch of family F's target into *OUT. */
static inline void mc_space_counts(const mc_space_family *F, const void *scratch, mc_counts *OUT) {
  if (scratch && F->target.scratch_counts) F->target.scratch_counts(scratch, OUT);
}

/* The spaces' create functions (pt_states.c, mmlt_states.c, bdpt_states.c). */
lmc_status mc_space_pt_create(mc_space *OUT, const scene *s, const render_settings *rs,
                              lmc_error *err);
lmc_status mc_space_mmlt_create(mc_space *OUT, const scene *s, const render_settings *rs,
                                lmc_error *err);
lmc_status mc_space_bdpt_create(mc_space *OUT, const scene *s, const render_settings *rs,
                                lmc_error *err);
lmc_status mc_space_path_create(mc_space *OUT, const scene *s, const render_settings *rs,
                                lmc_error *err);

#endif
