/*
 * lmc_kernel.h: the Langevin Monte Carlo proposal as a kernel of the chain
 * framework (chain.h), with its preconditioner schedules, and the cache's
 * independence proposal.
 *
 * Luan, Zhao, Bala and Gkioulekas 2020, "Langevin Monte Carlo Rendering
 * with Gradient-based Adaptation". The kernel is an MC_KERNEL_FULL: at the
 * current state x it proposes y ~ N(x + (s/2) M(x) g(x), s M(x)) wrapped
 * into [0,1)^D (mala.h), with g = grad log f = grad f / f truncated to
 * norm grad_bound, and reports the exact log densities of both directions;
 * the chain does the Metropolis-Hastings test with them.
 *
 * Fallback. A state "has a gradient" when the target returned one, f > 0
 * and some component of g is non-zero. At a state without one, the kernel
 * proposes Kelemen's small step instead (s1, s2 as the chain's small
 * step). The choice is a function of the state, so the reverse density
 * q(x | y) is MALA's when y has a gradient and Kelemen's when it has not:
 * the ratio stays exact and no state is ever reset.
 *
 * The preconditioner M (lmc_adapt, below):
 *   NONE       M = I.
 *   ADAM       M = Adam's clamp(1 / (eps + sqrt(v))) of this chain's
 *              gradients so far, updated after every step of the chain
 *              (on_step) and used directly: biased (see adam.h).
 *   DIMINISH   (1 - w_t) I + w_t M_adam with w_t = min(1, t0 / t).
 *   CACHE      stage 1: M = I, while Adam's moments are updated as for
 *              ADAM (not used), and every record_stride-th state this
 *              kernel proposed is stored in a gcache with its Adam moments
 *              (a fixed kernel: its images are unbiased). Stage 2
 *              (lmc_mala_begin_stage2): M(x) = gcache_precond(cache, x),
 *              a pure function of x, evaluated at x for the forward and at
 *              y for the reverse density.
 * For ADAM and DIMINISH the M of one step is the same in both directions
 * (it changes only between steps) up to the normalisation below.
 *
 * Step size. Each MALA step draws its own s, log-uniformly over
 * [s / R, s R] (R = step_range, 1: always s), before it looks at the
 * state, and uses it in both directions: the kernel is a mixture over s
 * of MALA kernels that each satisfy detailed balance, so the mixture does
 * too, without its (intractable) mixture density. As with Kelemen's
 * mutation, the occasional long step explores while the short ones keep
 * the acceptance up where f is sharp.
 *
 * Normalisation (lmc_kernel_params.norm, default off): an adapted M may be
 * divided by its mean, geometric mean or maximum over the state's key
 * coordinates (a function of the state, so both directions of a step stay
 * exact), so that s means for M what it means for I. On ring-caustics none
 * of the three made adaptation beat M = I (see the README), hence off.
 *
 * Step scale (lmc_kernel_params.scale: the target's step_scale, target.h).
 * A coordinate with a huge derivative (the triangle choice of a tessellated
 * area light) gets a constant factor c_i: the kernel runs MALA in the
 * rescaled coordinates z = u / c (mala.h), i.e. with preconditioner c^2 M
 * in u, and its Kelemen fallback scales the offsets by c_i, as the chain's
 * own small step does. g above is then c grad log f, the gradient in z:
 * the truncation to grad_bound and Adam's moments (hence M and the cache's
 * records) are taken of it, so one coordinate whose raw gradient is ~1/c_i
 * times the others neither shrinks the rest of g under the bound nor
 * drives M to its clamp. c is constant, so both directions stay exact.
 *
 * Delayed acceptance (lmc_kernel_params.delayed, chain.h). The screen
 * from x to y is log f(y) - log f(x) + (x - y) . g(x), with x - y the
 * shortest difference on the torus, in the rescaled coordinates z: the
 * full log ratio of the step with g(y) and M(y) replaced by g(x) and M(x)
 * (for a Gaussian proposal whose mean moves by (s/2) M g, the two
 * densities then differ by exactly (x - y) . g). From a state without a
 * gradient (the Kelemen fallback, symmetric) it is log f(y) - log f(x).
 * Where f is smooth over a step the screen is close to the full ratio, so
 * the second test passes nearly always, and a proposal the screen rejects
 * costs a plain evaluation of f instead of one with its gradient.
 *
 * Gradients are evaluated lazily by the chain (chain.h): a state reached
 * by a large or Kelemen step is evaluated without its gradient, and
 * re-evaluated with it only when this kernel proposes from it. Adam's
 * statistics (on_step) are updated at states whose gradient is known.
 *
 * Cache key. Paths of different lengths use different numbers of
 * coordinates; the cache keys a state by k(x) = 1 + the index of the last
 * non-zero gradient component (the coordinates the contribution depends
 * on), looks up only those k coordinates, and uses M = 1 (clamped) for the
 * coordinates k .. D-1. A toy target whose gradient is dense has k = D.
 *
 * Ownership: an lmc_mala holds one chain's adaptation state (one per
 * chain); it borrows the cache. No allocation after lmc_mala_init.
 */
