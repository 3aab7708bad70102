/*
 * test_mala.c: the MALA proposal on the torus and Kelemen's small step
 * (src/lmc/kernels/mala.h): their densities integrate to one, match the samples
 * the samplers draw (chi-square on 1-D and 2-D marginals), and wrap
 * around the torus correctly.
 *
 * Significance: the chi-square tests of this file are a suite of
 * CHI2_TESTS tests at overall level 1e-3 (Sidak), fixed seeds.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include <cmocka.h>

#include "chi2.h"
#include "lmc/kernels/mala.h"
#include "test_util.h"

#define CHI2_TESTS 6

/* One coordinate's proposal: x, g, M, s. */
typedef struct case1 {
  double x, g, M, s;
} case1;

/* Cases: narrow, wide, very wide (Fourier branch), drift across 0, near the seam. */
static const case1 cases[] = {
    {0.5, 0.0, 1.0, 1e-4},     /* sigma 0.01 */
    {0.02, -30.0, 1.0, 1e-3},  /* mean -0.013: wraps below 0 */
    {0.97, 50.0, 2.0, 5e-3},   /* sigma 0.1, mean 1.22: wraps above 1 */
    {0.3, 1.0, 100.0, 4e-3},   /* sigma 0.63 */
    {0.8, 0.5, 1000.0, 4e-3},  /* sigma 2: Fourier branch */
    {0.5, 0.0, 1e-3, 1e-4},    /* sigma 3e-4: very narrow */
};
#define N_CASES ((int)(sizeof cases / sizeof cases[0]))

static double q1(const case1 *c, double y) {
  return exp(mala_log_density(1, &c->x, &c->g, &c->M, c->s, &y));
}

/* q(y | x) integrates to one over [0,1) (1-D; midpoint rule fine enough for
 * the narrowest sigma: 2e6 cells of 5e-7). */
static void test_density_integrates_1d(void **state) {
  (void)state;
  int checked = 0;
  for (int ci = 0; ci < N_CASES; ci++) {
    const int n = 2000000;
    double sum = 0.0;
    for (int i = 0; i < n; i++) sum += q1(&cases[ci], (i + 0.5) / n);
    sum /= n;
    assert_near(sum, 1.0, 1e-6);
    checked++;
  }
  assert_int_equal(checked, N_CASES);
}

/* In 2-D with a different M per axis, and for Kelemen's step. */
static void test_density_integrates_2d(void **state) {
  (void)state;
  double x[2] = {0.95, 0.1}, g[2] = {20.0, -5.0}, M[2] = {4.0, 0.25}, s = 2e-3;
  const int n = 2000;
  double sum = 0.0;
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) {
      double y[2] = {(i + 0.5) / n, (j + 0.5) / n};
      sum += exp(mala_log_density(2, x, g, M, s, y));
    }
  sum /= (double)n * n;
  assert_near(sum, 1.0, 1e-6);

  /* Kelemen, 1-D: the density 1/(2|d| log(s2/s1)) on s1 < |d| <= s2; the
   * 1/|d| shape needs a fine grid: 4e6 cells of 2.5e-7 around x. */
  double s1 = 1.0 / 1024.0, s2 = 1.0 / 64.0, xk = 0.005, ksum = 0.0;
  const int nk = 4000000;
  for (int i = 0; i < nk; i++) {
    double d = -0.5 + (i + 0.5) / nk;
    double y = mala_wrap(xk + d);
    double l = mala_kelemen_log_density(1, &xk, s1, s2, &y);
    if (isfinite(l)) ksum += exp(l);
  }
  ksum /= nk;
  assert_near(ksum, 1.0, 1e-4);
}

/* The nearest image is what matters when sigma is small, both images at
 * the seam, and the two evaluation branches agree where they meet. */
