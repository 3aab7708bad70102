/*
 * test_mcmc_toy.c: the chain of src/lmc/kernels/chain.c on toy densities whose
 * normalised histograms are known.
 *
 * Densities: a bimodal 1-D density, a narrow ring in 2-D (radius 0.3,
 * width 0.02), a lazy-coordinate density in 2-D whose second coordinate is
 * read only on half of the first axis (f = 1 + 4 u1 when u0 < 1/2, else 1:
 * u0's marginal is 3 : 1 on the two halves and u1 given u0 < 1/2 has the
 * density (1 + 4 u1) / 3; this exercises the lazy replay and the restore on
 * rejection), and a 1-D density sampled with a full (non-lazy) kernel whose
 * independence proposal q(y) = 2y is not symmetric, so a wrong
 * Metropolis-Hastings ratio would show. Delayed acceptance (chain.h) runs
 * on the bimodal density with a drifted (asymmetric) wrapped walk whose
 * screen is deliberately not the full ratio.
 *
 * Chain histograms: N independent chains, each started from an exact
 * draw of the target (rejection sampling of uniform large-step states) and
 * run for B steps; only each chain's final state is counted, so the N
 * samples are independent and the plain chi-square test applies. A kernel
 * that does not leave the target invariant (a wrong acceptance ratio, a
 * wrong lazy replay or restore) moves the histogram away from it within a
 * few steps. Each chi-square test must pass at the Sidak-corrected level
 * for an overall false-alarm rate of 1e-3.
 *
 * Expected-value splatting: 32 independent groups of chains splat (weight a
 * at the proposal, 1 - a at the current state; under delayed acceptance the
 * second test's a2 after a passed first test) into a histogram; each bin's
 * mean over groups must lie within 5 standard errors (estimated from the
 * 32 groups) of the exact bin probability. With ~60 bins checked, a false
 * alarm has probability below 1e-3 even with Student-t tails (31 dof).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "chi2.h"
#include "lmc/kernels/chain.h"
#include "test_util.h"

#define N_CHI2_TESTS 14
static int g_chi2_tests;

/* --- toy targets -------------------------------------------------------- */

typedef double (*toy_fn)(const double *u);

static double toy_bimodal(const double *u) {
  double a = (u[0] - 0.3) / 0.05, b = (u[0] - 0.75) / 0.1;
  return exp(-0.5 * a * a) + 0.5 * exp(-0.5 * b * b);
}

static double toy_ring(const double *u) {
  double dx = u[0] - 0.5, dy = u[1] - 0.5;
  double r = (sqrt(dx * dx + dy * dy) - 0.3) / 0.02;
  return exp(-0.5 * r * r);
}

static double toy_linear(const double *u) { return 0.2 + u[0] * u[0]; }

typedef struct toy_ctx {
  toy_fn fn;
  int lazy; /* the lazy-coordinate density (reads u1 only when u0 < 1/2) */
} toy_ctx;

static int toy_eval(const mc_target *t, void *scratch, lmc_sampler *smp, mc_value *OUT_value,
                    double *OUT_grad, int *OUT_grad_ok) {
  const toy_ctx *c = t->ctx;
  (void)scratch, (void)OUT_grad;
  if (OUT_grad_ok) *OUT_grad_ok = 0;
  double u[2] = {0.0, 0.0};
  double f;
  sampler_use_stream(smp, 0);
  u[0] = sampler_next(smp);
  if (c->lazy) {
    f = 1.0;
    if (u[0] < 0.5) {
      u[1] = sampler_next(smp);
      f = 1.0 + 4.0 * u[1];
    }
  } else {
    for (int i = 1; i < t->dim; i++) u[i] = sampler_next(smp);
    f = c->fn(u);
  }
  OUT_value->f = f;
  OUT_value->value = rgb_gray(f);
  OUT_value->rx = u[0];
  OUT_value->ry = u[1];
  return 0;
}

static mc_target toy_target(toy_ctx *c, int dim) {
  mc_target t;
  memset(&t, 0, sizeof t);
  t.dim = dim;
  t.stream_dim[0] = dim;
  t.ctx = c;
  t.eval = toy_eval;
  return t;
}

/* Exact bin probabilities of a density on [0,1)^dim (dim 1 or 2) with
 * nb bins per axis, by the midpoint rule on a fine grid. */
