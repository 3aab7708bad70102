/*
 * test_bootstrap.c: the estimate of b (src/lmc/bootstrap.h). The main
 * phase's plan follows its formulas; --bootstrap N takes exactly N per
 * family; how many samples the main phase draws never depends on their
 * values; and on a heavy-tailed family (a rare bright sample, as long
 * caustic paths give) the estimate is unbiased over many independent
 * runs, where a rule that stops once its running standard error is small
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

#include "lmc/bootstrap.h"
#include "render/rng.h"
#include "test_util.h"

/* The toy families. Family 0: f = 1 always. Family 1: f = 1 / P_RARE with
 * probability P_RARE, else 0 (mean 1, variance 1 / P_RARE - 1). Both cost 1
 * per sample. Sample j of family g in run `run` is a pure function of
 * (seed, run, g, j); samples from index `resalt_from` on use another seed
 * (to show that the plan does not look at them). */
#define P_RARE (1.0 / 256.0)
typedef struct toy {
  uint64_t seed, run;
  int64_t resalt_from;
  int64_t draws;
} toy;

static double toy_value(const toy *t, int g, int64_t j) {
  if (g == 0) return 1.0;
  uint64_t salt = j >= t->resalt_from ? 0x9e3779b97f4a7c15ull : 0;
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

static mc_boot_params toy_params(void) {
  mc_boot_params p = {.fixed = 0,
                      .batch = 64,
                      .cap_total = 64 * 2 * 50,
                      .rel_err = 0.01,
                      .seconds = INFINITY,
                      .stop = NULL};
  return p;
}

/* The plan's shares and size against its formulas. */
static void test_plan(void **state) {
  (void)state;
  /* Two families of 100 pilot samples: per-sample variances 4 and 1,
   * costs per sample 4 and 1: Neyman weights sqrt(4 / 4) = sqrt(1 / 1),
   * so even shares; b = 1 + 1; Var = 4 / (N / 2) + 1 / (N / 2) must be
   * (0.1 * 2)^2, N = 250. */
  mc_boot B[3] = {{0}};
  B[0].n = B[1].n = 100;
  B[0].b = B[1].b = 1.0;
  B[0].b_var = 4.0 / 100.0;
  B[1].b_var = 1.0 / 100.0;
  B[0].cost = 400.0;
  B[1].cost = 100.0;
  double share[3];
  int64_t n = mc_boot_plan(B, 2, 0.1, 10, 1000, share);
  assert_int_equal(n, 250);
  assert_true(fabs(share[0] - 0.5) < 1e-12 && fabs(share[1] - 0.5) < 1e-12);
  /* Bounded by `left`, and at least one batch. */
  assert_int_equal(mc_boot_plan(B, 2, 0.1, 10, 100, share), 100);
  assert_int_equal(mc_boot_plan(B, 2, 10.0, 10, 1000, share), 20);
  /* A family without variance gets the floor, an eighth of an even share
   * (1/24 of three), the others split the rest by their weights (1 : 1). */
  B[2].n = 100;
  B[2].b = 0.5;
  n = mc_boot_plan(B, 3, 0.1, 10, 1 << 20, share);
  double floor = 1.0 / 24.0, rest = 1.0;
  assert_true(fabs(share[2] / share[0] - floor / (rest / 2.0)) < 1e-12);
  assert_true(fabs(share[0] + share[1] + share[2] - 1.0) < 1e-12);
  double need = 4.0 / share[0] + 1.0 / share[1];
  assert_int_equal(n, (int64_t)ceil(need / (0.1 * 2.5 * 0.1 * 2.5)));
}

/* --bootstrap N: exactly N per family, all of them in b. */
static void test_fixed(void **state) {
  (void)state;
  toy t = {.seed = 7, .run = 0, .resalt_from = INT64_MAX};
  mc_boot B[2] = {{0}};
  mc_boot_params p = toy_params();
  p.fixed = 1000;
  assert_int_equal(mc_boot_run(B, 2, &p, toy_draw, &t), 0);
  for (int g = 0; g < 2; g++) {
    assert_int_equal(B[g].n, 1000);
    assert_int_equal(B[g].first, 0);
    double s = 0.0;
    for (int64_t j = 0; j < 1000; j++) s += toy_value(&t, g, j);
    assert_true(fabs(B[g].b - s / 1000.0) < 1e-12);
    mc_boot_free(&B[g]);
  }
  assert_int_equal(t.draws, 2000);
}

/* The main phase's size is fixed by the pilot: the same pilot with other
 * main-phase values draws the same number of samples per family, and b
 * comes from the main phase alone. Counts the runs where the pilot met a
 * rare sample (the plan then asks for more than one batch). */
static void test_size_ignores_main_values(void **state) {
  (void)state;
  int checked = 0, planned_more = 0;
  for (uint64_t run = 0; run < 200; run++) {
    mc_boot A[2] = {{0}}, B[2] = {{0}};
    mc_boot_params p = toy_params();
    toy ta = {.seed = 11, .run = run, .resalt_from = INT64_MAX};
    toy tb = {.seed = 11, .run = run, .resalt_from = p.batch};
    assert_int_equal(mc_boot_run(A, 2, &p, toy_draw, &ta), 0);
    assert_int_equal(mc_boot_run(B, 2, &p, toy_draw, &tb), 0);
    for (int g = 0; g < 2; g++) {
      assert_int_equal(A[g].n, B[g].n);
      assert_int_equal(A[g].first, p.batch);
      double s = 0.0;
      for (int64_t j = A[g].first; j < A[g].n; j++) s += toy_value(&ta, g, j);
      assert_true(fabs(A[g].b - s / (double)(A[g].n - A[g].first)) < 1e-9);
      checked++;
    }
    planned_more += A[1].n - A[1].first > p.batch;
    for (int g = 0; g < 2; g++) mc_boot_free(&A[g]), mc_boot_free(&B[g]);
  }
  assert_int_equal(checked, 400);
  /* P(a rare sample among 64) = 1 - (255/256)^64 = 22%: about 44 of 200. */
  assert_true(planned_more > 20 && planned_more < 80);
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
    (void)mc_boot_plan(B, 2, p->rel_err, p->batch, p->cap_total - drawn, share);
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

/* Unbiased on the heavy-tailed family: the mean of b_1 over R independent
 * runs is within 4 standard errors (from the runs' own spread) of the true
 * 1; the running rule's mean is more than 8 of them away (low), so the
 * statistic has the power to see such a bias. Family 0 is always exact. */
static void test_unbiased_heavy_tail(void **state) {
  (void)state;
  const int R = 20000;
  mc_boot_params p = toy_params();
  double s = 0.0, s2 = 0.0, c = 0.0, c2 = 0.0;
  int64_t draws = 0;
  for (int run = 0; run < R; run++) {
    toy t = {.seed = 2026, .run = (uint64_t)run, .resalt_from = INT64_MAX};
    mc_boot B[2] = {{0}};
    assert_int_equal(mc_boot_run(B, 2, &p, toy_draw, &t), 0);
    assert_true(fabs(B[0].b - 1.0) < 1e-12);
    s += B[1].b, s2 += B[1].b * B[1].b;
    draws += t.draws;
    for (int g = 0; g < 2; g++) mc_boot_free(&B[g]);

    toy tc = {.seed = 2026, .run = (uint64_t)run, .resalt_from = INT64_MAX};
    double b1 = running_rule_b1(&tc, &p);
    c += b1, c2 += b1 * b1;
  }
  double mean = s / R, se = sqrt(fmax(0.0, s2 / R - mean * mean) / (R - 1));
  double cmean = c / R, cse = sqrt(fmax(0.0, c2 / R - cmean * cmean) / (R - 1));
  print_message("two-phase: mean b_1 %.4f +- %.4f (%.1f draws per run); running rule: %.4f +- %.4f\n",
                mean, se, (double)draws / R, cmean, cse);
  assert_true(se > 0.0 && cse > 0.0);
  assert_true(fabs(mean - 1.0) < 4.0 * se);
  assert_true(1.0 - cmean > 8.0 * cse);
}

/* A stop request right after the pilot keeps the pilot's estimate. */
static int always_stop(void) { return 1; }
static void test_stop_keeps_pilot(void **state) {
  (void)state;
  toy t = {.seed = 5, .run = 0, .resalt_from = INT64_MAX};
  mc_boot B[2] = {{0}};
  mc_boot_params p = toy_params();
  p.stop = always_stop;
  assert_int_equal(mc_boot_run(B, 2, &p, toy_draw, &t), 0);
  for (int g = 0; g < 2; g++) {
    assert_int_equal(B[g].n, p.batch);
    assert_int_equal(B[g].first, 0);
    mc_boot_free(&B[g]);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_plan),
      cmocka_unit_test(test_fixed),
      cmocka_unit_test(test_size_ignores_main_values),
      cmocka_unit_test(test_unbiased_heavy_tail),
      cmocka_unit_test(test_stop_keeps_pilot),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