static void test_wrap_around(void **state) {
  (void)state;
  const double ls2pi = 0.5 * log(2.0 * M_PI);
  /* y = 0.01, mu = 0.99: distance 0.02 across the seam. */
  double sigma = 0.01;
  double expect = -0.02 * 0.02 / (2 * sigma * sigma) - log(sigma) - ls2pi;
  assert_near(mala_log_wrapped_normal(0.01, 0.99, sigma), expect, 1e-12);
  assert_near(mala_log_wrapped_normal(0.01, -0.01, sigma), expect, 1e-12);
  assert_near(mala_log_wrapped_normal(0.99, 0.01, sigma), expect, 1e-12);
  assert_near(mala_log_wrapped_normal(0.01, 5.99, sigma), expect, 1e-9);
  /* At the antipode both images weigh the same: log(2 N(1/2)). */
  sigma = 0.1;
  expect = log(2.0) - 0.25 / (2 * sigma * sigma) - log(sigma) - ls2pi;
  assert_near(mala_log_wrapped_normal(0.75, 0.25, sigma), expect, 1e-6);
  /* Branch continuity at sigma = 1 (images below, Fourier above). */
  for (int i = 0; i < 10; i++) {
    double y = 0.1 * i + 0.03;
    double a = mala_log_wrapped_normal(y, 0.4, 1.0);
    double b = mala_log_wrapped_normal(y, 0.4, 1.0 + 1e-12);
    assert_near(a, b, 1e-10);
  }
  /* A far point with a tiny sigma: finite and very negative, never -inf. */
  double l = mala_log_wrapped_normal(0.5, 0.0, 1e-4);
  assert_true(isfinite(l));
  assert_true(l < -1e6);
  /* Sampled points always lie in [0, 1). */
  rng r;
  rng_seed(&r, 3, 0);
  for (int i = 0; i < 100000; i++) {
    double x = 0.999999, g = 1e3, M = 1.0, y;
    mala_sample(1, &x, &g, &M, 1e-4, &r, &y);
    assert_true(y >= 0.0 && y < 1.0);
    mala_kelemen_sample(1, &x, 1.0 / 1024, 1.0 / 64, &r, &y);
    assert_true(y >= 0.0 && y < 1.0);
  }
  assert_near(mala_wrap(-1e-18), 0.0, 0.0);
}

/* Expected counts of a 1-D density over nb bins (sub midpoints per bin). */
static void expected_1d(double (*pdf)(const void *, double), const void *ctx, int nb, int sub,
                        double n, double *OUT_e) {
  for (int b = 0; b < nb; b++) {
    double acc = 0.0;
    for (int k = 0; k < sub; k++) acc += pdf(ctx, (b + (k + 0.5) / sub) / nb);
    OUT_e[b] = acc / (sub * (double)nb) * n;
  }
}

static double pdf_case(const void *ctx, double y) { return q1(ctx, y); }

/* Distribution function of Kelemen's signed offset: |d| log-uniform on
 * (s1, s2], each sign with probability 1/2. */
static double kelemen_cdf(double t, double s1, double s2) {
  double L2 = 2.0 * log(s2 / s1);
  if (t < -s2) return 0.0;
  if (t < -s1) return (log(s2) - log(-t)) / L2;
  if (t < s1) return 0.5;
  if (t < s2) return 0.5 + (log(t) - log(s1)) / L2;
  return 1.0;
}

