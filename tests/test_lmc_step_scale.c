/*
 * test_lmc_step_scale.c: the per-coordinate step scale c of the LMC kernel
 * (lmc_kernel.h) and of mala.h's _c routines: MALA in the rescaled
 * coordinates z = u / c, i.e. y ~ N(x + (s/2) c M g_z, s c^2 M) with
 * g_z = c grad log f, and Kelemen's step with offsets in (c s1, c s2].
 *
 *   - c = NULL and c = 1 give exactly what the unscaled routines give
 *     (same draws from the same generator, same log densities).
 *   - The densities integrate to 1 on [0, 1) (midpoint rule on 2^20
 *     cells; within 1e-6) and match the samples: 200000 draws of one
 *     coordinate with c = 0.05 (MALA) and c = 0.1 (Kelemen), histogram of
 *     32 cells against the integrated density, chi-square at level 1e-3.
 *     c = 0 keeps the coordinate fixed with log density 0 there.
 *   - Adam sees the gradient in z: with grad f / f = (1, 1 / c) and
 *     c = (1, 0.01), both coordinates get the same first and second
 *     moments (before the change they differed by 100x and 10^4x, and
 *     the norm truncation at 1e3 would have shrunk coordinate 0 to ~1e-2
 *     had the raw gradient been larger).
 *   - The kernel stays exact: N = 10000 independent chains on the 2-D
 *     density f = 2 + sin(2 pi u0) + 0.8 cos(2 pi u1), each started from
 *     an exact draw (rejection) and run for 150 steps of large steps
 *     (0.1), the chain's Kelemen step (0.2, step_scale c) and the LMC
 *     kernel with adapt none and c (0.7), c = (1, 0.05), step 0.01; the
 *     histogram of the final states over 6 x 6 cells passes a chi-square
 *     test at level 1e-3. This guards the plumbing (the kernel and the
 *     chain's scaled Kelemen step together); it is weak against a wrong
 *     density, which mostly makes the kernel reject (still invariant).
 *     Wrong densities are caught by the histogram test above: dropping c
 *     from the density's sigma or from its drift (checked by hand while
 *     writing this test) gives p = 0 there.
 * Every test counts its checks; test_count asserts the total.
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
#include "lmc/kernels/lmc_kernel.h"
#include "lmc/kernels/mala.h"
#include "test_util.h"

static int g_checks;

static void test_identity(void **state) {
  (void)state;
  enum { N = 5 };
  const double x[N] = {0.1, 0.5, 0.93, 0.0, 0.7}, g[N] = {3.0, -20.0, 0.5, 100.0, 0.0};
  const double M[N] = {1.0, 0.5, 2.0, 0.1, 1.0}, ones[N] = {1, 1, 1, 1, 1};
  for (int rep = 0; rep < 50; rep++) {
    double y0[N], y1[N], y2[N];
    rng r0, r1, r2;
    rng_seed(&r0, 3, (uint64_t)rep), rng_seed(&r1, 3, (uint64_t)rep), rng_seed(&r2, 3, (uint64_t)rep);
    mala_sample(N, x, g, M, 1e-3, &r0, y0);
    mala_sample_c(N, x, g, M, NULL, 1e-3, &r1, y1);
    mala_sample_c(N, x, g, M, ones, 1e-3, &r2, y2);
    for (int i = 0; i < N; i++) assert_true(y0[i] == y1[i] && y0[i] == y2[i]);
    double l0 = mala_log_density(N, x, g, M, 1e-3, y0);
    assert_true(l0 == mala_log_density_c(N, x, g, M, NULL, 1e-3, y0));
    assert_true(l0 == mala_log_density_c(N, x, g, M, ones, 1e-3, y0));
    mala_kelemen_sample(N, x, 1.0 / 1024, 1.0 / 64, &r0, y0);
    mala_kelemen_sample_c(N, x, 1.0 / 1024, 1.0 / 64, ones, &r1, y1);
    for (int i = 0; i < N; i++) assert_true(y0[i] == y1[i]);
    assert_true(mala_kelemen_log_density(N, x, 1.0 / 1024, 1.0 / 64, y0) ==
                mala_kelemen_log_density_c(N, x, 1.0 / 1024, 1.0 / 64, ones, y0));
    g_checks++;
  }
  /* c = 0: the coordinate stays, density factor 1 there and 0 elsewhere. */
  const double c0[2] = {1.0, 0.0}, x2[2] = {0.3, 0.6}, g2[2] = {1.0, 5.0};
  rng r;
  rng_seed(&r, 9, 0);
  double y[2];
  mala_sample_c(2, x2, g2, NULL, c0, 1e-2, &r, y);
  assert_true(y[1] == x2[1]);
  assert_true(isfinite(mala_log_density_c(2, x2, g2, NULL, c0, 1e-2, y)));
  y[1] = 0.61;
  assert_true(mala_log_density_c(2, x2, g2, NULL, c0, 1e-2, y) == -INFINITY);
  mala_kelemen_sample_c(2, x2, 1.0 / 1024, 1.0 / 64, c0, &r, y);
  assert_true(y[1] == x2[1]);
  assert_true(isfinite(mala_kelemen_log_density_c(2, x2, 1.0 / 1024, 1.0 / 64, c0, y)));
  g_checks++;
}

