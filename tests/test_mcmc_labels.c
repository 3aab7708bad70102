/*
 * test_mcmc_labels.c: chains on labelled targets (target.h, chain.h): a
 * state is (u, l), the large step proposes a fresh u with l drawn in
 * proportion to f(u, l), and its ratio F(u') / F(u) needs F of the current
 * state, computed by a Russian roulette after other kernels moved it.
 *
 * The toy: u in [0,1)^2, three labels,
 *   f(u, 0) = bimodal(u0)                       (reads u0)
 *   f(u, 1) = 0.1 (1 + 4 u1) (0.5 + u0)         (reads u0 and u1)
 *   f(u, 2) = 0.2 + u0^2                        (reads u0)
 * so u1 is a coordinate only label 1 reads (the lazy vector's replay and
 * the roulette's materialisation of it are exercised), and the labels'
 * masses are 0.25, 0.3 and 0.53. A state's raster position is
 * ((u0 + l) / 3, u1 for label 1 else 0): the histograms bin labels apart,
 * 20 bins of u0 for labels 0 and 2 and 5 x 5 of (u0, u1) for label 1.
 *
 * Chain histograms (as test_mcmc_toy.c): N chains started from exact
 * draws of the joint target (rejection on F, then the chain's own label
 * choice), run B steps, final states counted; chi-square at a Sidak level
 * for an overall false-alarm rate of 1e-3. Expected-value splatting: 32
 * groups, each bin's mean within 5 standard errors of its probability.
 * The roulette must both evaluate and skip, and the proposal's splats
 * must cover every label (counted).
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
#include "lmc/kernels/gcache.h"
#include "lmc/kernels/lmc_kernel.h"
#include "lmc/kernels/mala.h"
#include "test_util.h"

#define N_CHI2_TESTS 8
#define NBIN 65 /* 20 + 25 + 20 */
static int g_chi2_tests;

static double lab_f(int l, double u0, double u1) {
  if (l == 0) {
    double a = (u0 - 0.3) / 0.05, b = (u0 - 0.75) / 0.1;
    return exp(-0.5 * a * a) + 0.5 * exp(-0.5 * b * b);
  }
  if (l == 1) return 0.1 * (1.0 + 4.0 * u1) * (0.5 + u0);
  return 0.2 + u0 * u0;
}

static void lab_value(mc_value *v, int l, double u0, double u1) {
  v->f = lab_f(l, u0, u1);
  v->value = rgb_gray(v->f);
  v->rx = (u0 + l) / 3.0;
  v->ry = l == 1 ? u1 : 0.0;
}

static int lab_eval_label(const mc_target *t, void *scratch, lmc_sampler *smp, int label,
                          mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok) {
  (void)t, (void)scratch, (void)OUT_grad;
  if (OUT_grad_ok) *OUT_grad_ok = 0;
  sampler_use_stream(smp, 0);
  double u0 = sampler_next(smp), u1 = label == 1 ? sampler_next(smp) : 0.0;
  lab_value(OUT_value, label, u0, u1);
  return 0;
}

static int lab_eval_all(const mc_target *t, void *scratch, lmc_sampler *smp, int from_label,
                        mc_contrib *OUT) {
  (void)t, (void)scratch, (void)from_label;
  sampler_use_stream(smp, 0);
  double u0 = sampler_next(smp), u1 = sampler_next(smp);
  for (int l = 0; l < 3; l++) {
    OUT[l].label = l;
    lab_value(&OUT[l].v, l, u0, u1);
  }
  return 3;
}

/* The same target with label 1 in its own coordinates (target.h,
 * relabel): its second number is v1 = sqrt(u1), so f(v, 1) = f(u, 1)
 * |du1/dv1| = f(u, 1) 2 v1. relabel reads u1 from the scratch of the
 * last eval_all (as the scene target reads its subpaths), so a chain
 * that evaluated another state in between would rewrite the wrong number. */
typedef struct lab_scratch {
  double u1;
} lab_scratch;

