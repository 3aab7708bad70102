/*
 * test_camera_film.c: the pinhole camera and the film's filters.
 *
 * Camera: a ray through a raster point maps back to that raster point
 * (camera_we), the importance has the documented per-pixel normalisation,
 * the direction density of rays through uniform raster points matches
 * camera_pdf_dir (chi-square) and integrates to 1, and the fov axes follow
 * Mitsuba's definitions.
 * Film: each filter's sampling matches its weights (chi-square on a 2-D
 * grid), the weights integrate to 1, and a splat away from the border
 * deposits exactly its value.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "test_util.h"

#include <string.h>

#include "chi2.h"
#include "render/camera.h"
#include "render/film.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static camera make_camera(void) {
  camera c;
  memset(&c, 0, sizeof c);
  xform_lookat(v3(1.0, 2.0, 3.0), v3(0.0, 0.5, 0.0), v3(0.0, 1.0, 0.0), &c.to_world);
  assert_true(camera_set_fov(&c, 50.0, "x", 64, 48));
  return c;
}

static void test_ray_raster_round_trip(void **state) {
  (void)state;
  camera c = make_camera();
  rng r;
  rng_seed(&r, 1, 1);
  double A = 4.0 * c.tan_half_x * c.tan_half_y;
  int checked = 0;
  for (int i = 0; i < 10000; i++) {
    double rx = rng_uniform(&r) * c.width, ry = rng_uniform(&r) * c.height, qx, qy;
    vec3 o, d;
    camera_generate_ray(&c, rx, ry, &o, &d);
    double we = camera_we(&c, d, &qx, &qy);
    assert_near(qx, rx, 1e-8);
    assert_near(qy, ry, 1e-8);
    double cos_t = v3_dot(d, c.forward);
    double expect = c.width * c.height / (A * pow(cos_t, 4.0));
    assert_near(we, expect, 1e-9 * expect);
    assert_near(camera_pdf_dir(&c, d), 1.0 / (A * pow(cos_t, 3.0)), 1e-9 * expect);
    checked++;
  }
  assert_int_equal(checked, 10000);
  /* Behind the camera and outside the frame: no importance. */
  double qx, qy;
  assert_true(camera_we(&c, v3_neg(c.forward), &qx, &qy) == 0.0);
  /* The image's left edge is camera +x (Mitsuba's lookat). */
  vec3 o, dl, dr;
  camera_generate_ray(&c, 0.0, 24.0, &o, &dl);
  camera_generate_ray(&c, 64.0, 24.0, &o, &dr);
  vec3 left = xform_vector(&c.to_world, v3(1.0, 0.0, 0.0));
  assert_true(v3_dot(dl, left) > 0.0);
  assert_true(v3_dot(dr, left) < 0.0);
}

/* Directions of rays through uniform raster points against camera_pdf_dir:
 * the camera looks along +z, so the cap cos(theta) > 0.625 lies inside the
 * frame (tan 51.3 deg = 1.25 < tan_half_y = 1.3) and its bands align with
 * the histogram's. Cells: 6 bands x 32 sectors in the cap, one for the rest. */
static void test_direction_density(void **state) {
  (void)state;
  camera c;
  memset(&c, 0, sizeof c);
  c.to_world = xform_identity();
  assert_true(camera_set_fov(&c, 120.0, "x", 64, 48));
  enum { BANDS = 6, SECT = 32, SUB = 16 };
  const double zmin = 0.625;
  static double obs[BANDS * SECT + 1], expct[BANDS * SECT + 1];
  const int64_t n = 1000000;
  rng r;
  rng_seed(&r, 3, 3);
  for (int64_t i = 0; i < n; i++) {
    vec3 o, d;
    camera_generate_ray(&c, rng_uniform(&r) * c.width, rng_uniform(&r) * c.height, &o, &d);
    if (d.z <= zmin) {
      obs[BANDS * SECT] += 1.0;
      continue;
    }
    int b = (int)((1.0 - d.z) / (1.0 - zmin) * BANDS), k;
    double phi = atan2(d.y, d.x);
    if (phi < 0.0) phi += 2.0 * M_PI;
    k = (int)(phi / (2.0 * M_PI) * SECT);
    obs[(b < BANDS ? b : BANDS - 1) * SECT + (k < SECT ? k : SECT - 1)] += 1.0;
  }
  double dz = (1.0 - zmin) / BANDS / SUB, dphi = 2.0 * M_PI / SECT / SUB, cap = 0.0;
  for (int b = 0; b < BANDS; b++)
    for (int k = 0; k < SECT; k++) {
      double acc = 0.0;
      for (int i = 0; i < SUB; i++)
        for (int j = 0; j < SUB; j++) {
          double z = 1.0 - (b * SUB + i + 0.5) * dz, phi = (k * SUB + j + 0.5) * dphi;
          double sn = sqrt(1.0 - z * z);
          acc += camera_pdf_dir(&c, v3(sn * cos(phi), sn * sin(phi), z));
        }
      expct[b * SECT + k] = acc * dz * dphi * n;
      cap += acc * dz * dphi;
    }
  expct[BANDS * SECT] = (1.0 - cap) * n;
  int dof;
  double stat, p = chi2_pvalue(obs, expct, BANDS * SECT + 1, 5.0, &dof, &stat);
  if (p < 0.01) fail_msg("camera directions: p = %g (stat %g, dof %d)", p, stat, dof);
  assert_int_equal(dof, BANDS * SECT);
  /* The density integrates to 1 over the whole frame (midpoint rule over
   * the image plane at distance 1: d omega = cos^3 dA). */
  double total = 0.0, hx = 2.0 * c.tan_half_x / 512, hy = 2.0 * c.tan_half_y / 384;
  for (int i = 0; i < 512; i++)
    for (int j = 0; j < 384; j++) {
      vec3 d = v3(-c.tan_half_x + (i + 0.5) * hx, -c.tan_half_y + (j + 0.5) * hy, 1.0);
      double l = v3_len(d), cos3 = 1.0 / (l * l * l);
      total += camera_pdf_dir(&c, v3_scale(d, 1.0 / l)) * cos3 * hx * hy;
    }
  assert_near(total, 1.0, 1e-9);
}

