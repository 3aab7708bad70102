/*
 * test_mut_hslt_slow.c: the one-step invariance test of HSLT's
 * half-vector perturbation (test_pathspace.c states the statistic; the
 * move as a kernel of its own, a path it does not apply to stays) on the
 * scenes of mut_manifold_test.h: E D G G L through the rough sphere under
 * the point light and the sky, E D S S L under the small area light (no
 * half vector drawn: S vertices), and E D D L and E D D D L over the
 * floor and the diffuse wall (`wall`: a diffuse vertex in the walked
 * chain, its half vector drawn); and the control it must reject: the
 * chain's generalized geometry term G left out of the density on `wall`
 * (the same draws with the right density pass). The exact checks of the
 * move are test_mut_hslt.c's.
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
} inv_cases[] = {{R_POINT, 4, 16000000},
                 {R_SKY, 4, 6000000},
                 {AREA, 4, 6000000},
                 {WALL, 3, 3000000},
                 {WALL, 4, 6000000}};

static void test_invariance(void **state) {
  hfixture *fx = *state;
  int checked = 0;
  for (size_t c = 0; c < sizeof inv_cases / sizeof inv_cases[0]; c++) {
    ps_inv *r = invariance_of(fx->sc[inv_cases[c].scene], 1, inv_cases[c].k_only, 81 + c, 1.0, 1.0,
                              inv_cases[c].n);
    print_message("%s (length %d): %d samples, %d moved, %d bins, min p %.3g (level %.3g)\n",
                  name_of(inv_cases[c].scene), inv_cases[c].k_only, r->samples, r->moved, r->bins,
                  r->min_p, r->level);
    assert_true(r->samples >= 20000 && r->moved >= 2000 && r->bins >= 20);
    assert_true(r->min_p >= r->level);
    checked++;
    free(r);
  }
  assert_int_equal(checked, 5);
}

static void test_invariance_detects_bias(void **state) {
  hfixture *fx = *state;
  /* The diffuse chain vertex's factor |det dc / dA| left out. */
  ps_inv *r = invariance_of(fx->sc[WALL], 1, 3, 84, 1.0, 0.0, 3000000);
  print_message(
      "wall (length 3), the chain vertices' factors left out: %d samples, %d moved, %d bins, min p "
      "%.3g (level %.3g)\n",
      r->samples, r->moved, r->bins, r->min_p, r->level);
  assert_true(r->samples >= 20000 && r->moved >= 2000 && r->bins >= 20);
  assert_true(r->min_p < r->level);
  free(r);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_invariance),
      cmocka_unit_test(test_invariance_detects_bias),
  };
  return cmocka_run_group_tests(tests, ext_setup, ext_teardown);
}
