/*
 * test_distribution.c: the piecewise-constant distributions of
 * src/render/distribution.c.
 *
 * What is checked: samples follow the claimed density (chi-square on a
 * histogram finer than the cells, and on the discrete cells), the density
 * integrates to 1, sample and invert are inverse functions (1e-12), the
 * remapped u of discrete sampling, the uniform fallback of all-zero
 * functions (1-D and 2-D, including an all-zero row of a 2-D function),
 * and the rejection of bad input. Seeds are fixed; the chi-square tests
 * share an overall level of 1% (Sidak), so the suite fails by chance with
 * probability below 1%.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "test_util.h"

#include "chi2.h"
#include "render/distribution.h"
#include "render/rng.h"


/* Number of chi-square tests in this file (for the Sidak level). */
#define N_CHI2_TESTS 4

static double alpha_per_test(void) { return chi2_sidak(0.01, N_CHI2_TESTS); }

/* A 1-D function with leading, interior and trailing zeros. */
static const double f1[] = {0.0, 1.0, 3.0, 0.0, 2.0, 0.5, 0.25, 0.0};
#define N1 ((int)(sizeof f1 / sizeof f1[0]))

static void test_1d_basics(void **state) {
  (void)state;
  distrib1d d;
  lmc_error err;
  int checks = 0;
  assert_int_equal(distrib1d_init(&d, f1, N1, &err), LMC_OK);
  checks++;

  /* Integral = sum f / n, and the CDF is pinned at both ends. */
  double sum = 0.0;
  for (int i = 0; i < N1; i++) sum += f1[i];
  assert_near(d.integral, sum / N1, 1e-15);
  assert_true(d.cdf[0] == 0.0 && d.cdf[N1] == 1.0);
  checks += 2;

  /* pmf sums to 1 and is f / sum; out-of-range indices have pmf 0. */
  double pmf_sum = 0.0;
  for (int i = 0; i < N1; i++) {
    assert_near(distrib1d_pmf(&d, i), f1[i] / sum, 1e-15);
    pmf_sum += distrib1d_pmf(&d, i);
    checks++;
  }
  assert_near(pmf_sum, 1.0, 1e-14);
  assert_true(distrib1d_pmf(&d, -1) == 0.0 && distrib1d_pmf(&d, N1) == 0.0);
  checks += 2;

  /* pdf integrates to 1 (midpoint rule is exact on a step function). */
  int m = 64 * N1;
  double integral = 0.0;
  for (int k = 0; k < m; k++) integral += distrib1d_pdf_cont(&d, (k + 0.5) / m) / m;
  assert_near(integral, 1.0, 1e-13);
  checks++;

  /* invert(sample(u)) == u, sample lands in a non-empty cell with the pdf
   * of that cell, and sample(invert(x)) == x inside non-empty cells. */
  rng r;
  rng_seed(&r, 1234, 1);
  int bad = 0, n_round = 100000;
  for (int k = 0; k < n_round; k++) {
    double u = rng_uniform(&r), pdf;
    int idx;
    double x = distrib1d_sample_cont(&d, u, &pdf, &idx);
    if (!(x >= 0.0 && x < 1.0)) bad++;
    if (f1[idx] == 0.0 || (int)(x * N1) != idx) bad++;
    if (fabs(pdf - distrib1d_pdf_cont(&d, x)) > 1e-14) bad++;
    if (fabs(distrib1d_invert_cont(&d, x) - u) > 1e-12) bad++;
    double x2 = rng_uniform(&r);
    if (f1[(int)(x2 * N1)] > 0.0) {
      double x3 = distrib1d_sample_cont(&d, distrib1d_invert_cont(&d, x2), NULL, NULL);
      if (fabs(x3 - x2) > 1e-12) bad++;
    }
  }
  assert_int_equal(bad, 0);
  checks++;

  /* Discrete sampling: u_remap in [0,1) and cdf[i] + remap * width == u;
   * u = 0 and u just below 1 pick the first and last non-empty cells. */
  bad = 0;
  for (int k = 0; k < n_round; k++) {
    double u = rng_uniform(&r), pmf, rem;
    int i = distrib1d_sample_discrete(&d, u, &pmf, &rem);
    if (!(rem >= 0.0 && rem < 1.0)) bad++;
    if (fabs(d.cdf[i] + rem * (d.cdf[i + 1] - d.cdf[i]) - u) > 1e-14) bad++;
    if (pmf != distrib1d_pmf(&d, i) || !(pmf > 0.0)) bad++;
  }
  assert_int_equal(bad, 0);
  double pmf;
  assert_int_equal(distrib1d_sample_discrete(&d, 0.0, &pmf, NULL), 1);
  assert_int_equal(distrib1d_sample_discrete(&d, nextafter(1.0, 0.0), &pmf, NULL), 6);
  double x_hi = distrib1d_sample_cont(&d, nextafter(1.0, 0.0), NULL, NULL);
  assert_true(x_hi < 1.0 && x_hi >= 6.0 / N1);
  checks += 4;

  distrib1d_free(&d);
  distrib1d_free(&d); /* idempotent */
  assert_null(d.func);
  checks++;
  assert_int_equal(checks, 12 + N1);
}