static void exact_bins(toy_fn fn, int dim, int nb, double *OUT_p) {
  const int sub = dim == 1 ? 400 : 60;
  int ny = dim == 1 ? 1 : nb;
  double total = 0.0;
  for (int by = 0; by < ny; by++)
    for (int bx = 0; bx < nb; bx++) {
      double s = 0.0;
      for (int j = 0; j < (dim == 1 ? 1 : sub); j++)
        for (int i = 0; i < sub; i++) {
          double u[2] = {(bx + (i + 0.5) / sub) / nb, dim == 1 ? 0.0 : (by + (j + 0.5) / sub) / nb};
          s += fn(u);
        }
      OUT_p[by * nb + bx] = s;
      total += s;
    }
  for (int i = 0; i < nb * ny; i++) OUT_p[i] /= total;
}

/* --- a full kernel: the independence proposal q(y) = 2 y on [0,1) ------- */

static double lin_propose(void *self, rng *r, const mc_state *x, double *OUT_y) {
  (void)self;
  for (int i = 0; i < x->dim; i++) OUT_y[i] = sqrt(rng_uniform(r));
  return log(2.0 * OUT_y[0]);
}

static double lin_log_density(void *self, const mc_state *from, const double *to_u) {
  (void)self, (void)from;
  return to_u[0] > 0.0 ? log(2.0 * to_u[0]) : -INFINITY;
}

/* --- a full kernel with delayed acceptance: a drifted wrapped walk ------- */

/* y = x + MU + SIGMA N(0, 1), wrapped: not symmetric (it drifts right), so
 * a wrong ratio would show. Its screen is deliberately not the full ratio:
 * it ignores q and adds a term that depends on the state proposed from, as
 * the gradient term of lmc's screen does. */
#define DRIFT_MU 0.05
#define DRIFT_SIGMA 0.08

static double drift_log_q(double from, double to) {
  double d = to - from - DRIFT_MU;
  d -= floor(d + 0.5);
  double s = 0.0;
  for (int k = -3; k <= 3; k++) {
    double e = (d + k) / DRIFT_SIGMA;
    s += exp(-0.5 * e * e);
  }
  return log(s / (DRIFT_SIGMA * sqrt(2.0 * M_PI)));
}

static double drift_propose(void *self, rng *r, const mc_state *x, double *OUT_y) {
  (void)self;
  /* Box-Muller. */
  double u1 = 1.0 - rng_uniform(r), u2 = rng_uniform(r);
  double y = x->u[0] + DRIFT_MU + DRIFT_SIGMA * sqrt(-2.0 * log(u1)) * cos(2.0 * M_PI * u2);
  y -= floor(y);
  if (y >= 1.0) y = 0.0;
  OUT_y[0] = y;
  return drift_log_q(x->u[0], y);
}

static double drift_log_density(void *self, const mc_state *from, const double *to_u) {
  (void)self;
  return drift_log_q(from->u[0], to_u[0]);
}

static double drift_log_screen(void *self, const mc_state *from, const double *to_u, double f_to) {
  (void)self, (void)to_u;
  return log(f_to) - log(from->v.f) + 0.5 * sin(2.0 * M_PI * from->u[0]);
}

static mc_kernel drift_kernel(void) {
  mc_kernel k = {0};
  k.name = "drift";
  k.kind = MC_KERNEL_FULL;
  k.propose = drift_propose;
  k.log_density = drift_log_density;
  k.log_screen = drift_log_screen;
  return k;
}

/* --- chain histograms --------------------------------------------------- */

/* Final states of n_chains chains after `burn` steps, binned by (rx, ry). */
static void chain_histogram(const mc_target *t, const mc_kernel *k, const double *p, int nk,
                            double f_max, int n_chains, int burn, int nb, int dim,
                            double *OUT_hist) {
  lmc_error err;
  mc_chain *c = NULL;
  assert_int_equal(mc_chain_create(&c, t, k, p, nk, &err), LMC_OK);
  memset(OUT_hist, 0, sizeof(double) * (size_t)(dim == 1 ? nb : nb * nb));
  for (int i = 0; i < n_chains; i++) {
    /* A start drawn from the target by rejection. */
    uint64_t seq = (uint64_t)i * 100000u;
    rng acc;
    rng_seed(&acc, 13, (uint64_t)i);
    while (!(rng_uniform(&acc) * f_max < mc_chain_start(c, 11, seq, 0x5eed0000u + (uint64_t)i)))
      seq++;
    for (int s = 0; s < burn; s++) mc_chain_step(c, NULL, NULL);
    int bx = (int)(c->x.v.rx * nb), by = dim == 1 ? 0 : (int)(c->x.v.ry * nb);
    if (bx >= nb) bx = nb - 1;
    if (by >= nb) by = nb - 1;
    OUT_hist[by * nb + bx] += 1.0;
  }
  mc_chain_destroy(c);
}

