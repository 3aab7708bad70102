/*
 * test_mcmc_ring_slow.c: pssmlt, mmlt and path-space MLT (mlt) agree with
 * bdpt on the ring-caustics scenes (scenes/ring-caustics,
 * scenes/ring-caustics-glass) at 64x48, and mlt on the Cornell box
 * (scenes/cornell-box) at 32x32 with 512 samples and mutations per pixel:
 * in the image mean and in the means of a 4 x 4 grid of regions. So do
 * the moves through the inverse path sampler: pssmlt and mmlt with
 * reversible jumps (--technique-jump 0.2) and fused path moves
 * (--path-mutations 0.3) on the rings (pssmlt also on the box), mlt
 * with its primary-sample step (--pss-mutation on) on the box, with the
 * manifold perturbation (--manifold-perturbation on) on the glass ring,
 * and with it and HSLT's half-vector perturbation (--hslt on) on the box
 * (the metal ring's reflected chains are the manifold tests' mirrors,
 * test_mut_manifold). This is the guard against start-up bias and wrong
 * normalisation.
 *
 * Variance: each integrator renders R = 5 independent seeds (MCMC: each with
 * its own bootstrap). For a statistic (a region's mean luminance) the runs
 * give a mean and a standard error SE = sd / sqrt(R) per integrator; the
 * MCMC mean must lie within 6.5 sqrt(SE_mcmc^2 + SE_bdpt^2) of bdpt's. The
 * difference over its estimated standard error follows roughly a Student t
 * with about 8 degrees of freedom (Welch), P(|t| > 6.5) ~ 2e-4 per check;
 * over the (5 + 6 + 4) x 17 = 255 checks the chance of a false alarm is
 * about 5%.
 * Effort: --spp 80 (Cornell box: 512) for bdpt, pssmlt and mmlt (MCMC:
 * mutations per pixel); mlt makes 640 on the ring scenes. Its
 * perturbations move a path locally and only its bidirectional mutation
 * (a third of the steps) moves it across the image, so at 80 a region
 * that holds a tiny share of the light (ring-caustics' right edge: about
 * 0.07% of what the chains render) is visited in one run out of several,
 * and 5 runs' standard error does not describe such a skewed estimate
 * (all five low, their spread near zero); at 640 every run visits it.
 * The bootstrap is the default, adaptive one (mmlt: Neyman-allocated over
 * the lengths), run to a 3% standard error instead of 1% to keep the test
 * short: b's error is part of each run's, so of the SE. The renders use
 * the default --direct separate (pt renders the paths of one and two
 * segments with the same spp, the chains the rest; test_mcmc_analytic
 * covers --direct mcmc). About 8 CPU-minutes in Release.
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
#include "load_scene.h"
#include "render/io/io.h"
#include "region_stats.h"
#include "test_util.h"

#define RUNS 5
#define GRID 4
#define N_STATS (GRID * GRID + 1)

static int g_checks;

/* An integrator with up to two flags of its own ({NULL}: none). */
typedef struct config {
  const char *name, *integrator;
  const char *flags[2][2];
} config;

/* Mean and SE over RUNS of the region means (index GRID*GRID: whole image). */
static void run_stats(const scene *s, const config *c, int64_t spp, double mean[N_STATS],
                      double se[N_STATS]) {
  render_settings rs = region_settings(s, c->integrator, spp);
  lmc_error err;
  for (int f = 0; f < 2 && c->flags[f][0]; f++)
    assert_int_equal(mcmc_set(&rs, c->flags[f][0], c->flags[f][1], &err), LMC_OK);
  region_runs(s, &rs, RUNS, 1000, GRID, mean, se);
}

/* The MCMC configurations c[0 .. n-1] against bdpt on scene `folder` at
 * w x h, spp samples per pixel (bdpt) and mutations per pixel (the MCMC
 * integrators; mlt: mlt_spp). */
static void check_scene(const char *folder, int w, int h, int64_t spp, int64_t mlt_spp,
                        const config *c, int n) {
  scene *s = load_source_scene("scenes/%s/scene.xml", folder);
  camera_set_resolution(&s->cam, w, h);

  double ref[N_STATS], ref_se[N_STATS];
  const config bdpt = {"bdpt", "bdpt", {{NULL, NULL}}};
  run_stats(s, &bdpt, spp, ref, ref_se);
  for (int i = 0; i < n; i++) {
    double m[N_STATS], se[N_STATS];
    run_stats(s, &c[i], strcmp(c[i].integrator, "mlt") == 0 ? mlt_spp : spp, m, se);
    char what[128];
    snprintf(what, sizeof what, "%s %s", folder, c[i].name);
    g_checks += region_agree(what, GRID, m, se, ref, ref_se, 6.5);
  }
  scene_destroy(s);
}

/* The integrators, and the moves through the inverse path sampler: pssmlt
 * on its bdpt states and mmlt with reversible jumps and fused path
 * moves, mlt with its primary-sample step. */
#define N_CONFIGS 6
static const config g_configs[N_CONFIGS] = {
    {"pssmlt", "pssmlt", {{NULL, NULL}}},
    {"mmlt", "mmlt", {{NULL, NULL}}},
    {"mlt", "mlt", {{NULL, NULL}}},
    {"pssmlt jumps+path", "pssmlt", {{"technique-jump", "0.2"}, {"path-mutations", "0.3"}}},
    {"mmlt jumps+path", "mmlt", {{"technique-jump", "0.2"}, {"path-mutations", "0.3"}}},
    {"mlt manifold", "mlt", {{"manifold-perturbation", "on"}, {NULL, NULL}}},
};

/* The metal ring: the first five (mlt's own moves, without the manifold
 * perturbation). mlt's primary-sample step is checked on the box (its
 * balance and invariance: test_perturb.c). */
#define N_METAL 5

static void test_ring_caustics(void **state) {
  (void)state;
  check_scene("ring-caustics", 64, 48, 80, 640, g_configs, N_METAL);
}

static void test_ring_caustics_glass(void **state) {
  (void)state;
  check_scene("ring-caustics-glass", 64, 48, 80, 640, g_configs, N_CONFIGS);
}

/* Path-space MLT on the Cornell box too (an area light, a glass sphere),
 * with its primary-sample step and pssmlt with the moves. */
static void test_cornell_box_mlt(void **state) {
  (void)state;
  static const config c[4] = {
      {"mlt", "mlt", {{NULL, NULL}}},
      {"mlt pss step", "mlt", {{"pss-mutation", "on"}, {NULL, NULL}}},
      {"pssmlt jumps+path", "pssmlt", {{"technique-jump", "0.2"}, {"path-mutations", "0.3"}}},
      {"mlt manifold+hslt", "mlt", {{"manifold-perturbation", "on"}, {"hslt", "on"}}},
  };
  check_scene("cornell-box", 32, 32, 512, 512, c, 4);
}

static void test_count(void **state) {
  (void)state;
  assert_int_equal(g_checks, (N_METAL + N_CONFIGS + 4) * N_STATS);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_ring_caustics),
      cmocka_unit_test(test_ring_caustics_glass),
      cmocka_unit_test(test_cornell_box_mlt),
      cmocka_unit_test(test_count),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