static void *lab_scratch_create(const mc_target *t) {
  (void)t;
  return calloc(1, sizeof(lab_scratch));
}
static void lab_scratch_destroy(void *s) { free(s); }

static int lab_eval_label_r(const mc_target *t, void *scratch, lmc_sampler *smp, int label,
                            mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok) {
  (void)t, (void)scratch, (void)OUT_grad;
  if (OUT_grad_ok) *OUT_grad_ok = 0;
  sampler_use_stream(smp, 0);
  double u0 = sampler_next(smp), v1 = label == 1 ? sampler_next(smp) : 0.0;
  lab_value(OUT_value, label, u0, v1 * v1);
  OUT_value->f_large = OUT_value->f;
  if (label == 1) {
    OUT_value->f *= 2.0 * v1;
    OUT_value->value = rgb_scale(OUT_value->value, 2.0 * v1);
  }
  return 0;
}

static int lab_eval_all_r(const mc_target *t, void *scratch, lmc_sampler *smp, int from_label,
                          mc_contrib *OUT) {
  (void)t;
  sampler_use_stream(smp, 0);
  double u0 = sampler_next(smp), x = sampler_next(smp);
  double u1 = from_label == 1 ? x * x : x;
  ((lab_scratch *)scratch)->u1 = u1;
  for (int l = 0; l < 3; l++) {
    OUT[l].label = l;
    lab_value(&OUT[l].v, l, u0, u1);
  }
  return 3;
}

static double lab_relabel(const mc_target *t, void *scratch, int label, double *u, rng *r) {
  (void)t, (void)r;
  if (label != 1) return 1.0;
  double v1 = sqrt(((lab_scratch *)scratch)->u1);
  u[1] = v1;
  return 2.0 * v1;
}

static mc_target lab_target_relabel(void) {
  mc_target t;
  memset(&t, 0, sizeof t);
  t.dim = 2;
  t.stream_dim[0] = 2;
  t.n_labels = 3;
  t.eval_label = lab_eval_label_r;
  t.eval_all = lab_eval_all_r;
  t.relabel = lab_relabel;
  t.scratch_create = lab_scratch_create;
  t.scratch_destroy = lab_scratch_destroy;
  return t;
}

static mc_target lab_target(void) {
  mc_target t;
  memset(&t, 0, sizeof t);
  t.dim = 2;
  t.stream_dim[0] = 2;
  t.n_labels = 3;
  t.eval_label = lab_eval_label;
  t.eval_all = lab_eval_all;
  return t;
}

/* The bin of a state (or splat) with raster position (rx, ry). */
static int lab_bin(double rx, double ry) {
  int l = (int)(rx * 3.0);
  if (l > 2) l = 2;
  double u0 = rx * 3.0 - l;
  if (l == 1) {
    int bx = (int)(u0 * 5), by = (int)(ry * 5);
    if (bx > 4) bx = 4;
    if (by > 4) by = 4;
    return 20 + by * 5 + bx;
  }
  int b = (int)(u0 * 20);
  if (b > 19) b = 19;
  return l == 0 ? b : 45 + b;
}

/* Exact bin probabilities by the midpoint rule. */
static void lab_exact(double *OUT_p) {
  const int sub = 200;
  double total = 0.0;
  memset(OUT_p, 0, NBIN * sizeof(double));
  for (int l = 0; l < 3; l++)
    for (int j = 0; j < sub; j++)
      for (int i = 0; i < sub; i++) {
        double u0 = (i + 0.5) / sub, u1 = (j + 0.5) / sub;
        double f = lab_f(l, u0, u1);
        OUT_p[lab_bin((u0 + l) / 3.0, l == 1 ? u1 : 0.0)] += f;
        total += f;
      }
  for (int b = 0; b < NBIN; b++) OUT_p[b] /= total;
}

/* A full kernel: a drifted wrapped Gaussian walk on u0, u1 unchanged
 * (asymmetric, so a wrong reverse density would show). */
