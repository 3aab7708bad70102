/*
 * chain.h: one Markov chain over primary sample space, its proposals
 * (kernels), Metropolis-Hastings acceptance and expected-value splatting.
 *
 * The state. A chain's state is a primary sample vector u in [0,1)^dim
 * (dim and its per-stream blocks come from the mc_target, see target.h)
 * held lazily as Kelemen et al. 2002 do (pss.h): a coordinate the target
 * did not read in an iteration is not touched; when it is read again it is
 * brought up to date, as if every accepted iteration in between had mutated
 * it (a fresh uniform if a large step was accepted since, else the
 * accumulated small steps). A rejected proposal restores the coordinates it
 * changed. So the cost of a step is that of the coordinates the path uses,
 * not of dim.
 *
 * The step (full Metropolis-Hastings). With probability p_k the chain picks
 * kernel k, draws a proposal y ~ q_k(. | x), evaluates f(y) (with its
 * gradient only when kernel k needs gradients), and accepts with
 *
 *     a = min(1, f(y) q_k(x | y) / (f(x) q_k(y | x))).
 *
 * Expected-value splatting (Veach 1997, sec. 11.5): the proposal is splatted
 * with weight a and the current state with weight 1 - a, each as
 * value / f (the chain's samples are distributed as f / b, so an image
 * scaled by b / (number of steps) is an unbiased estimate). Zero weights
 * are not splatted.
 *
 * Kernels. Built in, on the lazy vector: the large step
 * (every coordinate a fresh uniform; an independence proposal whose
 * density is 1, so the ratio is f(y) / f(x)) and Kelemen's small step
 * (each coordinate moves by +-r, r = s2 exp(-log(s2/s1) xi), wrapped into
 * [0,1); symmetric; a target may scale s1, s2 per coordinate by a constant
 * factor, mc_target.step_scale, which keeps it symmetric). Any other kernel is "full": it sees the whole
 * coordinate vector of x (materialised from the lazy vector), writes all
 * coordinates of y, and gives the two log densities; see mc_kernel.
 * The MMLT technique mutation is a third built-in lazy kind: one given
 * coordinate (the technique choice) is redrawn uniformly and every other
 * coordinate takes a small step (a product of symmetric proposals; the
 * lazy vector owes every accepted non-large iteration a small step).
 *
 * Coordinates a path reads beyond its stream's block get a fresh uniform
 * on every evaluation: f(u) is then an unbiased random estimate, and MH
 * with a stored estimate at the current state is the pseudo-marginal
 * method (Andrieu and Roberts 2009), still exact. Targets size their blocks
 * so this is rare (it is counted: mc_chain.overflow).
 *
 * Labelled targets (target.h, n_labels > 0: the state is (u, l)). Every
 * kernel but the large step and full kernels with a `label` keeps the
 * label and evaluates f(u, l) alone (eval_label). The large step proposes
 * a fresh uniform u' (drawn and recorded apart from the lazy vector),
 * evaluates every label there (eval_all) and picks l' with probability
 * f(u', l') / F(u'), F = sum_l f(., l): an independence proposal whose Metropolis-Hastings
 * ratio is F(u') / F(u). F(u) of the current state is known when that
 * state came from a large step; after a small step it is not, and is
 * computed only when needed, by a Russian roulette that keeps the step
 * exact: since F(u) >= f(u, l), a = min(1, F(u') / F(u)) is at most
 * p = min(1, F(u') / f(u, l)); with probability p the chain evaluates
 * every label at the current state (the coordinates the label does not
 * read are brought up to date first, a valid move for coordinates the
 * target ignores) and accepts with probability a / p, else rejects. The
 * acceptance probability is p (a / p) = a. The splats use the unbiased
 * estimate a^ = 1{evaluated} a / p of a (a^ <= 1): the current state gets
 * 1 - a^, and the proposal a^ spread over all its labels, each label's
 * value weighted by 1 / F(u') (the expectation of the proposal's splat
 * over the label choice: every strategy of a fresh BDPT sample splats,
 * as in Kelemen et al.'s bidirectional PSSMLT, while the chain moves to
 * one of them).
 *
 * Ownership: a chain borrows its target, its kernels and their `self`; it
 * owns its vectors and scratch. One chain is driven by one thread at a
 * time. No allocation after mc_chain_create.
 */
#ifndef LMC_MCMC_CHAIN_H
#define LMC_MCMC_CHAIN_H

#include <stdint.h>

#include "lmc/kernels/target.h"
#include "render/error.h"
#include "render/rng.h"

