/*
 * test_lmc_toy_slow.c: the LMC kernel (src/lmc/kernels/lmc_kernel.h) driven by the
 * chain framework (chain.h) on toy densities in 2 to 6 dimensions:
 *
 *   ridge    2-D, a narrow curved ridge u1 ~ 0.5 + 0.2 sin(2 pi u0), width 0.01;
 *   scales   4-D, a mixture of two products of wrapped normals whose
 *            standard deviations differ by up to 50x between axes;
 *   plateau  6-D, a product of functions flat (gradient exactly 0) on
 *            [0.3, 0.6] with Gaussian shoulders: the Kelemen fallback;
 *   ripple   2-D, for the bias of adam (below).
 *
 * For adapt = none, diminish, cache, and cache with delayed acceptance
 * (lmc_kernel.h's first-order screen), the histogram of the (u0, u1)
 * marginal (expected-value splats of every step of R independent chains)
 * passes a chi-square test against the normalised density. The chains are
 * correlated, so counts are scaled to the effective sample size:
 * N_eff = N / tau, with tau the integrated autocorrelation time estimated
 * per bin from the spread of the R chains' frequencies,
 * tau_b = L var_r(p_rb) / (p_b (1 - p_b)), averaged over the bins with
 * weights p_b. Per test the level is the Sidak share of 1e-3 over all
 * chi-square tests of this file (overall confidence 99.9%, up to the
 * approximation of tau).
 *
 * Adam's bias: on `ripple` (2-D; u0 < 1/2 carries ripples whose log
 * gradient reaches 250, u0 >= 1/2 is smooth, gradient below 4) with MALA
 * as the only kernel (plus, for cache, its independence proposal), step
 * 1e-2, so that Adam's preconditioner follows the chain from one region
 * to the other, the mass of u0 < 1/2 is estimated by each mode with its
 * standard error from the R chains. The test asserts that adam's error
 * exceeds 3.29 standard errors (it is biased: two-sided 99.9%), that none,
 * diminish and cache are within 3.29 of theirs, and that
 * |bias_adam| > |bias_mode| + 3.29 sqrt(se_adam^2 + se_mode^2) for each of
 * them (adam's bias larger, 99.9%). Under adam the chain moves slowly
 * where M is small (the rippled half) and so stays there too long: the
 * mass of u0 < 1/2 comes out too large.
 *
 * The kernel mixture of the chi-square runs: large step 0.02, Kelemen
 * small step 0.1, LMC the rest (cache: 0.05 of it the independence
 * proposal). Cache runs stage 1 (M = I, Adam's moments recorded) for a
 * burn-in and then L/2 steps per chain, then restarts the chains with the
 * frozen cache; as in the renderer, the L/2 samples of stage 1 are kept:
 * the histograms count both stages.
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
#include "lmc/kernels/h2mc.h"
#include "lmc/kernels/lmc_kernel.h"
#include "lmc/kernels/mala.h"
#include "test_util.h"

#define MAXD 6
#define NB 16        /* histogram bins per axis */
#define R_CHAINS 32  /* independent chains per run */
#define CHI2_TESTS 15 /* 3 targets x (4 unbiased LMC runs + H2MC) */
#define Z999 3.2905  /* two-sided 99.9% normal quantile */
#define BIAS_STEP 1e-2 /* the bias test's Langevin step */
#define BIAS_L 50000   /* and its steps per chain */

/* ---- Toy targets ---------------------------------------------------------- */

typedef enum toy_kind { TOY_RIDGE, TOY_SCALES, TOY_PLATEAU, TOY_RIPPLE } toy_kind;

typedef struct toy {
  toy_kind kind;
  int dim;
} toy;

/* Wrapped normal density and its derivative in y (images k = -4 .. 4;
 * sigma <= 0.2 here, so the rest is below 1e-60). */
