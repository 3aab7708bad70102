/*
 * test_transform.c: the 4x4 transforms of render/transform.c against values
 * computed by hand: elementary transforms, composition order (Mitsuba's
 * "each element is applied after the previous ones"), inverses, Mitsuba's
 * lookat basis, normals under non-uniform scale, the general matrix inverse
 * and its refusal of singular matrices.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <cmocka.h>

#include "render/transform.h"

#define EPS 1e-12

/* Asserts |a - b| <= tol per component, printing both vectors on failure. */
static void check_v3(vec3 got, vec3 want, double tol, const char *what) {
  int ok = fabs(got.x - want.x) <= tol && fabs(got.y - want.y) <= tol &&
           fabs(got.z - want.z) <= tol;
  if (!ok) {
    print_error("%s: got (%.15g, %.15g, %.15g), want (%.15g, %.15g, %.15g)\n", what, got.x,
                got.y, got.z, want.x, want.y, want.z);
  }
  assert_true(ok);
}

/* m * inv must be the identity. */
static void check_inverse(const xform *t, double tol, const char *what) {
  int bad = 0;
  for (int i = 0; i < 4; i++) {
    for (int j = 0; j < 4; j++) {
      double s = 0.0;
      for (int k = 0; k < 4; k++) s += t->m[i][k] * t->inv[k][j];
      double want = i == j ? 1.0 : 0.0;
      if (fabs(s - want) > tol) {
        print_error("%s: (m inv)[%d][%d] = %.15g\n", what, i, j, s);
        bad++;
      }
    }
  }
  assert_int_equal(bad, 0);
}

static void test_translate_scale(void **state) {
  (void)state;
  xform t = xform_translate(v3(1, -2, 3));
  check_v3(xform_point(&t, v3(1, 1, 1)), v3(2, -1, 4), EPS, "translate point");
  check_v3(xform_vector(&t, v3(1, 1, 1)), v3(1, 1, 1), EPS, "translate vector");
  check_v3(xform_inv_point(&t, v3(2, -1, 4)), v3(1, 1, 1), EPS, "translate inverse");
  check_inverse(&t, EPS, "translate");

  xform s = xform_scale(v3(2, 3, 4));
  check_v3(xform_point(&s, v3(1, 1, 1)), v3(2, 3, 4), EPS, "scale point");
  check_v3(xform_inv_vector(&s, v3(2, 3, 4)), v3(1, 1, 1), EPS, "scale inverse");
  check_inverse(&s, EPS, "scale");
  assert_true(fabs(xform_det3(&s) - 24.0) < EPS);

  /* A mirror has a negative determinant. */
  xform mir = xform_scale(v3(-1, 1, 1));
  assert_true(fabs(xform_det3(&mir) + 1.0) < EPS);

  xform id = xform_identity();
  assert_true(xform_is_identity(&id));
  id.m[2][1] = 1e-9;
  assert_false(xform_is_identity(&id));
  assert_false(xform_is_identity(&t));
}

static void test_rotate(void **state) {
  (void)state;
  /* Right-handed: +90 degrees about z takes x to y, about x takes y to z,
   * about y takes z to x. */
  xform rz = xform_rotate(v3(0, 0, 1), 90);
  xform rx = xform_rotate(v3(1, 0, 0), 90);
  xform ry = xform_rotate(v3(0, 1, 0), 90);
  check_v3(xform_vector(&rz, v3(1, 0, 0)), v3(0, 1, 0), EPS, "rot z");
  check_v3(xform_vector(&rx, v3(0, 1, 0)), v3(0, 0, 1), EPS, "rot x");
  check_v3(xform_vector(&ry, v3(0, 0, 1)), v3(1, 0, 0), EPS, "rot y");
  /* The axis needs no normalisation by the caller. */
  xform rz2 = xform_rotate(v3(0, 0, 5), 90);
  check_v3(xform_vector(&rz2, v3(1, 0, 0)), v3(0, 1, 0), EPS, "rot unnormalised axis");
  /* 120 degrees about (1,1,1) permutes the axes x -> y -> z -> x. */
  xform r3 = xform_rotate(v3(1, 1, 1), 120);
  check_v3(xform_vector(&r3, v3(1, 0, 0)), v3(0, 1, 0), 1e-12, "rot 111 x");
  check_v3(xform_vector(&r3, v3(0, 1, 0)), v3(0, 0, 1), 1e-12, "rot 111 y");
  check_inverse(&r3, EPS, "rotate");
  assert_true(fabs(xform_det3(&r3) - 1.0) < EPS);
}

static void test_compose_order(void **state) {
  (void)state;
  /* <scale value="2"/> then <translate x="1"/>: M = T * S, so
   * (1,1,1) -> (2,2,2) -> (3,2,2). */
  xform s = xform_scale(v3(2, 2, 2));
  xform t = xform_translate(v3(1, 0, 0));
  xform m = xform_compose(&t, &s);
  check_v3(xform_point(&m, v3(1, 1, 1)), v3(3, 2, 2), EPS, "T*S");
  check_v3(xform_inv_point(&m, v3(3, 2, 2)), v3(1, 1, 1), EPS, "(T*S)^-1");
  check_inverse(&m, EPS, "T*S");
  /* The other order: (1,1,1) -> (2,1,1) -> (4,2,2). */
  xform m2 = xform_compose(&s, &t);
  check_v3(xform_point(&m2, v3(1, 1, 1)), v3(4, 2, 2), EPS, "S*T");
  /* Rotate about z by 90 then translate by (0,0,5): (1,0,0) -> (0,1,5). */
  xform r = xform_rotate(v3(0, 0, 1), 90);
  xform tz = xform_translate(v3(0, 0, 5));
  xform m3 = xform_compose(&tz, &r);
  check_v3(xform_point(&m3, v3(1, 0, 0)), v3(0, 1, 5), EPS, "T*R");
  check_inverse(&m3, EPS, "T*R");
}

