/*
 * test_sampler.c: the Sobol sampler (render/sampler.h).
 *
 *  - the nested scramble is nested: inputs that agree in their first k
 *    bits give outputs that agree in their first k bits, and it is a
 *    bijection on the values it is shown;
 *  - the 2D Sobol points 0 .. 2^m - 1 form a (0,m,2)-net (checked
 *    directly: one point in every elementary interval);
 *  - through the sampler, a pixel's first 2^m samples keep that property
 *    in every pair group and are stratified in every lone dimension, for
 *    both layouts, all three streams and groups deep into the cycles;
 *  - every number is uniform (chi-square over pixels, one sample each, so
 *    the draws are independent), and numbers of different groups of the
 *    same sample are independent (chi-square of their joint histogram).
 * The 12 chi-square tests share alpha = 1e-4 (Sidak over all of them), with
 * fixed seeds.
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
#include "render/sampler.h"

#define N_CHI2 12 /* chi-square tests in this file */

/* Is the set of n = 2^m points (x, y in 32-bit fractions) a (0,m,2)-net:
 * exactly one point in each 2^a x 2^(m-a) elementary box, for every a? */
static int is_net(const uint32_t *x, const uint32_t *y, int m) {
  int n = 1 << m;
  static unsigned char seen[1 << 12];
  for (int a = 0; a <= m; a++) {
    memset(seen, 0, (size_t)n);
    for (int i = 0; i < n; i++) {
      uint32_t bx = a ? x[i] >> (32 - a) : 0;
      uint32_t by = (m - a) ? y[i] >> (32 - (m - a)) : 0;
      uint32_t cell = (bx << (m - a)) | by;
      if (seen[cell]++) return 0;
    }
  }
  return 1;
}

/* Are the n = 2^m values stratified: one in each interval of width 2^-m? */
static int is_stratified(const uint32_t *x, int m) {
  static unsigned char seen[1 << 12];
  memset(seen, 0, (size_t)1 << m);
  for (int i = 0; i < (1 << m); i++)
    if (seen[m ? x[i] >> (32 - m) : 0]++) return 0;
  return 1;
}

static void test_scramble_nested(void **state) {
  (void)state;
  rng r;
  rng_seed(&r, 11, 3);
  int checks = 0;
  for (int trial = 0; trial < 20000; trial++) {
    uint32_t key = rng_next_u32(&r), a = rng_next_u32(&r);
    int k = (int)rng_uniform_u32(&r, 32) + 1; /* bits kept in common: 1..32 */
    uint32_t keep = k == 32 ? 0xffffffffu : ~(0xffffffffu >> k);
    uint32_t b = (a & keep) | (rng_next_u32(&r) & ~keep);
    uint32_t sa = sampler_owen_scramble(a, key), sb = sampler_owen_scramble(b, key);
    assert_int_equal(sa & keep, sb & keep);
    if (a != b) assert_int_not_equal(sa, sb); /* a bijection */
    checks++;
  }
  assert_int_equal(checks, 20000);
}

static void test_sobol_net(void **state) {
  (void)state;
  static uint32_t x[1 << 12], y[1 << 12];
  int checks = 0;
  for (int m = 0; m <= 12; m++) {
    /* Every aligned block of 2^m points, not only the first. */
    for (uint32_t block = 0; block < 4; block++) {
      uint32_t base = block * 0x9e3779b9u & ~((1u << m) - 1u);
      for (int i = 0; i < (1 << m); i++) sampler_sobol_2d(base + (uint32_t)i, &x[i], &y[i]);
      assert_true(is_net(x, y, m));
      checks++;
    }
  }
  assert_int_equal(checks, 13 * 4);
}

/* Draws the first `n_groups` groups of `stream` for sample `index` of
 * `pixel`: OUT[g][0..1] as 32-bit fractions (the top bits of the double). */
