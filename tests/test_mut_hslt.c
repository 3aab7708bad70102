/*
 * test_mut_hslt.c: HSLT's half-vector perturbation (mut_manifold.h,
 * mut_manifold_init_hslt) on the seven scenes of mut_manifold_test.h and
 * an eighth, `wall`: the rough glass sphere over the diffuse floor with a
 * diffuse wall behind it, lit by the small area light, whose paths E D D L
 * hold a diffuse vertex in the chain the move walks.
 *
 *  - forms: mf_path_chain_fits says what mf_chain_from_path would under
 *    every combination of the chain flags, MF_PATH_ANY included; the
 *    paths the move applies to have its form (x_1 .. x_{b-1} S, x_b not,
 *    x_c the emitter end, at least one chain vertex between), and the
 *    wall's chains hold diffuse vertices.
 *  - reverse and balance: on random pairs, every cache of y against a
 *    fresh evaluation; the move from y through x's raster point and x's
 *    half vectors gives back x (vertices to 1e-6 of the scene's size); the
 *    reverse walk returns; detailed balance f(x) T(x -> y) a(x -> y) =
 *    f(y) T(y -> x) a(y -> x), the reverse ratio computed anew, to 1e-9.
 *  - jacobian: the change of measure the density holds, W H pdf_cam(y_1)
 *    Phi(y) / G(y) (mut_manifold.h), against central differences of the
 *    map from (raster point, half vectors) to the path's vertices in the
 *    area measure (each vertex on its triangle's plane), on chains without
 *    S vertices: |det| of the differences times the density is 1 to 1e-3.
 *  - the one-step invariance test and its control: test_mut_hslt_slow.c.
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
  int total_diffuse = 0;
  for (int q = 0; q <= WALL; q++) {
    movers mv;
    movers_init(&mv, fx->sc[q]);
    ps_path *x = malloc(sizeof *x);
    rng r;
    rng_seed(&r, 211 + q, 1);
    int drawn = 0, applies = 0, fits_checked = 0, fits_ok = 0, diffuse = 0, b_gt_1 = 0;
    for (int i = 0; i < 60000; i++) {
      int k = 1 + (int)(rng_uniform(&r) * KMAX);
      if (mut_bidir_sample_whole(&mv.mb, &r, k, x) != MUT_BIDIR_OK || !(x->lum > 0.0)) continue;
      drawn++;
      check_chain_fits(&mv, x, 8, &fits_checked, &fits_ok);
      int b, c;
      if (!mut_manifold_form(&mv.mh, x, &b, &c)) continue;
      applies++;
      b_gt_1 += b > 1;
      for (int j = 1; j < b; j++) assert_true(x->x[j].delta);
      assert_false(x->x[b].delta);
      assert_true(c == x->k && c >= b + 2);
      for (int j = b + 1; j < c; j++) {
        mf_kind kind;
        double eta;
        assert_int_equal(mf_path_vertex(&mv.ctx, x, j, MF_PATH_ANY, &kind, &eta), MF_OK);
        diffuse += !x->x[j].delta && !ps_glossy(&mv.ctx, x, j);
      }
      /* The targets are the half vectors, inside the unit disk. */
      double h[2 * PS_MAX_VERTICES];
      assert_true(mut_manifold_half_vectors(&mv.mh, x, h));
      for (int j = b + 1; j < c; j++)
        assert_true(h[2 * j] * h[2 * j] + h[2 * j + 1] * h[2 * j + 1] < 1.0);
    }
    print_message(
        "%s: %d paths, HSLT applies to %d (%d past a specular chain), %d diffuse chain "
        "vertices; %d chain forms checked\n",
        name_of(q), drawn, applies, b_gt_1, diffuse, fits_checked);
    assert_true(applies >= 50 && fits_checked >= 10000);
    if (q == MIRROR) assert_true(b_gt_1 >= 10);
    total_diffuse += diffuse;
    if (q == WALL) assert_true(diffuse >= 100);
    free(x);
  }
  assert_true(total_diffuse >= 100);
}

/* ---- Reverse moves, caches, detailed balance ------------------------------------ */

static void test_reverse_and_balance(void **state) {
  hfixture *fx = *state;
  static const int scenes[] = {POINT, AREA, SKY, R_POINT, R_SKY, R_MIRROR, WALL};
  int n_scenes = 0;
  for (size_t s = 0; s < sizeof scenes / sizeof scenes[0]; s++) {
    int q = scenes[s], rev = 0, bal = 0;
    double acc;
    check_pairs(fx->sc[q], 1, NULL, 331 + q, 1500, &rev, &bal, &acc);
    print_message("%s: %d reversed, %d balanced; mean acceptance %.3f\n", name_of(q), rev, bal,
                  acc);
    assert_true(rev >= 200 && bal >= 200 && acc > 0.05);
    n_scenes++;
  }
  assert_int_equal(n_scenes, 7);
}

/* ---- The change of measure against differences ---------------------------------- */

/* Path vertex j's point in the coordinates of its triangle's plane at y
 * (an orthonormal frame about y's geometric normal). */
static void plane_coords(const ps_path *y, const ps_path *z, int j, double out[2]) {
  frame f = frame_from_z(y->x[j].v.n);
  vec3 d = v3_sub(z->x[j].v.p, y->x[j].v.p);
  out[0] = v3_dot(d, f.s);
  out[1] = v3_dot(d, f.t);
}