static void check_chi2(const char *what, const double *hist, const double *prob, int n, int total) {
  double expct[400];
  for (int i = 0; i < n; i++) expct[i] = prob[i] * total;
  int dof;
  double stat;
  double pv = chi2_pvalue(hist, expct, n, 5.0, &dof, &stat);
  double alpha = chi2_sidak(1e-3, N_CHI2_TESTS);
  if (!(pv > alpha)) print_error("%s: chi2 %.1f, dof %d, p %.3g < %.3g\n", what, stat, dof, pv, alpha);
  assert_true(pv > alpha);
  assert_true(dof >= 5);
  g_chi2_tests++;
}

static void kernel_sets(mc_kernel k[3][2], double p[3][2], int nk[3]) {
  /* large only; small only; the mixture (largestep 0.3) */
  k[0][0] = mc_kernel_large();
  p[0][0] = 1.0;
  nk[0] = 1;
  k[1][0] = mc_kernel_small(1.0 / 1024.0, 1.0 / 16.0);
  p[1][0] = 1.0;
  nk[1] = 1;
  k[2][0] = mc_kernel_large();
  k[2][1] = mc_kernel_small(1.0 / 1024.0, 1.0 / 64.0);
  p[2][0] = 0.3;
  p[2][1] = 0.7;
  nk[2] = 2;
}

static void test_bimodal_1d(void **state) {
  (void)state;
  toy_ctx c = {toy_bimodal, 0};
  mc_target t = toy_target(&c, 1);
  mc_kernel k[3][2];
  double p[3][2];
  int nk[3];
  kernel_sets(k, p, nk);
  enum { NB = 20, N = 20000 };
  double prob[NB], hist[NB];
  exact_bins(toy_bimodal, 1, NB, prob);
  const char *names[3] = {"1-D large", "1-D small", "1-D mixture"};
  for (int s = 0; s < 3; s++) {
    chain_histogram(&t, k[s], p[s], nk[s], 1.1, N, 100, NB, 1, hist);
    check_chi2(names[s], hist, prob, NB, N);
  }
}

static void test_ring_2d(void **state) {
  (void)state;
  toy_ctx c = {toy_ring, 0};
  mc_target t = toy_target(&c, 2);
  mc_kernel k[3][2];
  double p[3][2];
  int nk[3];
  kernel_sets(k, p, nk);
  enum { NB = 10, N = 20000 };
  double prob[NB * NB], hist[NB * NB];
  exact_bins(toy_ring, 2, NB, prob);
  const char *names[3] = {"ring large", "ring small", "ring mixture"};
  for (int s = 0; s < 3; s++) {
    chain_histogram(&t, k[s], p[s], nk[s], 1.0, N, 100, NB, 2, hist);
    check_chi2(names[s], hist, prob, NB * NB, N);
  }
}