static void test_1d_chi2(void **state) {
  (void)state;
  distrib1d d;
  lmc_error err;
  assert_int_equal(distrib1d_init(&d, f1, N1, &err), LMC_OK);
  /* Continuous samples in 5 bins per cell: expected count n * integral of
   * the pdf over the bin = n * f / (I n_bins). */
  enum { SUB = 5, N = 200000 };
  double obs[N1 * SUB] = {0}, expct[N1 * SUB];
  double obs_d[N1] = {0}, expct_d[N1];
  rng r;
  rng_seed(&r, 99, 3);
  for (int k = 0; k < N; k++) {
    double x = distrib1d_sample_cont(&d, rng_uniform(&r), NULL, NULL);
    int b = (int)(x * N1 * SUB);
    obs[b < N1 * SUB ? b : N1 * SUB - 1] += 1.0;
    obs_d[distrib1d_sample_discrete(&d, rng_uniform(&r), NULL, NULL)] += 1.0;
  }
  for (int b = 0; b < N1 * SUB; b++)
    expct[b] = N * distrib1d_pdf_cont(&d, (b + 0.5) / (N1 * SUB)) / (N1 * SUB);
  for (int i = 0; i < N1; i++) expct_d[i] = N * distrib1d_pmf(&d, i);
  int dof;
  double stat;
  double p = chi2_pvalue(obs, expct, N1 * SUB, 5.0, &dof, &stat);
  print_message("1-D continuous: chi2 %.2f dof %d p %.4f\n", stat, dof, p);
  assert_true(p > alpha_per_test());
  assert_int_equal(dof, 5 * SUB - 1); /* five non-empty cells */
  p = chi2_pvalue(obs_d, expct_d, N1, 5.0, &dof, &stat);
  print_message("1-D discrete: chi2 %.2f dof %d p %.4f\n", stat, dof, p);
  assert_true(p > alpha_per_test());
  /* Negative control: the same samples against a function with one cell
   * 5% heavier must be rejected (the test has power). */
  double f_wrong[N1];
  for (int i = 0; i < N1; i++) f_wrong[i] = f1[i];
  f_wrong[2] *= 1.05;
  double sum_wrong = 0.0;
  for (int i = 0; i < N1; i++) sum_wrong += f_wrong[i];
  for (int i = 0; i < N1; i++) expct_d[i] = N * f_wrong[i] / sum_wrong;
  p = chi2_pvalue(obs_d, expct_d, N1, 5.0, &dof, &stat);
  print_message("1-D discrete, wrong pmf: chi2 %.2f p %.2g\n", stat, p);
  assert_true(p < 1e-6);
  distrib1d_free(&d);
}