static void test_fov_axes(void **state) {
  (void)state;
  camera c;
  memset(&c, 0, sizeof c);
  c.to_world = xform_identity();
  double t = tan(30.0 * M_PI / 180.0);
  assert_true(camera_set_fov(&c, 60.0, "x", 40, 20));
  assert_near(c.tan_half_x, t, 1e-12);
  assert_near(c.tan_half_y, t / 2.0, 1e-12);
  assert_true(camera_set_fov(&c, 60.0, "y", 40, 20));
  assert_near(c.tan_half_y, t, 1e-12);
  assert_near(c.tan_half_x, 2.0 * t, 1e-12);
  assert_true(camera_set_fov(&c, 60.0, "smaller", 40, 20));
  assert_near(c.tan_half_y, t, 1e-12);
  assert_true(camera_set_fov(&c, 60.0, "larger", 40, 20));
  assert_near(c.tan_half_x, t, 1e-12);
  assert_true(camera_set_fov(&c, 60.0, "diagonal", 30, 40));
  assert_near(hypot(c.tan_half_x, c.tan_half_y), t, 1e-12);
  /* A new resolution keeps the fov of the axis used. */
  assert_true(camera_set_fov(&c, 60.0, "x", 40, 20));
  camera_set_resolution(&c, 80, 80);
  assert_near(c.tan_half_x, t, 1e-12);
  assert_near(c.tan_half_y, t, 1e-12);
  assert_false(camera_set_fov(&c, 180.0, "x", 40, 20));
  assert_false(camera_set_fov(&c, 0.0, "x", 40, 20));
  assert_false(camera_set_fov(&c, 60.0, "z", 40, 20));
}

static void test_filters(void **state) {
  (void)state;
  enum { N = 24, SUB = 16 };
  static double obs[N * N], expct[N * N];
  const filter_type types[3] = {FILTER_BOX, FILTER_TENT, FILTER_GAUSSIAN};
  int tested = 0;
  for (int k = 0; k < 3; k++) {
    film_filter f;
    filter_init(&f, types[k]);
    double r = f.radius, cell = 2.0 * r / N;
    /* Expected counts: the weight integrated over each cell. */
    const int64_t n = 500000;
    double total = 0.0;
    for (int iy = 0; iy < N; iy++)
      for (int ix = 0; ix < N; ix++) {
        double acc = 0.0;
        for (int a = 0; a < SUB; a++)
          for (int b = 0; b < SUB; b++)
            acc += filter_eval(&f, -r + (ix + (a + 0.5) / SUB) * cell, -r + (iy + (b + 0.5) / SUB) * cell);
        acc *= cell * cell / (SUB * SUB);
        total += acc;
        expct[iy * N + ix] = acc * n;
        obs[iy * N + ix] = 0.0;
      }
    assert_near(total, 1.0, 1e-3);
    rng g;
    rng_seed(&g, 4, (uint64_t)k);
    for (int64_t i = 0; i < n; i++) {
      double dx, dy;
      filter_sample(&f, rng_uniform(&g), rng_uniform(&g), &dx, &dy);
      int ix = (int)((dx + r) / cell), iy = (int)((dy + r) / cell);
      assert_true(ix >= 0 && ix < N && iy >= 0 && iy < N);
      obs[iy * N + ix] += 1.0;
    }
    int dof;
    double stat, p = chi2_pvalue(obs, expct, N * N, 5.0, &dof, &stat);
    if (p < chi2_sidak(0.01, 3)) fail_msg("filter %d: p = %g (stat %g, dof %d)", k, p, stat, dof);

    /* A splat in the middle of a film deposits its value: exactly for box
     * and tent (their unit-spaced samples sum to 1), within 1% for the
     * Gaussian (sum of its samples at pixel centres; each pixel's expected
     * value is still the filtered image, so this is not a bias). */
    film fm;
    lmc_error err;
    assert_int_equal(film_init(&fm, 16, 16, &err), LMC_OK);
    film_splat(&fm, &f, 7.3, 8.9, rgb_make(1.0, 2.0, 3.0));
    double s[3] = {0, 0, 0};
    for (int i = 0; i < 16 * 16; i++)
      for (int ch = 0; ch < 3; ch++) s[ch] += fm.splat[3 * i + ch];
    double tol = types[k] == FILTER_GAUSSIAN ? 1e-2 : 1e-12;
    assert_near(s[0], 1.0, tol);
    assert_near(s[1], 2.0, 2.0 * tol);
    assert_near(s[2], 3.0, 3.0 * tol);
    film_free(&fm);
    tested++;
  }
  assert_int_equal(tested, 3);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_ray_raster_round_trip),
      cmocka_unit_test(test_direction_density),
      cmocka_unit_test(test_fov_axes),
      cmocka_unit_test(test_filters),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