/* The lazy density: u0 in 4 bins (3:1 halves), u1 given u0 < 1/2 in 5 bins. */
static void test_lazy_coordinates(void **state) {
  (void)state;
  toy_ctx c = {NULL, 1};
  mc_target t = toy_target(&c, 2);
  mc_kernel k[3][2];
  double p[3][2];
  int nk[3];
  kernel_sets(k, p, nk);
  enum { NB = 10, N = 20000 };
  /* Joint bins over (u0, u1) on a 10 x 10 grid: for u0 < 1/2 the density is
   * (1 + 4 u1) / 4 per unit area (normalising: 3 * 0.5 + 1 * 0.5 = 2, so
   * (1 + 4 u1) / 2 for u0 < 1/2 and 1/2 for u0 >= 1/2); u1 is not part of
   * the state's meaning for u0 >= 1/2, so those bins pool over u1. */
  double prob[NB * NB], hist[NB * NB];
  for (int by = 0; by < NB; by++)
    for (int bx = 0; bx < NB; bx++) {
      double y0 = (double)by / NB, y1 = (double)(by + 1) / NB;
      double area = 1.0 / NB;
      prob[by * NB + bx] = bx < NB / 2 ? area * 0.5 * ((y1 - y0) + 2.0 * (y1 * y1 - y0 * y0))
                                       : (by == 0 ? area * 0.5 : 0.0);
    }
  const char *names[2] = {"lazy small", "lazy mixture"};
  for (int s = 1; s < 3; s++) {
    chain_histogram(&t, k[s], p[s], nk[s], 5.0, N, 100, NB, 2, hist);
    /* Pool u0 >= 1/2 into the first row (ry is 0 there: u1 is not read). */
    check_chi2(names[s - 1], hist, prob, NB * NB, N);
  }
}

/* The Gaussian small step (its owed steps replayed as one of variance
 * n sigma^2) on the ring and on the lazy density, alone and with large
 * steps. */
static void test_gauss_small(void **state) {
  (void)state;
  enum { NB = 10, N = 20000 };
  double prob[NB * NB], hist[NB * NB];
  mc_kernel k[2] = {mc_kernel_small_gauss(0.03), mc_kernel_large()};
  double p1[1] = {1.0}, p2[2] = {0.7, 0.3};
  toy_ctx ring = {toy_ring, 0};
  mc_target t = toy_target(&ring, 2);
  exact_bins(toy_ring, 2, NB, prob);
  chain_histogram(&t, k, p1, 1, 1.0, N, 100, NB, 2, hist);
  check_chi2("ring gauss", hist, prob, NB * NB, N);
  toy_ctx lazy = {NULL, 1};
  t = toy_target(&lazy, 2);
  for (int by = 0; by < NB; by++)
    for (int bx = 0; bx < NB; bx++) {
      double y0 = (double)by / NB, y1 = (double)(by + 1) / NB;
      double area = 1.0 / NB;
      prob[by * NB + bx] = bx < NB / 2 ? area * 0.5 * ((y1 - y0) + 2.0 * (y1 * y1 - y0 * y0))
                                       : (by == 0 ? area * 0.5 : 0.0);
    }
  chain_histogram(&t, k, p1, 1, 5.0, N, 100, NB, 2, hist);
  check_chi2("lazy gauss", hist, prob, NB * NB, N);
  chain_histogram(&t, k, p2, 2, 5.0, N, 100, NB, 2, hist);
  check_chi2("lazy gauss mixture", hist, prob, NB * NB, N);
}

static void test_full_kernel_asymmetric(void **state) {
  (void)state;
  toy_ctx c = {toy_linear, 0};
  mc_target t = toy_target(&c, 1);
  mc_kernel k = {0};
  k.name = "linear";
  k.kind = MC_KERNEL_FULL;
  k.propose = lin_propose;
  k.log_density = lin_log_density;
  double p = 1.0;
  enum { NB = 20, N = 20000 };
  double prob[NB], hist[NB];
  exact_bins(toy_linear, 1, NB, prob);
  chain_histogram(&t, &k, &p, 1, 1.2, N, 100, NB, 1, hist);
  check_chi2("full asymmetric", hist, prob, NB, N);
}

/* Delayed acceptance (chain.h) with the drifted walk, alone and mixed with
 * large steps; both tests of the two-stage acceptance must be exercised. */
