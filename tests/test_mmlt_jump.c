/*
 * test_mmlt_jump.c: mmlt's reversible jump between strategies
 * (src/lmc/states/mmlt_jump.h) leaves the mmlt states' target invariant.
 *
 * One-step invariance. Independent uniform states u_i (a chain started by
 * mc_chain_start draws one as a large step does), weighted by f(u_i), are
 * a weighted sample of the target; one jump from each gives u'_i. If the
 * jump leaves the target invariant, every strategy j is as frequent,
 * weighted, before and after:
 *     E[ f(u) (1{t(u') = j} - 1{t(u) = j}) ] = 0.
 * Each such mean is compared with 0 in units of its standard error over N
 * independent starts, on tests/data/invert/mixed.xml (glossy, rough,
 * delta and mixed lobes, area, point and infinite lights) at lengths 2, 3
 * and 4: |z| below the normal quantile of a Sidak level of 1% over all
 * strategies of all lengths, from 400000 starts each. The jumps must move
 * the weighted states (at least 5% change strategy), and a negative
 * control, the same move with every proposal accepted, must fail the same
 * test (|z| > 8 for some strategy). This test found that an area light hit
 * by the camera walk, re-split as a light endpoint, must take the light
 * walk's record (bdpt_resplit) for its MIS weight. LMC_TEST_SCENE=FILE runs
 * it on another scene (for diagnosis).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "chi2.h"
#include "lmc/kernels/chain.h"
#include "lmc/states/mmlt_jump.h"
#include "lmc/states/mmlt_states.h"
#include "render/io/io.h"
#include "test_util.h"

static scene *g_sc;

static int setup(void **state) {
  (void)state;
  lmc_error err;
  if (scene_load_xml(getenv("LMC_TEST_SCENE") ? getenv("LMC_TEST_SCENE") : LMC_SOURCE_DIR "/tests/data/invert/mixed.xml", NULL, 0, &g_sc, &err) !=
      LMC_OK) {
    fprintf(stderr, "%s\n", err.msg);
    return -1;
  }
  return 0;
}

static int teardown(void **state) {
  (void)state;
  scene_destroy(g_sc);
  return 0;
}

/* The jump wrapped: it records the strategy coordinate before the move,
 * and (accept_all) makes every proposal accepted. */
typedef struct wrap {
  mc_kernel inner;
  int off;
  double tech_before;
  int accept_all;
} wrap;

static double wrap_propose(void *self, rng *r, const mc_state *x, double *OUT_y) {
  wrap *w = self;
  w->tech_before = x->u[w->off];
  return w->inner.propose(w->inner.self, r, x, OUT_y);
}

static double wrap_log_density(void *self, const mc_state *from, const double *to_u) {
  wrap *w = self;
  double l = w->inner.log_density(w->inner.self, from, to_u);
  return w->accept_all && l > -INFINITY ? INFINITY : l;
}

static int strategy(double tech, int n) {
  int i = (int)(tech * n);
  return i < n ? i : n - 1;
}

/* The largest |z| over the strategies of length k after N starts and one
 * jump each; *OUT_moved: the weighted share of states whose strategy changed. */
static double worst_z(int k, int n_starts, int accept_all, uint64_t seed, double *OUT_moved) {
  render_settings rs = render_settings_default();
  rs.maxdepth = 6;
  mc_target T;
  mc_mmlt_states ctx;
  lmc_error err;
  assert_int_equal(mc_mmlt_states_init(&T, &ctx, g_sc, &rs, k, &err), LMC_OK);
  mc_mmlt_jump j;
  assert_int_equal(mc_mmlt_jump_init(&j, &T, &err), LMC_OK);
  wrap w = {mc_mmlt_jump_kernel(&j), mc_target_stream_offset(&T, LMC_STREAM_CONNECT), 0.0,
            accept_all};
  mc_kernel kw = w.inner;
  kw.self = &w;
  kw.propose = wrap_propose;
  kw.log_density = wrap_log_density;
  double prob = 1.0;
  mc_chain *c;
  assert_int_equal(mc_chain_create(&c, &T, &kw, &prob, 1, &err), LMC_OK);
  int n = ctx.n_strategies;
  double sum[8] = {0}, sum2[8] = {0}, moved = 0.0, total = 0.0;
  int used = 0;
  for (int i = 0; i < n_starts; i++) {
    double f = mc_chain_start(c, seed, (uint64_t)i, (uint64_t)i);
    if (!(f > 0.0)) continue;
    w.tech_before = -1.0;
    mc_chain_step(c, NULL, NULL);
    if (w.tech_before < 0.0) continue; /* (the kernel always proposes: never here) */
    int a = strategy(w.tech_before, n), b = strategy(c->x.u[w.off], n);
    for (int q = 0; q < n; q++) {
      double d = f * ((b == q) - (a == q));
      sum[q] += d;
      sum2[q] += d * d;
    }
    moved += f * (a != b);
    total += f;
    used++;
  }
  assert_true(used > 3000);
  double worst = 0.0;
  for (int q = 0; q < n; q++) {
    double mean = sum[q] / n_starts;
    double var = sum2[q] / n_starts - mean * mean;
    double z = var > 0.0 ? mean / sqrt(var / n_starts) : 0.0;
    if (fabs(z) > worst) worst = fabs(z);
  }
  print_message("length %d%s: %d states with f > 0, %.1f%% (weighted) changed strategy, "
                "worst |z| %.2f; jumps refused %lld, walked elsewhere %lld\n",
                k, accept_all ? " (accept all)" : "", used, 100.0 * moved / total, worst,
                (long long)j.st.refused, (long long)j.st.mismatch);
  *OUT_moved = moved / total;
  mc_chain_destroy(c);
  mc_mmlt_jump_free(&j);
  mc_mmlt_states_free(&ctx);
  return worst;
}

static void test_invariance(void **state) {
  (void)state;
  /* Strategies: 3 + 4 + 5 = 12 means; two-sided normal at Sidak 1%. */
  double alpha = chi2_sidak(0.01, 12);
  double zc = 0.0;
  for (double z = 0.0; z < 10.0; z += 1e-3)
    if (erfc(z / sqrt(2.0)) < alpha) {
      zc = z;
      break;
    }
  int checked = 0;
  for (int k = 2; k <= 4; k++) {
    double moved;
    double z = worst_z(k, 400000, 0, 300 + (uint64_t)k, &moved);
    assert_true(z < zc);
    assert_true(moved > 0.05);
    checked++;
  }
  double moved;
  double zbad = worst_z(3, 400000, 1, 999, &moved);
  print_message("critical |z| %.2f; the control's %.2f\n", zc, zbad);
  assert_int_equal(checked, 3);
  assert_true(zbad > 8.0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_invariance),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