static void test_normals(void **state) {
  (void)state;
  /* Scaling x by 2 turns the plane x + y = 0 (normal (1,1,0)) into
   * x/2 + y = 0, with normal (1/2, 1, 0) = inv^T n. */
  xform s = xform_scale(v3(2, 1, 1));
  check_v3(xform_normal(&s, v3(1, 1, 0)), v3(0.5, 1, 0), EPS, "normal under scale");
  /* The transformed normal stays orthogonal to a transformed tangent. */
  xform r = xform_rotate(v3(1, 2, 3), 37);
  xform m = xform_compose(&r, &s);
  vec3 n = v3(1, 1, 0), tan = v3(1, -1, 4);
  double d = v3_dot(xform_normal(&m, n), xform_vector(&m, tan));
  assert_true(fabs(d) < 1e-12);
  /* Under a rotation normals move like vectors. */
  check_v3(xform_normal(&r, v3(0, 0, 1)), xform_vector(&r, v3(0, 0, 1)), EPS, "normal rot");
}

static void test_lookat(void **state) {
  (void)state;
  xform t;
  /* Looking along +z from (1,2,3) with up +y: dir=(0,0,1),
   * left = up x dir = (1,0,0), newUp = dir x left = (0,1,0): a translation. */
  assert_true(xform_lookat(v3(1, 2, 3), v3(1, 2, 10), v3(0, 1, 0), &t));
  check_v3(xform_point(&t, v3(0, 0, 0)), v3(1, 2, 3), EPS, "lookat origin");
  check_v3(xform_vector(&t, v3(1, 0, 0)), v3(1, 0, 0), EPS, "lookat x");
  check_v3(xform_vector(&t, v3(0, 0, 1)), v3(0, 0, 1), EPS, "lookat z");
  /* Looking along +x with up +z: dir=(1,0,0), left = (0,0,1)x(1,0,0) =
   * (0,1,0), newUp = (1,0,0)x(0,1,0) = (0,0,1). */
  assert_true(xform_lookat(v3(0, 0, 0), v3(5, 0, 0), v3(0, 0, 2), &t));
  check_v3(xform_vector(&t, v3(1, 0, 0)), v3(0, 1, 0), EPS, "lookat left");
  check_v3(xform_vector(&t, v3(0, 1, 0)), v3(0, 0, 1), EPS, "lookat up");
  check_v3(xform_vector(&t, v3(0, 0, 1)), v3(1, 0, 0), EPS, "lookat dir");
  /* An up that is not orthogonal to dir is re-orthogonalised. */
  assert_true(xform_lookat(v3(1, 1, 1), v3(1, 1, 0), v3(0, 1, 1), &t));
  check_v3(xform_vector(&t, v3(0, 0, 1)), v3(0, 0, -1), EPS, "lookat dir -z");
  check_v3(xform_vector(&t, v3(0, 1, 0)), v3(0, 1, 0), EPS, "lookat up reortho");
  check_v3(xform_vector(&t, v3(1, 0, 0)), v3(-1, 0, 0), EPS, "lookat left -x");
  check_v3(xform_inv_point(&t, v3(1, 1, 0)), v3(0, 0, 1), EPS, "lookat inverse");
  check_inverse(&t, EPS, "lookat");
  assert_true(fabs(xform_det3(&t) - 1.0) < EPS);
  /* Degenerate: up parallel to the view direction, or target = origin. */
  assert_false(xform_lookat(v3(0, 0, 0), v3(0, 3, 0), v3(0, 1, 0), &t));
  assert_false(xform_lookat(v3(1, 1, 1), v3(1, 1, 1), v3(0, 1, 0), &t));
}

static void test_matrix(void **state) {
  (void)state;
  xform t;
  /* A general affine matrix: rows (row-major, p' = m p). */
  const double v[16] = {2, 1, 0, 3,  0, 1, -1, 2,  1, 0, 4, -1,  0, 0, 0, 1};
  assert_true(xform_from_matrix(v, &t));
  check_v3(xform_point(&t, v3(1, 1, 1)), v3(6, 2, 4), EPS, "matrix point");
  check_v3(xform_vector(&t, v3(1, 1, 1)), v3(3, 0, 5), EPS, "matrix vector");
  check_inverse(&t, 1e-12, "matrix");
  check_v3(xform_inv_point(&t, v3(6, 2, 4)), v3(1, 1, 1), 1e-12, "matrix inverse");
  /* det3 = 2(4-0) - 1(0+1) + 0 = 7 */
  assert_true(fabs(xform_det3(&t) - 7.0) < 1e-12);
  /* A matrix needing a row swap (zero first pivot). */
  const double p[16] = {0, 1, 0, 0,  1, 0, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1};
  assert_true(xform_from_matrix(p, &t));
  check_inverse(&t, EPS, "permutation");
  assert_true(fabs(xform_det3(&t) + 1.0) < EPS);
  /* Singular: two equal rows. */
  const double s[16] = {1, 2, 3, 0,  1, 2, 3, 0,  0, 0, 1, 0,  0, 0, 0, 1};
  assert_false(xform_from_matrix(s, &t));
  /* All zero. */
  const double z[16] = {0};
  assert_false(xform_from_matrix(z, &t));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_translate_scale), cmocka_unit_test(test_rotate),
      cmocka_unit_test(test_compose_order),   cmocka_unit_test(test_normals),
      cmocka_unit_test(test_lookat),          cmocka_unit_test(test_matrix),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