/* A state as a full kernel sees it. */
typedef struct mc_state {
  int dim;
  double *u;    /* all dim coordinates (owned by the chain) */
  mc_value v;   /* f, value, raster position */
  double *grad; /* df/du (owned by the chain; valid when grad_ok) */
  int grad_ok;  /* 1 when grad holds the gradient of f at u */
  int grad_eval; /* the derivative order the state was evaluated with: 0 f alone, 1 with
                    its gradient (grad_ok meaningful), 2 also with its Hessian (hess_ok) */
  int label;    /* labelled targets: the state's label */
  int from_large; /* the state came from an accepted large step (no other move since) */
  int hess_ok;  /* 1 when hn, hidx, hess hold the target's Hessian of f (eval_hess) */
  int hn;       /* coordinates the Hessian spans */
  int *hidx;    /* their indices (owned by the chain, MC_HESS_MAX) */
  double *hess; /* d^2 f / du_i du_j over them, packed (target.h's eval_hess) */
} mc_state;

typedef enum mc_kernel_kind {
  MC_KERNEL_LARGE = 0, /* built in: independent uniform u */
  MC_KERNEL_SMALL,     /* built in: Kelemen's small step with s1, s2 */
  MC_KERNEL_TECHNIQUE, /* built in: coordinate `coord` redrawn uniformly, the rest small steps */
  MC_KERNEL_FULL,      /* propose / log_density below */
  MC_KERNEL_OWN        /* a move of a target's own chain (mc_chain_kind): `coord` says which */
} mc_kernel_kind;

/* A proposal. For MC_KERNEL_FULL:
 *  propose(self, r, x, OUT_y): draws y ~ q(. | x) with the chain's rng r,
 *    writes all x->dim coordinates (each in [0,1)) to OUT_y and returns
 *    log q(y | x), or -INFINITY when y falls where the target is zero
 *    outside [0,1)^dim (a kernel that does not wrap its proposal): the
 *    chain then rejects without evaluating anything, the exact outcome
 *    of a proposal with f(y) = 0. x->grad is valid when x->grad_ok (needs_grad kernels
 *    get states evaluated with their gradient: the proposal y of such a
 *    kernel is evaluated with it, and a current state reached by another
 *    kernel, evaluated with f alone, is re-evaluated with its gradient
 *    before such a kernel proposes from it; other kernels' proposals are
 *    evaluated without, which is the cheaper pass 1 of path.h).
 *  log_density(self, from, to_u): log q(to_u | from), from a state whose
 *    gradient is available as above; the chain calls it with from = y and
 *    to_u = x's coordinates for the reverse density. Return -INFINITY
 *    where the density is zero (the proposal is then rejected).
 *  log_screen(self, from, to_u, f_to) (may be NULL): delayed acceptance
 *    (Christen and Fox 2005). When set, the chain evaluates y first with f
 *    alone and makes a first test, accepting with a1(x, y) = min(1,
 *    exp(log_screen(x, y, f(y)))); only a proposal that passes is evaluated
 *    with its gradient (needs_grad), and a second test accepts it with
 *    a2 = min(1, [f(y) q(x|y) / (f(x) q(y|x))] a1(y, x) / a1(x, y)), where
 *    a1(y, x) = min(1, exp(log_screen(y, x, f(x)))) is the first test of
 *    the reverse move, from y with its gradient. The two tests together
 *    satisfy detailed balance for any screen that is a function of the
 *    two states (and of from's gradient) alone, so the screen need only be
 *    cheap and close to the full ratio: a proposal it rejects costs no
 *    gradient. The splats weigh y by 1{first test passed} a2, whose
 *    expectation is the acceptance probability a1 a2 (chain.c).
 *  on_step(self, current, accepted) (may be NULL): called after every step
 *    of the chain, whatever kernel made it, with the state now current
 *    (coordinates materialised only when the kernel was full; current->u
 *    may be stale otherwise). For Adam statistics and the like.
 * The chain treats `self` as opaque and never frees it; a kernel with
 * per-chain statistics needs one mc_kernel (and self) per chain. */
