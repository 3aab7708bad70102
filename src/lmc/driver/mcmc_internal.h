/*
 * mcmc_internal.h: the MCMC driver's own types, shared by its files:
 * mcmc.c (the flow of a render), mcmc_b.c (the bootstrap and the
 * normalisation b) and mcmc_dist.c (over MPI ranks). Not part of the API.
 */
#ifndef LMC_MCMC_MCMC_INTERNAL_H
#define LMC_MCMC_MCMC_INTERNAL_H

#include <stdint.h>

#include "lmc/driver/bootstrap.h"
#include "lmc/kernels/chain.h"
#include "lmc/driver/method.h"
#include "lmc/driver/space.h"
#include "render/film.h"
#include "render/integrators/integrator.h"

#define MCMC_CHAINS 256
#define MCMC_MIN_CHAINS 16 /* per family: one stuck chain must not carry a whole length */
#define MCMC_GAUSS_SIGMA 0.01 /* --small-step gauss: default standard deviation (the LMC
                                 paper's implementation's perturbStdDev) */
#define MCMC_LARGESTEP_SCALE_AFTER 0.1 /* --largestep-scale applies after this share of
                                          the chains' budget (the paper's LS_RATIO) */
#define MCMC_ROUND 64
#define MCMC_BOOT_BATCH 8192
#define MCMC_BOOT_CAP (1 << 22) /* bootstrap samples in all, over the families */
#define MCMC_EXPECT_SEQ 0x5eed0fb0075a3e11ull /* eval_expect's bootstrap streams: (seed, seq ^ this) */
#define MCMC_ERROR_GROUPS 16 /* --error: chain groups (at most MCMC_MIN_CHAINS: one chain of
                                every family in each) */
#define MCMC_FAMILY_FILM_BYTES ((int64_t)512 << 20) /* per-family splat buffers, at most */

/* --- a chain's splat records --------------------------------------------------- */

typedef struct mcmc_splat {
  double rx, ry;
  rgb v;
} mcmc_splat;

typedef struct mcmc_chain_slot {
  mc_chain *chain;
  int family;
  double scale;     /* b_g / n_g */
  uint64_t start_seq; /* bootstrap sample the chain started from */
  mcmc_splat *rec;  /* this round's splats */
  int n_rec, cap_rec;
  int rec_failed;   /* a splat was dropped: no memory to grow rec */
  int group;        /* --error: the chain group whose image it adds to (mcmc_error.c) */
  double gscale;    /* and the factor its splats take there */
} mcmc_chain_slot;

/* --- one render ------------------------------------------------------------------ */

typedef struct mcmc_family {
  const mc_space_family *sf; /* borrowed from the space: its target */
  mc_boot bt;         /* the bootstrap's samples and estimate of b (bootstrap.h) */
  double b_ref, b_ref_var; /* b refined with the chains' large steps, and its variance */
  int64_t n_large;    /* large-step proposals counted in b_ref */
  double *splat;      /* per-family buffers: this family's splats, not yet times b (owned) */
  int n_chains, first_chain;
  int m_round;        /* mutations per chain in a full round (1 .. MCMC_ROUND; see Allocation) */
  int64_t done;       /* mutations per chain of this family so far */
} mcmc_family;

/* How the splats meet b (see Normalisation above). */
typedef enum mcmc_norm {
  MCMC_NORM_BOOT = 0, /* b from before the chains baked into each splat (no buffer memory) */
  MCMC_NORM_SCALE,    /* one family: refined b in film.splat_scale */
  MCMC_NORM_BUFFERS   /* per-family buffers, summed times refined b_g */
} mcmc_norm;

typedef struct mcmc_render {
  const scene *s;
  const render_settings *rs; /* the caller's */
  render_settings crs;       /* the chains': mindepth after the direct pass */
  mcmc_settings ms;          /* the driver's (its flags), sigma resolved at setup */
  film *out;
  render_stats *st;
  progress bar;
  double t0;
  int timed, by_spp, nthreads;
  const mc_method *M;
  void *mrun;
  mc_method_setup setup;
  mc_space sp;
  void *moves;               /* the space's moves (sp.moves; NULL: none asked) */
  int n_fam;
  mcmc_family *fam;
  mcmc_chain_slot *slots;
  int n_slots;
  render_counters *cnt; /* per thread */
  void **ws;            /* per thread and family (tid * n_fam + g): the workspace its chains
                           share (target.h), made on first use; NULL: none */
  mcmc_norm norm;
  int64_t shared_paths; /* samples of the space's own estimate of b */
  double b_total, b_var; /* b before the chains */
  int64_t per_chain, done_per_chain;
  int ls_pending;       /* --largestep-scale not yet in force */
  double chain_seconds;
  int n_snapshots;
  double snapshot_seconds; /* preparing them: b, the counters and splats of every rank */
  double *egroup;  /* --error: MCMC_ERROR_GROUPS images of the chain groups (owned; NULL: none) */
} mcmc_render;

/* The streams of family g's bootstrap sample j and of its chain i. */
uint64_t mcmc__boot_seq(int g, int64_t j);
uint64_t mcmc__chain_seq(int g, int i);

/* The bootstrap and b before the chains (mcmc_b.c). */
lmc_status mcmc__bootstrap(mcmc_render *R, lmc_error *err);

/* b refined with the chains' large steps: the sum over the families, its
 * variance in OUT_var (mcmc_b.c). */
double mcmc__refine_b(mcmc_render *R, double *OUT_var);

/* The chains' image after `done` mutations per chain into the film
 * (compose: per-family buffers summed in) (mcmc_b.c). */
void mcmc__publish(mcmc_render *R, int64_t done, int compose);

/* The statistics lines at the end of a render (mcmc_report.c); counts:
 * the scene targets' counters of every rank. */
void mcmc__report(mcmc_render *R, const mc_counts *counts);

/* The scene targets' counters of this rank's chains added to *c, and
 * their mutations to *mutations (may be NULL) (mcmc_dist.c). */
void mcmc__counts_here(const mcmc_render *R, mc_counts *c, int64_t *mutations);
/* The scene targets' counters of every chain summed over the ranks, and
 * the integrator's own statistics shared (method.h), on every rank. */
void mcmc__share_stats(mcmc_render *R, mc_counts *OUT);

/* --error (mcmc_error.c): the chain groups' images, after the chains are
 * allocated and started; then, at the end of the chains (collective), each
 * pixel's variance into the film's evar. */
lmc_status mcmc__error_init(mcmc_render *R, lmc_error *err);
void mcmc__error_develop(mcmc_render *R);

/* Over several MPI ranks (mcmc_dist.c): every chain's counters from the
 * rank that steps it, onto every rank (collective; a no-op under one). */
void mcmc__sync_chains(mcmc_render *R);
/* A snapshot: the image so far, every rank's, to rs->snapshot_fn on rank 0
 * (collective). */
void mcmc__snapshot(mcmc_render *R, double seconds);

#endif
