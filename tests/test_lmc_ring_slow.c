/*
 * test_lmc_ring_slow.c: Langevin Monte Carlo (--integrator lmc) with
 * --adapt diminish and --adapt cache on mmlt's multiplexed states, cache
 * on the pt states (--states pt), and H2MC (--integrator h2mc) on the bdpt
 * states (its default) and on mmlt's, agree with bdpt on the ring-caustics
 * scenes (scenes/ring-caustics, scenes/ring-caustics-glass) at 24x18: in
 * the image mean and in the means of a 4 x 4 grid of regions. These are
 * the unbiased modes; a bias from the adaptation, the cache's stage
 * switch, the restart of the chains or the normalisation would show here.
 *
 * Variance: each integrator renders R = 6 independent seeds (lmc: each
 * with its own bootstrap, stage 1 and chains). Per statistic the runs give
 * a mean and a standard error SE = sd / sqrt(R); lmc's mean must lie within
 * 6 sqrt(SE_lmc^2 + SE_bdpt^2) of bdpt's. The difference over its
 * estimated standard error is roughly Student t with about 10 degrees of
 * freedom (Welch), P(|t| > 6) ~ 1.3e-4 per check; over 2 scenes x 5 modes
 * x 17 statistics = 170 checks a false alarm has a chance of about 2%.
 * Equal effort: --spp 128 for each (lmc: mutations per pixel, stage 1 of
 * cache included); lmc's bootstrap is fixed at 131072 paths (it would
 * otherwise dominate the time at this resolution). lmc runs with the
 * default --direct separate: pt renders the paths of one and two segments
 * (128 spp), the chains the longer ones.
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

#define RUNS 6
#define MODES 5 /* lmc diminish and cache on mmlt states, cache on pt states, h2mc on bdpt and mmlt states */
#define GRID 4
#define N_STATS (GRID * GRID + 1)

static int g_checks;

/* Mean and SE over RUNS of the region means (index GRID*GRID: the image). */
static void run_stats(const scene *s, const char *integrator, const char *adapt, const char *states,
                      double mean[N_STATS], double se[N_STATS]) {
  render_settings rs = s->settings;
  snprintf(rs.integrator, sizeof rs.integrator, "%s", integrator);
  lmc_error err;
  assert_int_equal(mcmc_set(&rs, "adapt", adapt, &err), LMC_OK);
  if (states) assert_int_equal(mcmc_set(&rs, "states", states, &err), LMC_OK);
  rs.spp = 128;
  rs.set |= SET_SPP;
  assert_int_equal(mcmc_set(&rs, "bootstrap", "131072", &err), LMC_OK); /* b to a few percent: its error is part of each run's, so of the SE */
  rs.time_limit = 0.0;
  rs.threads = 2;
  rs.quiet = 1;
  region_runs(s, &rs, RUNS, 500, GRID, mean, se);
}

static void check_scene(const char *folder) {
  scene *s = load_source_scene("scenes/%s/scene.xml", folder);
  camera_set_resolution(&s->cam, 24, 18);

  double ref[N_STATS], ref_se[N_STATS];
  run_stats(s, "bdpt", "none", NULL, ref, ref_se);
  const char *const modes[MODES] = {"diminish", "cache", "cache", "none", "none"};
  const char *const states[MODES] = {"mmlt", "mmlt", "pt", "bdpt", "mmlt"};
  const char *names[MODES] = {"diminish", "cache", "cache, pt states", "bdpt states",
                              "mmlt states"};
  const char *integ[MODES] = {"lmc", "lmc", "lmc", "h2mc", "h2mc"};
  for (int i = 0; i < MODES; i++) {
    double m[N_STATS], se[N_STATS];
    run_stats(s, integ[i], modes[i], states[i], m, se);
    char what[128];
    snprintf(what, sizeof what, "%s %s %s", folder, integ[i], names[i]);
    g_checks += region_agree(what, GRID, m, se, ref, ref_se, 6.0);
  }
  scene_destroy(s);
}

static void test_ring_caustics(void **state) {
  (void)state;
  check_scene("ring-caustics");
}

static void test_ring_caustics_glass(void **state) {
  (void)state;
  check_scene("ring-caustics-glass");
}

static void test_count(void **state) {
  (void)state;
  assert_int_equal(g_checks, 2 * MODES * N_STATS);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_ring_caustics),
      cmocka_unit_test(test_ring_caustics_glass),
      cmocka_unit_test(test_count),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
