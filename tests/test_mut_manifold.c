/*
 * test_mut_manifold.c: the manifold perturbation (src/lmc/path/mut_manifold.c)
 * on the seven scenes of mut_manifold_test.h, each a sphere of glass over a
 * diffuse floor, smooth (S chains) or rough (alpha 0.05: G chains, walked
 * with their half vectors held): lit by a point light (`point`, `rough
 * point`: E D S S L, the chain's start a point), a small area light
 * (`area`: a point on the light with its normal), a constant environment
 * (`sky`, `rough sky`: a direction at infinity; the torus's form), and with
 * a mirror wall that shows the floor (`mirror`, `rough mirror`: E S D S S
 * L, the camera's chain retraced through the reflection, about its half
 * vector when rough). Paths of 1 .. KMAX = 5 segments from the whole-path
 * sampler.
 *
 *  - forms: mf_path_chain_fits says what mf_chain_from_path would on
 *    every range of every path drawn; the paths the move applies to have
 *    its form (x_b the first
 *    vertex neither S nor G, S or G vertices up to x_c), G vertices in
 *    every rough scene's chains and none in the smooth ones', and the move
 *    applies to enough of them.
 *  - dir_jacobian: mf_half_vector_dir_jacobian (the sky form's density at
 *    a G vertex) against central differences.
 *  - reverse and balance: on random pairs, every cache of y against a
 *    fresh evaluation; the move from y through x's raster point gives back
 *    x (vertices to 1e-6 of the scene's size, f to 1e-5; 1e-3 through G
 *    vertices, whose narrow lobes feel the walk's tolerance); the reverse
 *    walk returns; detailed balance f(x) T(x -> y) a(x -> y) = f(y) T(y ->
 *    x) a(y -> x), the reverse ratio computed anew from y, to 1e-9.
 *  - the one-step invariance test of the move and its controls:
 *    test_mut_manifold_slow.c (a minute of draws in Release, three in the
 *    sanitizer build, which runs this file's exact checks only).
 * Every check is counted and the counts asserted.
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

/* ---- Forms ------------------------------------------------------------------- */