/* One coordinate: the density of the scaled proposal (kind 0: MALA, 1:
 * Kelemen) at y. */
typedef struct one_case {
  int kind;
  double x, g, M, c, s;
} one_case;

static double one_density(const one_case *k, double y) {
  if (k->kind == 0) return exp(mala_log_density_c(1, &k->x, &k->g, &k->M, &k->c, k->s, &y));
  return exp(mala_kelemen_log_density_c(1, &k->x, 1.0 / 1024, 1.0 / 64, &k->c, &y));
}

static void check_one(const one_case *k, double lo, double hi) {
  /* Normalisation on [0, 1); Kelemen's density 1 / (2 |d| log(s2/s1))
   * on c s1 < |d| <= c s2 is integrated in t = log |d| (constant there),
   * since a uniform grid would straddle its jumps. */
  enum { FINE = 1 << 20 };
  double sum = 0.0;
  if (k->kind == 0) {
    for (int i = 0; i < FINE; i++) sum += one_density(k, (i + 0.5) / FINE);
    sum /= FINE;
  } else {
    double t0 = log(k->c / 1024), t1 = log(k->c / 64), dt = (t1 - t0) / FINE;
    for (int i = 0; i < FINE; i++) {
      double d = exp(t0 + (i + 0.5) * dt);
      sum += (one_density(k, k->x + d) + one_density(k, k->x - d)) * d * dt;
    }
  }
  assert_near(sum, 1.0, 1e-6);
  /* Histogram over [lo, hi) in 32 cells plus the rest (for Kelemen the
   * cells' edges fall on the support's: x +- c s2 and x +- c s2 / 16). */
  enum { NB = 32, NS = 200000, SUB = 200 };
  double hist[NB + 1] = {0}, expct[NB + 1], w = (hi - lo) / NB, in = 0.0;
  for (int b = 0; b < NB; b++) {
    double p = 0.0;
    for (int j = 0; j < SUB; j++) p += one_density(k, lo + (b + (j + 0.5) / SUB) * w);
    p *= w / SUB;
    expct[b] = p * NS;
    in += p;
  }
  expct[NB] = fmax(0.0, 1.0 - in) * NS;
  rng r;
  rng_seed(&r, 77, (uint64_t)k->kind);
  for (int i = 0; i < NS; i++) {
    double y;
    if (k->kind == 0) mala_sample_c(1, &k->x, &k->g, &k->M, &k->c, k->s, &r, &y);
    else mala_kelemen_sample_c(1, &k->x, 1.0 / 1024, 1.0 / 64, &k->c, &r, &y);
    int b = y >= lo && y < hi ? (int)((y - lo) / w) : NB;
    hist[b > NB ? NB : b] += 1.0;
  }
  int dof;
  double stat, pv = chi2_pvalue(hist, expct, NB + 1, 5.0, &dof, &stat);
  if (!(pv > 1e-3)) print_error("kind %d: chi2 %.1f, dof %d, p %.3g\n", k->kind, stat, dof, pv);
  assert_true(pv > 1e-3);
  assert_true(dof >= 20);
  g_checks++;
}

static void test_densities(void **state) {
  (void)state;
  /* MALA: mu = 0.98 + 0.5 * 0.01 * 0.05 * 2 * 40 = 0.999 (wraps), sigma
   * = 0.05 sqrt(0.02) = 0.00707; the window covers mu +- 5 sigma. */
  one_case m = {0, 0.98, 40.0, 2.0, 0.05, 0.01};
  check_one(&m, 0.96, 1.0);
  /* Kelemen with c = 0.1: offsets in (1/10240, 1/640]. */
  one_case kl = {1, 0.5, 0.0, 1.0, 0.1, 0.0};
  check_one(&kl, 0.5 - 1.0 / 640, 0.5 + 1.0 / 640);
}

static void test_adam_rescaled(void **state) {
  (void)state;
  const double c[2] = {1.0, 0.01};
  lmc_kernel_params p = lmc_kernel_params_default();
  p.adapt = LMC_ADAPT_ADAM;
  p.scale = c;
  lmc_mala k;
  lmc_error err;
  assert_int_equal(lmc_mala_init(&k, 2, &p, &err), LMC_OK);
  mc_kernel kn = lmc_mala_kernel(&k);
  double u[2] = {0.3, 0.4}, grad[2] = {2.0, 200.0}; /* f = 2: grad log f = (1, 100) */
  mc_state x = {2, u, {2.0, {2.0, 2.0, 2.0}, 0.0, 0.0, 2.0}, grad, 1, 1, 0, 0, 0, 0, NULL, NULL};
  for (int i = 0; i < 10; i++) kn.on_step(kn.self, &x, 1);
  double m1[2], m2[2];
  adam_moments(&k.adam, 0, &m1[0], &m2[0]);
  adam_moments(&k.adam, 1, &m1[1], &m2[1]);
  assert_true(m1[0] > 0.0 && m2[0] > 0.0);
  assert_near(m1[1], m1[0], 1e-12 * m1[0]);
  assert_near(m2[1], m2[0], 1e-12 * m2[0]);
  lmc_mala_free(&k);
  g_checks++;
}