#ifndef LMC_MCMC_LMC_KERNEL_H
#define LMC_MCMC_LMC_KERNEL_H

#include <stdint.h>

#include "lmc/kernels/adam.h"
#include "lmc/kernels/chain.h"
#include "lmc/kernels/gcache.h"
#include "render/settings.h"

/* LMC preconditioner adaptation (--adapt). */
typedef enum lmc_adapt {
  LMC_ADAPT_NONE = 0, /* plain MALA, M = I */
  LMC_ADAPT_ADAM,     /* Adam along the chain, used directly (biased; for comparison) */
  LMC_ADAPT_DIMINISH, /* Adam whose influence fades as 1/t (asymptotically unbiased) */
  LMC_ADAPT_CACHE     /* Adam in stage 1, frozen k-d tree cache in stage 2 (default) */
} lmc_adapt;

/* lmc's own settings, its flags (integrator_lmc.c's table). */
typedef struct lmc_settings {
  int adapt;             /* lmc_adapt */
  double step;           /* s: proposal N(x + s/2 M g, s M) */
  double step_range;     /* R: each LMC step draws s log-uniformly from [s / R, s R] */
  double adam_eps;       /* M = clamp(1 / (eps + sqrt(v)), lo, hi) */
  double precond_lo, precond_hi;
  double grad_bound;     /* |g| is truncated to this norm */
  double cache_fraction; /* --adapt cache: share of the budget spent building the cache */
  double iso_prob;       /* probability of Kelemen's isotropic small step */
  int cache_gradient;    /* stage 2 of the cache evaluates gradients (MALA with the cached M)
                            instead of the cached walk */
  double cache_step, cache_prior, cache_radius; /* the cached walk's (0: its defaults) */
  int cache_k;           /* its neighbours (0: default) */
  double cache_indep;    /* probability of the cache's independence proposal */
  int cache_no_drift;    /* no drift from the cached first moment */
  int delayed;           /* Langevin proposals get a gradient-free first test */
} lmc_settings;

/* The defaults of lmc_settings. */
extern const lmc_settings lmc_settings_defaults;
lmc_settings lmc_settings_default(void);

/* Normalisation of an adapted M over the state's key coordinates (the
 * first k(x)): M / c with c their mean, geometric mean or maximum, so the
 * step s keeps the meaning it has for M = I. */
typedef enum lmc_norm { LMC_NORM_OFF = 0, LMC_NORM_MEAN, LMC_NORM_GEOMEAN, LMC_NORM_MAX } lmc_norm;

typedef struct lmc_kernel_params {
  lmc_adapt adapt;
  double step;          /* s (the centre of its range) */
  double step_range;    /* R >= 1: each MALA step draws its s log-uniformly from [s / R, s R] */
  double eps, lo, hi;   /* preconditioner: clamp(1 / (eps + sqrt(v)), lo, hi) */
  double grad_bound;    /* |g| truncated to this norm */
  double s1, s2;        /* Kelemen fallback offsets */
  double diminish_t0;   /* DIMINISH: w_t = min(1, t0 / t) */
  gcache_params cache;  /* CACHE stage 2 lookup */
  int record_stride;    /* CACHE stage 1: record every n-th own state (0: none) */
  int norm;             /* lmc_norm: how M is normalised over the key coordinates */
  const double *scale;  /* borrowed, dim entries (NULL: all 1): the step scale c (below) */
  int delayed;          /* delayed acceptance with the first-order screen (below) */
} lmc_kernel_params;