static double wn(double y, double mu, double sigma, double *OUT_d) {
  double p = 0.0, dp = 0.0, d0 = mala_torus_diff(y, mu);
  for (int k = -4; k <= 4; k++) {
    double d = d0 + k, e = exp(-0.5 * d * d / (sigma * sigma)) / (sigma * sqrt(2.0 * M_PI));
    p += e;
    dp += -d / (sigma * sigma) * e;
  }
  *OUT_d = dp;
  return p;
}

static const double sc_c[2][4] = {{0.3, 0.3, 0.5, 0.5}, {0.7, 0.7, 0.2, 0.8}};
static const double sc_s[2][4] = {{0.1, 0.004, 0.03, 0.2}, {0.005, 0.1, 0.2, 0.02}};
static const double sc_w[2] = {0.5, 0.5};

#define PL_A 0.3
#define PL_B 0.6
#define PL_S 0.03

/* Plateau factor h(t) = exp(-dist(t, [A, B])^2 / (2 S^2)) and h'. */
static double plateau_h(double t, double *OUT_d) {
  double e = t < PL_A ? t - PL_A : (t > PL_B ? t - PL_B : 0.0);
  double h = exp(-0.5 * e * e / (PL_S * PL_S));
  *OUT_d = -e / (PL_S * PL_S) * h;
  return h;
}

/* The density (unnormalised) and its gradient. */
static double toy_f(const toy *t, const double *u, double *OUT_g) {
  switch (t->kind) {
    case TOY_RIDGE: {
      const double w = 0.01, a = 0.2;
      double c = 0.5 + a * sin(2 * M_PI * u[0]);
      double dr = mala_torus_diff(u[1], c);
      double f = exp(-0.5 * dr * dr / (w * w));
      OUT_g[1] = -dr / (w * w) * f;
      OUT_g[0] = dr / (w * w) * f * a * 2 * M_PI * cos(2 * M_PI * u[0]);
      return f;
    }
    case TOY_SCALES: {
      double f = 0.0;
      for (int i = 0; i < 4; i++) OUT_g[i] = 0.0;
      for (int m = 0; m < 2; m++) {
        double p[4], dp[4], prod = sc_w[m];
        for (int i = 0; i < 4; i++) {
          p[i] = wn(u[i], sc_c[m][i], sc_s[m][i], &dp[i]);
          prod *= p[i];
        }
        f += prod;
        for (int i = 0; i < 4; i++) {
          double r = sc_w[m] * dp[i];
          for (int j = 0; j < 4; j++)
            if (j != i) r *= p[j];
          OUT_g[i] += r;
        }
      }
      return f;
    }
    case TOY_RIPPLE: {
      /* u0 < 1/2: log f0 = 2 sin(40 pi u0) (|d log f / du0| up to 250);
       * u0 >= 1/2: log f0 = 0.3 sin(4 pi u0) (up to 3.8); f1 = exp(0.5 cos(2 pi u1)). */
      double l0, d0;
      if (u[0] < 0.5)
        l0 = 2.0 * sin(40 * M_PI * u[0]), d0 = 80 * M_PI * cos(40 * M_PI * u[0]);
      else
        l0 = 0.3 * sin(4 * M_PI * u[0]), d0 = 1.2 * M_PI * cos(4 * M_PI * u[0]);
      double l1 = 0.5 * cos(2 * M_PI * u[1]), d1 = -M_PI * sin(2 * M_PI * u[1]);
      double f = exp(l0 + l1);
      OUT_g[0] = f * d0;
      OUT_g[1] = f * d1;
      return f;
    }
    case TOY_PLATEAU: {
      double h[MAXD], dh[MAXD], f = 1.0;
      for (int i = 0; i < t->dim; i++) f *= h[i] = plateau_h(u[i], &dh[i]);
      for (int i = 0; i < t->dim; i++) {
        double r = dh[i];
        for (int j = 0; j < t->dim; j++)
          if (j != i) r *= h[j];
        OUT_g[i] = r;
      }
      return f;
    }
  }
  return 0.0;
}

/* Evaluations with a gradient and without a Hessian, and with a Hessian
 * (check_h2mc: every state an H2MC proposal reaches needs its Hessian for
 * the reverse density, so the first must stay 0 there). */
