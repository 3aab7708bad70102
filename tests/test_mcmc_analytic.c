/*
 * test_mcmc_analytic.c: pssmlt and mmlt on the analytic scenes of the
 * renderer core (tests/data/analytic, see test_analytic.c), and the
 * determinism of the MCMC driver.
 *
 *  furnace.xml         every pixel has expectation exactly 1;
 *  diffuse_sphere.xml  covered pixels 0.5 L, background pixels L,
 *                      L = (1, 2, 4);
 *  mask.xml            a masked square (0.875, 1.5, 2.5), a lossless
 *                      masked sphere and the background L, in pssmlt,
 *                      mmlt, lmc, h2mc and mlt (whose path space holds the
 *                      pass-through as a delta lobe of a mixed BSDF).
 *
 * An MCMC image's pixels are correlated (chains wander over the film, and
 * the bootstrap's b scales the whole image), so the spread of pixels does
 * not give the standard error. Each configuration is rendered with R = 6
 * independent seeds (each with its own bootstrap); the group means of the
 * R runs give their mean and its standard error SE = sd / sqrt(R). The
 * mean must lie within 8 SE of the exact value (plus 0.3% for mmlt on the
 * furnace, whose state stops at 24 segments when maxdepth is unbounded and
 * so loses the longer paths). mmlt runs the furnace twice: with its default
 * allocation (mutations per length in proportion to b_k) and with
 * --allocate even. With R = 6 the t statistic has 5 degrees of
 * freedom, P(|t_5| > 8) = 5e-4 per check, about 0.9% over the 18 checks
 * that are not exact. Every render must also make spp mutations per pixel
 * (up to less than 10% of whole rounds).
 *
 * --direct separate (the default of the command line): the same image
 * means on both scenes with pt rendering the paths of one and two segments
 * and the chains the rest, and the same determinism.
 *
 * Determinism: the same seed gives a bit-identical film; --threads 1 and 2
 * give a bit-identical film under --spp, also with mmlt's default, adaptive
 * bootstrap (a pilot, then planning and estimating streams until b's error
 * target, shared out by rays counted, not by time), and
 * for lmc with --adapt none, diminish and cache (Adam's statistics, the
 * stage-1 records and the frozen cache are made in chain order).
 *
 * mmlt's b is its bootstrap's alone (its large steps are not pooled):
 * the b it reports after the chains equals the bootstrap's, to the bit.
 *
 * pssmlt's b refined with the large steps (mcmc.c): on the furnace every pixel's
 * radiance is exactly 1 (grey), so pssmlt's b = E[luminance(A L)] = A, the
 * film area grown by the filter radius. For each of RUNS seeds the refined
 * b the render reports must lie within 4 of its own stated standard errors
 * of A (two-sided normal, 6e-5 per check), and that standard error must be
 * at most 0.8 times the bootstrap-only one (at 64 mutations per pixel the
 * large steps add 0.3 * 64 W H, about 30000, samples to the bootstrap's
 * 16384: sqrt(16384 / 46000) = 0.6 expected).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lmc/mcmc.h"
#include "render/io/io.h"
#include "test_util.h"

#include "analytic_check.h"

static int g_cache_gradient; /* lmc --cache-gradient on for render_film */

static void test_furnace_pssmlt(void **state) {
  (void)state;
  rgb one = rgb_gray(1.0);
  check_scene("furnace.xml", "pssmlt", 16, &one, 1, 0.0);
}

static void test_furnace_mmlt(void **state) {
  (void)state;
  rgb one = rgb_gray(1.0);
  check_scene("furnace.xml", "mmlt", 16, &one, 1, 0.003);
  /* The same with every chain making the same number of mutations (the
   * default shares them among the lengths in proportion to b_k). */
  g_even = 1;
  check_scene("furnace.xml", "mmlt", 16, &one, 1, 0.003);
  g_even = 0;
}