static void draw_groups(uint64_t seed, uint64_t pixel, uint32_t index, const sampler_layout *l,
                        int stream, int n_groups, int *sizes, uint32_t OUT[][2]) {
  lmc_sobol_sampler s;
  sobol_sampler_init(&s, seed, pixel, index, l);
  sampler_use_stream(&s.base, stream);
  for (int g = 0; g < n_groups; g++)
    for (int c = 0; c < sizes[g]; c++) {
      double u = sampler_next(&s.base);
      assert_true(u >= 0.0 && u < 1.0);
      OUT[g][c] = (uint32_t)(u * 4294967296.0);
    }
}

/* The group sizes of the first n groups of a stream, read from the layout. */
static void layout_sizes(const sampler_layout *l, int stream, int n, int *sizes) {
  for (int g = 0; g < n; g++) {
    int h = l->stream[stream].n_head;
    sizes[g] = g < h ? l->stream[stream].head[g]
                     : l->stream[stream].cycle[(g - h) % l->stream[stream].n_cycle];
  }
}

static void test_sampler_stratified(void **state) {
  (void)state;
  enum { G = 24, M = 10 };
  static uint32_t v[1 << M][G][2];
  static uint32_t a[1 << M], b[1 << M];
  const sampler_layout *layouts[2] = {&sampler_layout_pt, &sampler_layout_bdpt};
  int nets = 0, strata = 0;
  for (int li = 0; li < 2; li++)
    for (int stream = 0; stream < LMC_STREAM_COUNT; stream++)
      for (uint64_t pixel = 0; pixel < 3; pixel++) {
        int sizes[G];
        layout_sizes(layouts[li], stream, G, sizes);
        for (uint32_t i = 0; i < (1u << M); i++)
          draw_groups(5, pixel * 7919, i, layouts[li], stream, G, sizes, v[i]);
        for (int g = 0; g < G; g++)
          for (int m = 0; m <= M; m += 2) {
            for (int i = 0; i < (1 << m); i++) {
              a[i] = v[i][g][0];
              b[i] = v[i][g][1];
            }
            if (sizes[g] == 2) {
              assert_true(is_net(a, b, m));
              nets++;
            } else {
              assert_true(is_stratified(a, m));
              strata++;
            }
          }
      }
  /* Both kinds were met in quantity (6 m values per group). */
  assert_int_equal((nets + strata) % 6, 0);
  assert_true(nets >= 6 * 60 && strata >= 6 * 60);
  assert_int_equal(nets + strata, 2 * 3 * 3 * G * 6);
}

/* Uniformity of each number across pixels and independence of two groups
 * of one sample: 16 x 16 histograms over 40000 pixels, one random sample
 * number each. */
static void test_sampler_uniform(void **state) {
  (void)state;
  enum { P = 40000, B = 16, G = 10 };
  double alpha = chi2_sidak(1e-4, N_CHI2);
  rng r;
  rng_seed(&r, 99, 1);
  static double hx[G][B * B], hpair[B * B];
  memset(hx, 0, sizeof hx);
  memset(hpair, 0, sizeof hpair);
  int sizes[G];
  layout_sizes(&sampler_layout_bdpt, LMC_STREAM_LIGHT, G, sizes);
  /* Groups 0 (lone), 1, 2 (pairs), 3 (lone), 4 (pair) ... */
  assert_int_equal(sizes[0], 1);
  assert_int_equal(sizes[1], 2);
  for (int p = 0; p < P; p++) {
    uint32_t v[G][2] = {{0}};
    uint32_t index = rng_uniform_u32(&r, 1u << 20);
    draw_groups(17, (uint64_t)p, index, &sampler_layout_bdpt, LMC_STREAM_LIGHT, G, sizes, v);
    for (int g = 0; g < G; g++) {
      /* Pairs: the joint histogram; lone numbers: with a fresh uniform. */
      uint32_t second = sizes[g] == 2 ? v[g][1] : rng_next_u32(&r);
      hx[g][(v[g][0] >> 28) * B + (second >> 28)]++;
    }
    /* Two different pair groups of the same sample: x of group 1 against
     * y of group 2. */
    hpair[(v[1][0] >> 28) * B + (v[2][1] >> 28)]++;
  }
  double expct[B * B];
  for (int i = 0; i < B * B; i++) expct[i] = (double)P / (B * B);
  int tests = 0;
  for (int g = 0; g < G; g++) {
    double pv = chi2_pvalue(hx[g], expct, B * B, 5.0, NULL, NULL);
    if (pv < alpha) fail_msg("group %d: chi-square p = %g < %g", g, pv, alpha);
    tests++;
  }
  double pv = chi2_pvalue(hpair, expct, B * B, 5.0, NULL, NULL);
  if (pv < alpha) fail_msg("groups 1 and 2: chi-square p = %g < %g", pv, alpha);
  tests++;
  assert_int_equal(tests, G + 1);
}