static void test_1d_uniform_fallback_and_errors(void **state) {
  (void)state;
  distrib1d d;
  lmc_error err;
  int checks = 0;
  double zeros[5] = {0};
  assert_int_equal(distrib1d_init(&d, zeros, 5, &err), LMC_OK);
  checks++;
  for (int i = 0; i < 5; i++) {
    assert_near(distrib1d_pmf(&d, i), 0.2, 1e-15);
    assert_near(distrib1d_pdf_cont(&d, (i + 0.3) / 5.0), 1.0, 1e-15);
    checks += 2;
  }
  double pdf;
  double x = distrib1d_sample_cont(&d, 0.37, &pdf, NULL);
  assert_near(x, 0.37, 1e-15);
  assert_near(pdf, 1.0, 0.0);
  assert_near(distrib1d_invert_cont(&d, 0.81), 0.81, 1e-15);
  checks += 3;
  distrib1d_free(&d);

  /* A single cell. */
  double one = 4.0;
  assert_int_equal(distrib1d_init(&d, &one, 1, &err), LMC_OK);
  assert_near(distrib1d_sample_cont(&d, 0.6, &pdf, NULL), 0.6, 1e-15);
  assert_near(pdf, 1.0, 1e-15);
  distrib1d_free(&d);
  checks += 3;

  /* Bad input: no cells, negative, NaN and infinite values. */
  double neg[3] = {1.0, -1.0, 2.0}, nan3[3] = {1.0, NAN, 2.0}, inf3[3] = {INFINITY, 1.0, 1.0};
  lmc_error_clear(&err);
  assert_int_equal(distrib1d_init(&d, neg, 0, &err), LMC_EINVAL);
  assert_int_equal(err.code, LMC_EINVAL);
  assert_int_equal(distrib1d_init(&d, neg, 3, &err), LMC_EINVAL);
  assert_null(d.func);
  assert_int_equal(distrib1d_init(&d, nan3, 3, &err), LMC_EINVAL);
  assert_int_equal(distrib1d_init(&d, inf3, 3, &err), LMC_EINVAL);
  distrib1d_free(&d);
  distrib1d_free(NULL);
  checks += 6;
  assert_int_equal(checks, 23);
}

/* A 6 x 4 function (nu = 6, nv = 4) with an all-zero row (row 2) and
 * zeros inside rows. */
#define NU 6
#define NV 4
static const double f2[NV * NU] = {
    1.0, 2.0, 0.0, 0.5, 0.5, 3.0, /* row 0 */
    0.0, 0.0, 4.0, 1.0, 0.0, 0.0, /* row 1 */
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, /* row 2 */
    2.0, 2.0, 2.0, 2.0, 2.0, 0.1, /* row 3 */
};