#define DRIFT_MU 0.04
#define DRIFT_SIGMA 0.07

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
  double u1 = 1.0 - rng_uniform(r), u2 = rng_uniform(r);
  double y = x->u[0] + DRIFT_MU + DRIFT_SIGMA * sqrt(-2.0 * log(u1)) * cos(2.0 * M_PI * u2);
  y -= floor(y);
  if (y >= 1.0) y = 0.0;
  OUT_y[0] = y;
  OUT_y[1] = x->u[1];
  return drift_log_q(x->u[0], y);
}

static double drift_log_density(void *self, const mc_state *from, const double *to_u) {
  (void)self;
  if (to_u[1] != from->u[1]) return -INFINITY;
  return drift_log_q(from->u[0], to_u[0]);
}

static mc_kernel drift_kernel(void) {
  mc_kernel k = {0};
  k.name = "drift";
  k.kind = MC_KERNEL_FULL;
  k.propose = drift_propose;
  k.log_density = drift_log_density;
  return k;
}

/* The kernel sets: large alone; large + Kelemen; large + the full walk;
 * all three. */
static int kernel_set(int s, mc_kernel *k, double *p) {
  switch (s) {
  case 0:
    k[0] = mc_kernel_large(), p[0] = 1.0;
    return 1;
  case 1:
    k[0] = mc_kernel_large(), p[0] = 0.3;
    k[1] = mc_kernel_small(1.0 / 1024.0, 1.0 / 16.0), p[1] = 0.7;
    return 2;
  case 2:
    k[0] = mc_kernel_large(), p[0] = 0.3;
    k[1] = drift_kernel(), p[1] = 0.7;
    return 2;
  default:
    k[0] = mc_kernel_large(), p[0] = 0.2;
    k[1] = mc_kernel_small(1.0 / 1024.0, 1.0 / 16.0), p[1] = 0.4;
    k[2] = drift_kernel(), p[2] = 0.4;
    return 3;
  }
}

/* Starts ch from an exact draw of the joint target: u by rejection on
 * F(u) <= 3, then the chain's own label choice in proportion to f. */
static void lab_start(mc_chain *ch, uint64_t seed, uint64_t seq, uint64_t chain_seq) {
  rng acc;
  rng_seed(&acc, seed + 1, seq);
  for (;;) {
    mc_chain_start(ch, seed, seq, chain_seq);
    if (rng_uniform(&acc) * 3.0 < ch->sum_x) break;
    seq++;
  }
}

static void test_label_histograms(void **state) {
  (void)state;
  enum { N = 20000, BURN = 60 };
  double prob[NBIN], hist[NBIN], expct[NBIN];
  lab_exact(prob);
  const char *names[6] = {"large", "large + small", "large + full", "large + small + full",
                          "relabel: large + small", "relabel: large + small + full"};
  int64_t evals = 0, large = 0;
  for (int s = 0; s < 6; s++) {
    mc_target t = s < 4 ? lab_target() : lab_target_relabel();
    mc_kernel k[3];
    double p[3];
    int nk = kernel_set(s < 4 ? s : s == 4 ? 1 : 3, k, p);
    lmc_error err;
    mc_chain *ch = NULL;
    assert_int_equal(mc_chain_create(&ch, &t, k, p, nk, &err), LMC_OK);
    memset(hist, 0, sizeof hist);
    for (int i = 0; i < N; i++) {
      lab_start(ch, 11, (uint64_t)i * 100000u, 0x5eed0000u + (uint64_t)i);
      for (int q = 0; q < BURN; q++) mc_chain_step(ch, NULL, NULL);
      hist[lab_bin(ch->x.v.rx, ch->x.v.ry)] += 1.0;
      /* The state's label agrees with its value. */
      assert_int_equal((int)(ch->x.v.rx * 3.0) < 3 ? (int)(ch->x.v.rx * 3.0) : 2, ch->x.label);
    }
    if (s > 0) evals += ch->sum_evals;
    large += ch->stats[0].proposed;
    mc_chain_destroy(ch);
    for (int b = 0; b < NBIN; b++) expct[b] = prob[b] * N;
    int dof;
    double stat;
    double pv = chi2_pvalue(hist, expct, NBIN, 5.0, &dof, &stat);
    double alpha = chi2_sidak(1e-3, N_CHI2_TESTS);
    if (!(pv > alpha))
      print_error("%s: chi2 %.1f, dof %d, p %.3g < %.3g\n", names[s], stat, dof, pv, alpha);
    assert_true(pv > alpha);
    assert_true(dof >= 40);
    g_chi2_tests++;
  }
  /* The roulette evaluated F at moved states, but not at every large step. */
  printf("  large steps %lld, current states evaluated for F %lld\n", (long long)large,
         (long long)evals);
  assert_true(evals > 1000);
  assert_true(evals < large / 2);
}