typedef struct mc_kernel {
  const char *name; /* for the statistics lines */
  mc_kernel_kind kind;
  int needs_grad;   /* states must be evaluated with their gradient (1) or with gradient
                       and Hessian (2: the target's eval_hess; as 1 without one) */
  double s1, s2;    /* MC_KERNEL_SMALL: offsets log-uniform in (s1, s2], s2 < 1/2, or for
                       s1 = 0 Gaussian offsets of standard deviation s2; all small
                       steps of one chain share them (default 1/1024, 1/64) */
  int coord;        /* MC_KERNEL_TECHNIQUE: the coordinate redrawn */
  void *self;
  double (*propose)(void *self, rng *r, const mc_state *x, double *OUT_y);
  double (*log_density)(void *self, const mc_state *from, const double *to_u);
  double (*log_screen)(void *self, const mc_state *from, const double *to_u, double f_to);
  void (*on_step)(void *self, const mc_state *current, int accepted);
  /* coords(self, x, OUT_idx) (may be NULL: all): a full kernel that
   * moves only some coordinates, written to OUT_idx (room for dim),
   * chosen by x's label alone. The chain then brings only those up to
   * date in x->u (the others are stale there: propose and log_density
   * must not read them) and takes only those from OUT_y; every other
   * coordinate gets the lazy vector's small step, a symmetric factor of
   * the proposal that cancels in the ratio. */
  int (*coords)(void *self, const mc_state *x, int *OUT_idx);
  /* label(self) (may be NULL: x's label): labelled targets, the label of
   * the proposal propose has just made. A full kernel that changes the
   * label (a move between strategies of one path, mmlt_jump.h) writes
   * every coordinate of y in the new label's coordinates; its densities
   * are those of (u, label) pairs. */
  int (*label)(void *self);
  /* value(self, OUT) (may be NULL): a full kernel without gradients or a
   * screen whose propose has evaluated its proposal y itself, with the
   * target's own function of y's coordinates (and label): returns 1 and
   * y's value, which the chain then takes instead of evaluating y; 0 when
   * it has none (the chain evaluates y). */
  int (*value)(void *self, mc_value *OUT);
} mc_kernel;

/* Built-in kernels. */
mc_kernel mc_kernel_large(void);
mc_kernel mc_kernel_small(double s1, double s2);
/* The Gaussian small step: every coordinate moves by N(0, sigma^2) (times
 * the target's step scale), wrapped into [0, 1); symmetric. Owed steps are
 * replayed as one step of variance n sigma^2. As a kernel it is
 * MC_KERNEL_SMALL with s1 = 0, s2 = sigma. */
mc_kernel mc_kernel_small_gauss(double sigma);
mc_kernel mc_kernel_technique(int coord);

#define MC_MAX_KERNELS 8

/* Acceptance statistics of one kernel. */
typedef struct mc_kernel_stats {
  int64_t proposed, accepted;
  double accept_sum; /* sum of acceptance probabilities */
  double f_sum, f_sum2; /* sum of f(y) and f(y)^2 over the proposals y (for the large
                           step: independent uniform samples of b = E[f], mcmc.c) */
  /* Moves through the inverse path sampler (own kernels; else 0): subpaths
   * inverted, steps the inverses could not take back to numbers, and
   * numbers that walked to another path (a failed round trip). */
  int64_t inverted, refused, elsewhere;
  /* Manifold walks (the manifold perturbation; else 0): begun, reached their
   * target, and proposals refused because the reverse walk did not return. */
  int64_t walks, walked, irreversible;
  /* Rays traced by the kernel's steps: its proposals, the current states
   * it re-evaluated (for a gradient, or the roulette's F(u) of the
   * labelled large step). */
  int64_t rays;
} mc_kernel_stats;

/* Where a chain's splats go: w * value / f at (rx, ry); for toy targets the
 * value and raster position are the target's own (see target.h). */
typedef void (*mc_splat_fn)(void *ctx, const mc_value *v, double weight);

typedef struct mc_pss mc_pss;

typedef struct mc_chain {
  const mc_target *target;
  int n_kernels;
  mc_kernel kernels[MC_MAX_KERNELS];
  double cdf[MC_MAX_KERNELS]; /* cumulative kernel probabilities */
  mc_kernel_stats stats[MC_MAX_KERNELS];
  int with_grad;              /* some kernel needs gradients */
  int64_t regrad;             /* current states re-evaluated for their gradient */
  int64_t screened;           /* proposals of delayed-acceptance kernels: first tests made */
  int64_t screen_passed;      /* ... passed (the proposal then got its gradient) */
  rng r;                      /* the chain's own random stream */
  mc_pss *pss;                /* the lazy vector of the current state */
  mc_state x, y;              /* current and proposed (x.u valid after a full step) */
  void *scratch;              /* the target's per-chain scratch */
  void *scratch_alt;          /* a second one (labelled targets with relabel, chain.c) */
  int64_t steps;
  int64_t overflow;           /* coordinates drawn past a stream's block */
  int64_t eval_failures;      /* target evaluations that returned an error */
  /* Labelled targets (see above). */
  mc_contrib *cy;             /* the large-step proposal's labels (n_labels) */
  mc_contrib *cx;             /* the current state's, when the roulette evaluates them */
  int n_cy;
  double sum_x;               /* F of the current state, 0 when not known */
  int *drawn;                 /* coordinates the large-step proposal drew */
  int n_drawn;
  int64_t sum_evals;          /* current states evaluated for F (the roulette) */
  int64_t sum_rays;           /* ... the rays they traced (also in the large step's stats) */
  /* Labelled targets: per label l, the steps made from a state of label l
   * (the chain's time there), the steps of kernels other than the large
   * step among them and the rays those traced: lab[3 l + 0, 1, 2]. */
  int64_t *lab;
  int *sub;                   /* scratch: a subset kernel's coordinates */
  void *own;                  /* a target's own chain's state (mc_chain_kind) */
} mc_chain;