/* Across the samples of one pixel, different groups are not tied to one
 * another. Group 2's and group 4's x (pt layout, both pairs) over the
 * first 16 samples of a pixel are each stratified into 4 strata of 4
 * points; if the groups shared the sample order, the top two bits of both
 * would be functions of the sample number's two lowest bits, and the 16
 * points would fill exactly 4 of the 4 x 4 cells. With independent
 * shuffles they fill about as many as independent points do
 * (16 (1 - (15/16)^16) = 10.3). Over 4096 pixels the mean must exceed 9
 * (its SE is about 0.02). Pooled over pixels, the joint histogram is
 * uniform (chi-square) and the correlation is within 5 SE of zero. */
static void test_sampler_groups_decorrelated(void **state) {
  (void)state;
  enum { P = 4096, N = 16, B = 8, G = 6 };
  double alpha = chi2_sidak(1e-4, N_CHI2);
  static double h[B * B];
  memset(h, 0, sizeof h);
  int sizes[G];
  layout_sizes(&sampler_layout_pt, LMC_STREAM_CAMERA, G, sizes);
  assert_int_equal(sizes[2], 2);
  assert_int_equal(sizes[4], 2);
  double sxy = 0.0, occupied = 0.0;
  for (int p = 0; p < P; p++) {
    unsigned cells = 0;
    for (uint32_t i = 0; i < N; i++) {
      uint32_t v[G][2] = {{0}};
      draw_groups(23, (uint64_t)p, i, &sampler_layout_pt, LMC_STREAM_CAMERA, G, sizes, v);
      h[(v[2][0] >> 29) * B + (v[4][0] >> 29)]++;
      cells |= 1u << ((v[2][0] >> 30) * 4 + (v[4][0] >> 30));
      sxy += ((double)v[2][0] / 4294967296.0 - 0.5) * ((double)v[4][0] / 4294967296.0 - 0.5);
    }
    occupied += __builtin_popcount(cells);
  }
  occupied /= P;
  if (!(occupied > 9.0)) fail_msg("the first 16 samples fill %.2f of 16 cells on average", occupied);
  double expct[B * B];
  for (int i = 0; i < B * B; i++) expct[i] = (double)P * N / (B * B);
  double pv = chi2_pvalue(h, expct, B * B, 5.0, NULL, NULL);
  if (pv < alpha) fail_msg("chi-square p = %g < %g", pv, alpha);
  /* The correlation: for independent uniforms its SE is 1/sqrt(n). */
  double corr = sxy / (P * N) * 12.0;
  if (fabs(corr) > 5.0 / sqrt((double)P * N)) fail_msg("correlation %g", corr);
  printf("groups 2 and 4: %.2f of 16 cells filled on average, correlation %.4f\n", occupied, corr);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_scramble_nested),
      cmocka_unit_test(test_sobol_net),
      cmocka_unit_test(test_sampler_stratified),
      cmocka_unit_test(test_sampler_uniform),
      cmocka_unit_test(test_sampler_groups_decorrelated),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
