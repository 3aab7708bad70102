/*
 * test_mut_manifold_slow.c: the manifold perturbation's one-step
 * invariance test on the seven scenes of mut_manifold_test.h (the exact
 * checks of the move are test_mut_manifold.c's).
 *
 *  - invariance / invariance_detects_bias: test_pathspace.c's one-step
 *    invariance test (the statistic is stated there) with the move as a
 *    kernel of its own (a path it does not apply to stays), on all seven
 *    scenes and the sky scenes' sky form, and the controls it must reject:
 *    on the three smooth scenes with a curved chain the chain's
 *    generalized geometry term G left out, on the rough sky's sky form the
 *    G vertices' factors.
 *  - rough controls: the controls on the other rough scenes (G chains,
 *    walked with their half vectors held): through narrow glossy lobes a
 *    path moves less between x and y, so a wrong density shows only with
 *    more samples. Each control must be rejected at the Sidak level on
 *    its bins: the chain's generalized geometry term G left out on `rough
 *    point` and `rough sky`, and the G vertices' factors |det dc_i /
 *    dA_{i+1}| left out on `rough mirror`, whose camera-side chain is
 *    retraced about a G vertex's half vector. The same draws with the
 *    right densities pass (the control of the control).
 *  - area light form: the sky form reaching an area light (E S L, E G L on
 *    the lit mirrors of mut_manifold_test.h), its invariance and its
 *    control (the light's area factor left out).
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

/* E D S S L and E S D S S L: lengths 4 and 5 alone (pi restricted to a
 * set the kernel never leaves is invariant under it too). */
static const struct {
  int scene, k_only, n;
} inv_cases[] = {{POINT, 4, 6000000},   {AREA, 4, 3000000},    {SKY, 4, 3000000},
                 {MIRROR, 5, 4000000},  {R_POINT, 4, 4000000}, {R_SKY, 4, 2000000},
                 {R_MIRROR, 5, 3000000}, {SKY, 3, 3000000},    {R_SKY, 3, 2000000}};

static void test_invariance(void **state) {
  hfixture *fx = *state;
  for (size_t c = 0; c < sizeof inv_cases / sizeof inv_cases[0]; c++) {
    ps_inv *r = invariance(fx->sc[inv_cases[c].scene], inv_cases[c].k_only, 71 + c, 1.0, 1.0,
                           inv_cases[c].n);
    print_message("%s: %d samples, %d moved, %d bins, min p %.3g (level %.3g)\n",
                  scene_names[inv_cases[c].scene], r->samples, r->moved, r->bins, r->min_p,
                  r->level);
    assert_true(r->samples >= 20000 && r->moved >= 2000 && r->bins >= 20);
    assert_true(r->min_p >= r->level);
    free(r);
  }
}

static void test_invariance_detects_bias(void **state) {
  hfixture *fx = *state;
  int controls = 0;
  for (size_t c = 0; c < sizeof inv_cases / sizeof inv_cases[0]; c++) {
    /* G left out on the smooth scenes with a curved chain behind x_b; the
     * G vertices' factors on the rough sky's sky form. */
    int sky_form = inv_cases[c].scene == R_SKY && inv_cases[c].k_only == 3;
    if (!sky_form && (inv_cases[c].scene == MIRROR || inv_cases[c].scene >= R_POINT ||
                      inv_cases[c].k_only == 3))
      continue;
    controls++;
    ps_inv *r = invariance(fx->sc[inv_cases[c].scene], inv_cases[c].k_only, 71 + c,
                           sky_form ? 1.0 : 0.0, sky_form ? 0.0 : 1.0, inv_cases[c].n);
    print_message("%s (length %d), %s left out: %d samples, %d moved, %d bins, min p %.3g "
                  "(level %.3g)\n",
                  scene_names[inv_cases[c].scene], inv_cases[c].k_only,
                  sky_form ? "the G vertices' factors" : "G", r->samples, r->moved, r->bins,
                  r->min_p, r->level);
    assert_true(r->samples >= 20000 && r->moved >= 2000 && r->bins >= 20);
    assert_true(r->min_p < r->level);
    free(r);
  }
  assert_int_equal(controls, 4); /* the other rough scenes': test_rough_controls */
}

static const struct {
  int scene, k_only, n;
  double power, glossy_power; /* the wrong densities */
} controls[] = {{R_POINT, 4, 16000000, 0.0, 1.0},
                {R_SKY, 4, 4000000, 0.0, 1.0},
                {R_MIRROR, 5, 8000000, 1.0, 0.0}};

static void test_rough_controls(void **state) {
  hfixture *fx = *state;
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

/* The sky form reaching an area light (E S L, E G L on the lit mirrors):
 * invariance, and the control it must reject on both, the light's area
 * factor |cos| / d^2 left out (the same draws with the right densities
 * pass). (The G vertex's factor hardly changes across a flat rough
 * mirror: left out, it is not seen on these draws.) */
static void test_area_light_form(void **state) {
  hfixture *fx = *state;
  int checked = 0;
  for (int q = LIT_MIRROR; q <= LIT_R_MIRROR; q++) {
    const scene *sc = fx->sc[q];
    int n = q == LIT_R_MIRROR ? 6000000 : 1500000; /* the rough lobe moves paths less */
    ps_inv *right = invariance(sc, 2, 191 + q, 1.0, 1.0, n);
    ps_inv *wrong = invariance(sc, 2, 191 + q, 0.0, 1.0, n);
    print_message("%s: right %d samples, %d moved, %d bins, min p %.3g; the light's area factor "
                  "left out: %d moved, min p %.3g (level %.3g)\n",
                  name_of(q), right->samples, right->moved, right->bins, right->min_p,
                  wrong->moved, wrong->min_p, wrong->level);
    assert_true(right->samples >= 20000 && right->moved >= 2000 && right->bins >= 20);
    assert_true(wrong->moved >= 2000 && wrong->bins >= 20);
    assert_true(right->min_p >= right->level);
    assert_true(wrong->min_p < wrong->level);
    checked++;
    free(right), free(wrong);
  }
  assert_int_equal(checked, 2);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_invariance),
      cmocka_unit_test(test_invariance_detects_bias),
      cmocka_unit_test(test_rough_controls),
      cmocka_unit_test(test_area_light_form),
  };
  return cmocka_run_group_tests(tests, ext_setup, ext_teardown);
}