/* H2MC (--integrator h2mc) on both analytic scenes, on the bdpt states
 * and on mmlt's per-length states: the furnace's every path and the
 * sphere's two groups. */
static void test_h2mc(void **state) {
  (void)state;
  rgb one = rgb_gray(1.0);
  rgb e[2] = {rgb_make(1.0, 2.0, 4.0), rgb_make(0.5, 1.0, 2.0)};
  check_scene("furnace.xml", "h2mc", 16, &one, 1, 0.0);
  check_scene("diffuse_sphere.xml", "h2mc", 16, e, 2, 0.0);
  g_states = "mmlt";
  check_scene("furnace.xml", "h2mc", 16, &one, 1, 0.003);
  check_scene("diffuse_sphere.xml", "h2mc", 16, e, 2, 0.0);
  g_states = NULL;
  /* Delayed acceptance (a first test at the current state's model): the same expectations,
   * from chains that do move differently (the images of one seed differ). */
  g_delayed = 1;
  check_scene("furnace.xml", "h2mc", 16, &one, 1, 0.0);
  check_scene("diffuse_sphere.xml", "h2mc", 16, e, 2, 0.0);
  film fd, fp;
  render_seed7("diffuse_sphere.xml", "h2mc", &fd);
  g_delayed = 0;
  render_seed7("diffuse_sphere.xml", "h2mc", &fp);
  assert_films_differ(&fd, &fp);
}

/* Mitsuba's mask (mask.xml: the environment, a masked square seen
 * through, a lossless masked sphere) in every MCMC integrator: the
 * pass-through lobe, in the plain and (lmc, h2mc) dual paths. */
static void test_mask(void **state) {
  (void)state;
  rgb e[3] = {rgb_make(1.0, 2.0, 4.0), rgb_make(0.875, 1.5, 2.5), rgb_make(1.0, 2.0, 4.0)};
  static const char *const integrators[] = {"pssmlt", "mmlt", "lmc", "h2mc", "mlt"};
  /* mlt's chains move slowly over the film: more mutations for a useful SE. */
  for (int i = 0; i < 5; i++) check_scene("mask.xml", integrators[i], i == 4 ? 256 : 16, e, 3, 0.0);
}

static void test_diffuse_sphere(void **state) {
  (void)state;
  rgb e[2] = {rgb_make(1.0, 2.0, 4.0), rgb_make(0.5, 1.0, 2.0)};
  check_scene("diffuse_sphere.xml", "pssmlt", 16, e, 2, 0.0);
  check_scene("diffuse_sphere.xml", "mmlt", 16, e, 2, 0.0);
}

/* Path-space MLT under the constant environment (a light at infinity):
 * the sphere's two groups, and the furnace (its paths stop at the path
 * space's longest length, which loses what the furnace's longer paths
 * carry: the 0.3% of mmlt's bound). */
static void test_mlt_environment(void **state) {
  (void)state;
  rgb one = rgb_gray(1.0);
  rgb e[2] = {rgb_make(1.0, 2.0, 4.0), rgb_make(0.5, 1.0, 2.0)};
  check_scene("diffuse_sphere.xml", "mlt", 16, e, 2, 0.0);
  check_scene("furnace.xml", "mlt", 16, &one, 1, 0.003);
}

/* --direct separate, the default: pt renders the paths of one and two
 * segments with spp samples per pixel, MCMC the longer ones (mindepth 3),
 * into one film. On the furnace a pixel's 1 is split between the two
 * (the environment seen directly or after one bounce off a lossless
 * sphere: pt; two or more bounces, inside the glass sphere or between the
 * spheres: MCMC); the diffuse sphere is convex, so every path has one or
 * two segments: pt renders the whole image, and the MCMC part, whose b
 * is 0, must add nothing and not fail. Each group's mean must be exact
 * within 8 SE; lmc too (its default adaptation, cache), on the sphere. */
