/*
 * test_media_mcmc_slow.c: pssmlt (on its bdpt states) and mmlt (on its
 * mmlt states) through participating media agree with bdpt on two scenes
 * without a closed form, in the image mean and in the means of a 4 x 4
 * grid of regions: the volumetric caustic (scenes/volcaustic at 64 x 48:
 * a smooth glass sphere of fog over an area light in a fog-filled box)
 * and tests/data/media/rough_glass_fog.xml (a rough glass sphere of dense
 * fog in a thin fog no shape encloses: the bdpt states' absolute
 * directions at rough vertices, whose numbers follow each vertex's flight
 * numbers through media). The pt states: test_media_mcmc.c's furnace.
 *
 * Variance, as test_mcmc_ring_slow.c: each integrator renders R = 5
 * independent seeds (the MCMC ones each with its own bootstrap, to a 3%
 * standard error); per statistic the runs give a mean and SE = sd /
 * sqrt(R), and the MCMC mean must lie within 6.5 sqrt(SE_mcmc^2 +
 * SE_bdpt^2) of bdpt's (P(|t| > 6.5) ~ 2e-4 per check at about 8 degrees
 * of freedom; over 4 x 17 = 68 checks a false alarm about 1.5%). Effort:
 * 80 samples (mutations) per pixel, the default --direct separate (pt
 * renders one and two segments through the media).
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

/* An integrator and the states it runs on (NULL: its own). */
typedef struct config {
  const char *integrator, *states;
} config;

static void run_stats(const scene *s, const config *c, int64_t spp, double mean[N_STATS],
                      double se[N_STATS]) {
  render_settings rs = region_settings(s, c->integrator, spp);
  lmc_error err;
  if (c->states) assert_int_equal(mcmc_set(&rs, "states", c->states, &err), LMC_OK);
  region_runs(s, &rs, RUNS, 2000, GRID, mean, se);
}

static void check_scene(const char *path, int w, int h, const config *c, int n) {
  scene *s = load_source_scene("%s", path);
  assert_true(s->n_media > 0);
  camera_set_resolution(&s->cam, w, h);
  double ref[N_STATS], ref_se[N_STATS], m[N_STATS], se[N_STATS];
  const config bdpt = {"bdpt", NULL};
  run_stats(s, &bdpt, 80, ref, ref_se);
  for (int i = 0; i < n; i++) {
    char what[256];
    snprintf(what, sizeof what, "%s %s%s%s", path, c[i].integrator, c[i].states ? " on " : "",
             c[i].states ? c[i].states : "");
    run_stats(s, &c[i], 80, m, se);
    g_checks += region_agree(what, GRID, m, se, ref, ref_se, 6.5);
  }
  scene_destroy(s);
}

static void test_volcaustic(void **state) {
  (void)state;
  static const config c[2] = {{"pssmlt", NULL}, {"mmlt", NULL}};
  check_scene("scenes/volcaustic/scene.xml", 64, 48, c, 2);
}

static void test_rough_glass_fog(void **state) {
  (void)state;
  static const config c[2] = {{"pssmlt", NULL}, {"mmlt", NULL}};
  check_scene("tests/data/media/rough_glass_fog.xml", 32, 24, c, 2);
}

static void test_count(void **state) {
  (void)state;
  assert_int_equal(g_checks, 4 * N_STATS);
}

int main(void) {
  lmc_warn_set_quiet(1);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_volcaustic),
      cmocka_unit_test(test_rough_glass_fog),
      cmocka_unit_test(test_count),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