static int64_t n_eval_grad, n_eval_hess;

static int toy_eval(const mc_target *tg, void *scratch, lmc_sampler *smp, mc_value *OUT_value,
                    double *OUT_grad, int *OUT_grad_ok) {
  (void)scratch;
  n_eval_grad += OUT_grad != NULL;
  const toy *t = tg->ctx;
  double u[MAXD] = {0}, g[MAXD] = {0};
  sampler_use_stream(smp, 0);
  for (int i = 0; i < t->dim; i++) u[i] = sampler_next(smp);
  double f = toy_f(t, u, g);
  OUT_value->f = f;
  OUT_value->value = (rgb){f, f, f};
  OUT_value->rx = u[0];
  OUT_value->ry = u[1];
  if (OUT_grad) {
    for (int i = 0; i < t->dim; i++) OUT_grad[i] = g[i];
    *OUT_grad_ok = f > 0.0;
  }
  return 0;
}

/* eval_hess for the toys: the analytic gradient and a Hessian by central
 * differences of it (h = 1e-6; the toys are periodic, so u +- h is
 * defined). H2MC's exactness does not depend on how good the Hessian is,
 * only on its being a function of the state, which this is. */
static int toy_eval_hess(const mc_target *tg, void *scratch, lmc_sampler *smp, int label,
                         mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok, int *OUT_hn,
                         int *OUT_hidx, double *OUT_hess, int *OUT_hess_ok) {
  (void)scratch;
  (void)label;
  n_eval_hess++;
  const toy *t = tg->ctx;
  int n = t->dim;
  double u[MAXD] = {0}, g[MAXD] = {0};
  sampler_use_stream(smp, 0);
  for (int i = 0; i < n; i++) u[i] = sampler_next(smp);
  double f = toy_f(t, u, g);
  OUT_value->f = f;
  OUT_value->value = (rgb){f, f, f};
  OUT_value->rx = u[0];
  OUT_value->ry = u[1];
  for (int i = 0; i < n; i++) OUT_grad[i] = g[i];
  *OUT_grad_ok = f > 0.0;
  const double h = 1e-6;
  double H[MAXD][MAXD];
  for (int j = 0; j < n; j++) {
    double up[MAXD], um[MAXD], gp[MAXD], gm[MAXD];
    memcpy(up, u, sizeof up);
    memcpy(um, u, sizeof um);
    up[j] += h;
    um[j] -= h;
    toy_f(t, up, gp);
    toy_f(t, um, gm);
    for (int i = 0; i < n; i++) H[i][j] = (gp[i] - gm[i]) / (2.0 * h);
  }
  *OUT_hn = n;
  int q = 0;
  for (int a = 0; a < n; a++) {
    OUT_hidx[a] = a;
    for (int b = a; b < n; b++) OUT_hess[q++] = 0.5 * (H[a][b] + H[b][a]);
  }
  *OUT_hess_ok = f > 0.0;
  return 0;
}

/* Expected probability of histogram cell (a, b) of the (u0, u1) marginal,
 * all NB x NB cells into OUT_p. */
static void toy_expected(const toy *t, double *OUT_p) {
  const int sub = 48;
  double total = 0.0;
  for (int a = 0; a < NB; a++)
    for (int b = 0; b < NB; b++) {
      double acc = 0.0;
      for (int i = 0; i < sub; i++)
        for (int j = 0; j < sub; j++) {
          double u0 = (a + (i + 0.5) / sub) / NB, u1 = (b + (j + 0.5) / sub) / NB, d;
          switch (t->kind) {
            case TOY_RIPPLE:
            case TOY_RIDGE: {
              double g[2], u[2] = {u0, u1};
              acc += toy_f(t, u, g);
              break;
            }
            case TOY_SCALES:
              /* The other axes integrate to one (normalised factors). */
              for (int m = 0; m < 2; m++)
                acc += sc_w[m] * wn(u0, sc_c[m][0], sc_s[m][0], &d) * wn(u1, sc_c[m][1], sc_s[m][1], &d);
              break;
            case TOY_PLATEAU:
              acc += plateau_h(u0, &d) * plateau_h(u1, &d);
              break;
          }
        }
      OUT_p[a * NB + b] = acc;
      total += acc;
    }
  for (int c = 0; c < NB * NB; c++) OUT_p[c] /= total;
}

