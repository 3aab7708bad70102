/*
 * adam.h: Adam's moment statistics of the gradient along a Markov chain,
 * and the diagonal preconditioners LMC builds from them.
 *
 * Adam (Kingma and Ba 2015) keeps exponential moving averages of the
 * gradient g and of its square, per coordinate:
 *
 *     adam_m1 <- beta1 adam_m1 + (1 - beta1) g        (beta1 = 0.9)
 *     adam_m2 <- beta2 adam_m2 + (1 - beta2) g^2      (beta2 = 0.999)
 *
 * with the bias corrections m1 / (1 - beta1^t), m2 / (1 - beta2^t) for t
 * updates. Luan et al. 2020 ("Langevin Monte Carlo Rendering with
 * Gradient-based Adaptation", sec. 4) precondition MALA with the diagonal
 * M = 1 / (eps + sqrt(v)), v the corrected second moment, an RMSprop/Adam
 * estimate of the inverse curvature scale; we clamp it to [lo, hi] so the
 * kernel family stays bounded (the containment condition of adaptive MCMC,
 * Roberts and Rosenthal 2007).
 *
 * The counts are per coordinate: a chain over paths of varying length
 * updates only the coordinates its current path uses. A coordinate never
 * updated, or whose gradient has always been exactly zero (a discrete
 * choice such as a lobe or Russian roulette, whose derivative is 0 by
 * construction), has M = 1 (clamped), not the upper clamp that
 * 1 / (eps + 0) would give.
 *
 * Preconditioner schedules (lmc_adapt in render/settings.h):
 *   none      M = I.
 *   adam      M = M_adam(t), used directly. The kernel changes with the
 *             chain's own history without fading, which breaks the
 *             stationarity of pi: biased, kept for comparison.
 *   diminish  M = (1 - w_t) I + w_t M_adam(t), w_t = min(1, t0 / t): the
 *             adaptation fades as 1/t towards the fixed kernel M = I, so
 *             successive kernels differ by O(1/t) (diminishing adaptation;
 *             with the clamp, the chain is ergodic: Roberts and Rosenthal
 *             2007, theorem 1).
 *   cache     stage 1 runs adam and records moments; stage 2 looks M up in
 *             the frozen cache (gcache.h).
 */
#ifndef LMC_MCMC_ADAM_H
#define LMC_MCMC_ADAM_H

#include <math.h>
#include <stdint.h>

#include "render/error.h"

#define ADAM_BETA1 0.9
#define ADAM_BETA2 0.999

/* The moments of one chain over up to `cap` coordinates. Owns its arrays. */
typedef struct adam_stats {
  int cap;
  double *adam_m1;  /* first moment, uncorrected */
  double *adam_m2;  /* second moment, uncorrected */
  int64_t *count;   /* updates per coordinate */
  double *beta1_t;  /* beta1^count per coordinate (the bias corrections, kept by multiplication) */
  double *beta2_t;  /* beta2^count per coordinate */
  int64_t t;        /* updates of the whole vector (the diminishing schedule's clock) */
} adam_stats;

/* Allocates zeroed moments for cap coordinates (cap >= 1). */
lmc_status adam_init(adam_stats *a, int cap, lmc_error *err);
/* Frees the arrays (a may be NULL or zeroed). */
void adam_free(adam_stats *a);
/* Forgets all updates. */
void adam_reset(adam_stats *a);

/* One update with the gradient g of the first n coordinates (n <= cap). */
void adam_update(adam_stats *a, int n, const double *g);

/* Bias-corrected moments of coordinate i (0, 0 before its first update). */
void adam_moments(const adam_stats *a, int i, double *OUT_m1, double *OUT_m2);

/* M_i = clamp(1 / (eps + sqrt(v_i)), lo, hi) from a corrected second moment v_i. */
static inline double adam_precond_from_m2(double v, double eps, double lo, double hi) {
  double m = 1.0 / (eps + sqrt(v > 0.0 ? v : 0.0));
  return m < lo ? lo : (m > hi ? hi : m);
}

/* The Adam preconditioner of the first n coordinates (1, clamped, for a
 * coordinate never updated or with second moment exactly 0). */
void adam_precond(const adam_stats *a, int n, double eps, double lo, double hi, double *OUT_M);

/* The diminishing schedule: (1 - w) + w M_adam with w = min(1, t0 / t). */
void adam_precond_diminish(const adam_stats *a, int n, double eps, double lo, double hi,
                           double t0, double *OUT_M);

#endif
