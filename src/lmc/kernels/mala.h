/*
 * mala.h: the Metropolis-adjusted Langevin proposal on the unit torus, and
 * Kelemen's isotropic small step with its exact density, as pure functions
 * over vectors.
 *
 * MALA (Roberts and Tweedie 1996; for rendering: Luan, Zhao, Bala and
 * Gkioulekas 2020, "Langevin Monte Carlo Rendering with Gradient-based
 * Adaptation"). At a state x in [0,1)^n with g = grad log pi(x) (its norm
 * truncated to a bound, as the paper's implementation does, so that a huge
 * gradient near a singularity cannot throw the chain away) and a diagonal
 * preconditioner M, the proposal is
 *
 *     y ~ N(x + (s/2) M g, s M),   then every coordinate wrapped into [0,1).
 *
 * The Metropolis-Hastings ratio needs the density of y on the torus, not on
 * the real line: a coordinate y_i has the wrapped normal density
 *
 *     q_i(y_i | x) = sum over integers k of N(y_i + k; mu_i, sigma_i^2),
 *     mu_i = x_i + (s/2) M_i g_i,   sigma_i^2 = s M_i,
 *
 * and q(y | x) is the product over i (M is diagonal). mala_log_wrapped_normal
 * evaluates it to double precision: for sigma <= 1 it sums images around the
 * nearest one until a pair adds less than 1e-18 of the sum (terms shrink
 * like exp(-k^2 / (2 sigma^2)), so the tail is below rounding); for
 * sigma > 1 the Fourier form of the same function (Jacobi theta),
 * 1 + 2 sum_n exp(-2 pi^2 n^2 sigma^2) cos(2 pi n d), converges in a few
 * terms. Logs are computed relative to the nearest image, so a far y gives
 * a large negative log density, never log(0) from underflow.
 *
 * Kelemen's small step (Kelemen, Szirmay-Kalos, Antal and Csonka 2002): each
 * coordinate moves by +-r, r = s2 exp(-log(s2 / s1) xi) with xi uniform, so
 * |offset| is log-uniform on (s1, s2] and the offset density is
 * 1 / (2 |d| log(s2 / s1)) there, zero elsewhere. With s2 < 1/2 only one
 * image of y can lie within s2 of x, so that is also the torus density.
 * The step is symmetric; the density matters only where it is mixed with
 * MALA in one state-dependent kernel (the fallback where a state has no
 * gradient: the forward density is Kelemen's, the reverse may be MALA's).
 *
 * Per-coordinate step scale c (the _c variants; mc_target.step_scale): a
 * constant diagonal change of variables z_i = u_i / c_i, for a coordinate
 * whose mapping has a huge derivative (the triangle choice of a finely
 * tessellated area light). MALA in z with gradient g_z = c g_u (the caller
 * passes g_z, so that truncation and Adam's statistics see the gradient
 * in the rescaled coordinates) is, in u,
 *
 *     y ~ N(x + (s/2) c^2 M g_u, s c^2 M) = N(x + (s/2) c M g_z, s c^2 M),
 *
 * a constant diagonal factor c^2 of the preconditioner: the densities are
 * the wrapped normals above with mu_i = x_i + (s/2) c_i M_i g_z,i and
 * sigma_i = c_i sqrt(s M_i), exact on the torus. Kelemen's step scales its
 * offsets to (c_i s1, c_i s2]. c_i = 0 keeps coordinate i fixed (its
 * density factor is a point mass: 0 in log where y_i = x_i, else -inf).
 * c == NULL means c = 1.
 *
 * Conventions: n coordinates, double vectors, M == NULL means M = I. The
 * sampling routines take their random numbers from an rng; they do not
 * allocate. OUT_ arrays may not alias inputs.
 */
#ifndef LMC_MCMC_MALA_H
#define LMC_MCMC_MALA_H

#include <math.h>

#include "render/rng.h"

/* Euclidean norm of g. */
double mala_norm(int n, const double *g);

/* Scales g in place to norm `bound` when its norm exceeds it (bound <= 0 or
 * infinite: no truncation). Non-finite entries are set to 0 first. Returns
 * the norm before truncation. */
double mala_truncate(int n, double *g, double bound);

/* A standard normal deviate (Box-Muller, one of the pair; two uniforms). */
double mala_std_normal(rng *r);
/* Two independent standard normal numbers from one Box-Muller pair. */
void mala_std_normal_pair(rng *r, double *OUT_z0, double *OUT_z1);

/* log sqrt(2 pi), the normal density's constant. */
#define MALA_LOG_SQRT_TWO_PI 0.91893853320467274178

/* 1 when the wrapped normal of inv = 1 / (2 sigma^2) at nearest-image
 * offset d0 is its nearest image alone to double precision: the next image
 * is at least 1 - 2 |d0| farther in squared distance, so its weight is
 * below e^-40 relative. */
static inline int mala_nearest_image_exact(double d0, double inv) {
  return (1.0 - 2.0 * fabs(d0)) * inv > 40.0;
}

/* Wraps a real number into [0, 1). */
static inline double mala_wrap(double y) {
  double w = y - floor(y);
  return w < 1.0 ? w : 0.0;
}

/* log of the wrapped normal density on [0,1) at y for mean mu (any real)
 * and standard deviation sigma > 0. */
double mala_log_wrapped_normal(double y, double mu, double sigma);

/* Draws y ~ N(x + (s/2) M g, s M) wrapped into [0,1)^n. g: the (truncated)
 * gradient of log pi at x; M: diagonal (NULL: identity); s > 0. */
void mala_sample(int n, const double *x, const double *g, const double *M, double s, rng *r,
                 double *OUT_y);

/* log q(y | x) of mala_sample with the same g, M and s (exact on the torus). */
double mala_log_density(int n, const double *x, const double *g, const double *M, double s,
                        const double *y);

/* mala_sample and mala_log_density with the step scale c (see above; g is
 * the gradient in the rescaled coordinates, c g_u). */
void mala_sample_c(int n, const double *x, const double *g, const double *M, const double *c,
                   double s, rng *r, double *OUT_y);
double mala_log_density_c(int n, const double *x, const double *g, const double *M,
                          const double *c, double s, const double *y);

/* Kelemen's small step with offsets log-uniform in (s1, s2], 0 < s1 < s2 < 1/2. */
void mala_kelemen_sample(int n, const double *x, double s1, double s2, rng *r, double *OUT_y);

/* log density of mala_kelemen_sample at y given x (-INFINITY where zero). */
double mala_kelemen_log_density(int n, const double *x, double s1, double s2, const double *y);

/* Kelemen's step with coordinate i's offsets in (c_i s1, c_i s2], and its
 * log density (c_i in [0, 1]; NULL: 1). */
void mala_kelemen_sample_c(int n, const double *x, double s1, double s2, const double *c, rng *r,
                           double *OUT_y);
double mala_kelemen_log_density_c(int n, const double *x, double s1, double s2, const double *c,
                                  const double *y);

/* Signed torus difference y - x, in [-1/2, 1/2). */
static inline double mala_torus_diff(double y, double x) {
  double d = y - x;
  return d - floor(d + 0.5);
}

#endif