static void test_forms(void **state) {
  hfixture *fx = *state;
  static const int min_applies[N_SCENES] = {200, 200, 200, 50, 200, 200, 50};
  for (int q = 0; q < N_SCENES; q++) {
    movers mv;
    movers_init(&mv, fx->sc[q]);
    ps_path *x = malloc(sizeof *x);
    rng r;
    rng_seed(&r, 11 + q, 1);
    int drawn = 0, applies = 0, b_gt_1 = 0, inf = 0, glossy = 0, fits_checked = 0, fits_ok = 0;
    int sky = 0, lit = 0;
    for (int i = 0; i < 200000; i++) {
      int k = 1 + (int)(rng_uniform(&r) * KMAX);
      if (mut_bidir_sample_whole(&mv.mb, &r, k, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) continue;
      drawn++;
      check_chain_fits(&mv, x, 4, &fits_checked, &fits_ok);
      int b, c;
      if (!mut_manifold_form(&mv.mm, x, &b, &c)) continue;
      applies++;
      if (b == x->k) {
        /* The sky form: the camera's chain reaches the sky (or an area
         * light: test_area_light_form). */
        sky += x->x[b].inf, lit += !x->x[b].inf;
        assert_true(c == b && x->k >= 2);
        for (int j = 1; j < b; j++) assert_true(specular(&mv, x, j));
        continue;
      }
      b_gt_1 += b > 1;
      for (int j = 1; j < b; j++) assert_true(specular(&mv, x, j));
      assert_false(specular(&mv, x, b));
      assert_true(c >= b + 2 && c <= x->k);
      for (int j = b + 1; j < c; j++) assert_true(specular(&mv, x, j));
      assert_true(c == x->k || !specular(&mv, x, c));
      for (int j = 1; j < c; j++) glossy += ps_glossy(&mv.ctx, x, j);
      inf += c == x->k && x->x[c].inf;
    }
    print_message("%s: %d paths, the move applies to %d (%d with x_b past a specular chain, %d "
                  "from a direction, %d to the sky, %d to an area light)\n",
                  scene_names[q], drawn, applies, b_gt_1, inf, sky, lit);
    assert_true(applies >= min_applies[q]);
    if (q == MIRROR || q == R_MIRROR) assert_true(b_gt_1 >= 20);
    /* G vertices exactly in the rough scenes' chains. */
    if (q >= R_POINT) assert_true(glossy >= applies - sky - lit);
    else assert_int_equal(glossy, 0);
    if (q == SKY || q == R_SKY) assert_true(inf >= 100 && sky >= 100);
    else assert_int_equal(sky, 0);
    if (q != AREA) assert_int_equal(lit, 0); /* the only area light's scene */
    print_message("  chain forms: %d checked, %d chains\n", fits_checked, fits_ok);
    assert_true(fits_checked >= 10000 && fits_ok >= applies);
    free(x);
  }
}

/* mf_half_vector_dir_jacobian against central differences of
 * mf_half_vector_dirs over wo's tangent plane, at the G vertices of the
 * rough scenes' paths (reflections and refractions from both sides). */
static void test_dir_jacobian(void **state) {
  hfixture *fx = *state;
  int checked = 0, refract = 0;
  for (int q = R_POINT; q < N_SCENES; q++) {
    movers mv;
    movers_init(&mv, fx->sc[q]);
    ps_path *x = malloc(sizeof *x);
    rng r;
    rng_seed(&r, 91 + q, 1);
    for (int i = 0; i < 40000 && checked < 600 * (q - R_POINT + 1); i++) {
      int k = 1 + (int)(rng_uniform(&r) * KMAX);
      if (mut_bidir_sample_whole(&mv.mb, &r, k, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) continue;
      for (int j = 1; j < x->k; j++) {
        if (!ps_glossy(&mv.ctx, x, j)) continue;
        mf_vertex v;
        memset(&v, 0, sizeof v);
        const surface_hit *h = &x->x[j].v.hit;
        if (mf_path_vertex(&mv.ctx, x, j, MF_PATH_GLOSSY, &v.kind, &v.eta) != MF_OK ||
            mf_vertex_set(fx->sc[q], &v, h->mesh, h->prim, h->b1, h->b2) != MF_OK)
          continue;
        vec3 wi = ps_dir(x, j, j - 1), wo = ps_dir(x, j, j + 1);
        frame g = frame_from_z(wo);
        double e = 1e-6, J[2][2];
        for (int a = 0; a < 2; a++) {
          vec3 t = a == 0 ? g.s : g.t, cp[2], cm[2];
          double hp[2], hm[2];
          cp[0] = v3_normalize(v3_add(wo, v3_scale(t, e)));
          cm[0] = v3_normalize(v3_sub(wo, v3_scale(t, e)));
          mf_half_vector_dirs(&v, wi, cp[0], hp);
          mf_half_vector_dirs(&v, wi, cm[0], hm);
          for (int b = 0; b < 2; b++) J[b][a] = (hp[b] - hm[b]) / (2.0 * e);
        }
        double fd = fabs(J[0][0] * J[1][1] - J[0][1] * J[1][0]);
        double an = mf_half_vector_dir_jacobian(&v, wi, wo);
        if (!(fabs(fd - an) <= 1e-6 * (1.0 + an)))
          print_message("dir jacobian %.12g vs differences %.12g\n", an, fd);
        assert_true(fabs(fd - an) <= 1e-6 * (1.0 + an));
        checked++;
        refract += v.kind == MF_REFRACT;
      }
    }
    free(x);
  }
  print_message("dir jacobian: %d G vertices checked, %d refractions\n", checked, refract);
  assert_true(checked >= 1500 && refract >= 300 && checked - refract >= 300);
}

/* ---- Reverse moves, caches, detailed balance ------------------------------------ */

static void test_reverse_and_balance(void **state) {
  hfixture *fx = *state;
  for (int q = 0; q < N_SCENES; q++) {
    int rev = 0, bal = 0;
    double acc;
    check_pairs(fx->sc[q], 0, NULL, 31 + q, 3000, &rev, &bal, &acc);
    print_message("%s: %d reversed, %d balanced; mean acceptance %.3f\n", scene_names[q], rev, bal,
                  acc);
    assert_true(rev >= 1000 && bal >= 1000 && acc > 0.2);
  }
}

/* ---- The sky form reaching an area light -------------------------------------- */

/* Whether x is of the sky form with its emitter end on an area light. */
static int light_form(const mut_manifold *m, const ps_path *x) {
  int b, c;
  return mut_manifold_form(m, x, &b, &c) && b == x->k && !x->x[x->k].inf;
}

/* A path of that form with f > 0 (draw_fn), or 0 after many tries. */
static int draw_light_form(const movers *mv, const mut_manifold *m, rng *r, ps_path *x) {
  for (int tries = 0; tries < 2000000; tries++) {
    int k = 1 + (int)(rng_uniform(r) * KMAX);
    if (mut_bidir_sample_whole(&mv->mb, r, k, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) continue;
    if (light_form(m, x)) return 1;
  }
  return 0;
}

/* On the lit mirrors (E S L, E G L; a large area light on the floor seen in
 * the mirror wall): the form is found, its emitter end a point of the
 * light (not at infinity); the pairs of check_pairs drawn among those paths
 * reverse and balance (the form has no walk: the camera's chain is traced
 * to the light, its own inverse); the proposals land on the same light. */
static void test_area_light_form(void **state) {
  hfixture *fx = *state;
  int checked = 0;
  for (int q = LIT_MIRROR; q <= LIT_R_MIRROR; q++) {
    movers mv;
    movers_init(&mv, fx->sc[q]);
    ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y);
    rng r;
    rng_seed(&r, 61 + q, 1);
    int drawn = 0, lit = 0, moved = 0;
    for (int i = 0; i < 50000; i++) {
      int k = 1 + (int)(rng_uniform(&r) * KMAX);
      if (mut_bidir_sample_whole(&mv.mb, &r, k, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) continue;
      drawn++;
      if (!light_form(&mv.mm, x)) continue;
      lit++;
      for (int j = 1; j < x->k; j++) assert_true(specular(&mv, x, j));
      double ratio;
      if (!mut_manifold_propose(&mv.mm, &r, x, y, &ratio, NULL, NULL) || !(y->lum > 0.0)) continue;
      assert_true(light_form(&mv.mm, y));
      assert_int_equal(y->x[y->k].v.light, x->x[x->k].v.light);
      moved++;
    }
    print_message("%s: %d paths, %d of the form reaching the area light, %d proposals with f > 0\n",
                  name_of(q), drawn, lit, moved);
    assert_true(lit >= 100 && moved >= 50);
    int rev = 0, bal = 0;
    double acc;
    check_pairs(fx->sc[q], 0, draw_light_form, 81 + q, 400, &rev, &bal, &acc);
    print_message("%s: %d reversed, %d balanced; mean acceptance %.3f\n", name_of(q), rev, bal,
                  acc);
    assert_true(rev >= 200 && bal >= 200 && acc > 0.2);
    checked++;
    free(x), free(y);
  }
  assert_int_equal(checked, 2);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_forms),
      cmocka_unit_test(test_dir_jacobian),
      cmocka_unit_test(test_reverse_and_balance),
      cmocka_unit_test(test_area_light_form),
  };
  return cmocka_run_group_tests(tests, ext_setup, ext_teardown);
}