static void test_direct_separate(void **state) {
  (void)state;
  g_direct = 1; /* reset by reset_direct whatever happens here */
  rgb one = rgb_gray(1.0);
  rgb e[2] = {rgb_make(1.0, 2.0, 4.0), rgb_make(0.5, 1.0, 2.0)};
  check_scene("furnace.xml", "pssmlt", 16, &one, 1, 0.0);
  check_scene("furnace.xml", "mmlt", 16, &one, 1, 0.003);
  g_mcmc_empty = 1;
  check_scene("diffuse_sphere.xml", "pssmlt", 16, e, 2, 0.0);
  check_scene("diffuse_sphere.xml", "mmlt", 16, e, 2, 0.0);
  check_scene("diffuse_sphere.xml", "lmc", 16, e, 2, 0.0);
}

/* --- b refined with the large steps ------------------------------------------- */

static void test_refined_b(void **state) {
  (void)state;
  scene *s = load_analytic_scene("furnace.xml");
  double r = s->filter.radius;
  double area = (s->cam.width + 2.0 * r) * (s->cam.height + 2.0 * r);
  for (int i = 0; i < RUNS; i++) {
    render_settings rs = settings(s, "pssmlt", 64, 200 + (uint64_t)i, 2);
    film f;
    render_stats st;
    lmc_error err;
    lmc_error_clear(&err);
    assert_int_equal(mcmc_render_run(s, &rs, &f, &st, &err), LMC_OK);
    fprintf(stderr, "  furnace pssmlt seed %d: b %.6g +- %.3g (bootstrap %.6g +- %.3g), exact %.6g\n",
            200 + i, st.mcmc_b, st.mcmc_b_se, st.mcmc_b_boot, st.mcmc_b_boot_se, area);
    assert_near(st.mcmc_b, area, 4.0 * st.mcmc_b_se + 1e-9 * area);
    assert_le(st.mcmc_b_se, 0.8 * st.mcmc_b_boot_se);
    assert_true(st.mcmc_b_se > 0.0);
    g_checks++;
    film_free(&f);
    /* mmlt keeps its bootstrap's b: its large steps (one strategy's value,
     * heavier-tailed than the bootstrap's expectation over the strategies)
     * are not pooled. */
    rs = settings(s, "mmlt", 64, 200 + (uint64_t)i, 2);
    assert_int_equal(mcmc_render_run(s, &rs, &f, &st, &err), LMC_OK);
    assert_true(st.mcmc_b == st.mcmc_b_boot && st.mcmc_b_se == st.mcmc_b_boot_se);
    assert_true(st.mcmc_b > 0.0);
    g_checks++;
    film_free(&f);
  }
  scene_destroy(s);
}

/* --- determinism ------------------------------------------------------- */

/* adaptive: the default bootstrap (bootstrap.h: batches until b's standard
 * error is below --bootstrap-error, Neyman-allocated over mmlt's lengths)
 * instead of a fixed count; returns the bootstrap's size. */
static int64_t render_film(const scene *s, const char *integrator, const char *adapt, uint64_t seed,
                           int threads, int adaptive, film *OUT_f) {
  render_settings rs = settings(s, integrator, 4, seed, threads);
  lmc_error err;
  assert_int_equal(mcmc_set(&rs, "adapt", adapt, &err), LMC_OK);
  assert_int_equal(mcmc_set(&rs, "cache-gradient", g_cache_gradient ? "on" : "off", &err), LMC_OK);
  if (adaptive) {
    lmc_opt_unset(&rs, "bootstrap");
    assert_int_equal(mcmc_set(&rs, "bootstrap-error", "0.003", &err), LMC_OK);
  }
  render_stats st;
  assert_int_equal(mcmc_render_run(s, &rs, OUT_f, &st, &err), LMC_OK);
  /* Every integrator makes the whole budget (lmc's cache mode too: its
   * stage 1 is part of the image). */
  int64_t want = 4 * (int64_t)s->cam.width * s->cam.height;
  assert_true(st.samples >= want);
  return st.mcmc_boot_paths;
}