/* A target's own chain (mc_target.chain_kind), for states that are not
 * primary sample vectors. Its kernels are MC_KERNEL_OWN moves, chosen with
 * the chain's probabilities (mc_chain_pick); it keeps their statistics in
 * the chain's stats and its state in c->own. The chain still evaluates
 * the starting state (the bootstrap sample (seed, seq)) through the
 * target, into c->scratch, before `start` takes it from there. */
typedef struct mc_chain_kind {
  void *ctx;                                      /* the kind's own data (borrowed) */
  lmc_status (*create)(struct mc_chain *c, lmc_error *err); /* allocates c->own */
  void (*destroy)(struct mc_chain *c);            /* frees c->own */
  /* The state from c->scratch after the target evaluated the starting
   * sample; returns its f. */
  double (*start)(struct mc_chain *c);
  /* One step (mc_chain_step); returns the kernel index used. */
  int (*step)(struct mc_chain *c, mc_splat_fn splat, void *ctx);
  int64_t (*rays)(const struct mc_chain *c);      /* rays traced by the steps so far */
} mc_chain_kind;

/* The index of the next kernel, drawn with the chain's probabilities from
 * its stream (for mc_chain_kind's step). */
int mc_chain_pick(mc_chain *c);

/* Creates a chain for `target` with kernels k[0..n-1] chosen with
 * probabilities prob[] (normalised here). The state is empty until
 * mc_chain_start. */
lmc_status mc_chain_create(mc_chain **OUT_chain, const mc_target *target, const mc_kernel *k,
                           const double *prob, int n, lmc_error *err);
void mc_chain_destroy(mc_chain *c);

/* Starts the chain at the state a large step draws from a generator
 * seeded with (seed, seq): the same (seed, seq) as mc_eval_independent
 * gives the same state (that is how bootstrap samples become starting
 * states). Then reseeds the chain's own stream with (seed, chain_seq).
 * Returns f of the starting state. */
double mc_chain_start(mc_chain *c, uint64_t seed, uint64_t seq, uint64_t chain_seq);

/* Replaces the chain's kernels (as mc_chain_create takes them; the small
 * step must keep the chain's s1, s2). The state is kept; a kernel that
 * differs from the one it replaces starts its statistics afresh. */
lmc_status mc_chain_set_kernels(mc_chain *c, const mc_kernel *k, const double *prob, int n,
                                lmc_error *err);

/* Sets the kernel probabilities (normalised here; as many as the chain has
 * kernels). Each step is then a mixture with the new weights: still a
 * kernel that leaves the target invariant, so a schedule of weights fixed
 * in advance (the large-step scale of mcmc.c) keeps the chain exact. */
void mc_chain_set_probs(mc_chain *c, const double *prob);

/* Makes the chain's scratches use workspace ws (target.h's scratch_bind;
 * borrowed, from the target's workspace_create, NULL: their own) until
 * bound again. The chains a thread drives one after the other may share one
 * workspace. Nothing when the target has no workspace. */
void mc_chain_bind(mc_chain *c, void *ws);

/* Rays traced in the chain's scratches so far (the target's scratch_rays). */
int64_t mc_chain_rays(const mc_chain *c);

/* The most splats one step makes (2; labelled targets n_labels + 1). */
int mc_chain_max_splats(const mc_chain *c);

/* One Metropolis-Hastings step; splats through splat(ctx, ...) when not
 * NULL. Returns the kernel index used. Counts the step's rays into its
 * kernel's stats (and the label's tallies, c->lab). */
int mc_chain_step(mc_chain *c, mc_splat_fn splat, void *ctx);

/* Evaluates one independent uniform sample drawn from (seed, seq), without
 * a chain (bootstrap). scratch: the target's scratch (may be NULL when the
 * target has none). OUT_value may be NULL. Returns f. */
double mc_eval_independent(const mc_target *t, void *scratch, uint64_t seed, uint64_t seq,
                           mc_value *OUT_value);

#endif
