/*
 * test_mut_manifold_slow.c: the negative controls of the manifold
 * perturbation's one-step invariance test on the rough scenes of
 * mut_manifold_test.h (G chains, walked with their half vectors held),
 * which test_mut_manifold.c runs without them: through narrow glossy
 * lobes a path moves less between x and y, so a wrong density shows only
 * with more samples. Each control must be rejected at the Sidak level on
 * its bins: the chain's generalized geometry term G left out on `rough
 * point` and `rough sky`, and the G vertices' factors |det dc_i / dA_{i+1}|
 * left out on `rough mirror`, whose camera-side chain is retraced about a
 * G vertex's half vector. The same draws with the right densities pass
 * (the control of the control).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "lmc/path/mut_manifold.h" /* (tests/CMakeLists.txt links by the includes) */
#include "mut_manifold_test.h"
#include "test_util.h"

static const struct {
  int scene, k_only, n;
  double power, glossy_power; /* the wrong densities */
} controls[] = {{R_POINT, 4, 16000000, 0.0, 1.0},
                {R_SKY, 4, 4000000, 0.0, 1.0},
                {R_MIRROR, 5, 8000000, 1.0, 0.0}};

static void test_rough_controls(void **state) {
  fixture *fx = *state;
  int checked = 0;
  for (size_t c = 0; c < sizeof controls / sizeof controls[0]; c++) {
    const scene *sc = fx->sc[controls[c].scene];
    ps_inv *right = invariance(sc, controls[c].k_only, 171 + c, 1.0, 1.0, controls[c].n);
    ps_inv *wrong = invariance(sc, controls[c].k_only, 171 + c, controls[c].power,
                               controls[c].glossy_power, controls[c].n);
    print_message("%s: right %d samples, %d moved, min p %.3g; %s left out: %d moved, min p %.3g "
                  "(level %.3g)\n",
                  scene_names[controls[c].scene], right->samples, right->moved, right->min_p,
                  controls[c].power == 0.0 ? "G" : "the G vertices' factors", wrong->moved,
                  wrong->min_p, wrong->level);
    assert_true(right->samples >= 100000 && right->moved >= 5000 && right->bins >= 20);
    assert_true(wrong->moved >= 5000 && wrong->bins >= 20);
    assert_true(right->min_p >= right->level);
    assert_true(wrong->min_p < wrong->level);
    checked++;
    free(right), free(wrong);
  }
  assert_int_equal(checked, 3);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_rough_controls),
  };
  return cmocka_run_group_tests(tests, mm_setup, mm_teardown);
}