static void test_2d(void **state) {
  (void)state;
  distrib2d d;
  lmc_error err;
  int checks = 0;
  assert_int_equal(distrib2d_init(&d, f2, NU, NV, &err), LMC_OK);
  checks++;

  /* The density is f / integral(f) on the unit square; it integrates to 1
   * and vanishes on the zero row. */
  double total = 0.0;
  for (int i = 0; i < NU * NV; i++) total += f2[i];
  total /= NU * NV;
  double integral = 0.0;
  int bad = 0;
  for (int j = 0; j < NV; j++)
    for (int i = 0; i < NU; i++) {
      double p = distrib2d_pdf(&d, (i + 0.5) / NU, (j + 0.5) / NV);
      if (fabs(p - f2[j * NU + i] / total) > 1e-13) bad++;
      integral += p / (NU * NV);
    }
  assert_int_equal(bad, 0);
  assert_near(integral, 1.0, 1e-13);
  assert_true(distrib2d_pdf(&d, 0.5, (2 + 0.5) / NV) == 0.0);
  assert_true(distrib2d_pdf(&d, 1.5, 0.5) == 0.0);
  checks += 4;

  /* Round trips and pdf consistency. */
  rng r;
  rng_seed(&r, 4321, 2);
  bad = 0;
  for (int k = 0; k < 100000; k++) {
    double u0 = rng_uniform(&r), u1 = rng_uniform(&r), out[2], back[2], pdf;
    distrib2d_sample(&d, u0, u1, out, &pdf);
    if (!(out[0] >= 0.0 && out[0] < 1.0 && out[1] >= 0.0 && out[1] < 1.0)) bad++;
    if (!(pdf > 0.0) || fabs(pdf - distrib2d_pdf(&d, out[0], out[1])) > 1e-12 * pdf) bad++;
    distrib2d_invert(&d, out[0], out[1], back);
    if (fabs(back[0] - u0) > 1e-12 || fabs(back[1] - u1) > 1e-12) bad++;
  }
  assert_int_equal(bad, 0);
  checks++;

  /* Chi-square on a 2x-refined grid. */
  enum { RU = 2 * NU, RV = 2 * NV, N = 200000 };
  double obs[RU * RV] = {0}, expct[RU * RV];
  for (int k = 0; k < N; k++) {
    double out[2];
    distrib2d_sample(&d, rng_uniform(&r), rng_uniform(&r), out, NULL);
    int bu = (int)(out[0] * RU), bv = (int)(out[1] * RV);
    obs[(bv < RV ? bv : RV - 1) * RU + (bu < RU ? bu : RU - 1)] += 1.0;
  }
  for (int j = 0; j < RV; j++)
    for (int i = 0; i < RU; i++)
      expct[j * RU + i] = N * distrib2d_pdf(&d, (i + 0.5) / RU, (j + 0.5) / RV) / (RU * RV);
  int dof;
  double stat;
  double p = chi2_pvalue(obs, expct, RU * RV, 5.0, &dof, &stat);
  print_message("2-D: chi2 %.2f dof %d p %.4f\n", stat, dof, p);
  assert_true(p > alpha_per_test());
  assert_true(dof >= 40);
  checks += 2;
  distrib2d_free(&d);
  assert_null(d.conditional);
  checks++;

  /* An all-zero 2-D function is uniform. */
  double zeros[12] = {0};
  assert_int_equal(distrib2d_init(&d, zeros, 4, 3, &err), LMC_OK);
  double out[2], pdf;
  distrib2d_sample(&d, 0.3, 0.7, out, &pdf);
  assert_near(out[0], 0.3, 1e-15);
  assert_near(out[1], 0.7, 1e-15);
  assert_near(pdf, 1.0, 1e-15);
  assert_near(distrib2d_pdf(&d, 0.9, 0.1), 1.0, 1e-15);
  distrib2d_free(&d);
  checks += 5;

  /* Bad input. */
  double neg[4] = {1.0, -1.0, 1.0, 1.0};
  assert_int_equal(distrib2d_init(&d, neg, 2, 2, &err), LMC_EINVAL);
  assert_null(d.conditional);
  assert_int_equal(distrib2d_init(&d, neg, 0, 2, &err), LMC_EINVAL);
  distrib2d_free(&d);
  distrib2d_free(NULL);
  checks += 3;
  assert_int_equal(checks, 17);
}

/* A large random distribution: round trip and pdf/pmf agreement. */
static void test_1d_large_random(void **state) {
  (void)state;
  enum { N = 4096 };
  double *f = malloc(N * sizeof(double));
  assert_non_null(f);
  rng r;
  rng_seed(&r, 77, 5);
  for (int i = 0; i < N; i++) {
    double v = rng_uniform(&r);
    f[i] = v < 0.3 ? 0.0 : v * v * 1e3; /* 30% empty cells */
  }
  distrib1d d;
  lmc_error err;
  assert_int_equal(distrib1d_init(&d, f, N, &err), LMC_OK);
  int bad = 0;
  for (int k = 0; k < 200000; k++) {
    double u = rng_uniform(&r), pdf;
    int idx;
    double x = distrib1d_sample_cont(&d, u, &pdf, &idx);
    if (f[idx] == 0.0) bad++;
    if (fabs(pdf - distrib1d_pmf(&d, idx) * N) > 1e-9 * pdf) bad++;
    if (fabs(distrib1d_invert_cont(&d, x) - u) > 1e-12) bad++;
  }
  assert_int_equal(bad, 0);
  distrib1d_free(&d);
  free(f);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_1d_basics),
      cmocka_unit_test(test_1d_chi2),
      cmocka_unit_test(test_1d_uniform_fallback_and_errors),
      cmocka_unit_test(test_2d),
      cmocka_unit_test(test_1d_large_random),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
