/*
 * test_bsdf_invert.c: bsdf_invert, the inverse of bsdf_sample_f, and
 * mf_invert, the inverse of the microfacet sampler.
 *
 * What is checked, on every configuration of bsdf_configs.h (every
 * non-delta model) and on the delta ones made here (conductor, dielectric
 * from both sides and past the critical angle, thindielectric, plastic,
 * masks whose pass-through competes with a wrapped delta lobe, twosided):
 *   - sample(invert(wi)) = wi: re-sampling from the inverted numbers gives
 *     the same direction (to 1e-9) and the same kind of event (delta or
 *     not, reflection or transmission);
 *   - invert(sample(u)) = u for the continuous numbers (u1, u2) whenever
 *     the inverse chose the lobe that made wi (to 1e-9, u away from the
 *     square's edges); for single-lobe models that is every sample;
 *   - the inverse is the exact posterior of u given wi: u uniform on
 *     [0, 1)^3, each u the sampler accepts replaced by its inverse (with
 *     fresh random choices), the others kept, must still be uniform
 *     (chi-square over 4 x 6 x 6 cells, Sidak level of an overall 1%);
 *     a negative control that always takes the diffuse lobe of a mixture
 *     must fail that test;
 *   - mf_invert round trips for both distributions, visible or not.
 * Each test counts its checks and asserts the count.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "test_util.h"

#include "bsdf_configs.h"
#include "chi2.h"
#include "render/bsdf/bsdf.h"
#include "render/bsdf/microfacet.h"
#include "render/rng.h"

/* The delta models and mixtures with a delta lobe, appended to c[n...]. */
static int make_delta_configs(config *c, int n) {
  const double phi0 = 1.1;
  const double eta = 1.5;
  bsdf_init_defaults(&c[n].b, "conductor");
  c[n].wo = dir(0.6, phi0);
  snprintf(c[n].name, sizeof c[n].name, "conductor wo.z=0.60");
  n++;
  const double di_z[] = {0.8, 0.2, -0.9, -0.5}; /* -0.5: past the critical angle */
  for (int i = 0; i < 4; i++) {
    bsdf_init_defaults(&c[n].b, "dielectric");
    c[n].b.eta = eta;
    c[n].wo = dir(di_z[i], phi0);
    snprintf(c[n].name, sizeof c[n].name, "dielectric wo.z=%.2f", di_z[i]);
    n++;
  }
  bsdf_init_defaults(&c[n].b, "thindielectric");
  c[n].b.eta = eta;
  c[n].wo = dir(-0.4, phi0);
  snprintf(c[n].name, sizeof c[n].name, "thindielectric wo.z=-0.40");
  n++;
  bsdf_init_defaults(&c[n].b, "plastic");
  c[n].wo = dir(0.3, phi0);
  snprintf(c[n].name, sizeof c[n].name, "plastic wo.z=0.30");
  n++;
  /* A mask on thindielectric: its pass-through and the slab's transmission
   * both give -wo. */
  c[n] = c[n - 2];
  c[n].b.masked = 1;
  c[n].b.opacity = tex_constant(rgb_make(0.2, 0.5, 0.8));
  snprintf(c[n].name, sizeof c[n].name, "mask thindielectric wo.z=-0.40");
  n++;
  bsdf_init_defaults(&c[n].b, "phong");
  c[n].b.exponent = 10.0;
  c[n].b.twosided = 1;
  c[n].b.masked = 1;
  c[n].b.opacity = tex_constant(rgb_gray(0.7));
  c[n].wo = dir(-0.5, phi0);
  snprintf(c[n].name, sizeof c[n].name, "mask twosided phong wo.z=-0.50");
  n++;
  return n;
}

static int all_configs(config *c) {
  memset(c, 0, MAX_CONFIGS * sizeof *c);
  int n = make_configs(c);
  return make_delta_configs(c, n);
}

/* u away from the square's edges, where wrap-around and clamping live. */
static double inner(rng *r) { return 1e-3 + (1.0 - 2e-3) * rng_uniform(r); }

/* ---- Round trips ------------------------------------------------------------ */

static void test_round_trip(void **state) {
  (void)state;
  static config c[MAX_CONFIGS];
  int n = all_configs(c);
  assert_true(n > 100 && n <= MAX_CONFIGS);
  long checks = 0, same_lobe = 0, samples = 0;
  for (int k = 0; k < n; k++) {
    rng g;
    rng_seed(&g, 17, (uint64_t)k);
    long ok_here = 0;
    for (int i = 0; i < 2000; i++) {
      double u[3] = {inner(&g), inner(&g), inner(&g)};
      bsdf_sample s;
      if (!bsdf_sample_f(&c[k].b, 0.5, 0.5, c[k].wo, u[0], u[1], u[2], c[k].mode, &s)) continue;
      samples++;
      double r[4] = {rng_uniform(&g), rng_uniform(&g), rng_uniform(&g), rng_uniform(&g)};
      double v[3];
      int delta = (s.flags & BSDF_DELTA) != 0;
      if (!bsdf_invert(&c[k].b, 0.5, 0.5, c[k].wo, s.wi, delta, r, v)) {
        print_error("%s: u (%.9f %.9f %.9f) gave wi (%g %g %g) that does not invert\n", c[k].name,
                    u[0], u[1], u[2], s.wi.x, s.wi.y, s.wi.z);
        fail();
      }
      for (int j = 0; j < 3; j++) assert_true(v[j] >= 0.0 && v[j] < 1.0);
      bsdf_sample t;
      assert_true(bsdf_sample_f(&c[k].b, 0.5, 0.5, c[k].wo, v[0], v[1], v[2], c[k].mode, &t));
      /* A mixture's other lobe may have been chosen: same kind of event. */
      const int kind = BSDF_DELTA | BSDF_REFLECTION | BSDF_TRANSMISSION;
      assert_int_equal(t.flags & kind, s.flags & kind);
      assert_near(v3_len(v3_sub(t.wi, s.wi)), 0.0, 1e-9);
      checks += 2;
      /* The lobe that made wi chosen again: its continuous numbers come back. */
      if (!delta && t.flags == s.flags) {
        assert_near(v[1], u[1], 1e-9);
        assert_near(v[2], u[2], 1e-9);
        same_lobe++;
      }
      ok_here++;
    }
    if (ok_here < 200) {
      print_error("%s: only %ld of 2000 samples accepted\n", c[k].name, ok_here);
      fail();
    }
  }
  printf("round trips: %d configurations, %ld samples, %ld checks, %ld numbers recovered\n", n,
         samples, checks, same_lobe);
  assert_int_equal(checks, 2 * samples);
  assert_true(same_lobe > samples / 2);
}

