/*
 * test_mmlt_moves_slow.c: mmlt with its moves through the inverse path
 * sampler (src/lmc/states/mmlt_jump.h) on the analytic scenes, as
 * test_mcmc_analytic.c checks every MCMC integrator (analytic_check.h: R
 * = 6 seeds, each image group's mean within 8 of its standard errors of
 * the exact value, P(|t_5| > 8) = 5e-4 per check, about 3% over these
 * 63): with reversible jumps (--technique-jump 0.5) the furnace, the
 * diffuse sphere's two groups and the mask's three (whose pass-through is
 * a delta lobe no connection may end on); with the fused path
 * perturbations too (--path-mutations 0.3) the sphere and the mask, on
 * the mmlt states and on the bdpt states with pssmlt and with lmc (its
 * Langevin steps in the same chain); and the jumps do move the
 * chains (one seed's images with and without differ). Slow: not part of
 * the sanitizer's run, whose unit tests of the moves are test_mmlt_jump's.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "lmc/mcmc.h"
#include "analytic_check.h"

/* mmlt with reversible jumps between strategies (--technique-jump, half
 * of the mutations that are not large steps): the furnace, the sphere's
 * two groups and the mask's three (whose pass-through is a delta lobe no
 * connection may end on); with the fused path perturbations too
 * (--path-mutations 0.3) the sphere and the mask; and the jumps do move
 * the chains (one seed's images with and without differ). */
static void test_mmlt_jump(void **state) {
  (void)state;
  rgb one = rgb_gray(1.0);
  rgb e[2] = {rgb_make(1.0, 2.0, 4.0), rgb_make(0.5, 1.0, 2.0)};
  rgb em[3] = {rgb_make(1.0, 2.0, 4.0), rgb_make(0.875, 1.5, 2.5), rgb_make(1.0, 2.0, 4.0)};
  g_jump = "0.5";
  check_scene("furnace.xml", "mmlt", 16, &one, 1, 0.003);
  check_scene("diffuse_sphere.xml", "mmlt", 16, e, 2, 0.0);
  check_scene("mask.xml", "mmlt", 16, em, 3, 0.0);
  /* The fused path perturbations with the jumps. */
  g_perturb = "0.3";
  check_scene("diffuse_sphere.xml", "mmlt", 16, e, 2, 0.0);
  check_scene("mask.xml", "mmlt", 16, em, 3, 0.0);
  /* The same moves on the bdpt states (pssmlt's): the path moves change
   * the path's length there. */
  check_scene("diffuse_sphere.xml", "pssmlt", 16, e, 2, 0.0);
  check_scene("mask.xml", "pssmlt", 16, em, 3, 0.0);
  /* ... and lmc's Langevin steps among them (its default states too). */
  check_scene("diffuse_sphere.xml", "lmc", 16, e, 2, 0.0);
  check_scene("mask.xml", "lmc", 16, em, 3, 0.0);
  g_perturb = NULL;
  film fj, fn;
  render_seed7("furnace.xml", "mmlt", &fj);
  g_jump = NULL;
  render_seed7("furnace.xml", "mmlt", &fn);
  assert_films_differ(&fj, &fn);
}

static void test_count(void **state) {
  (void)state;
  /* jumps: furnace 1, sphere 2, mask 3 groups; with perturbations: sphere
   * 2, mask 3, on the mmlt states and with pssmlt and lmc on the bdpt
   * states; 3 channels each. */
  assert_int_equal(g_checks, (1 + 2 + 3 + 3 * (2 + 3)) * 3);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_mmlt_jump),
      cmocka_unit_test(test_count),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