/* Expected-value splatting over all labels of the proposal. */
typedef struct lab_splats {
  double h[NBIN];
  int64_t per_label[3];
} lab_splats;

static void lab_splat(void *ctx, const mc_value *v, double w) {
  lab_splats *s = ctx;
  s->h[lab_bin(v->rx, v->ry)] += w * v->f; /* value / f * weight, value = f */
  int l = (int)(v->rx * 3.0);
  s->per_label[l > 2 ? 2 : l]++;
}

static void test_label_splatting(void **state) {
  (void)state;
  mc_target t = lab_target();
  enum { G = 32, CH = 16, STEPS = 3000 };
  double prob[NBIN];
  lab_exact(prob);
  int checked = 0;
  for (int s = 1; s < 4; s++) {
    mc_kernel k[3];
    double p[3];
    int nk = kernel_set(s, k, p);
    double sum[NBIN] = {0}, sum2[NBIN] = {0};
    int64_t per_label[3] = {0};
    for (int g = 0; g < G; g++) {
      lab_splats acc;
      memset(&acc, 0, sizeof acc);
      lmc_error err;
      mc_chain *ch = NULL;
      assert_int_equal(mc_chain_create(&ch, &t, k, p, nk, &err), LMC_OK);
      for (int i = 0; i < CH; i++) {
        lab_start(ch, 5, 7000000u + (uint64_t)(g * CH + i) * 997u, 0xabc000u + (uint64_t)(g * CH + i));
        for (int q = 0; q < STEPS; q++) mc_chain_step(ch, lab_splat, &acc);
      }
      mc_chain_destroy(ch);
      for (int b = 0; b < NBIN; b++) {
        double v = acc.h[b] / ((double)CH * STEPS);
        sum[b] += v;
        sum2[b] += v * v;
      }
      for (int l = 0; l < 3; l++) per_label[l] += acc.per_label[l];
    }
    for (int b = 0; b < NBIN; b++) {
      double mean = sum[b] / G, var = (sum2[b] - G * mean * mean) / (G - 1);
      double se = sqrt(fmax(var, 0.0) / G);
      if (!(fabs(mean - prob[b]) <= 5.0 * se + 1e-4))
        print_error("set %d bin %d: %.5f against %.5f (se %.2g)\n", s, b, mean, prob[b], se);
      assert_true(fabs(mean - prob[b]) <= 5.0 * se + 1e-4);
      checked++;
    }
    for (int l = 0; l < 3; l++) assert_true(per_label[l] > 1000);
  }
  assert_int_equal(checked, 3 * NBIN);
}

static void test_label_errors(void **state) {
  (void)state;
  mc_target t = lab_target();
  mc_kernel k[2] = {mc_kernel_large(), mc_kernel_technique(0)};
  double p[2] = {0.5, 0.5};
  lmc_error err;
  mc_chain *ch = NULL;
  assert_int_not_equal(mc_chain_create(&ch, &t, k, p, 2, &err), LMC_OK);
  assert_null(ch);
  t.eval_all = NULL;
  assert_int_not_equal(mc_chain_create(&ch, &t, k, p, 1, &err), LMC_OK);
  assert_null(ch);
}