static int films_equal(const film *a, const film *b) {
  size_t n = (size_t)a->width * (size_t)a->height;
  return a->splat_scale == b->splat_scale && !memcmp(a->splat, b->splat, 3 * n * sizeof(double)) &&
         !memcmp(a->sum, b->sum, 3 * n * sizeof(double));
}

static void test_determinism(void **state) {
  (void)state;
  scene *s = load_analytic_scene("furnace.xml"), *sphere = load_analytic_scene("diffuse_sphere.xml");
  /* lmc with each unbiased adaptation: its Adam statistics, stage-1 records
   * and frozen cache must be as deterministic as the chains. */
  /* Then --direct separate (the default), pt's pass and the chains' in
   * one film; the last: lmc --cache-gradient on (stage 2 of the cache with
   * Langevin proposals, whose preconditioner is looked up per label). */
  const char *names[9] = {"pssmlt", "mmlt", "mmlt", "lmc", "lmc", "lmc", "mmlt", "lmc", "lmc"};
  const char *const adapts[9] = {"cache", "cache",    "cache", "none", "diminish",
                                 "cache", "cache",    "cache", "cache"};
  int checked = 0;
  for (int i = 0; i < 9; i++) {
    g_direct = i >= 6 && i < 8;
    g_cache_gradient = i == 8;
    /* The third: mmlt's adaptive bootstrap, several batches shared out by
     * the lengths' costs and variances. */
    const scene *sc = i == 2 ? sphere : s;
    int adaptive = i == 2;
    film a, b, c, d;
    int64_t n = render_film(sc, names[i], adapts[i], 3, 2, adaptive, &a);
    render_film(sc, names[i], adapts[i], 3, 2, adaptive, &b);
    render_film(sc, names[i], adapts[i], 3, 1, adaptive, &c);
    render_film(sc, names[i], adapts[i], 4, 2, adaptive, &d);
    if (adaptive) assert_true(n > 4 * 8192); /* more than the first batch */
    assert_true(films_equal(&a, &b)); /* same seed, same threads */
    assert_true(films_equal(&a, &c)); /* 1 vs 2 threads */
    assert_false(films_equal(&a, &d)); /* another seed differs */
    checked++;
    film_free(&a);
    film_free(&b);
    film_free(&c);
    film_free(&d);
  }
  g_direct = 0;
  g_cache_gradient = 0;
  assert_int_equal(checked, 9);
  scene_destroy(s);
  scene_destroy(sphere);
}

static void test_count(void **state) {
  (void)state;
  /* furnace pssmlt, mmlt twice, sphere 2 x 2 groups, mlt's sphere 2 groups
   * and furnace, mask 5 x 3 groups,
   * h2mc furnace and sphere 2 groups on two state spaces and with delayed
   * acceptance, then separate: furnace 2, sphere 3 x 2 groups; 3 channels each; and the
   * refined b. */
  assert_int_equal(g_checks, 3 + 3 + 3 + 2 * 2 * 3 + (2 + 1) * 3 + 5 * 3 * 3 +
                                 3 * (1 + 2) * 3 + (2 + 3 * 2) * 3 +
                                 2 * RUNS);
}

static int reset_direct(void **state) {
  (void)state;
  g_direct = 0;
  g_even = 0;
  g_mcmc_empty = 0;
  return 0;
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_furnace_pssmlt),
      cmocka_unit_test(test_furnace_mmlt),
      cmocka_unit_test(test_diffuse_sphere),
      cmocka_unit_test(test_mlt_environment),
      cmocka_unit_test(test_mask),
      cmocka_unit_test(test_h2mc),
      cmocka_unit_test_teardown(test_direct_separate, reset_direct),
      cmocka_unit_test(test_refined_b),
      cmocka_unit_test_teardown(test_determinism, reset_direct),
      cmocka_unit_test(test_count),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