/* The parameters of lmc's settings (step, adam_eps, precond_lo/hi,
 * grad_bound, adapt, delayed), with s1 = 1/1024, s2 = sigma (the small
 * step's, --sigma) and the defaults below for the rest. */
lmc_kernel_params lmc_kernel_params_from_settings(const lmc_settings *ls, double sigma);
lmc_kernel_params lmc_kernel_params_default(void);

#define LMC_STAT_KEYS 64 /* per-key statistics: keys 0 .. 63 (larger ones in the last) */

/* Counters of one chain's kernel. */
typedef struct lmc_mala_stats {
  /* Per cache key of the state proposed from (the integrator maps keys to
   * path lengths), [0]: MALA proposals, [1]: Kelemen fallbacks. */
  int64_t key_proposed[2][LMC_STAT_KEYS];
  int64_t key_accepted[2][LMC_STAT_KEYS];
  int64_t steps;        /* steps of the chain */
  int64_t streak;       /* steps of the chain since its last accepted one */
  int64_t max_streak;   /* the longest such run (stalls) */
  int64_t mala;         /* proposals made with the gradient */
  int64_t fallback;     /* proposals from states without a gradient (Kelemen) */
  int64_t lookups;      /* stage-2 cache lookups */
  int64_t lookup_hits;  /* ... that found neighbours within the radius */
  int64_t recorded;     /* stage-1 states stored */
  int64_t record_full;  /* stage-1 states not stored: the cache was full */
} lmc_mala_stats;

typedef struct lmc_mala {
  lmc_kernel_params p;
  int dim;
  const mc_target *target; /* borrowed: labelled targets record by label (lmc_mala_set_target) */
  int last_label;        /* the label Adam's moments belong to (labelled targets) */
  int *cidx;             /* scratch: a label's coordinates */
  double *cu;            /* scratch: the state at them */
  int stage2;            /* CACHE: lookups in `cache` instead of online Adam */
  const gcache *cache;   /* borrowed (stage 2) */
  gcache *record;        /* borrowed (stage 1; NULL: nothing recorded) */
  adam_stats adam;
  double *M_chain;       /* ADAM, DIMINISH: the chain's current M (unused by CACHE) */
  int M_chain_stale;     /* Adam moved since M_chain was computed (it is rebuilt when next used) */
  double *g, *M;         /* scratch */
  double *m1, *m2;       /* scratch for recording */
  /* Stage 2: the last two lookups (state, key, M), reused when the chain
   * proposes from or returns to the same state (a pure function of it). */
  double *memo_u[2], *memo_M[2];
  int memo_key[2];
  int memo_next;
  double cur_step;       /* s of the step in progress */
  int own_step;          /* the step in progress was proposed here */
  int own_key;           /* its state's key (0: fallback) */
  int64_t own_steps;
  lmc_mala_stats st;
} lmc_mala;

lmc_status lmc_mala_init(lmc_mala *k, int dim, const lmc_kernel_params *p, lmc_error *err);
/* Frees the buffers (k may be zeroed). */
void lmc_mala_free(lmc_mala *k);
/* The mc_kernel (kind FULL, needs_grad) over k; k must outlive the chain. */
mc_kernel lmc_mala_kernel(lmc_mala *k);
/* CACHE stage 1: where states are recorded (NULL: nowhere). */
void lmc_mala_set_record(lmc_mala *k, gcache *record);
/* A labelled target with label_coords (target.h): stage 1 then records a
 * state under the key label + 1 with its label's coordinates and their
 * moments (a keyed cache, gcache_create_keyed), and Adam's moments start
 * afresh when the label changes or a large step moved the state. */