/* ---- The cached walk (lmc_kernel.h) on the toy -------------------------
 * Label 0 and 2 move u0, label 1 (u0, u1). A keyed cache holds synthetic
 * moments on a grid of states, so that the Gaussian's mean and width
 * change from state to state (and states far from the grid get the
 * prior's); with large steps mixed in, the chain must still sample the
 * joint target exactly (a wrong reverse density would bias it). */
static int lab_coords(const mc_target *t, int label, int *OUT_idx) {
  (void)t;
  OUT_idx[0] = 0;
  if (label == 1) OUT_idx[1] = 1;
  return label == 1 ? 2 : 1;
}

static gcache *lab_cache(void) {
  int len[3] = {1, 2, 1};
  gcache *c = NULL;
  lmc_error err;
  assert_int_equal(gcache_create_keyed(&c, 3, len, 1 << 16, &err), LMC_OK);
  int added = 0;
  for (int l = 0; l < 3; l++)
    for (int i = 0; i < 12; i++)
      for (int j = 0; j < (l == 1 ? 12 : 1); j++) {
        /* Entries on the left half only: the right half has no neighbour. */
        double u[2] = {0.02 + 0.04 * i, 0.04 + 0.08 * j};
        double m1[2] = {400.0 * sin(7.0 * u[0]), -300.0 * cos(5.0 * u[1])};
        double m2[2] = {0.01 + 3.0 * u[0] * u[0], 0.5 + u[1]};
        added += gcache_add(c, l + 1, u, m1, m2, 1.0);
      }
  assert_int_equal(added, 12 + 144 + 12);
  assert_int_equal(gcache_freeze(c, 0, 0, &err), LMC_OK);
  return c;
}

static void test_cached_walk(void **state) {
  (void)state;
  mc_target t = lab_target();
  t.label_coords = lab_coords;
  gcache *cache = lab_cache();
  lmc_cwalk_params cp = lmc_cwalk_params_default();
  cp.step = 0.05, cp.prior = 0.08, cp.radius = 0.06, cp.k = 3, cp.drift_max = 50.0;
  lmc_cwalk cw;
  lmc_error err;
  assert_int_equal(lmc_cwalk_init(&cw, &t, cache, &cp, &err), LMC_OK);
  mc_kernel k[3] = {mc_kernel_large(), lmc_cwalk_kernel(&cw), mc_kernel_small(1.0 / 1024.0, 1.0 / 16.0)};
  double p[3] = {0.2, 0.6, 0.2};
  enum { N = 20000, BURN = 60 };
  double prob[NBIN], hist[NBIN], expct[NBIN];
  lab_exact(prob);
  mc_chain *ch = NULL;
  assert_int_equal(mc_chain_create(&ch, &t, k, p, 3, &err), LMC_OK);
  memset(hist, 0, sizeof hist);
  for (int i = 0; i < N; i++) {
    lab_start(ch, 31, (uint64_t)i * 100000u, 0x5eed1000u + (uint64_t)i);
    for (int q = 0; q < BURN; q++) mc_chain_step(ch, NULL, NULL);
    hist[lab_bin(ch->x.v.rx, ch->x.v.ry)] += 1.0;
  }
  for (int b = 0; b < NBIN; b++) expct[b] = prob[b] * N;
  int dof;
  double stat;
  double pv = chi2_pvalue(hist, expct, NBIN, 5.0, &dof, &stat);
  double alpha = chi2_sidak(1e-3, N_CHI2_TESTS);
  print_message("  cached walk: %lld proposed, %lld accepted, %lld lookups, %lld with "
                "neighbours; chi2 %.1f, dof %d\n",
                (long long)cw.st.proposed, (long long)cw.st.accepted, (long long)cw.st.lookups,
                (long long)cw.st.hits, stat, dof);
  assert_true(pv > alpha);
  assert_true(dof >= 40);
  g_chi2_tests++;
  /* Both kinds of Gaussian were used, and moves were accepted. */
  assert_true(cw.st.hits > cw.st.lookups / 10 && cw.st.hits < cw.st.lookups * 9 / 10);
  assert_true(cw.st.accepted > cw.st.proposed / 10);
  mc_chain_destroy(ch);
  lmc_cwalk_free(&cw);
  gcache_destroy(cache);
}