/* ---- The inverse is the posterior of u given wi ------------------------------- */

enum { NB0 = 4, NB1 = 6, NB2 = 6, NCELL = NB0 * NB1 * NB2 };

static int cell(const double u[3]) {
  int a = (int)(u[0] * NB0), b = (int)(u[1] * NB1), c = (int)(u[2] * NB2);
  return (a * NB1 + b) * NB2 + c;
}

/* p-value of uniformity of the numbers after replacing every accepted u by
 * an inverse of its wi; force_first: the negative control (r[0] = 0, the
 * first candidate lobe always). */
static double posterior_pvalue(const config *cf, uint64_t seed, int n_samples, int force_first) {
  static double obs[NCELL], expct[NCELL];
  for (int i = 0; i < NCELL; i++) {
    obs[i] = 0.0;
    expct[i] = (double)n_samples / NCELL;
  }
  rng g;
  rng_seed(&g, seed, 3);
  for (int i = 0; i < n_samples; i++) {
    double u[3] = {rng_uniform(&g), rng_uniform(&g), rng_uniform(&g)};
    bsdf_sample s;
    if (bsdf_sample_f(&cf->b, 0.5, 0.5, cf->wo, u[0], u[1], u[2], cf->mode, &s)) {
      double r[4] = {rng_uniform(&g), rng_uniform(&g), rng_uniform(&g), rng_uniform(&g)};
      if (force_first) r[0] = 0.0;
      double v[3];
      if (bsdf_invert(&cf->b, 0.5, 0.5, cf->wo, s.wi, (s.flags & BSDF_DELTA) != 0, r, v))
        memcpy(u, v, sizeof u);
      else
        return 0.0;
    }
    obs[cell(u)] += 1.0;
  }
  return chi2_pvalue(obs, expct, NCELL, 5.0, NULL, NULL);
}

static void test_posterior(void **state) {
  (void)state;
  static config c[MAX_CONFIGS];
  int n = all_configs(c);
  double level = chi2_sidak(0.01, n);
  int checked = 0;
  for (int k = 0; k < n; k++) {
    double p = posterior_pvalue(&c[k], 1000 + (uint64_t)k, 72000, 0);
    if (!(p >= level)) {
      print_error("%s: uniformity p = %g below %g\n", c[k].name, p, level);
      fail();
    }
    checked++;
  }
  /* Negative controls: mixtures whose lobes overlap, inverted always by
   * the first candidate (the diffuse lobe wherever it has density). */
  int controls = 0, candidates = 0;
  for (int k = 0; k < n; k++) {
    if (!bsdf_is(&c[k].b, "phong") && !bsdf_is(&c[k].b, "roughplastic")) continue;
    candidates++;
    double p = posterior_pvalue(&c[k], 5000 + (uint64_t)k, 72000, 1);
    if (p < 1e-6) controls++;
    else print_error("control %s: p = %g (not rejected)\n", c[k].name, p);
  }
  printf("posterior: %d configurations at level %.2e; %d of %d negative controls rejected\n",
         checked, level, controls, candidates);
  assert_int_equal(checked, n);
  assert_true(candidates >= 20);
  assert_int_equal(controls, candidates);
}

/* ---- mf_invert ---------------------------------------------------------------- */

static void test_microfacet_invert(void **state) {
  (void)state;
  int checks = 0;
  const double alphas[] = {0.05, 0.3, 1.0};
  const double vz[] = {1.0, 0.7, 0.2, 0.02};
  for (int d = 0; d < 2; d++)
    for (int vis = 0; vis < 2; vis++)
      for (int a = 0; a < 3; a++)
        for (int iv = 0; iv < 4; iv++) {
          rng g;
          rng_seed(&g, 99, (uint64_t)(((d * 2 + vis) * 3 + a) * 4 + iv));
          vec3 v = dir(vz[iv], 0.4);
          for (int i = 0; i < 300; i++) {
            double u1 = inner(&g), u2 = inner(&g);
            vec3 m = mf_sample(d ? MF_GGX : MF_BECKMANN, alphas[a], v, vis, u1, u2);
            double w1, w2;
            assert_true(mf_invert(d ? MF_GGX : MF_BECKMANN, alphas[a], v, vis, m, &w1, &w2));
            /* Beckmann's visible slopes are clamped to |x| <= 9 (an
             * alpha = 1 tail of mass below 1e-35). */
            assert_near(w1, u1, 1e-9);
            assert_near(w2, u2, 1e-9);
            checks++;
          }
        }
  assert_int_equal(checks, 2 * 2 * 3 * 4 * 300);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_microfacet_invert),
      cmocka_unit_test(test_round_trip),
      cmocka_unit_test(test_posterior),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