/* |det| of an n x n matrix (partial pivoting). */
static double abs_det(int n, double a[][8]) {
  double det = 1.0;
  for (int c = 0; c < n; c++) {
    int p = c;
    for (int r = c + 1; r < n; r++)
      if (fabs(a[r][c]) > fabs(a[p][c])) p = r;
    if (p != c)
      for (int k = 0; k < n; k++) {
        double t = a[c][k];
        a[c][k] = a[p][k], a[p][k] = t;
      }
    if (a[c][c] == 0.0) return 0.0;
    det *= a[c][c];
    for (int r = c + 1; r < n; r++) {
      double f = a[r][c] / a[c][c];
      for (int k = c; k < n; k++) a[r][k] -= f * a[c][k];
    }
  }
  return fabs(det);
}

/* The differences' |det d(vertices) / d(raster, h)| at y, moving from y
 * itself; 0 when a vertex changed triangle or a move failed. */
static double fd_det(const movers *mv, const ps_path *y, int b, int c, ps_path *z) {
  double hy[2 * PS_MAX_VERTICES], in[2 + 2 * PS_MAX_VERTICES], J[8][8];
  if (!mut_manifold_half_vectors(&mv->mh, y, hy)) return 0.0;
  int n = 2 * (c - b);
  if (n > 8) return 0.0;
  for (int i = 0; i < n; i++) {
    double e = i < 2 ? 1e-4 : 1e-6, out[2][8];
    for (int sgn = 0; sgn < 2; sgn++) {
      in[0] = y->rx, in[1] = y->ry;
      double h[2 * PS_MAX_VERTICES];
      memcpy(h, hy, sizeof h);
      double step = sgn ? -e : e;
      if (i < 2)
        in[i] += step;
      else
        h[2 * (b + 1) + (i - 2)] += step;
      if (!mut_manifold_generate(&mv->mh, y, in[0], in[1], h, z, NULL, NULL)) return 0.0;
      for (int j = b; j < c; j++) {
        if (z->x[j].v.hit.prim != y->x[j].v.hit.prim) return 0.0;
        plane_coords(y, z, j, &out[sgn][2 * (j - b)]);
      }
    }
    for (int o = 0; o < n; o++) J[o][i] = (out[0][o] - out[1][o]) / (2.0 * e);
  }
  return abs_det(n, J);
}

static void test_jacobian(void **state) {
  hfixture *fx = *state;
  static const int scenes[] = {R_POINT, R_SKY, WALL};
  int checked_all = 0;
  for (size_t s = 0; s < sizeof scenes / sizeof scenes[0]; s++) {
    const scene *sc = fx->sc[scenes[s]];
    movers mv;
    movers_init(&mv, sc);
    ps_path *x = malloc(sizeof *x), *y = malloc(sizeof *y), *z = malloc(sizeof *z);
    rng r;
    rng_seed(&r, 517 + s, 3);
    int checked = 0, skipped = 0;
    double worst = 0.0;
    for (int i = 0; i < 4000 && checked < 150; i++) {
      if (!draw_state_for(&mv, &mv.mh, &r, x)) fail();
      int b, c, plain = 1;
      mut_manifold_form(&mv.mh, x, &b, &c);
      for (int j = 1; j < c; j++) plain &= !x->x[j].delta;
      double ratio;
      if (!plain || !mut_manifold_propose(&mv.mh, &r, x, y, &ratio, NULL, NULL) ||
          !(y->lum > 0.0) || !(ratio > 0.0))
        continue;
      /* The density without the draws' own densities (offset, q). */
      double t = mut_manifold_density(&mv.mh, x, y);
      double dr = hypot(y->rx - x->rx, y->ry - x->ry);
      double p = mut_perturb_log_pdf(mv.mp.r1, mv.mp.r2, dr) / (2.0 * 3.14159265358979323846 * dr);
      double hx[2 * PS_MAX_VERTICES], hy[2 * PS_MAX_VERTICES];
      assert_true(mut_manifold_half_vectors(&mv.mh, x, hx));
      assert_true(mut_manifold_half_vectors(&mv.mh, y, hy));
      for (int j = b + 1; j < c; j++) {
        double sg = mv.mh.hslt_step * mut_manifold_hslt_width(&mv.ctx, x, j);
        double dx = hy[2 * j] - hx[2 * j], dy = hy[2 * j + 1] - hx[2 * j + 1];
        p *= exp(-(dx * dx + dy * dy) / (2.0 * sg * sg)) / (2.0 * 3.14159265358979323846 * sg * sg);
      }
      double det = fd_det(&mv, y, b, c, z);
      if (!(det > 0.0)) {
        skipped++;
        continue;
      }
      double e = fabs(det * (t / p) - 1.0);
      if (!(e < 1e-3))
        print_message("det %.9g, density %.9g: product %.9g\n", det, t / p, det * t / p);
      assert_true(e < 1e-3);
      worst = fmax(worst, e);
      checked++;
    }
    print_message("%s: %d densities against differences (worst %.2g off), %d skipped\n",
                  name_of(scenes[s]), checked, worst, skipped);
    assert_true(checked >= 100);
    checked_all += checked;
    free(x), free(y), free(z);
  }
  assert_true(checked_all >= 300);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_forms),
      cmocka_unit_test(test_reverse_and_balance),
      cmocka_unit_test(test_jacobian),
  };
  return cmocka_run_group_tests(tests, ext_setup, ext_teardown);
}
