/*
 * test_adam.c: Adam's moments and the preconditioners built from them
 * (lmc/adam.h), against their definitions written out directly.
 *
 *   - Moments. Coordinate i of a 3-coordinate stats object gets t_i
 *     updates (t = 1, 7, 1000, 20000: coordinate 2 is updated only every
 *     few steps, coordinate 1 only by the shorter vectors), with
 *     gradients from a fixed sequence. The bias-corrected moments must
 *     equal sum_k (1 - beta) beta^(t-k) g_k / (1 - beta^t), summed here
 *     term by term with pow(), to 1e-10 relative (the code keeps beta^t by
 *     repeated multiplication; 20000 rounding steps stay far below that).
 *   - Never-updated and always-zero coordinates give M = 1 (clamped to
 *     [lo, hi]); others clamp(1 / (eps + sqrt(v))).
 *   - The diminishing schedule: (1 - w) + w M_adam with w = min(1, t0 / t).
 *   - adam_reset forgets everything (moments 0, M = 1).
 * Every test counts its checks; test_count asserts the total.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "lmc/kernels/adam.h"
#include "test_util.h"

static int g_checks;

/* The k-th gradient of coordinate i (a fixed, sign-changing sequence). */
static double grad_of(int i, int64_t k) {
  return (i + 1) * sin(0.37 * (double)k + i) + 0.25 * (double)(k % 5) - 0.3;
}

/* The bias-corrected moments of the sequence g_1 .. g_t, term by term. */
static void direct_moments(int i, int64_t t, double *m1, double *m2) {
  double s1 = 0.0, s2 = 0.0;
  for (int64_t k = 1; k <= t; k++) {
    double g = grad_of(i, k);
    s1 += (1.0 - ADAM_BETA1) * pow(ADAM_BETA1, (double)(t - k)) * g;
    s2 += (1.0 - ADAM_BETA2) * pow(ADAM_BETA2, (double)(t - k)) * g * g;
  }
  *m1 = s1 / (1.0 - pow(ADAM_BETA1, (double)t));
  *m2 = s2 / (1.0 - pow(ADAM_BETA2, (double)t));
}

static void test_moments(void **state) {
  (void)state;
  const int64_t counts[] = {1, 7, 1000, 20000};
  for (int c = 0; c < 4; c++) {
    int64_t T = counts[c];
    adam_stats a;
    lmc_error err;
    lmc_error_clear(&err);
    assert_int_equal(adam_init(&a, 3, &err), LMC_OK);
    /* Coordinate 0 updated T times, coordinate 1 T times through shorter
     * vectors (n = 2), coordinate 2 only when the step is odd. */
    int64_t t2 = 0;
    for (int64_t k = 1; k <= T; k++) {
      double g[3] = {grad_of(0, k), grad_of(1, k), grad_of(2, t2 + 1)};
      int n = (k % 2) ? 3 : 2;
      if (n == 3) t2++;
      adam_update(&a, n, g);
    }
    assert_int_equal(a.t, T);
    const int64_t t_of[3] = {T, T, t2};
    for (int i = 0; i < 3; i++) {
      assert_int_equal(a.count[i], t_of[i]);
      double m1, m2, e1, e2;
      adam_moments(&a, i, &m1, &m2);
      direct_moments(i, t_of[i], &e1, &e2);
      assert_near(m1, e1, 1e-10 * fmax(fabs(e1), 1e-3));
      assert_near(m2, e2, 1e-10 * e2);
      /* The preconditioner and the diminishing schedule from them. */
      double M[3], Md[3];
      adam_precond(&a, 3, 1e-8, 1e-3, 1e3, M);
      double want = 1.0 / (1e-8 + sqrt(e2));
      want = want < 1e-3 ? 1e-3 : (want > 1e3 ? 1e3 : want);
      assert_near(M[i], want, 1e-9 * want);
      adam_precond_diminish(&a, 3, 1e-8, 1e-3, 1e3, 100.0, Md);
      double w = fmin(1.0, 100.0 / (double)T);
      assert_near(Md[i], (1.0 - w) + w * M[i], 1e-12 * (1.0 + M[i]));
      g_checks += 6;
    }
    /* Reset: everything forgotten. */
    adam_reset(&a);
    double M[3];
    adam_precond(&a, 3, 1e-8, 1e-3, 1e3, M);
    for (int i = 0; i < 3; i++) {
      double m1, m2;
      adam_moments(&a, i, &m1, &m2);
      assert_true(m1 == 0.0 && m2 == 0.0);
      assert_true(M[i] == 1.0);
      g_checks += 2;
    }
    adam_free(&a);
  }
}

static void test_untouched_coordinates(void **state) {
  (void)state;
  adam_stats a;
  lmc_error err;
  lmc_error_clear(&err);
  assert_int_equal(adam_init(&a, 4, &err), LMC_OK);
  /* Coordinate 1's gradient is always exactly 0 (a discrete choice),
   * coordinate 3 is never updated (n = 3). */
  for (int k = 0; k < 50; k++) {
    double g[4] = {0.5 + k, 0.0, -2.0, 99.0};
    adam_update(&a, 3, g);
  }
  double M[4];
  adam_precond(&a, 4, 1e-8, 0.5, 0.9, M); /* a clamp that excludes 1 */
  assert_true(M[1] == 0.9 && M[3] == 0.9); /* 1, clamped */
  assert_true(M[0] == 0.5);                /* 1 / sqrt(v) is tiny: lower clamp */
  assert_true(M[2] == 0.5);                /* 1 / 2 */
  adam_precond(&a, 4, 1e-8, 1e-3, 1e3, M);
  assert_true(M[1] == 1.0 && M[3] == 1.0);
  assert_near(M[2], 1.0 / (1e-8 + 2.0), 1e-12);
  g_checks += 6;
  adam_free(&a);
  adam_free(NULL); /* destructors accept NULL */
}

static void test_count(void **state) {
  (void)state;
  /* 4 runs x (3 coordinates x 6 + 3 x 2) + 6 */
  assert_int_equal(g_checks, 4 * (18 + 6) + 6);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_moments),
      cmocka_unit_test(test_untouched_coordinates),
      cmocka_unit_test(test_count),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