/* Samples of mala_sample match mala_log_density: 1-D histograms. */
static void test_samples_match_1d(void **state) {
  (void)state;
  double alpha = chi2_sidak(1e-3, CHI2_TESTS);
  enum { NB = 200, NS = 400000 };
  static double obs[NB], ex[NB];
  rng r;
  rng_seed(&r, 11, 1);
  int checked = 0;
  for (int ci = 1; ci <= 4; ci++) {
    const case1 *c = &cases[ci];
    for (int b = 0; b < NB; b++) obs[b] = 0.0;
    for (int i = 0; i < NS; i++) {
      double y;
      mala_sample(1, &c->x, &c->g, &c->M, c->s, &r, &y);
      int b = (int)(y * NB);
      obs[b < NB ? b : NB - 1] += 1.0;
    }
    expected_1d(pdf_case, c, NB, 64, NS, ex);
    int dof;
    double stat, p = chi2_pvalue(obs, ex, NB, 5.0, &dof, &stat);
    if (p < alpha) print_error("case %d: p = %g, stat %g, dof %d\n", ci, p, stat, dof);
    assert_true(p >= alpha);
    assert_true(dof > 10);
    checked++;
  }
  /* Kelemen's step near the seam. */
  double xk = 0.003, s1 = 1.0 / 1024, s2 = 1.0 / 64;
  for (int b = 0; b < NB; b++) obs[b] = ex[b] = 0.0;
  /* Bins over the offset d in [-s2, s2] (40 bins), expected from the
   * closed-form distribution function. */
  const int nd = 40;
  for (int i = 0; i < NS; i++) {
    double y;
    mala_kelemen_sample(1, &xk, s1, s2, &r, &y);
    double d = mala_torus_diff(y, xk);
    int b = (int)((d + s2) / (2 * s2) * nd);
    obs[b < 0 ? 0 : (b >= nd ? nd - 1 : b)] += 1.0;
  }
  for (int b = 0; b < nd; b++) {
    double lo = -s2 + 2 * s2 * b / nd, hi = lo + 2 * s2 / nd;
    ex[b] = (kelemen_cdf(hi, s1, s2) - kelemen_cdf(lo, s1, s2)) * NS;
  }
  int dof;
  double stat, p = chi2_pvalue(obs, ex, nd, 5.0, &dof, &stat);
  if (p < alpha) print_error("kelemen: p = %g, stat %g, dof %d\n", p, stat, dof);
  assert_true(p >= alpha);
  checked++;
  assert_int_equal(checked, 5);
}

/* 2-D marginal (y0, y1) of a 3-D proposal with a different M per axis. */
static void test_samples_match_2d(void **state) {
  (void)state;
  double alpha = chi2_sidak(1e-3, CHI2_TESTS);
  enum { NB = 30, NS = 600000 };
  static double obs[NB * NB], ex[NB * NB];
  double x[3] = {0.98, 0.05, 0.5}, g[3] = {10.0, -4.0, 1.0}, M[3] = {1.0, 0.3, 5.0}, s = 4e-3;
  rng r;
  rng_seed(&r, 12, 2);
  for (int i = 0; i < NS; i++) {
    double y[3];
    mala_sample(3, x, g, M, s, &r, y);
    int a = (int)(y[0] * NB), b = (int)(y[1] * NB);
    obs[(a < NB ? a : NB - 1) * NB + (b < NB ? b : NB - 1)] += 1.0;
  }
  /* The marginal of a product density is the product of its factors. */
  const int sub = 32;
  for (int a = 0; a < NB; a++)
    for (int b = 0; b < NB; b++) {
      double pa = 0.0, pb = 0.0;
      for (int k = 0; k < sub; k++) {
        double ya = (a + (k + 0.5) / sub) / NB, yb = (b + (k + 0.5) / sub) / NB;
        pa += exp(mala_log_density(1, &x[0], &g[0], &M[0], s, &ya));
        pb += exp(mala_log_density(1, &x[1], &g[1], &M[1], s, &yb));
      }
      ex[a * NB + b] = pa / (sub * NB) * pb / (sub * NB) * NS;
    }
  int dof;
  double stat, p = chi2_pvalue(obs, ex, NB * NB, 5.0, &dof, &stat);
  if (p < alpha) print_error("2-D: p = %g, stat %g, dof %d\n", p, stat, dof);
  assert_true(p >= alpha);
  assert_true(dof > 20);
}

/* Truncation scales the gradient to the bound and cleans non-finite values. */
static void test_truncate(void **state) {
  (void)state;
  double g[3] = {3.0, 4.0, 0.0};
  double n = mala_truncate(3, g, 1.0);
  assert_near(n, 5.0, 1e-15);
  assert_near(mala_norm(3, g), 1.0, 1e-15);
  assert_near(g[0], 0.6, 1e-15);
  double h[2] = {NAN, 2.0};
  mala_truncate(2, h, 10.0);
  assert_near(h[0], 0.0, 0.0);
  assert_near(h[1], 2.0, 0.0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_density_integrates_1d), cmocka_unit_test(test_density_integrates_2d),
      cmocka_unit_test(test_wrap_around),           cmocka_unit_test(test_samples_match_1d),
      cmocka_unit_test(test_samples_match_2d),      cmocka_unit_test(test_truncate),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