/* ---- Running chains --------------------------------------------------------- */

typedef struct hist {
  double h[NB * NB];
  double quad; /* mass with u0 < 0.5 */
} hist;

static void hist_splat(void *ctx, const mc_value *v, double weight) {
  hist *h = ctx;
  double w = weight * v->f; /* the acceptance share of this state */
  int a = (int)(v->rx * NB), b = (int)(v->ry * NB);
  h->h[(a < NB ? a : NB - 1) * NB + (b < NB ? b : NB - 1)] += w;
  if (v->rx < 0.5) h->quad += w;
}

typedef struct run_result {
  double p[NB * NB];   /* mean frequency per cell */
  double var[NB * NB]; /* between-chain variance of a chain's frequency */
  double quad, quad_se;
  int64_t fallback, mala, hits, lookups, screened;
  int64_t n;           /* samples per chain in the histograms */
} run_result;

/* Kernel mixture: large step, Kelemen small step, LMC (and, for cache
 * stage 2, the independence kernel). */
static void make_chain(mc_chain **OUT_c, const mc_target *tg, lmc_mala *k, lmc_indep *ind,
                       double p_large, double p_small) {
  mc_kernel ks[4] = {mc_kernel_large(), mc_kernel_small(1.0 / 1024, 1.0 / 64), lmc_mala_kernel(k)};
  double pr[4] = {p_large, p_small, 1.0 - p_large - p_small, 0.0};
  int n = 3;
  if (ind) {
    ks[3] = lmc_indep_kernel(ind);
    pr[2] -= 0.05, pr[3] = 0.05;
    n = 4;
  }
  lmc_error err;
  assert_int_equal(mc_chain_create(OUT_c, tg, ks, pr, n, &err), LMC_OK);
}

/* R chains of `burn` + L steps each with mode `adapt`; for CACHE, stage 1
 * runs the same chains for `burn` + `stage1` steps first (the stage1 ones
 * counted in the histograms, as the renderer keeps them). */
