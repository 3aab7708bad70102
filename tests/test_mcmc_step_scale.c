/*
 * test_mcmc_step_scale.c: the per-coordinate small-step factors of
 * mc_target.step_scale (target.h), which mmlt uses for the light-position
 * coordinate of a finely tessellated area light (mcmc.c,
 * mcmc__light_u1_scale).
 *
 *   - A factor of 0 freezes the coordinate under small steps: with small
 *     steps only, the coordinate keeps its starting value while the other
 *     one moves.
 *   - Factors below 1 leave the target invariant, also through the lazy
 *     replay of owed steps: a 2-D density whose second coordinate is read
 *     only when u0 < 1/2 (f = 1 + 4 u1 there, else 1; so P(u0 < 1/2) = 3/4
 *     and u1 given u0 < 1/2 has density (1 + 4 u1) / 3) is sampled by
 *     N = 20000 independent chains (each started from an exact draw, 60
 *     steps of large steps 0.3 and small steps with factors {1, 0.1}); the
 *     histogram of their final states over 5 x 5 cells of u0 < 1/2 plus 5
 *     cells of u0 >= 1/2 passes a chi-square test at level 1e-3. A wrong
 *     replay (e.g. the factor lost on owed steps, or a non-symmetric step)
 *     would not be caught by this alone, but a step that ignored the
 *     factor would fail the freeze test, and one that broke the invariance
 *     fails here.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "chi2.h"
#include "lmc/kernels/chain.h"
#include "test_util.h"

static int g_checks;

/* The lazy density: u1 read only when u0 < 1/2. rx = u0, ry = u1 (or -1). */
static int lazy_eval(const mc_target *t, void *scratch, lmc_sampler *smp, mc_value *OUT_value,
                     double *OUT_grad, int *OUT_grad_ok) {
  (void)t, (void)scratch, (void)OUT_grad;
  if (OUT_grad_ok) *OUT_grad_ok = 0;
  sampler_use_stream(smp, 0);
  double u0 = sampler_next(smp), u1 = -1.0, f = 1.0;
  if (u0 < 0.5) {
    u1 = sampler_next(smp);
    f = 1.0 + 4.0 * u1;
  }
  OUT_value->f = f;
  OUT_value->value = rgb_gray(f);
  OUT_value->rx = u0;
  OUT_value->ry = u1;
  return 0;
}

/* A smooth 2-D density that reads both coordinates. */
static int bump_eval(const mc_target *t, void *scratch, lmc_sampler *smp, mc_value *OUT_value,
                     double *OUT_grad, int *OUT_grad_ok) {
  (void)t, (void)scratch, (void)OUT_grad;
  if (OUT_grad_ok) *OUT_grad_ok = 0;
  sampler_use_stream(smp, 0);
  double u0 = sampler_next(smp), u1 = sampler_next(smp);
  double f = 1.0 + sin(6.0 * u0) * sin(6.0 * u0) + u1;
  OUT_value->f = f;
  OUT_value->value = rgb_gray(f);
  OUT_value->rx = u0;
  OUT_value->ry = u1;
  return 0;
}

static mc_target make_target(int (*eval)(const mc_target *, void *, lmc_sampler *, mc_value *,
                                         double *, int *),
                             const double *scale) {
  mc_target t;
  memset(&t, 0, sizeof t);
  t.dim = 2;
  t.stream_dim[0] = 2;
  t.eval = eval;
  t.step_scale = scale;
  return t;
}

static void test_scale_zero_freezes(void **state) {
  (void)state;
  const double scale[2] = {1.0, 0.0};
  mc_target t = make_target(bump_eval, scale);
  mc_kernel k = mc_kernel_small(1.0 / 1024.0, 0.1);
  double p = 1.0;
  mc_chain *c = NULL;
  lmc_error err;
  assert_int_equal(mc_chain_create(&c, &t, &k, &p, 1, &err), LMC_OK);
  for (int run = 0; run < 8; run++) {
    assert_true(mc_chain_start(c, 5, (uint64_t)run, 100 + (uint64_t)run) > 0.0);
    double u0 = c->x.v.rx, u1 = c->x.v.ry;
    int moved = 0;
    for (int s = 0; s < 300; s++) {
      mc_chain_step(c, NULL, NULL);
      assert_true(c->x.v.ry == u1);
      if (c->x.v.rx != u0) moved = 1;
    }
    assert_true(moved);
    g_checks++;
  }
  mc_chain_destroy(c);
}

/* Exact cell probabilities: cells 0..24 are (u0, u1) in 5 x 5 over
 * [0, 1/2) x [0, 1); cells 25..29 split u0 in [1/2, 1) in five. The
 * integral of f over the whole square is 2. */
static void lazy_cells(double OUT_p[30]) {
  for (int i = 0; i < 5; i++)
    for (int j = 0; j < 5; j++) {
      double a = j * 0.2, b = a + 0.2;
      /* int (1 + 4 u1) du1 over [a, b), times the u0 width 0.1 */
      OUT_p[i * 5 + j] = 0.1 * ((b - a) + 2.0 * (b * b - a * a)) / 2.0;
    }
  for (int i = 0; i < 5; i++) OUT_p[25 + i] = 0.1 / 2.0;
}

static void test_scale_keeps_target(void **state) {
  (void)state;
  const double scale[2] = {1.0, 0.1};
  mc_target t = make_target(lazy_eval, scale);
  mc_kernel k[2] = {mc_kernel_large(), mc_kernel_small(1.0 / 1024.0, 0.2)};
  double p[2] = {0.3, 0.7};
  mc_chain *c = NULL;
  lmc_error err;
  assert_int_equal(mc_chain_create(&c, &t, k, p, 2, &err), LMC_OK);
  enum { N = 20000, STEPS = 60 };
  double hist[30] = {0}, prob[30], expct[30];
  for (int i = 0; i < N; i++) {
    /* An exact start: rejection of large-step states against f_max = 5. */
    uint64_t seq = (uint64_t)i * 1000u;
    rng acc;
    rng_seed(&acc, 17, (uint64_t)i);
    while (!(rng_uniform(&acc) * 5.0 < mc_chain_start(c, 23, seq, 0xabc00000u + (uint64_t)i)))
      seq++;
    for (int s = 0; s < STEPS; s++) mc_chain_step(c, NULL, NULL);
    double u0 = c->x.v.rx, u1 = c->x.v.ry;
    int cell;
    if (u0 < 0.5) {
      int a = (int)(u0 * 10.0), b = (int)(u1 * 5.0);
      cell = (a > 4 ? 4 : a) * 5 + (b > 4 ? 4 : b);
    } else {
      int a = (int)((u0 - 0.5) * 10.0);
      cell = 25 + (a > 4 ? 4 : a);
    }
    hist[cell] += 1.0;
  }
  mc_chain_destroy(c);
  lazy_cells(prob);
  for (int i = 0; i < 30; i++) expct[i] = prob[i] * N;
  int dof;
  double stat;
  double pv = chi2_pvalue(hist, expct, 30, 5.0, &dof, &stat);
  if (!(pv > 1e-3)) print_error("chi2 %.1f, dof %d, p %.3g\n", stat, dof, pv);
  assert_true(pv > 1e-3);
  assert_true(dof >= 20);
  g_checks++;
}

static void test_count(void **state) {
  (void)state;
  assert_int_equal(g_checks, 9);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_scale_zero_freezes),
      cmocka_unit_test(test_scale_keeps_target),
      cmocka_unit_test(test_count),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
