/*
 * test_bootstrap.c: the estimate of b (src/lmc/driver/bootstrap.h). Neyman's
 * shares and the error rule follow their formulas; --bootstrap N takes
 * exactly N per family; how many samples estimate b never depends on
 * their values (in both main-phase modes); and on a heavy-tailed family (a
 * rare bright sample, as long caustic paths give) the estimate is
 * unbiased over many independent runs in both modes, where a rule that
 * pools every sample and stops once its running standard error is small
 * (the rule this module replaced, rebuilt here as a control) is shown by
 * the same statistic to be far too low.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include <cmocka.h>

#include "lmc/driver/bootstrap.h"
#include "render/rng.h"
#include "test_util.h"

/* The toy families. Family 0: f = 1 always. Family 1: f = 1 / P_RARE with
 * probability P_RARE, else 0 (mean 1, variance 1 / P_RARE - 1). Both cost 1
 * per sample. Sample j of family g in run `run` is a pure function of
 * (seed, run, g, j); with `resalt` the samples from index `from` on that
 * estimate (all of them, or with `odd` only from + 1, + 3, ...) use
 * another seed, to show that the sizes do not look at them. */
#define P_RARE (1.0 / 256.0)
typedef struct toy {
  uint64_t seed, run;
  int resalt, odd;
  int64_t from;
  int64_t draws;
} toy;

static double toy_value(const toy *t, int g, int64_t j) {
  if (g == 0) return 1.0;
  int est = j >= t->from && (!t->odd || (j - t->from) % 2 == 1);
  uint64_t salt = t->resalt && est ? 0x9e3779b97f4a7c15ull : 0;
  uint64_t h = rng_hash64(rng_hash64(t->seed ^ salt ^ (t->run << 20)) ^ ((uint64_t)g << 56) ^
                          (uint64_t)j);
  double u = (double)(h >> 11) * 0x1.0p-53;
  return u < P_RARE ? 1.0 / P_RARE : 0.0;
}

static void toy_draw(void *ctx, mc_boot *boot, int n_fam, const int64_t *to) {
  toy *t = ctx;
  for (int g = 0; g < n_fam; g++) {
    for (int64_t j = boot[g].n; j < to[g]; j++) boot[g].f[j] = toy_value(t, g, j);
    if (to[g] > boot[g].n) {
      boot[g].cost += (double)(to[g] - boot[g].n);
      t->draws += to[g] - boot[g].n;
    }
  }
}

/* timed: the main phase runs to cap_total (a time no run reaches). */
static mc_boot_params toy_params(int timed) {
  mc_boot_params p = {.fixed = 0,
                      .batch = 64,
                      .cap_total = 64 * 2 * 50,
                      .rel_err = 0.01,
                      .seconds = timed ? 1e9 : INFINITY,
                      .stop = NULL};
  return p;
}

/* Neyman's shares and the error rule against their formulas. */
static void test_shares_and_error(void **state) {
  (void)state;
  /* Per-sample variances 4 and 1, costs per sample 4 and 1 (100 samples
   * each): weights sqrt(4 / 4) = sqrt(1 / 1), even shares. */
  mc_boot B[3] = {{0}};
  B[0].n = B[1].n = B[2].n = 100;
  B[0].plan_var = 4.0, B[0].cost = 400.0, B[0].plan_b = 1.0;
  B[1].plan_var = 1.0, B[1].cost = 100.0, B[1].plan_b = 1.0;
  double share[3];
  mc_boot_shares(B, 2, share);
  assert_true(fabs(share[0] - 0.5) < 1e-12 && fabs(share[1] - 0.5) < 1e-12);
  /* Error of 125 + 125 estimating samples: sqrt(4 / 125 + 1 / 125) / 2 = 0.1. */
  int64_t n_est[3] = {125, 125, 0};
  assert_true(fabs(mc_boot_rel_err(B, 2, n_est) - 0.1) < 1e-12);
  /* A family with variance but no estimating sample: infinite error. */
  n_est[1] = 0;
  assert_true(isinf(mc_boot_rel_err(B, 2, n_est)));
  /* A family without variance gets the floor, an eighth of an even share
   * (1/24 of three), the others split the rest by their weights (1 : 1);
   * it adds nothing to the error. */
  B[2].plan_b = 0.5;
  mc_boot_shares(B, 3, share);
  assert_true(fabs(share[2] / share[0] - (1.0 / 24.0) / 0.5) < 1e-12);
  assert_true(fabs(share[0] + share[1] + share[2] - 1.0) < 1e-12);
  n_est[1] = 125;
  assert_true(fabs(mc_boot_rel_err(B, 3, n_est) - sqrt(5.0 / 125.0) / 2.5) < 1e-12);
}