static void run_mode(const toy *t, lmc_adapt adapt, int delayed, double step, double p_large,
                     double p_small, int64_t burn, int64_t L, int64_t stage1, uint64_t seed,
                     run_result *OUT) {
  mc_target tg;
  memset(&tg, 0, sizeof tg);
  tg.dim = t->dim;
  tg.stream_dim[0] = t->dim;
  tg.ctx = (void *)t;
  tg.eval = toy_eval;
  lmc_kernel_params p = lmc_kernel_params_default();
  p.adapt = adapt;
  p.step = step;
  p.record_stride = 4;
  p.delayed = delayed;
  lmc_error err;
  static lmc_mala km[R_CHAINS];
  static mc_chain *ch[R_CHAINS];
  static hist hs[R_CHAINS];
  memset(OUT, 0, sizeof *OUT);
  gcache *cache = NULL;
  if (adapt == LMC_ADAPT_CACHE) assert_int_equal(gcache_create(&cache, t->dim, 8000000, &err), LMC_OK);
  lmc_indep ind = {NULL, 0.02, 1.0 / 1024, 1.0 / 64};
  /* Stage 1 (CACHE only): M = I with online Adam recording into the cache. */
  int64_t kept = cache ? stage1 : 0;
  for (int r = 0; r < R_CHAINS; r++) {
    assert_int_equal(lmc_mala_init(&km[r], t->dim, &p, &err), LMC_OK);
    make_chain(&ch[r], &tg, &km[r], NULL, p_large, p_small);
    mc_chain_start(ch[r], seed, 1000 + r, 2000 + r);
    memset(&hs[r], 0, sizeof hs[r]);
    if (cache) {
      lmc_mala_set_record(&km[r], cache);
      for (int64_t i = 0; i < burn; i++) mc_chain_step(ch[r], NULL, NULL);
      for (int64_t i = 0; i < stage1; i++) mc_chain_step(ch[r], hist_splat, &hs[r]);
    }
  }
  if (cache) {
    assert_int_equal(gcache_freeze(cache, 256, 0, &err), LMC_OK);
    ind.cache = cache;
    /* Stage 2: the same states continue with a frozen kernel (a new chain
     * object, since the kernel list changes; it starts where stage 1 ended
     * through a burn-in from its own start). */
    for (int r = 0; r < R_CHAINS; r++) {
      mc_chain_destroy(ch[r]);
      lmc_mala_begin_stage2(&km[r], cache);
      make_chain(&ch[r], &tg, &km[r], &ind, p_large, p_small);
      mc_chain_start(ch[r], seed, 1000 + r, 3000 + r);
    }
  }
  for (int r = 0; r < R_CHAINS; r++) {
    for (int64_t i = 0; i < burn; i++) mc_chain_step(ch[r], NULL, NULL);
    for (int64_t i = 0; i < L; i++) mc_chain_step(ch[r], hist_splat, &hs[r]);
  }
  /* Per-cell mean and between-chain variance of the frequencies. */
  double qs = 0.0, qs2 = 0.0;
  for (int c = 0; c < NB * NB; c++) {
    double s = 0.0, s2 = 0.0;
    for (int r = 0; r < R_CHAINS; r++) {
      double f = hs[r].h[c] / (double)(L + kept);
      s += f, s2 += f * f;
    }
    OUT->p[c] = s / R_CHAINS;
    OUT->var[c] = (s2 - s * s / R_CHAINS) / (R_CHAINS - 1);
  }
  for (int r = 0; r < R_CHAINS; r++) {
    double f = hs[r].quad / (double)(L + kept);
    qs += f, qs2 += f * f;
    OUT->screened += ch[r]->screened;
    OUT->fallback += km[r].st.fallback;
    OUT->mala += km[r].st.mala;
    OUT->hits += km[r].st.lookup_hits;
    OUT->lookups += km[r].st.lookups;
    mc_chain_destroy(ch[r]);
    lmc_mala_free(&km[r]);
  }
  OUT->n = L + kept;
  OUT->quad = qs / R_CHAINS;
  OUT->quad_se = sqrt((qs2 - qs * qs / R_CHAINS) / (R_CHAINS - 1) / R_CHAINS);
  gcache_destroy(cache);
}

/* Chi-square of a run against the expected cell probabilities, counts
 * scaled to the effective sample size. Returns the p-value. */
static double chi2_ess(const run_result *rr, const double *pe, int64_t L, double *OUT_tau) {
  double tw = 0.0, tsum = 0.0;
  for (int c = 0; c < NB * NB; c++) {
    if (pe[c] < 1e-3) continue;
    double tau_c = (double)L * rr->var[c] / (pe[c] * (1.0 - pe[c]));
    tsum += pe[c] * tau_c;
    tw += pe[c];
  }
  double tau = tsum / tw;
  if (tau < 1.0) tau = 1.0;
  double neff = (double)L * R_CHAINS / tau;
  static double obs[NB * NB], ex[NB * NB];
  for (int c = 0; c < NB * NB; c++) obs[c] = rr->p[c] * neff, ex[c] = pe[c] * neff;
  int dof;
  double stat, pv = chi2_pvalue(obs, ex, NB * NB, 5.0, &dof, &stat);
  *OUT_tau = tau;
  return pv;
}

static const char *mode_name[] = {"none", "adam", "diminish", "cache"};

