/*
 * h2mc.h: the Hessian-Hamiltonian proposal of H2MC (Li, Lehtinen,
 * Ramamoorthi, Jakob and Durand 2015, "Anisotropic Gaussian Mutations for
 * Metropolis Light Transport through Hessian-Hamiltonian Dynamics") as a
 * kernel of the chain framework (chain.h).
 *
 * The local model. At a state x with f(x) > 0, g = grad log f and
 * H = hess log f over the coordinates the kernel moves (those the target's
 * Hessian spans, target.h's eval_hess) give the quadratic model
 *   log f(x + d) ~ log f(x) + g . d + d . H d / 2.
 * Hamiltonian dynamics on the potential -log f of that model, started at x
 * with a momentum p ~ N(0, I), decouple in the eigenbasis H = V diag(l) V^T:
 * with b = V^T g, coordinate i of the offset at time t is
 *   l_i < 0:  b_i / |l_i| (1 - cos(w t)) + p_i / w sin(w t),   w = sqrt(|l_i|)
 *   l_i > 0:  b_i / l_i (cosh(w t) - 1) + p_i / w sinh(w t),   w = sqrt(l_i)
 *   l_i = 0:  b_i t^2 / 2 + p_i t
 * (an oscillation where log f curves down, an escape where it curves up).
 * Each direction runs for its own time, w t = L (L = pi / 2 by default, a
 * quarter period where log f curves down), so the offset is Gaussian with
 * mean o_i and variance s_i:
 *   l_i < 0:  o_i = (1 - cos L) b_i / |l_i|,  s_i = sin(L)^2 / |l_i|
 *   l_i > 0:  o_i = (cosh L - 1) b_i / l_i,   s_i = sinh(L)^2 / l_i
 *   l_i = 0:  o_i = b_i L^2 / 2,              s_i = L^2
 * (|l_i| <= 1e-10 counts as 0). The paper then takes the product with a
 * prior N(0, sigma^2 I) on the offset, which bounds the step where the
 * model is flat or wrong: in the eigenbasis the proposal offset is
 *   N(m, diag(1 / P)),   P_i = 1 / s_i + 1 / sigma^2,   m_i = o_i / (s_i P_i).
 * Where the curvature is negligible against the prior (|H|_F < 0.5 /
 * sigma^2) or the state has no derivatives, the offset is the prior alone,
 * N(0, sigma^2 I).
 *
 * Exactness. The Gaussian at a state is a pure function of that state, so
 * q(y | x) is N(y - x; m(x), C(x)) and the reverse density N(x - y; m(y),
 * C(y)) is built the same way at y; the chain's ratio uses both. Offsets
 * are not wrapped: a proposal that leaves [0,1)^n has target 0 there, and
 * the chain rejects it without an evaluation (chain.h). Coordinates the
 * kernel does not move keep their values in both directions.
 *
 * Step scale. With the target's constant factors c (target.h's
 * step_scale) the model is built in z = u / c (g_z = c g, H_z = c H c) and
 * the offset mapped back by c; the Jacobian is a constant that cancels.
 *
 * Cost: one evaluation with gradient and Hessian per proposal (about 7 to
 * 60 times a plain one, bench_grad) and a symmetric eigendecomposition
 * (LAPACK dsyev) of the n x n Hessian of the proposed state; the current
 * state's Gaussian is kept from when it was built (h2mc_slot).
 */
#ifndef LMC_MCMC_H2MC_H
#define LMC_MCMC_H2MC_H

#include <stdint.h>

#include "lmc/kernels/chain.h"
#include "render/error.h"

typedef struct h2mc_params {
  double sigma; /* the prior's standard deviation (the paper's implementation: 0.01) */
  double L;     /* the time w t of every direction (pi / 2) */
  int delayed;  /* delayed acceptance (chain.h): a first test at the current state's
                   model, the Hessian at y only for the proposals that pass it (0: off) */
} h2mc_params;

h2mc_params h2mc_params_default(void);

