/*
 * chi2.h: chi-square goodness-of-fit tests for sampling routines (header
 * only, for the tests).
 *
 *   chi2_pvalue    observed counts against expected counts; cells whose
 *                  expectation is below `min_expected` are pooled into one
 *                  cell (as pbrt's test does), so the chi-square
 *                  approximation holds; returns the p-value.
 *   chi2_sphere    draws directions with a sampling routine, bins them on
 *                  the sphere in equal-area cells (cos theta x phi), and
 *                  compares with the integral of the claimed pdf over each
 *                  cell (midpoint rule on a sub-grid). Samples the routine
 *                  rejects count as absorbed; so does the missing mass of
 *                  the pdf, which is one more cell (pooled when small).
 *
 * Significance: a suite of k tests at overall level alpha uses the Sidak
 * level 1 - (1 - alpha)^(1/k) per test: chi2_sidak.
 */
#ifndef LMC_TESTS_CHI2_H
#define LMC_TESTS_CHI2_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "render/rng.h"
#include "render/vec3.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Regularised upper incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a):
 * series for x < a + 1, Lentz's continued fraction otherwise. */
static inline double chi2_gamma_q(double a, double x) {
  if (x <= 0.0) return 1.0;
  double gln = lgamma(a);
  if (x < a + 1.0) {
    double ap = a, sum = 1.0 / a, del = sum;
    for (int i = 0; i < 100000; i++) {
      ap += 1.0;
      del *= x / ap;
      sum += del;
      if (fabs(del) < fabs(sum) * 1e-15) break;
    }
    return 1.0 - sum * exp(-x + a * log(x) - gln);
  }
  double b = x + 1.0 - a, c = 1.0 / 1e-300, d = 1.0 / b, h = d;
  for (int i = 1; i < 100000; i++) {
    double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (fabs(d) < 1e-300) d = 1e-300;
    c = b + an / c;
    if (fabs(c) < 1e-300) c = 1e-300;
    d = 1.0 / d;
    double del = d * c;
    h *= del;
    if (fabs(del - 1.0) < 1e-15) break;
  }
  return exp(-x + a * log(x) - gln) * h;
}

/* Per-test significance level for k tests at overall level alpha. */
static inline double chi2_sidak(double alpha, int k) { return 1.0 - pow(1.0 - alpha, 1.0 / k); }

/* p-value of observed vs expected over n cells. Cells with expectation
 * below min_expected are pooled. A cell with zero expectation but observed
 * samples makes the p-value 0. *dof_out (may be NULL) gets the degrees of
 * freedom, *stat_out (may be NULL) the statistic. */
static inline double chi2_pvalue(const double *obs, const double *expct, int n, double min_expected,
                                 int *dof_out, double *stat_out) {
  double stat = 0.0, pool_obs = 0.0, pool_exp = 0.0;
  int cells = 0;
  for (int i = 0; i < n; i++) {
    if (expct[i] <= 0.0) {
      if (obs[i] > 0.0) {
        if (dof_out) *dof_out = -1;
        if (stat_out) *stat_out = INFINITY;
        return 0.0;
      }
      continue;
    }
    if (expct[i] < min_expected) {
      pool_obs += obs[i];
      pool_exp += expct[i];
      continue;
    }
    double d = obs[i] - expct[i];
    stat += d * d / expct[i];
    cells++;
  }
  if (pool_exp > 0.0) {
    double d = pool_obs - pool_exp;
    stat += d * d / pool_exp;
    cells++;
  }
  int dof = cells - 1;
  if (dof_out) *dof_out = dof;
  if (stat_out) *stat_out = stat;
  if (dof < 1) return 1.0;
  return chi2_gamma_q(0.5 * dof, 0.5 * stat);
}

/* A sampling routine: from three uniforms, a unit direction; returns 0 when
 * the sample is absorbed / invalid. */
typedef int (*chi2_sample_fn)(void *ctx, double u1, double u2, double u3, vec3 *w);
/* The density the routine claims, per unit solid angle. */
typedef double (*chi2_pdf_fn)(void *ctx, vec3 w);

typedef struct chi2_result {
  double pvalue;
  double pdf_integral; /* integral of the pdf over the sphere */
  double stat;
  int dof;
  int64_t accepted;    /* samples the routine did not reject */
} chi2_result;

/* Bins: n_theta bands equal in cos(theta), n_phi sectors. The sub-grid for
 * integrating the pdf has `sub` x `sub` midpoints per cell. */
static inline chi2_result chi2_sphere(chi2_sample_fn sample, chi2_pdf_fn pdf, void *ctx, int n_theta,
                                      int n_phi, int sub, int64_t n_samples, uint64_t seed) {
  int cells = n_theta * n_phi;
  double *obs = calloc((size_t)cells + 1, sizeof(double));
  double *expct = calloc((size_t)cells + 1, sizeof(double));
  chi2_result res = {0};
  if (!obs || !expct) {
    free(obs);
    free(expct);
    res.pvalue = -1.0;
    return res;
  }
  /* Draw the samples and histogram them; rejected ones go to the last cell. */
  rng r;
  rng_seed(&r, seed, 7);
  for (int64_t i = 0; i < n_samples; i++) {
    double u1 = rng_uniform(&r), u2 = rng_uniform(&r), u3 = rng_uniform(&r);
    vec3 w;
    if (!sample(ctx, u1, u2, u3, &w) || !v3_isfinite(w)) {
      obs[cells] += 1.0;
      continue;
    }
    res.accepted++;
    double z = fmin(1.0, fmax(-1.0, w.z));
    int it = (int)((1.0 - z) * 0.5 * n_theta);
    if (it >= n_theta) it = n_theta - 1;
    double phi = atan2(w.y, w.x);
    if (phi < 0.0) phi += 2.0 * M_PI;
    int ip = (int)(phi / (2.0 * M_PI) * n_phi);
    if (ip >= n_phi) ip = n_phi - 1;
    obs[it * n_phi + ip] += 1.0;
  }
  /* Integrate the pdf over each cell: d omega = d(cos theta) d phi. */
  double dz = 2.0 / n_theta / sub, dphi = 2.0 * M_PI / n_phi / sub, total = 0.0;
  for (int it = 0; it < n_theta; it++)
    for (int ip = 0; ip < n_phi; ip++) {
      double acc = 0.0;
      for (int a = 0; a < sub; a++)
        for (int b = 0; b < sub; b++) {
          double z = 1.0 - (it * sub + a + 0.5) * dz;
          double phi = (ip * sub + b + 0.5) * dphi;
          double s = sqrt(fmax(0.0, 1.0 - z * z));
          acc += pdf(ctx, v3(s * cos(phi), s * sin(phi), z));
        }
      acc *= dz * dphi;
      expct[it * n_phi + ip] = acc * (double)n_samples;
      total += acc;
    }
  /* The rejected cell always has a (tiny) positive expectation: the
   * midpoint integral of a sharp lobe can exceed 1 by more than the true
   * rejected mass, and a zero expectation with observed rejections would
   * make the p-value 0; a tiny one is pooled with the other small cells. */
  expct[cells] = fmax(1e-9, 1.0 - total) * (double)n_samples;
  res.pdf_integral = total;
  res.pvalue = chi2_pvalue(obs, expct, cells + 1, 5.0, &res.dof, &res.stat);
  free(obs);
  free(expct);
  return res;
}

#endif