static int check_target(toy_kind kind, int dim, double step, int64_t L, uint64_t seed) {
  toy t = {kind, dim};
  static double pe[NB * NB];
  toy_expected(&t, pe);
  double alpha = chi2_sidak(1e-3, CHI2_TESTS);
  /* none, diminish, cache, and cache with delayed acceptance (whose screen
   * ignores that M differs between x and y: the second test corrects it). */
  const lmc_adapt modes[4] = {LMC_ADAPT_NONE, LMC_ADAPT_DIMINISH, LMC_ADAPT_CACHE, LMC_ADAPT_CACHE};
  int checked = 0;
  for (int m = 0; m < 4; m++) {
    static run_result rr;
    int delayed = m == 3;
    run_mode(&t, modes[m], delayed, step, 0.02, 0.1, 2000, L, L / 2, seed, &rr);
    double tau, pv = chi2_ess(&rr, pe, rr.n, &tau);
    printf("  target %d (%d-D) %-8s%s: p = %.3g, tau = %.1f, mala %lld, fallback %lld, lookups %lld (hits %lld), first tests %lld\n",
           (int)kind, dim, mode_name[modes[m]], delayed ? " delayed" : "", pv, tau, (long long)rr.mala,
           (long long)rr.fallback, (long long)rr.lookups, (long long)rr.hits, (long long)rr.screened);
    if (pv < alpha) print_error("%s: p = %g below %g\n", mode_name[modes[m]], pv, alpha);
    assert_true(pv >= alpha);
    assert_true(rr.mala > 0);
    assert_true(delayed ? rr.screened > 0 : rr.screened == 0);
    if (kind == TOY_PLATEAU) assert_true(rr.fallback > 0);
    if (modes[m] == LMC_ADAPT_CACHE) assert_true(rr.hits > 0);
    checked++;
  }
  return checked;
}

static void test_ridge(void **state) {
  (void)state;
  assert_int_equal(check_target(TOY_RIDGE, 2, 1e-4, 20000, 21), 4);
}

static void test_scales(void **state) {
  (void)state;
  assert_int_equal(check_target(TOY_SCALES, 4, 1e-4, 20000, 22), 4);
}

static void test_plateau(void **state) {
  (void)state;
  assert_int_equal(check_target(TOY_PLATEAU, 6, 1e-4, 20000, 23), 4);
}

/* H2MC (h2mc.h) in the same mixture (large step 0.02, Kelemen 0.1, H2MC
 * the rest) on the three chi-square targets: R chains of burn + L steps,
 * the histogram against the density as above. Also asserts that the
 * Hessian's model made the proposals where the target is curved enough
 * and that proposals leaving the cube were rejected unevaluated (h2mc
 * does not wrap). */