/* --bootstrap N: exactly N per family, all of them in b. */
static void test_fixed(void **state) {
  (void)state;
  toy t = {.seed = 7, .run = 0};
  mc_boot B[2] = {{0}};
  mc_boot_params p = toy_params(0);
  p.fixed = 1000;
  assert_int_equal(mc_boot_run(B, 2, &p, toy_draw, &t), 0);
  for (int g = 0; g < 2; g++) {
    assert_int_equal(B[g].n, 1000);
    assert_int_equal(B[g].n_est, 1000);
    double s = 0.0;
    for (int64_t j = 0; j < 1000; j++) s += toy_value(&t, g, j);
    assert_true(fabs(B[g].b - s / 1000.0) < 1e-12);
    mc_boot_free(&B[g]);
  }
  assert_int_equal(t.draws, 2000);
}

/* How many samples estimate b does not depend on their values: the same
 * run with other estimating values draws the same number per family, in
 * both modes, and b is the mean of exactly the estimating samples (every
 * second one of the main phase under an error target, all of it under a
 * time). Counts the runs whose main phase went past one batch. */
static void test_size_ignores_estimating_values(void **state) {
  (void)state;
  int checked = 0, longer = 0;
  for (int timed = 0; timed < 2; timed++)
    for (uint64_t run = 0; run < 200; run++) {
      mc_boot A[2] = {{0}}, B[2] = {{0}};
      mc_boot_params p = toy_params(timed);
      toy ta = {.seed = 11, .run = run, .from = p.batch, .odd = !timed};
      toy tb = ta;
      tb.resalt = 1;
      assert_int_equal(mc_boot_run(A, 2, &p, toy_draw, &ta), 0);
      assert_int_equal(mc_boot_run(B, 2, &p, toy_draw, &tb), 0);
      for (int g = 0; g < 2; g++) {
        assert_int_equal(A[g].n, B[g].n);
        double s = 0.0;
        int64_t m = 0;
        for (int64_t j = p.batch; j < A[g].n; j++)
          if (timed || (j - p.batch) % 2 == 1) s += toy_value(&ta, g, j), m++;
        assert_int_equal(A[g].n_est, m);
        assert_true(fabs(A[g].b - s / (double)m) < 1e-9);
        checked++;
      }
      longer += A[1].n - p.batch > 2 * p.batch;
      for (int g = 0; g < 2; g++) mc_boot_free(&A[g]), mc_boot_free(&B[g]);
    }
  assert_int_equal(checked, 800);
  /* Timed runs all go to the cap (200); under the error target the ones
   * whose planning samples met a rare one (P = 1 - (255/256)^64 = 22% in
   * the pilot alone) go on. */
  assert_true(longer > 200 + 20 && longer < 400);
}

/* The replaced rule, rebuilt as a control: all samples pooled, Neyman
 * shares re-planned after every batch, stop once the running standard
 * error of the sum is below rel_err of it. Returns family 1's estimate. */