static void test_delayed_acceptance(void **state) {
  (void)state;
  toy_ctx c = {toy_bimodal, 0};
  mc_target t = toy_target(&c, 1);
  mc_kernel k[2] = {drift_kernel(), mc_kernel_large()};
  double p[2] = {0.8, 0.2};
  enum { NB = 20, N = 20000 };
  double prob[NB], hist[NB];
  exact_bins(toy_bimodal, 1, NB, prob);
  chain_histogram(&t, k, p, 1, 1.1, N, 100, NB, 1, hist);
  check_chi2("delayed acceptance", hist, prob, NB, N);
  chain_histogram(&t, k, p, 2, 1.1, N, 100, NB, 1, hist);
  check_chi2("delayed acceptance + large", hist, prob, NB, N);

  /* Both outcomes of the first test occur. */
  lmc_error err;
  mc_chain *ch = NULL;
  assert_int_equal(mc_chain_create(&ch, &t, k, p, 1, &err), LMC_OK);
  mc_chain_start(ch, 3, 1, 2);
  for (int i = 0; i < 10000; i++) mc_chain_step(ch, NULL, NULL);
  printf("  delayed acceptance: %lld first tests, %lld passed, %lld accepted\n",
         (long long)ch->screened, (long long)ch->screen_passed, (long long)ch->stats[0].accepted);
  assert_true(ch->screened > 9000);
  assert_true(ch->screen_passed > 1000 && ch->screen_passed < ch->screened - 1000);
  assert_true(ch->stats[0].accepted > 500 && ch->stats[0].accepted < ch->screen_passed);
  mc_chain_destroy(ch);
}

/* --- expected-value splatting -------------------------------------------- */

typedef struct splat_hist {
  double h[20];
} splat_hist;

static void splat_into(void *ctx, const mc_value *v, double w) {
  splat_hist *s = ctx;
  int b = (int)(v->rx * 20);
  if (b > 19) b = 19;
  s->h[b] += w * v->f; /* value / f * weight, with value = f */
}

static void test_expected_value_splatting(void **state) {
  (void)state;
  toy_ctx c = {toy_bimodal, 0};
  mc_target t = toy_target(&c, 1);
  mc_kernel k[3][2];
  double p[3][2];
  int nk[3];
  kernel_sets(k, p, nk);
  enum { NB = 20, G = 32, CH = 16, STEPS = 4000 };
  double prob[NB];
  exact_bins(toy_bimodal, 1, NB, prob);
  /* A 4th set: delayed acceptance, whose splat weight is an estimate of a. */
  mc_kernel kd[2] = {drift_kernel(), mc_kernel_large()};
  double pd[2] = {0.8, 0.2};
  int checked = 0;
  for (int s = 0; s < 4; s++) {
    const mc_kernel *ks = s < 3 ? k[s] : kd;
    const double *ps = s < 3 ? p[s] : pd;
    int nks = s < 3 ? nk[s] : 2;
    double sum[NB] = {0}, sum2[NB] = {0};
    for (int g = 0; g < G; g++) {
      splat_hist hist;
      memset(&hist, 0, sizeof hist);
      lmc_error err;
      mc_chain *ch = NULL;
      assert_int_equal(mc_chain_create(&ch, &t, ks, ps, nks, &err), LMC_OK);
      for (int i = 0; i < CH; i++) {
        /* Start from the stationary law (rejection sampling of uniform
         * starts), so no burn-in is needed. */
        uint64_t seq = 7000000u + (uint64_t)(g * CH + i) * 997u;
        rng acc;
        rng_seed(&acc, 5, seq);
        for (;;) {
          double f = mc_chain_start(ch, 5, seq, 0xabc000u + (uint64_t)(g * CH + i));
          if (rng_uniform(&acc) * 1.1 < f) break;
          seq++;
        }
        for (int q = 0; q < STEPS; q++) mc_chain_step(ch, splat_into, &hist);
      }
      mc_chain_destroy(ch);
      for (int b = 0; b < NB; b++) {
        double v = hist.h[b] / ((double)CH * STEPS);
        sum[b] += v;
        sum2[b] += v * v;
      }
    }
    for (int b = 0; b < NB; b++) {
      double mean = sum[b] / G, var = (sum2[b] - G * mean * mean) / (G - 1);
      double se = sqrt(fmax(var, 0.0) / G);
      assert_near(mean, prob[b], 5.0 * se + 1e-4);
      checked++;
    }
  }
  assert_int_equal(checked, 4 * NB);
}

static void test_count(void **state) {
  (void)state;
  assert_int_equal(g_chi2_tests, N_CHI2_TESTS);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_bimodal_1d),
      cmocka_unit_test(test_ring_2d),
      cmocka_unit_test(test_lazy_coordinates),
      cmocka_unit_test(test_gauss_small),
      cmocka_unit_test(test_full_kernel_asymmetric),
      cmocka_unit_test(test_delayed_acceptance),
      cmocka_unit_test(test_expected_value_splatting),
      cmocka_unit_test(test_count),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