/* f = 2 + sin(2 pi u0) + 0.8 cos(2 pi u1), with its gradient. */
static int wave_eval(const mc_target *t, void *scratch, lmc_sampler *smp, mc_value *OUT_value,
                     double *OUT_grad, int *OUT_grad_ok) {
  (void)t, (void)scratch;
  sampler_use_stream(smp, 0);
  const double tp = 2.0 * M_PI;
  double u0 = sampler_next(smp), u1 = sampler_next(smp);
  double f = 2.0 + sin(tp * u0) + 0.8 * cos(tp * u1);
  OUT_value->f = f;
  OUT_value->value = rgb_gray(f);
  OUT_value->rx = u0;
  OUT_value->ry = u1;
  if (OUT_grad) {
    OUT_grad[0] = tp * cos(tp * u0);
    OUT_grad[1] = -0.8 * tp * sin(tp * u1);
    *OUT_grad_ok = 1;
  }
  return 0;
}

/* The integral of f over cell [a0, b0) x [a1, b1) divided by 2 (its total). */
static double wave_cell(double a0, double b0, double a1, double b1) {
  const double tp = 2.0 * M_PI;
  double w0 = b0 - a0, w1 = b1 - a1;
  double v = 2.0 * w0 * w1 + w1 * (cos(tp * a0) - cos(tp * b0)) / tp +
             0.8 * w0 * (sin(tp * b1) - sin(tp * a1)) / tp;
  return v / 2.0;
}

static void test_kernel_invariant(void **state) {
  (void)state;
  const double c[2] = {1.0, 0.05};
  mc_target t;
  memset(&t, 0, sizeof t);
  t.dim = 2;
  t.stream_dim[0] = 2;
  t.eval = wave_eval;
  t.step_scale = c;
  lmc_kernel_params p = lmc_kernel_params_default();
  p.adapt = LMC_ADAPT_NONE;
  p.step = 0.01;
  p.scale = c;
  lmc_mala k;
  lmc_error err;
  assert_int_equal(lmc_mala_init(&k, 2, &p, &err), LMC_OK);
  mc_kernel ks[3] = {mc_kernel_large(), mc_kernel_small(1.0 / 1024, 1.0 / 64), lmc_mala_kernel(&k)};
  double pr[3] = {0.1, 0.2, 0.7};
  mc_chain *ch = NULL;
  assert_int_equal(mc_chain_create(&ch, &t, ks, pr, 3, &err), LMC_OK);
  enum { N = 10000, STEPS = 150, NB = 6 };
  double hist[NB * NB] = {0}, expct[NB * NB];
  for (int i = 0; i < N; i++) {
    /* An exact start: rejection of large-step states against f_max = 3.8. */
    uint64_t seq = (uint64_t)i * 1000u;
    rng acc;
    rng_seed(&acc, 31, (uint64_t)i);
    while (!(rng_uniform(&acc) * 3.8 < mc_chain_start(ch, 41, seq, 0x5ca1e000u + (uint64_t)i)))
      seq++;
    for (int s = 0; s < STEPS; s++) mc_chain_step(ch, NULL, NULL);
    int a = (int)(ch->x.v.rx * NB), b = (int)(ch->x.v.ry * NB);
    hist[(a >= NB ? NB - 1 : a) * NB + (b >= NB ? NB - 1 : b)] += 1.0;
  }
  int64_t mala_acc = ch->stats[2].accepted;
  mc_chain_destroy(ch);
  lmc_mala_free(&k);
  assert_true(mala_acc > N * STEPS / 10); /* the kernel did move the chains */
  for (int a = 0; a < NB; a++)
    for (int b = 0; b < NB; b++)
      expct[a * NB + b] = N * wave_cell((double)a / NB, (a + 1.0) / NB, (double)b / NB, (b + 1.0) / NB);
  int dof;
  double stat, pv = chi2_pvalue(hist, expct, NB * NB, 5.0, &dof, &stat);
  if (!(pv > 1e-3)) print_error("chi2 %.1f, dof %d, p %.3g\n", stat, dof, pv);
  assert_true(pv > 1e-3);
  assert_true(dof >= 30);
  g_checks++;
}

static void test_count(void **state) {
  (void)state;
  assert_int_equal(g_checks, 50 + 1 + 2 + 1 + 1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_identity),
      cmocka_unit_test(test_densities),
      cmocka_unit_test(test_adam_rescaled),
      cmocka_unit_test(test_kernel_invariant),
      cmocka_unit_test(test_count),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