static double running_rule_b1(toy *t, const mc_boot_params *p) {
  mc_boot B[2] = {{0}};
  int64_t to[2] = {p->batch, p->batch}, drawn = 2 * p->batch;
  for (int g = 0; g < 2; g++) assert_int_equal(mc_boot_reserve(&B[g], p->cap_total), 1);
  for (;;) {
    toy_draw(t, B, 2, to);
    double b = 0.0, v = 0.0;
    for (int g = 0; g < 2; g++) {
      mc_boot_update(&B[g], to[g]);
      b += B[g].b, v += B[g].b_var;
    }
    if (drawn >= p->cap_total || sqrt(v) < p->rel_err * b) break;
    double share[2];
    for (int g = 0; g < 2; g++) B[g].plan_var = B[g].b_var * (double)B[g].n_est; /* pooled */
    mc_boot_shares(B, 2, share);
    for (int g = 0; g < 2; g++) {
      int64_t add = (int64_t)(2.0 * (double)p->batch * share[g]);
      if (drawn + add > p->cap_total) add = p->cap_total - drawn;
      to[g] = B[g].n + add;
      drawn += add;
    }
  }
  double b1 = B[1].b;
  for (int g = 0; g < 2; g++) mc_boot_free(&B[g]);
  return b1;
}

/* Unbiased on the heavy-tailed family: in both modes the mean of b_1 over
 * R independent runs is within 4 standard errors (from the runs' own
 * spread) of the true 1; the running rule's mean is more than 8 of them
 * away (low), so the statistic has the power to see such a bias. Family 0
 * is always exact. */
static void test_unbiased_heavy_tail(void **state) {
  (void)state;
  const int R = 20000;
  for (int timed = 0; timed < 2; timed++) {
    mc_boot_params p = toy_params(timed);
    double s = 0.0, s2 = 0.0, c = 0.0, c2 = 0.0;
    int64_t draws = 0;
    for (int run = 0; run < R; run++) {
      toy t = {.seed = 2026 + (uint64_t)timed, .run = (uint64_t)run};
      mc_boot B[2] = {{0}};
      assert_int_equal(mc_boot_run(B, 2, &p, toy_draw, &t), 0);
      assert_true(fabs(B[0].b - 1.0) < 1e-12);
      s += B[1].b, s2 += B[1].b * B[1].b;
      draws += t.draws;
      for (int g = 0; g < 2; g++) mc_boot_free(&B[g]);
      if (timed) continue;
      toy tc = t;
      tc.draws = 0;
      double b1 = running_rule_b1(&tc, &p);
      c += b1, c2 += b1 * b1;
    }
    double mean = s / R, se = sqrt(fmax(0.0, s2 / R - mean * mean) / (R - 1));
    print_message("%s: mean b_1 %.4f +- %.4f (%.1f draws per run)\n",
                  timed ? "to a time" : "to an error", mean, se, (double)draws / R);
    assert_true(se > 0.0);
    assert_true(fabs(mean - 1.0) < 4.0 * se);
    if (!timed) {
      double cmean = c / R, cse = sqrt(fmax(0.0, c2 / R - cmean * cmean) / (R - 1));
      print_message("running rule: mean b_1 %.4f +- %.4f\n", cmean, cse);
      assert_true(cse > 0.0);
      assert_true(1.0 - cmean > 8.0 * cse);
    }
  }
}

/* A stop request right after the pilot keeps the pilot's estimate. */
static int always_stop(void) { return 1; }
static void test_stop_keeps_pilot(void **state) {
  (void)state;
  toy t = {.seed = 5, .run = 0};
  mc_boot B[2] = {{0}};
  mc_boot_params p = toy_params(0);
  p.stop = always_stop;
  assert_int_equal(mc_boot_run(B, 2, &p, toy_draw, &t), 0);
  for (int g = 0; g < 2; g++) {
    assert_int_equal(B[g].n, p.batch);
    assert_int_equal(B[g].n_est, p.batch);
    mc_boot_free(&B[g]);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_shares_and_error),
      cmocka_unit_test(test_fixed),
      cmocka_unit_test(test_size_ignores_estimating_values),
      cmocka_unit_test(test_unbiased_heavy_tail),
      cmocka_unit_test(test_stop_keeps_pilot),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