/* q(y | x) of the cached walk integrates to one and its samples follow it
 * (at a state with neighbours, so the mean is shifted and the widths
 * differ): a histogram of 200000 proposals of u0 against the density. */
static void test_cached_walk_density(void **state) {
  (void)state;
  mc_target t = lab_target();
  t.label_coords = lab_coords;
  gcache *cache = lab_cache();
  lmc_cwalk_params cp = lmc_cwalk_params_default();
  cp.step = 0.05, cp.prior = 0.08, cp.radius = 0.06, cp.k = 3, cp.drift_max = 50.0;
  lmc_cwalk cw;
  lmc_error err;
  assert_int_equal(lmc_cwalk_init(&cw, &t, cache, &cp, &err), LMC_OK);
  mc_kernel kn = lmc_cwalk_kernel(&cw);
  double xu[2] = {0.21, 0.37}, yu[2], grad[2] = {0.0, 0.0};
  mc_state x = {2, xu, {1.0, {1.0, 1.0, 1.0}, 0.0, 0.0, 1.0}, grad, 0, 0, 1, 0, 0, 0, NULL, NULL};
  enum { NB = 40, N = 200000 };
  double hist[NB] = {0}, dens[NB] = {0};
  rng r;
  rng_seed(&r, 41, 1);
  for (int i = 0; i < N; i++) {
    kn.propose(kn.self, &r, &x, yu);
    int b = (int)(yu[0] * NB);
    hist[b < NB ? b : NB - 1] += 1.0;
  }
  assert_true(cw.st.hits > 0);
  /* The density of u0 alone: integrate q over u1 on a grid. */
  double total = 0.0;
  const int sub = 50;
  for (int b = 0; b < NB; b++)
    for (int i = 0; i < sub; i++)
      for (int j = 0; j < 200; j++) {
        double to[2] = {(b + (i + 0.5) / sub) / NB, (j + 0.5) / 200.0};
        double q = exp(kn.log_density(kn.self, &x, to)) / (sub * NB * 200.0);
        dens[b] += q;
        total += q;
      }
  /* log q term by term: the walk's sum (nearest images summed apart) is
   * the sum of mala_log_wrapped_normal over the coordinates it moves. */
  int n_cmp = 0, n_far = 0;
  for (int i = 0; i < 2000; i++) {
    double to[2] = {rng_uniform(&r), rng_uniform(&r)};
    double lq = kn.log_density(kn.self, &x, to), ref = 0.0;
    for (int c = 0; c < 2; c++) {
      double mu = cw.v[c] + cw.mean[c];
      ref += mala_log_wrapped_normal(to[cw.idx[c]], mu, cw.sd[c]);
      if (fabs(mala_torus_diff(to[cw.idx[c]], mu)) > 0.4) n_far++;
    }
    assert_true(fabs(lq - ref) <= 1e-12 * fmax(1.0, fabs(ref)));
    n_cmp++;
  }
  assert_int_equal(n_cmp, 2000);
  assert_true(n_far > 100); /* the far images' branch was compared too */
  print_message("  cached walk density integrates to %.6f\n", total);
  assert_near(total, 1.0, 1e-3);
  double expct[NB];
  for (int b = 0; b < NB; b++) expct[b] = dens[b] * N;
  int dof;
  double stat;
  double pv = chi2_pvalue(hist, expct, NB, 5.0, &dof, &stat);
  assert_true(pv > chi2_sidak(1e-3, N_CHI2_TESTS));
  assert_true(dof >= 10);
  g_chi2_tests++;
  lmc_cwalk_free(&cw);
  gcache_destroy(cache);
}

static void test_count(void **state) {
  (void)state;
  assert_int_equal(g_chi2_tests, N_CHI2_TESTS);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_label_histograms),
      cmocka_unit_test(test_label_splatting),
      cmocka_unit_test(test_label_errors),
      cmocka_unit_test(test_cached_walk),
      cmocka_unit_test(test_cached_walk_density),
      cmocka_unit_test(test_count),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