void lmc_mala_set_target(lmc_mala *k, const mc_target *target);
/* CACHE: switch to stage 2 with a frozen cache. */
void lmc_mala_begin_stage2(lmc_mala *k, const gcache *cache);

/* The cache key k(x) of a state (0 without a gradient). */
int lmc_state_key(const mc_state *x);

/* ---- The cached walk: stage 2 of --adapt cache without gradients --------
 *
 * Luan et al.'s implementation runs stage 2 of its cache on cached moments
 * alone: at a state x of label l the proposal is a diagonal Gaussian on the
 * label's coordinates (label_coords), from the moments (m1, m2) of x's
 * nearest cached neighbours of the same label, k of them within radius
 * sqrt(n) r (n coordinates), weighted by 1 / (d^2 + 1e-6) (d^2 the
 * squared distance):
 *     M_i = clamp(1 / (eps + sqrt(m2_i)), lo, hi)
 *     cov_i = 1 / (1 / (step^2 (M_i + 1)) + 1 / prior^2)
 *     mean_i = clamp(m1_i, -drift_max, drift_max) cov_i / 2   (0 without drift)
 * and with no neighbour N(0, prior^2) per coordinate. m1 is Adam's first
 * moment of grad log f (the momentum): its drift replaces the gradient, so
 * a step costs one evaluation of f and no derivative. The Gaussian is a
 * pure function of x through the frozen cache, so q(y | x) and q(x | y)
 * (the same construction at y) are exact, and the chain is a fixed,
 * reversible kernel. Coordinates other than the label's stay put, which
 * both directions share. The step scale c of the target (a light's
 * triangle choice) scales mean and standard deviation of its coordinate.
 */
typedef struct lmc_cwalk_params {
  double step;        /* step (the paper's implementation: 0.005) */
  double prior;       /* prior standard deviation (0.005) */
  double drift_max;   /* clamp of m1 (5; 0: no drift) */
  int k;              /* neighbours (5) */
  double radius;      /* r (0.01) */
  double eps, lo, hi; /* M's clamp (1e-3, 0.01, 100) */
} lmc_cwalk_params;

lmc_cwalk_params lmc_cwalk_params_default(void);
/* The defaults with lmc's --cache-step, --cache-prior, --cache-radius,
 * --cache-k and --cache-drift where given. */
lmc_cwalk_params lmc_cwalk_params_from_settings(const lmc_settings *ls);

typedef struct lmc_cwalk_stats {
  int64_t proposed, accepted;
  int64_t lookups, hits;
} lmc_cwalk_stats;

typedef struct lmc_cwalk {
  lmc_cwalk_params p;
  const mc_target *target; /* borrowed, labelled, with label_coords */
  const gcache *cache;     /* borrowed, frozen, keyed by label + 1 */
  const double *scale;     /* borrowed (NULL: 1): the target's step scale */
  int dim;
  int *idx;                /* scratch: the label's coordinates */
  double *v, *mean, *sd;   /* scratch: at them */
  /* The last two Gaussians (state, label), reused for the same state. */
  double *memo_v[2], *memo_mean[2], *memo_sd[2];
  int memo_label[2], memo_n[2], memo_next;
  int own;                 /* the step in progress was proposed here */
  lmc_cwalk_stats st;
} lmc_cwalk;

lmc_status lmc_cwalk_init(lmc_cwalk *k, const mc_target *target, const gcache *cache,
                          const lmc_cwalk_params *p, lmc_error *err);
void lmc_cwalk_free(lmc_cwalk *k);
/* The mc_kernel (kind FULL, no gradient) over k; k must outlive the chain. */
mc_kernel lmc_cwalk_kernel(lmc_cwalk *k);

/* The cache's independence proposal (gcache_indep_*) as a kernel. Without
 * a cache (or anchors) it makes Kelemen's small step (s1, s2) instead, so
 * its slot in a chain's mixture is a valid kernel in every stage. */
typedef struct lmc_indep {
  const gcache *cache; /* borrowed, frozen, with anchors (NULL: Kelemen) */
  double sigma;
  double s1, s2;
} lmc_indep;
mc_kernel lmc_indep_kernel(lmc_indep *k);

#endif