/* The proposal's Gaussian at one state, over n coordinates. */
typedef struct h2mc_gauss {
  int n;
  int isotropic; /* N(0, sigma^2 I) (no usable curvature) */
  double *V;     /* eigenvectors, column i at V[i * n .. i * n + n - 1] (n x n) */
  double *P;     /* precisions along them */
  double *m;     /* mean in the eigenbasis */
  double *l;     /* the model's eigenvalues l_i (H's, in the step-scaled coordinates) */
  double *k;     /* m_i = k_i b_i: the mean's factor on the gradient's component b_i */
  double log_norm; /* sum log P_i / 2 - n log(2 pi) / 2 */
} h2mc_gauss;

/* Counters of one chain's kernel. */
typedef struct h2mc_stats {
  int64_t proposed;   /* proposals made */
  int64_t model;      /* ... from the Hessian's model (the rest: the prior alone) */
  int64_t outside;    /* ... that left [0,1)^n (rejected unevaluated) */
  int64_t eig_fail;   /* eigendecompositions that failed (the prior was used) */
  int64_t built;      /* Gaussians built (the rest of the 2 per proposal were kept) */
} h2mc_stats;

/* A state's Gaussian, kept with what identifies the state: its label, f,
 * whether it had derivatives, the coordinates moved and their values (all
 * coordinates' values when the kernel moves every one the chain keeps up
 * to date). */
typedef struct h2mc_slot {
  h2mc_gauss G;
  int valid, label, ok, n;
  double f;
  int *idx; /* the coordinates moved (room for MC_HESS_MAX) */
  double *u; /* the values compared (room for dim) */
} h2mc_slot;

typedef struct h2mc_kernel {
  h2mc_params p;
  const mc_target *target; /* borrowed (label_coords for labelled targets, step_scale) */
  int dim;
  /* Scratch, sized for MC_HESS_MAX coordinates. */
  int *idx;                /* the coordinates moved */
  double *g, *H, *work, *z, *d;
  int lwork;
  int subset;              /* the chain keeps only the moved coordinates up to date (coords) */
  /* The Gaussians of the last two states met: the current state's (cur)
   * and the last proposal's. A Gaussian is a pure function of its state,
   * so the one kept for a state is the one that would be built anew (the
   * same numbers, bit for bit): after a rejection the current state's is
   * used again, after an accepted H2MC step the proposal's. */
  h2mc_slot slot[2];
  int cur;
  h2mc_stats st;
} h2mc_kernel;

lmc_status h2mc_kernel_init(h2mc_kernel *k, const mc_target *target, const h2mc_params *p,
                            lmc_error *err);
void h2mc_kernel_free(h2mc_kernel *k);
/* The mc_kernel (kind FULL, needs_grad 2) over k; k must outlive the chain. */
mc_kernel h2mc_kernel_make(h2mc_kernel *k);

/* The Gaussian of the model at a state with f > 0, from g and H of log f
 * over n coordinates (H dense, n x n, row-major; overwritten). Exposed for
 * the tests. Returns 0, or -1 when the eigendecomposition failed (G is
 * then the prior). */
int h2mc_gauss_build(const h2mc_params *p, int n, const double *g, double *H, double *work,
                     int lwork, h2mc_gauss *G);
/* log N(d; m, C) of an offset d (n coordinates) under G. */
double h2mc_gauss_log_density(const h2mc_gauss *G, const double *d, double sigma);
/* The first test of delayed acceptance at the model: log of
 * f(y) q~(x | y) / (f(x) q(y | x)) for the offset d = y - x (step-scaled)
 * with log f_ratio = log f(y) - log f(x), where q~ is the Gaussian the
 * quadratic model of x predicts at y: the same Hessian (V, l, P), the
 * gradient moved by H d (b + l (V^T d)), so its mean m + k l (V^T d). Exact
 * when log f is quadratic; a function of x and y alone, as delayed
 * acceptance asks. The prior alone is symmetric: then log f_ratio. */
double h2mc_gauss_log_screen(const h2mc_gauss *G, const double *d, double log_f_ratio);
/* An offset d ~ G, from n standard normals z. */
void h2mc_gauss_sample(const h2mc_gauss *G, const double *z, double sigma, double *OUT_d);
/* The workspace dsyev wants for n x n (doubles). */
int h2mc_lwork(int n);

#endif
