/*
 * test_warp.c: every warp's sample against its pdf (chi-square on the
 * sphere with tests/chi2.h) and invert(sample(u)) == u.
 *
 * Six chi-square tests at an overall level of 1% (Sidak); the round trips
 * use 100,000 random points each and a tolerance of 1e-9 (the maps are
 * compositions of a few elementary functions; the worst case is near the
 * concentric map's diagonals, where the error is a few ulps times 1/r).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "test_util.h"

#include "chi2.h"
#include "render/warp.h"

/* On a band boundary of the 16-band histogram, where the pdf jumps. */
static const double cone_cos = 0.75;

static int s_cos(void *c, double a, double b, double d, vec3 *w) {
  (void)c, (void)d;
  *w = warp_square_to_cosine_hemisphere(a, b);
  return 1;
}
static double p_cos(void *c, vec3 w) { return (void)c, warp_square_to_cosine_hemisphere_pdf(w); }
static int s_sph(void *c, double a, double b, double d, vec3 *w) {
  (void)c, (void)d;
  *w = warp_square_to_uniform_sphere(a, b);
  return 1;
}
static double p_sph(void *c, vec3 w) { return (void)c, warp_square_to_uniform_sphere_pdf(w); }
static int s_hem(void *c, double a, double b, double d, vec3 *w) {
  (void)c, (void)d;
  *w = warp_square_to_uniform_hemisphere(a, b);
  return 1;
}
static double p_hem(void *c, vec3 w) { return (void)c, warp_square_to_uniform_hemisphere_pdf(w); }
static int s_cone(void *c, double a, double b, double d, vec3 *w) {
  (void)c, (void)d;
  *w = warp_square_to_uniform_cone(a, b, cone_cos);
  return 1;
}
static double p_cone(void *c, vec3 w) { return (void)c, warp_square_to_uniform_cone_pdf(w, cone_cos); }
/* The disk, lifted to the hemisphere by z = sqrt(1 - r^2): area density
 * 1/pi becomes the solid-angle density cos/pi, the same test as Malley. */
static int s_disk(void *c, double a, double b, double d, vec3 *w) {
  (void)c, (void)d;
  double x, y;
  warp_square_to_disk_concentric(a, b, &x, &y);
  *w = v3(x, y, sqrt(fmax(0.0, 1.0 - x * x - y * y)));
  return 1;
}
static double p_disk(void *c, vec3 w) {
  (void)c;
  return w.z > 0.0 ? warp_square_to_disk_concentric_pdf(w.x, w.y) * w.z : 0.0;
}
static void test_chi2_warps(void **state) {
  (void)state;
  struct {
    const char *name;
    chi2_sample_fn s;
    chi2_pdf_fn p;
  } cases[] = {{"cosine hemisphere", s_cos, p_cos}, {"uniform sphere", s_sph, p_sph},
               {"uniform hemisphere", s_hem, p_hem}, {"uniform cone", s_cone, p_cone},
               {"concentric disk", s_disk, p_disk}};
  const int n = sizeof cases / sizeof cases[0];
  double level = chi2_sidak(0.01, n);
  int passed = 0;
  for (int i = 0; i < n; i++) {
    chi2_result r = chi2_sphere(cases[i].s, cases[i].p, NULL, 16, 32, 12, 400000, 11 + i);
    if (r.pvalue < level)
      fail_msg("%s: chi-square p = %g < %g (stat %g, dof %d)", cases[i].name, r.pvalue, level,
               r.stat, r.dof);
    if (fabs(r.pdf_integral - 1.0) > 2e-3)
      fail_msg("%s: pdf integrates to %.6f", cases[i].name, r.pdf_integral);
    passed++;
  }
  assert_int_equal(passed, n);
}

/* The triangle warp on its own domain: an N x N grid over the unit square,
 * whose cells below the diagonal x + y = 1 lie inside the triangle and whose
 * diagonal cells are cut exactly in half; density 2 (area 1/2). */
static void test_chi2_triangle(void **state) {
  (void)state;
  enum { N = 20 };
  static double obs[N * N], expct[N * N];
  const int64_t n = 400000;
  rng r;
  rng_seed(&r, 9, 9);
  for (int64_t i = 0; i < n; i++) {
    double b1, b2;
    warp_square_to_triangle(rng_uniform(&r), rng_uniform(&r), &b1, &b2);
    int ix = (int)(b1 * N), iy = (int)(b2 * N);
    if (ix >= N) ix = N - 1;
    if (iy >= N) iy = N - 1;
    obs[iy * N + ix] += 1.0;
  }
  int inside = 0;
  for (int iy = 0; iy < N; iy++)
    for (int ix = 0; ix < N; ix++) {
      double frac = ix + iy < N - 1 ? 1.0 : (ix + iy == N - 1 ? 0.5 : 0.0);
      expct[iy * N + ix] = (double)n * 2.0 * frac / (N * N);
      inside += frac > 0.0;
    }
  int dof;
  double stat, p = chi2_pvalue(obs, expct, N * N, 5.0, &dof, &stat);
  if (p < 0.01) fail_msg("triangle: chi-square p = %g (stat %g, dof %d)", p, stat, dof);
  assert_int_equal(inside, N * (N + 1) / 2);
  assert_int_equal(dof, inside - 1);
}

static void test_round_trips(void **state) {
  (void)state;
  rng r;
  rng_seed(&r, 5, 5);
  int checked = 0;
  for (int i = 0; i < 100000; i++) {
    double a = rng_uniform(&r), b = rng_uniform(&r), u1, u2;
    double x, y;
    warp_square_to_disk_concentric(a, b, &x, &y);
    warp_disk_concentric_to_square(x, y, &u1, &u2);
    assert_near(u1, a, 1e-9);
    assert_near(u2, b, 1e-9);
    warp_cosine_hemisphere_to_square(warp_square_to_cosine_hemisphere(a, b), &u1, &u2);
    assert_near(u1, a, 1e-9);
    assert_near(u2, b, 1e-9);
    warp_uniform_sphere_to_square(warp_square_to_uniform_sphere(a, b), &u1, &u2);
    assert_near(u1, a, 1e-9);
    assert_near(u2, b, 1e-9);
    warp_uniform_hemisphere_to_square(warp_square_to_uniform_hemisphere(a, b), &u1, &u2);
    assert_near(u1, a, 1e-9);
    assert_near(u2, b, 1e-9);
    warp_uniform_cone_to_square(warp_square_to_uniform_cone(a, b, cone_cos), cone_cos, &u1, &u2);
    assert_near(u1, a, 1e-9);
    assert_near(u2, b, 1e-9);
    double b1, b2;
    warp_square_to_triangle(a, b, &b1, &b2);
    warp_triangle_to_square(b1, b2, &u1, &u2);
    assert_near(u1, a, 1e-9);
    assert_near(u2, b, 1e-9);
    assert_near(warp_tent_to_interval(warp_interval_to_tent(a)), a, 1e-9);
    checked += 7;
  }
  assert_int_equal(checked, 700000);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_chi2_warps),
      cmocka_unit_test(test_chi2_triangle),
      cmocka_unit_test(test_round_trips),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