static int check_h2mc(toy_kind kind, int dim, int64_t L, uint64_t seed, int curved) {
  toy t = {kind, dim};
  static double pe[NB * NB];
  toy_expected(&t, pe);
  mc_target tg;
  memset(&tg, 0, sizeof tg);
  tg.dim = dim;
  tg.stream_dim[0] = dim;
  tg.ctx = &t;
  tg.eval = toy_eval;
  tg.eval_hess = toy_eval_hess;
  h2mc_params hp = h2mc_params_default();
  static h2mc_kernel kh[R_CHAINS];
  static mc_chain *ch[R_CHAINS];
  static hist hs[R_CHAINS];
  lmc_error err;
  int64_t model = 0, proposed = 0, outside = 0;
  n_eval_grad = n_eval_hess = 0;
  for (int r = 0; r < R_CHAINS; r++) {
    assert_int_equal(h2mc_kernel_init(&kh[r], &tg, &hp, &err), LMC_OK);
    mc_kernel ks[3] = {mc_kernel_large(), mc_kernel_small(1.0 / 1024, 1.0 / 64),
                       h2mc_kernel_make(&kh[r])};
    double pr[3] = {0.02, 0.1, 0.88};
    assert_int_equal(mc_chain_create(&ch[r], &tg, ks, pr, 3, &err), LMC_OK);
    mc_chain_start(ch[r], seed, 1000 + r, 2000 + r);
    memset(&hs[r], 0, sizeof hs[r]);
    for (int64_t i = 0; i < 2000; i++) mc_chain_step(ch[r], NULL, NULL);
    for (int64_t i = 0; i < L; i++) mc_chain_step(ch[r], hist_splat, &hs[r]);
  }
  static run_result rr;
  memset(&rr, 0, sizeof rr);
  for (int c = 0; c < NB * NB; c++) {
    double sm = 0.0, s2 = 0.0;
    for (int r = 0; r < R_CHAINS; r++) {
      double f = hs[r].h[c] / (double)L;
      sm += f, s2 += f * f;
    }
    rr.p[c] = sm / R_CHAINS;
    rr.var[c] = (s2 - sm * sm / R_CHAINS) / (R_CHAINS - 1);
  }
  for (int r = 0; r < R_CHAINS; r++) {
    model += kh[r].st.model;
    proposed += kh[r].st.proposed;
    outside += kh[r].st.outside;
    mc_chain_destroy(ch[r]);
    h2mc_kernel_free(&kh[r]);
  }
  double tau, pv = chi2_ess(&rr, pe, L, &tau);
  double alpha = chi2_sidak(1e-3, CHI2_TESTS);
  printf("  target %d (%d-D) h2mc: p = %.3g, tau = %.1f, proposed %lld, from the model %lld, "
         "outside %lld\n",
         (int)kind, dim, pv, tau, (long long)proposed, (long long)model, (long long)outside);
  assert_true(pv >= alpha);
  /* The plateau's curvature (1 / 0.03^2) is below the prior's 0.5 / 0.01^2:
   * it runs on the prior alone; the others on the model. */
  if (curved)
    assert_true(model > proposed / 2);
  else
    assert_true(model == 0);
  assert_true(outside > 0);
  /* Every proposal evaluated (those inside the cube) came with its
   * Hessian, none with a gradient alone. */
  printf("  evaluations with a Hessian %lld, with a gradient alone %lld\n", (long long)n_eval_hess,
         (long long)n_eval_grad);
  assert_int_equal(n_eval_grad, 0);
  assert_true(n_eval_hess >= proposed - outside);
  return 1;
}

static void test_h2mc(void **state) {
  (void)state;
  int checked = check_h2mc(TOY_RIDGE, 2, 20000, 41, 1) + check_h2mc(TOY_SCALES, 4, 20000, 42, 1) +
                check_h2mc(TOY_PLATEAU, 6, 20000, 43, 0);
  assert_int_equal(checked, 3);
}

/* Adam's bias against the unbiased modes on `ripple`. */
static void test_adam_bias(void **state) {
  (void)state;
  toy t = {TOY_RIPPLE, 2};
  static double pe[NB * NB];
  toy_expected(&t, pe);
  double q = 0.0;
  for (int a = 0; a < NB / 2; a++)
    for (int b = 0; b < NB; b++) q += pe[a * NB + b];
  const lmc_adapt modes[4] = {LMC_ADAPT_ADAM, LMC_ADAPT_NONE, LMC_ADAPT_DIMINISH, LMC_ADAPT_CACHE};
  double bias[4], se[4];
  for (int m = 0; m < 4; m++) {
    static run_result rr;
    run_mode(&t, modes[m], 0, BIAS_STEP, 0.0, 0.0, 2000, BIAS_L, BIAS_L / 2, 31, &rr);
    bias[m] = rr.quad - q;
    se[m] = rr.quad_se;
    printf("  mass of u0 < 1/2 %-8s: %.4f (exact %.4f), bias %+.4f +- %.4f\n", mode_name[modes[m]],
           rr.quad, q, bias[m], se[m]);
  }
  assert_true(fabs(bias[0]) > Z999 * se[0]);
  for (int m = 1; m < 4; m++) {
    assert_le(fabs(bias[m]), Z999 * se[m]);
    assert_le(fabs(bias[m]) + Z999 * sqrt(se[0] * se[0] + se[m] * se[m]), fabs(bias[0]));
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_ridge),
      cmocka_unit_test(test_scales),
      cmocka_unit_test(test_plateau),
      cmocka_unit_test(test_adam_bias),
      cmocka_unit_test(test_h2mc),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
