/*
 * mala.c: the MALA proposal on the torus and Kelemen's small step (see
 * mala.h for the model and the density conventions).
 */
#include "lmc/kernels/mala.h"

#include <math.h>
#include <stddef.h>

#define MALA_TWO_PI 6.28318530717958647692

double mala_norm(int n, const double *g) {
  double s = 0.0;
  for (int i = 0; i < n; i++) s += g[i] * g[i];
  return sqrt(s);
}

double mala_truncate(int n, double *g, double bound) {
  for (int i = 0; i < n; i++)
    if (!isfinite(g[i])) g[i] = 0.0;
  double norm = mala_norm(n, g);
  if (bound > 0.0 && isfinite(bound) && norm > bound) {
    double k = bound / norm;
    for (int i = 0; i < n; i++) g[i] *= k;
  }
  return norm;
}

double mala_std_normal(rng *r) {
  /* Box-Muller: sqrt(-2 log u1) cos(2 pi u2), u1 in (0, 1]. */
  double u1 = 1.0 - rng_uniform(r), u2 = rng_uniform(r);
  return sqrt(-2.0 * log(u1)) * cos(MALA_TWO_PI * u2);
}

void mala_std_normal_pair(rng *r, double *OUT_z0, double *OUT_z1) {
  double u1 = 1.0 - rng_uniform(r), u2 = rng_uniform(r);
  double rad = sqrt(-2.0 * log(u1));
  *OUT_z0 = rad * cos(MALA_TWO_PI * u2);
  *OUT_z1 = rad * sin(MALA_TWO_PI * u2);
}

double mala_log_wrapped_normal(double y, double mu, double sigma) {
  /* The nearest image: d0 in [-1/2, 1/2). */
  double d0 = mala_torus_diff(y, mu);
  if (sigma > 1.0) {
    /* Fourier form: 1 + 2 sum_n exp(-2 pi^2 n^2 sigma^2) cos(2 pi n d0);
     * the first term is below 3e-9 and each next one far smaller. */
    double a = 0.5 * MALA_TWO_PI * MALA_TWO_PI * sigma * sigma, sum = 1.0;
    for (int k = 1; k < 64; k++) {
      double t = exp(-a * (double)k * (double)k);
      sum += 2.0 * t * cos(MALA_TWO_PI * k * d0);
      if (t < 1e-18) break;
    }
    return log(sum);
  }
  double inv = 0.5 / (sigma * sigma);
  /* The common case, sigma small against the distance to the next image
   * (at least 1 - 2 |d0| farther in squared distance): its weight
   * exp(-(1 - 2 |d0|) / (2 sigma^2)) is below e^-40 relative, under
   * rounding, and the nearest image alone is exact to double precision. */
  if (mala_nearest_image_exact(d0, inv)) return -d0 * d0 * inv - log(sigma) - MALA_LOG_SQRT_TWO_PI;
  /* Images d0 + k and d0 - k relative to the nearest: exponent
   * -((d0 + k)^2 - d0^2) / (2 sigma^2) = -k (k + 2 d0) / (2 sigma^2). Both
   * grow with k, so once a pair adds less than 1e-18 of the sum the rest
   * (decaying faster than geometrically) is below rounding. */
  double sum = 1.0;
  for (int k = 1; k < 1000; k++) {
    double kd = (double)k;
    double ea = exp(-kd * (kd + 2.0 * d0) * inv);
    double eb = exp(-kd * (kd - 2.0 * d0) * inv);
    sum += ea + eb;
    if (ea + eb < 1e-18 * sum) break;
  }
  return -d0 * d0 * inv + log(sum) - log(sigma) - MALA_LOG_SQRT_TWO_PI;
}

void mala_sample_c(int n, const double *x, const double *g, const double *M, const double *c,
                   double s, rng *r, double *OUT_y) {
  /* Box-Muller gives two independent normals per pair of uniforms. */
  for (int i = 0; i < n; i += 2) {
    double z[2];
    mala_std_normal_pair(r, &z[0], &z[1]);
    for (int j = 0; j < 2 && i + j < n; j++) {
      double m = M ? M[i + j] : 1.0, ci = c ? c[i + j] : 1.0;
      double mu = x[i + j] + 0.5 * s * ci * m * g[i + j];
      OUT_y[i + j] = ci > 0.0 ? mala_wrap(mu + ci * sqrt(s * m) * z[j]) : x[i + j];
    }
  }
}

void mala_sample(int n, const double *x, const double *g, const double *M, double s, rng *r,
                 double *OUT_y) {
  mala_sample_c(n, x, g, M, NULL, s, r, OUT_y);
}

double mala_log_density_c(int n, const double *x, const double *g, const double *M,
                          const double *c, double s, const double *y) {
  double lq = 0.0;
  for (int i = 0; i < n; i++) {
    double m = M ? M[i] : 1.0, ci = c ? c[i] : 1.0;
    if (!(ci > 0.0)) {
      if (y[i] != x[i]) return -INFINITY;
      continue;
    }
    lq += mala_log_wrapped_normal(y[i], x[i] + 0.5 * s * ci * m * g[i], ci * sqrt(s * m));
  }
  return lq;
}

double mala_log_density(int n, const double *x, const double *g, const double *M, double s,
                        const double *y) {
  return mala_log_density_c(n, x, g, M, NULL, s, y);
}

void mala_kelemen_sample_c(int n, const double *x, double s1, double s2, const double *c, rng *r,
                           double *OUT_y) {
  double logr = log(s2 / s1);
  for (int i = 0; i < n; i++) {
    /* One uniform gives the sign (its first half) and the magnitude. */
    double xi = rng_uniform(r), ci = c ? c[i] : 1.0;
    int neg = xi < 0.5;
    xi = neg ? 2.0 * xi : 2.0 * xi - 1.0;
    double d = ci * s2 * exp(-logr * xi);
    OUT_y[i] = ci > 0.0 ? mala_wrap(neg ? x[i] - d : x[i] + d) : x[i];
  }
}

void mala_kelemen_sample(int n, const double *x, double s1, double s2, rng *r, double *OUT_y) {
  mala_kelemen_sample_c(n, x, s1, s2, NULL, r, OUT_y);
}

double mala_kelemen_log_density_c(int n, const double *x, double s1, double s2, const double *c,
                                  const double *y) {
  /* The offset recomputed from the wrapped coordinates can differ from the
   * drawn one by rounding; a relative slack of 1e-9 at the edges of the
   * support keeps such proposals from getting density zero (a set of
   * measure ~1e-9 of the step, the same for both directions). */
  double logr = log(s2 / s1), lq = 0.0;
  for (int i = 0; i < n; i++) {
    double ci = c ? c[i] : 1.0, d = fabs(mala_torus_diff(y[i], x[i]));
    if (!(ci > 0.0)) {
      if (y[i] != x[i]) return -INFINITY;
      continue;
    }
    if (d < ci * s1 * (1.0 - 1e-9) || d > ci * s2 * (1.0 + 1e-9)) return -INFINITY;
    lq -= log(2.0 * d * logr);
  }
  return lq;
}

double mala_kelemen_log_density(int n, const double *x, double s1, double s2, const double *y) {
  return mala_kelemen_log_density_c(n, x, s1, s2, NULL, y);
}
