/*
 * test_mut_manifold.c: the manifold perturbation on smooth specular chains
 * (src/lmc/path/mut_manifold.c) on four small scenes, each with a glass
 * sphere (two refractions) over a diffuse floor: lit by a point light
 * (`point`: E D S S L, the chain's start a point), a small area light
 * (`area`: the start a point on the light with its normal), a constant
 * environment (`sky`: the start a direction at infinity), and `mirror`,
 * where a mirror wall shows the floor (E S D S S L: the camera's chain
 * retraced through a reflection before the walk). Paths of 1 .. KMAX = 5
 * segments from the whole-path sampler.
 *
 *  - forms: the paths the move applies to have its form (x_b the first
 *    non-delta vertex, delta vertices up to x_c) and the move applies to
 *    enough of them.
 *  - reverse and balance: on random pairs, every cache of y against a
 *    fresh evaluation; the move from y through x's raster point gives back
 *    x (vertices to 1e-6 of the scene's size, f to 1e-5); the reverse walk
 *    returns; detailed balance f(x) T(x -> y) a(x -> y) = f(y) T(y -> x)
 *    a(y -> x), the reverse ratio computed anew from y, to 1e-9.
 *  - invariance / invariance_detects_bias: test_pathspace.c's one-step
 *    invariance test (the statistic is stated there) with the move as a
 *    kernel of its own (a path it does not apply to stays), and with the
 *    chain's Jacobian J left out, which it must reject.
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

#include "chi2.h"
#include "lmc/path/mut_bidir.h"
#include "lmc/path/mut_manifold.h"
#include "pathspace_test.h"
#include "test_util.h"

#define KMAX 5

#define SCENE_HEAD                                                                              \
  "<scene version=\"0.6.0\">\n"                                                                 \
  "  <sensor type=\"perspective\">\n"                                                           \
  "    <float name=\"fov\" value=\"40\"/>\n"                                                    \
  "    <transform name=\"toWorld\"><lookat origin=\"0, 3, 3\" target=\"0, 0, 0\" up=\"0, 1, "  \
  "0\"/></transform>\n"                                                                         \
  "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" " \
  "value=\"24\"/><rfilter type=\"box\"/></film>\n"                                              \
  "  </sensor>\n"                                                                               \
  "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>"     \
  "<scale x=\"2\" y=\"1\" z=\"2\"/></transform>"                                                \
  "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.7\"/></bsdf></shape>\n"          \
  "  <shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0.8\" z=\"0\"/><float "         \
  "name=\"radius\" value=\"0.5\"/>"                                                             \
  "<bsdf type=\"dielectric\"><float name=\"intIOR\" value=\"1.5\"/></bsdf></shape>\n"

static const char *point_xml = SCENE_HEAD
    "  <emitter type=\"point\"><point name=\"position\" x=\"0.2\" y=\"2\" z=\"0\"/>"
    "<rgb name=\"intensity\" value=\"8, 8, 7\"/></emitter>\n"
    "</scene>\n";

static const char *area_xml = SCENE_HEAD
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/>"
    "<scale value=\"0.2\"/><translate x=\"0.2\" y=\"2\"/></transform>"
    "<emitter type=\"area\"><rgb name=\"radiance\" value=\"40\"/></emitter></shape>\n"
    "</scene>\n";

static const char *sky_xml = SCENE_HEAD
    "  <emitter type=\"constant\"><rgb name=\"radiance\" value=\"1, 1, 1\"/></emitter>\n"
    "</scene>\n";

static const char *mirror_xml = SCENE_HEAD
    "  <shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"2\" y=\"1.5\" z=\"1\"/>"
    "<rotate x=\"1\" angle=\"25\"/><translate x=\"0\" y=\"1\" z=\"-1.5\"/></transform>"
    "<bsdf type=\"conductor\"/></shape>\n"
    "  <emitter type=\"point\"><point name=\"position\" x=\"0.2\" y=\"2\" z=\"0\"/>"
    "<rgb name=\"intensity\" value=\"8, 8, 7\"/></emitter>\n"
    "</scene>\n";

enum { POINT = 0, AREA, SKY, MIRROR, N_SCENES };
static const char *const scene_names[N_SCENES] = {"point", "area", "sky", "mirror"};

typedef struct fixture {
  scene *sc[N_SCENES];
} fixture;

static int setup(void **state) {
  fixture *fx = calloc(1, sizeof *fx);
  fx->sc[POINT] = try_load_scene_text(point_xml, "mm_point");
  fx->sc[AREA] = try_load_scene_text(area_xml, "mm_area");
  fx->sc[SKY] = try_load_scene_text(sky_xml, "mm_sky");
  fx->sc[MIRROR] = try_load_scene_text(mirror_xml, "mm_mirror");
  for (int q = 0; q < N_SCENES; q++)
    if (!fx->sc[q]) return -1;
  *state = fx;
  return 0;
}

static int teardown(void **state) {
  fixture *fx = *state;
  for (int q = 0; q < N_SCENES; q++) scene_destroy(fx->sc[q]);
  free(fx);
  return 0;
}

typedef struct movers {
  ps_context ctx;
  mut_bidir mb;
  mut_perturb mp;
  mut_manifold mm;
} movers;

static void movers_init(movers *mv, const scene *sc) {
  ps_test_context(sc, KMAX, &mv->ctx);
  mut_bidir_init(&mv->mb, &mv->ctx);
  mut_perturb_init(&mv->mp, &mv->ctx);
  mut_manifold_init(&mv->mm, &mv->ctx, &mv->mp);
}

/* A path with f > 0 that the move applies to, or 0 after many tries. */
static int draw_state(const movers *mv, rng *r, ps_path *x) {
  for (int tries = 0; tries < 2000000; tries++) {
    int k = 1 + (int)(rng_uniform(r) * KMAX);
    if (mut_bidir_sample_whole(&mv->mb, r, k, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) continue;
    if (mut_manifold_applies(&mv->mm, x)) return 1;
  }
  return 0;
}

/* ---- Forms ------------------------------------------------------------------- */

static void test_forms(void **state) {
  fixture *fx = *state;
  static const int min_applies[N_SCENES] = {200, 200, 200, 50};
  for (int q = 0; q < N_SCENES; q++) {
    movers mv;
    movers_init(&mv, fx->sc[q]);
    ps_path *x = malloc(sizeof *x);
    rng r;
    rng_seed(&r, 11 + q, 1);
    int drawn = 0, applies = 0, b_gt_1 = 0, inf = 0;
    for (int i = 0; i < 200000; i++) {
      int k = 1 + (int)(rng_uniform(&r) * KMAX);
      if (mut_bidir_sample_whole(&mv.mb, &r, k, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) continue;
      drawn++;
      int b, c;
      if (!mut_manifold_form(&mv.mm, x, &b, &c)) continue;
      applies++;
      b_gt_1 += b > 1;
      for (int j = 1; j < b; j++) assert_true(x->x[j].delta);
      assert_false(x->x[b].delta);
      assert_true(c >= b + 2 && c <= x->k);
      for (int j = b + 1; j < c; j++) assert_true(x->x[j].delta);
      assert_true(c == x->k || !x->x[c].delta);
      inf += c == x->k && x->x[c].inf;
    }
    print_message("%s: %d paths, the move applies to %d (%d with x_b past a specular chain, %d "
                  "from a direction)\n",
                  scene_names[q], drawn, applies, b_gt_1, inf);
    assert_true(applies >= min_applies[q]);
    if (q == MIRROR) assert_true(b_gt_1 >= 20);
    if (q == SKY) assert_true(inf >= 100);
    free(x);
  }
}

/* ---- Reverse moves, caches, detailed balance ------------------------------------ */

static void check_pairs(const scene *sc, uint64_t seed, int n, int *OUT_reverse,
                        int *OUT_balance, double *OUT_acc) {
  movers mv;
  movers_init(&mv, sc);
  ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y), *z = malloc(sizeof *z);
  rng r;
  rng_seed(&r, seed, 3);
  double acc = 0.0;
  int n_acc = 0;
  mut_manifold_tally t = {0, 0, 0, 0};
  for (int i = 0; i < n; i++) {
    if (!draw_state(&mv, &r, x)) fail();
    double ratio;
    if (!mut_manifold_propose(&mv.mm, &r, x, y, &ratio, NULL, &t)) continue;
    assert_true(ps_test_caches_fresh(&mv.ctx, y, z));
    if (!(y->lum > 0.0) || !(ratio > 0.0)) continue;
    /* The move from y through x's raster point gives back x. */
    assert_true(mut_manifold_generate(&mv.mm, y, x->rx, x->ry, z, NULL, NULL));
    for (int j = 0; j <= x->k; j++) {
      double d = v3_len(v3_sub(z->x[j].v.p, x->x[j].v.p));
      if (!(d < 1e-6 * sc->radius))
        print_message("vertex %d of %d back at %.3g\n", j, x->k, d);
      assert_true(d < 1e-6 * sc->radius);
    }
    assert_true(rel_close(z->lum, x->lum, 1e-5));
    assert_true(mut_manifold_reversible(&mv.mm, y, x, NULL, NULL));
    (*OUT_reverse)++;
    /* Detailed balance, T and the reverse ratio from y anew. */
    double tf = mut_manifold_density(&mv.mm, x, y), tr = mut_manifold_density(&mv.mm, y, x);
    assert_true(tf > 0.0 && tr > 0.0);
    double ratio_rev = x->lum * tf / (y->lum * tr);
    double lhs = fmin(1.0, ratio), rhs = y->lum * tr / (x->lum * tf) * fmin(1.0, ratio_rev);
    if (!rel_close(lhs, rhs, 1e-9)) print_message("balance %.17g vs %.17g\n", lhs, rhs);
    assert_true(rel_close(lhs, rhs, 1e-9));
    (*OUT_balance)++;
    acc += fmin(1.0, ratio);
    n_acc++;
  }
  *OUT_acc = n_acc > 0 ? acc / n_acc : 0.0;
  print_message("  walks %lld, reached %lld, %.2f projections each, %lld refused as irreversible\n",
                (long long)t.walks, (long long)t.walked,
                t.walks > 0 ? (double)t.traces / (double)t.walks : 0.0, (long long)t.irreversible);
  assert_true(t.walks > 0 && t.walked >= t.walks / 2);
  free(x), free(y), free(z);
}

static void test_reverse_and_balance(void **state) {
  fixture *fx = *state;
  for (int q = 0; q < N_SCENES; q++) {
    int rev = 0, bal = 0;
    double acc;
    check_pairs(fx->sc[q], 31 + q, 3000, &rev, &bal, &acc);
    print_message("%s: %d reversed, %d balanced; mean acceptance %.3f\n", scene_names[q], rev, bal,
                  acc);
    assert_true(rev >= 1000 && bal >= 1000 && acc > 0.2);
  }
}

/* ---- One-step invariance (test_pathspace.c states the test) ------------------------ */

#define INV_COLS 8
#define INV_ROWS 12
#define INV_BINS (KMAX * INV_COLS * INV_ROWS)
_Static_assert(INV_BINS <= PS_INV_MAX_BINS, "the bins fit ps_inv");

static int inv_bin(const scene *sc, const ps_path *x) {
  int cx = (int)(x->rx * INV_COLS / sc->cam.width), cy = (int)(x->ry * INV_ROWS / sc->cam.height);
  cx = cx < 0 ? 0 : cx >= INV_COLS ? INV_COLS - 1 : cx;
  cy = cy < 0 ? 0 : cy >= INV_ROWS ? INV_ROWS - 1 : cy;
  return ((x->k - 1) * INV_ROWS + cy) * INV_COLS + cx;
}

/* Weighted whole paths of length k_only (their weight C(x) / q(x), q the
 * sampler's density), each moved once. */
static ps_inv *invariance(const scene *sc, int k_only, uint64_t seed, double power, int n) {
  movers mv;
  movers_init(&mv, sc);
  mv.mm.test_jac_power = power;
  /* Larger moves than the defaults: more power against a wrong density. */
  mv.mp.r1 *= 4.0, mv.mp.r2 *= 4.0;
  ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y);
  ps_inv *res = calloc(1, sizeof *res);
  rng r;
  rng_seed(&r, seed, 5);
  for (int i = 0; i < n; i++) {
    if (mut_bidir_sample_whole(&mv.mb, &r, k_only, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) continue;
    double q = mut_bidir_whole_pdf(&mv.mb, x, 0);
    assert_true(q > 0.0);
    double w = x->lum / q, ratio = 0.0;
    res->samples++;
    int moved = mut_manifold_applies(&mv.mm, x) &&
                mut_manifold_propose(&mv.mm, &r, x, y, &ratio, NULL, NULL) &&
                rng_uniform(&r) < ratio;
    int b0 = inv_bin(sc, x), b1 = moved ? inv_bin(sc, y) : b0;
    ps_inv_add(res, w, b0, b1);
  }
  ps_inv_finish(res);
  free(x), free(y);
  return res;
}

/* E D S S L and E S D S S L: lengths 4 and 5 alone (pi restricted to a
 * set the kernel never leaves is invariant under it too). */
static const struct {
  int scene, k_only, n;
} inv_cases[] = {{POINT, 4, 6000000}, {AREA, 4, 3000000}, {SKY, 4, 3000000}, {MIRROR, 5, 4000000}};

static void test_invariance(void **state) {
  fixture *fx = *state;
  for (size_t c = 0; c < sizeof inv_cases / sizeof inv_cases[0]; c++) {
    ps_inv *r = invariance(fx->sc[inv_cases[c].scene], inv_cases[c].k_only, 71 + c, 1.0,
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
  fixture *fx = *state;
  int controls = 0;
  for (size_t c = 0; c < sizeof inv_cases / sizeof inv_cases[0]; c++) {
    if (inv_cases[c].scene == MIRROR) continue;
    controls++;
    ps_inv *r = invariance(fx->sc[inv_cases[c].scene], inv_cases[c].k_only, 71 + c, 0.0,
                           inv_cases[c].n);
    print_message("%s, J left out: %d samples, %d moved, %d bins, min p %.3g (level %.3g)\n",
                  scene_names[inv_cases[c].scene], r->samples, r->moved, r->bins, r->min_p,
                  r->level);
    assert_true(r->samples >= 20000 && r->moved >= 2000 && r->bins >= 20);
    assert_true(r->min_p < r->level);
    free(r);
  }
  assert_int_equal(controls, 3);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_forms),
      cmocka_unit_test(test_reverse_and_balance),
      cmocka_unit_test(test_invariance),
      cmocka_unit_test(test_invariance_detects_bias),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
