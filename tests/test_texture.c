/*
 * test_texture.c: the textures of src/render/texture.c.
 *
 * What is checked: constants; the bitmap lookup of Mitsuba (pixel centres
 * at half-integers, bilinear weights, repeat wrapping on both axes and for
 * negative and large coordinates, v = 0 at the top row without a flip, the
 * uv scale and offset, grey and RGBA images) and its mean (cached or not);
 * the checkerboard's parity rule (truncation toward zero, squares of 1/2,
 * color0 when both parities agree), its defaults and its mean. The wrap
 * modes (mirror, clamp, zero, one) and the nearest filter against texels
 * worked out by hand. The MIP map: the level count and sizes of Mitsuba,
 * the exact area average of odd and even sizes, each level's mean that of
 * the image. Filtered lookups (trilinear, EWA) over a footprint: a zero
 * footprint reads level 0; a footprint of exactly 2^k texels reads level
 * k; EWA returns a constant image's value and, centred on a texel, a
 * linear ramp's value at the centre (its weights are symmetric and
 * normalised); over uniformly random points, the mean of every filter's
 * lookups is the image mean (each texel's normalised weight integrates to
 * 1/N by the repeat symmetry), tested at 4 standard errors. Each test
 * counts its checks and asserts the count.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "test_util.h"

#include "render/bsdf/texture.h"
#include "render/rng.h"


/* A w x h image whose pixel (x, y) has red = x + 10 y, green = 100 + x,
 * blue = 200 + y (owned by the caller: free img->data). */
static lmc_image make_image(int w, int h, int channels) {
  lmc_image img = {w, h, channels, calloc((size_t)w * h * channels, sizeof(float))};
  assert_non_null(img.data);
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      float *p = img.data + ((size_t)y * w + x) * channels;
      p[0] = (float)(x + 10 * y);
      if (channels >= 3) {
        p[1] = (float)(100 + x);
        p[2] = (float)(200 + y);
      }
      if (channels == 4) p[3] = 0.25f;
    }
  return img;
}

static void test_constant(void **state) {
  (void)state;
  texture t = tex_constant(rgb_make(0.1, 0.2, 0.3));
  rgb v = tex_eval(&t, 12.5, -3.25);
  assert_near(v.r, 0.1, 0);
  assert_near(v.b, 0.3, 0);
  assert_near(tex_mean(&t).g, 0.2, 0);
  assert_true(tex_is_constant(&t));
  assert_near(t.uscale, 1.0, 0);
}

static void test_bitmap_lookup(void **state) {
  (void)state;
  int checks = 0;
  lmc_image img = make_image(4, 3, 3);
  texture t = tex_bitmap(&img);
  assert_false(tex_is_constant(&t));
  checks++;
  /* Texel centres: u = (x + 1/2) / w, v = (y + 1/2) / h give the texel
   * exactly; v = small is the top row (row 0): no flip. */
  for (int y = 0; y < 3; y++)
    for (int x = 0; x < 4; x++) {
      rgb c = tex_eval(&t, (x + 0.5) / 4.0, (y + 0.5) / 3.0);
      assert_near(c.r, x + 10 * y, 1e-12);
      assert_near(c.g, 100 + x, 1e-12);
      assert_near(c.b, 200 + y, 1e-12);
      checks += 3;
    }
  /* Halfway between texel centres (1,1) and (2,1): the average. A quarter
   * of the way from (1,0) toward (1,1) in v: bilinear weights 3/4, 1/4. */
  assert_near(tex_eval(&t, 2.0 / 4.0, 1.5 / 3.0).r, 0.5 * (11 + 12), 1e-12);
  assert_near(tex_eval(&t, 1.5 / 4.0, 0.75 / 3.0).r, 0.75 * 1 + 0.25 * 11, 1e-12);
  checks += 2;
  /* Repeat wrapping: u = 0 lies between the last and the first column;
   * v = 0 between the last and the first row. */
  assert_near(tex_eval(&t, 0.0, 0.5 / 3.0).r, 0.5 * (3 + 0), 1e-12);
  assert_near(tex_eval(&t, 0.5 / 4.0, 0.0).r, 0.5 * (20 + 0), 1e-12);
  assert_near(tex_eval(&t, 0.0, 0.0).r, 0.25 * (0 + 3 + 20 + 23), 1e-12);
  checks += 3;
  /* Periodicity: integer shifts, negative and large coordinates. */
  const double us[] = {0.13, 0.61, 0.97}, vs[] = {0.05, 0.52, 0.88};
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double ref = tex_eval(&t, us[i], vs[j]).r;
      assert_near(tex_eval(&t, us[i] - 3.0, vs[j] + 7.0).r, ref, 1e-9);
      assert_near(tex_eval(&t, us[i] + 1000.0, vs[j] - 1000.0).r, ref, 1e-9);
      checks += 2;
    }
  /* uv scale and offset: (u, v) -> (u * uscale + uoffset, v * vscale + voffset). */
  texture ts = t;
  ts.uscale = 2.0;
  ts.vscale = 3.0;
  ts.uoffset = 0.125;
  ts.voffset = -0.5;
  for (int i = 0; i < 3; i++) {
    double u = us[i], v = vs[i];
    assert_near(tex_eval(&ts, u, v).g, tex_eval(&t, u * 2.0 + 0.125, v * 3.0 - 0.5).g, 1e-12);
    checks++;
  }
  /* Non-finite coordinates give black, never a crash. */
  assert_near(tex_eval(&t, NAN, 0.5).r, 0.0, 0);
  checks++;
  /* Mean: red = mean(x) + 10 mean(y) = 1.5 + 10; cached and recomputed agree. */
  rgb m = tex_mean(&t);
  assert_near(m.r, 11.5, 1e-12);
  assert_near(m.g, 101.5, 1e-12);
  assert_near(m.b, 201.0, 1e-12);
  texture tu = t;
  tu.mean_valid = 0;
  assert_near(tex_mean(&tu).r, 11.5, 1e-12);
  checks += 4;
  free(img.data);

  /* Grey (1 channel) and RGBA images. */
  lmc_image grey = make_image(2, 2, 1);
  texture tg = tex_bitmap(&grey);
  rgb g = tex_eval(&tg, 0.75, 0.25);
  assert_near(g.r, 1.0, 1e-12);
  assert_near(g.b, 1.0, 1e-12);
  free(grey.data);
  lmc_image rgba = make_image(2, 2, 4);
  texture ta = tex_bitmap(&rgba);
  rgb a = tex_eval(&ta, 0.25, 0.75);
  assert_near(a.r, 10.0, 1e-12);
  assert_near(a.g, 100.0, 1e-12);
  assert_near(a.b, 201.0, 1e-12);
  free(rgba.data);
  checks += 5;
  assert_int_equal(checks, 1 + 36 + 2 + 3 + 18 + 3 + 1 + 4 + 5);
}

static void test_checkerboard(void **state) {
  (void)state;
  int checks = 0;
  /* Mitsuba's defaults and mean. */
  texture t = tex_checkerboard(rgb_gray(0.4), rgb_gray(0.2));
  assert_near(tex_mean(&t).r, 0.3, 1e-15);
  assert_near(t.uscale, 1.0, 0);
  assert_false(tex_is_constant(&t));
  checks += 3;
  /* Squares are 1/2 wide: color0 where trunc(2u) and trunc(2v) have the
   * same parity. */
  static const struct {
    double u, v;
    int c0;
  } pts[] = {
      {0.25, 0.25, 1}, {0.75, 0.25, 0}, {0.25, 0.75, 0}, {0.75, 0.75, 1},
      {1.25, 0.25, 1}, {1.75, 1.75, 1}, {1.25, 1.75, 0}, {0.49, 0.51, 0},
      /* Truncation toward zero: (-0.5, 0.5) maps to 0 like [0, 0.5), so
       * the square around the origin is twice as wide... */
      {-0.25, 0.25, 1}, {-0.25, -0.25, 1}, {0.25, -0.25, 1},
      /* ...and beyond it the parity of trunc(2u) mod 2 (non-negative). */
      {-0.75, 0.25, 0}, {-0.75, -0.75, 1}, {-1.25, 0.25, 1},
  };
  for (size_t i = 0; i < sizeof pts / sizeof pts[0]; i++) {
    rgb c = tex_eval(&t, pts[i].u, pts[i].v);
    if (!(c.r == (pts[i].c0 ? 0.4 : 0.2))) print_error("point %zu (%g, %g)\n", i, pts[i].u, pts[i].v);
    assert_true(c.r == (pts[i].c0 ? 0.4 : 0.2));
    checks++;
  }
  /* Scale and offset apply before the parity test. */
  texture s = t;
  s.uscale = 4.0;
  s.voffset = 0.5;
  assert_true(tex_eval(&s, 0.1875, 0.25).r == tex_eval(&t, 0.75, 0.75).r);
  assert_true(tex_eval(&s, 0.0625, 0.25).r == tex_eval(&t, 0.25, 0.75).r);
  checks += 2;
  assert_int_equal(checks, 3 + 14 + 2);
}

/* A 4 x 3 image's lookups outside [0, 1] under each wrap mode, and the
 * nearest filter, against the texels by hand (red = x + 10 y). */
static void test_wrap_nearest(void **state) {
  (void)state;
  int checks = 0;
  lmc_image img = make_image(4, 3, 3);
  texture t = tex_bitmap(&img);
  t.filter = TEX_FILTER_NEAREST;
  /* nearest: texel (floor(4 u), floor(3 v)), with repeat by default. */
  assert_near(tex_eval(&t, 0.30, 0.40).r, 1 + 10 * 1, 0);
  assert_near(tex_eval(&t, 0.99, 0.01).r, 3, 0);
  assert_near(tex_eval(&t, -0.10, 0.50).r, 3 + 10, 0); /* x = -1 repeats to 3 */
  checks += 3;
  /* mirror: x = 4 mirrors to 3, x = 5 to 2, x = -1 to 0, x = 9 (mod 8 = 1) to 1. */
  t.wrap_u = TEX_WRAP_MIRROR;
  assert_near(tex_eval(&t, 1.10, 0.1).r, 3, 0);
  assert_near(tex_eval(&t, 1.30, 0.1).r, 2, 0);
  assert_near(tex_eval(&t, -0.10, 0.1).r, 0, 0);
  assert_near(tex_eval(&t, 2.30, 0.1).r, 1, 0);
  checks += 4;
  /* clamp: the edge texels; zero and one: that value outside. */
  t.wrap_u = TEX_WRAP_CLAMP;
  t.wrap_v = TEX_WRAP_CLAMP;
  assert_near(tex_eval(&t, -5.0, 7.0).r, 0 + 10 * 2, 0);
  assert_near(tex_eval(&t, 1e9, -1e9).r, 3, 0);
  t.wrap_u = TEX_WRAP_ZERO;
  assert_near(tex_eval(&t, 1.2, 0.5).g, 0, 0);
  t.wrap_u = TEX_WRAP_ONE;
  assert_near(tex_eval(&t, -0.2, 0.5).b, 1, 0);
  checks += 4;
  /* Bilinear at u = 0 (between x = -1 and x = 0), v at row 1's centre:
   * clamp averages texel 0 with itself, zero with black, one with white,
   * mirror with itself (x = -1 mirrors to 0). */
  t.filter = TEX_FILTER_BILINEAR;
  t.wrap_v = TEX_WRAP_REPEAT;
  double v = 1.5 / 3.0;
  const tex_wrap modes[4] = {TEX_WRAP_CLAMP, TEX_WRAP_ZERO, TEX_WRAP_ONE, TEX_WRAP_MIRROR};
  const double want[4] = {10, 5, 5.5, 10};
  for (int k = 0; k < 4; k++) {
    t.wrap_u = modes[k];
    assert_near(tex_eval(&t, 0.0, v).r, want[k], 1e-12);
    checks++;
  }
  /* Its slope (a bump map's) is 0 under nearest, as Mitsuba's. */
  t.filter = TEX_FILTER_NEAREST;
  double du, dv;
  tex_lum_gradient(&t, 0.3, 0.4, &du, &dv);
  assert_true(du == 0.0 && dv == 0.0);
  checks++;
  free(img.data);
  assert_int_equal(checks, 3 + 4 + 4 + 4 + 1);
}

/* A w x h image of pseudo-random texels in [0, 1) (3 channels). */
static lmc_image random_image(int w, int h, uint64_t seed) {
  lmc_image img = {w, h, 3, calloc((size_t)w * h * 3, sizeof(float))};
  assert_non_null(img.data);
  rng r;
  rng_seed(&r, seed, 1);
  for (size_t i = 0; i < (size_t)w * h * 3; i++) img.data[i] = (float)rng_uniform(&r);
  return img;
}

/* The MIP levels of img (levels[0] = img, copied), n = tex_mip_levels. */
static lmc_image *build_levels(const lmc_image *img, int *OUT_n) {
  int n = tex_mip_levels(img->width, img->height);
  lmc_image *lv = calloc((size_t)n, sizeof *lv);
  assert_non_null(lv);
  lmc_error err = {0};
  assert_int_equal(image_init(&lv[0], img->width, img->height, 3, &err), LMC_OK);
  memcpy(lv[0].data, img->data, (size_t)img->width * img->height * 3 * sizeof(float));
  for (int k = 1; k < n; k++) assert_int_equal(tex_mip_halve(&lv[k - 1], &lv[k], &err), LMC_OK);
  *OUT_n = n;
  return lv;
}

static void free_levels(lmc_image *lv, int n) {
  for (int k = 0; k < n; k++) image_free(&lv[k]);
  free(lv);
}

static double image_mean_r(const lmc_image *img) {
  double s = 0.0;
  for (int i = 0; i < img->width * img->height; i++) s += img->data[3 * i];
  return s / (img->width * img->height);
}

static void test_mip_levels(void **state) {
  (void)state;
  int checks = 0;
  /* Mitsuba's sizes: (w + 1) / 2 down to 1 x 1. */
  assert_int_equal(tex_mip_levels(1, 1), 1);
  assert_int_equal(tex_mip_levels(8, 8), 4);
  assert_int_equal(tex_mip_levels(5, 3), 4); /* 5x3, 3x2, 2x1, 1x1 */
  assert_int_equal(tex_mip_levels(1, 9), 5); /* 1x9, 1x5, 1x3, 1x2, 1x1 */
  checks += 4;
  /* An odd row: 3 texels into 2, each over 1.5 texels of the source. */
  lmc_image img = make_image(3, 2, 3), half = {0};
  lmc_error err = {0};
  assert_int_equal(tex_mip_halve(&img, &half, &err), LMC_OK);
  assert_int_equal(half.width, 2);
  assert_int_equal(half.height, 1);
  /* red = x + 10 y: rows averaged (5 + x), then (x0 + x1 / 2) / 1.5. */
  assert_near(half.data[0], (5.0 + 0.5 * 6.0) / 1.5, 1e-5);
  assert_near(half.data[3], (0.5 * 6.0 + 7.0) / 1.5, 1e-5);
  checks += 4;
  image_free(&half);
  free(img.data);
  /* Every level keeps the image's mean (float storage: 1e-5). */
  const int sizes[3][2] = {{37, 23}, {64, 64}, {1, 17}};
  for (int c = 0; c < 3; c++) {
    lmc_image r = random_image(sizes[c][0], sizes[c][1], 7 + c);
    int n;
    lmc_image *lv = build_levels(&r, &n);
    assert_int_equal(lv[n - 1].width * lv[n - 1].height, 1);
    double m = image_mean_r(&r);
    for (int k = 1; k < n; k++) {
      assert_near(image_mean_r(&lv[k]), m, 1e-5);
      checks++;
    }
    free_levels(lv, n);
    free(r.data);
  }
  assert_int_equal(checks, 4 + 4 + 6 + 6 + 5);
}

/* A texture over levels lv (n of them) with filter f and footprint fp. */
static texture filtered(const lmc_image *lv, int n, tex_filter f, tex_footprint fp) {
  texture t = tex_bitmap(&lv[0]);
  t.levels = n;
  t.filter = f;
  tex_set_footprint(&t, &fp);
  return t;
}

static void test_filtered_lookup(void **state) {
  (void)state;
  int checks = 0;
  lmc_image img = random_image(64, 32, 3);
  int n;
  lmc_image *lv = build_levels(&img, &n);
  texture plain = tex_bitmap(&lv[0]);
  assert_true(tex_is_filtered(&(texture){.type = TEX_BITMAP, .levels = 2}));
  assert_false(tex_is_filtered(&plain));
  checks += 2;
  /* A zero footprint reads level 0 bilinearly, under both filters. */
  rng r;
  rng_seed(&r, 11, 2);
  for (int i = 0; i < 20; i++) {
    double u = rng_uniform(&r), v = rng_uniform(&r);
    double ref = tex_eval(&plain, u, v).r;
    texture te = filtered(lv, n, TEX_FILTER_EWA, (tex_footprint){0, 0, 0, 0});
    texture tt = filtered(lv, n, TEX_FILTER_TRILINEAR, (tex_footprint){0, 0, 0, 0});
    assert_near(tex_eval(&te, u, v).r, ref, 1e-12);
    assert_near(tex_eval(&tt, u, v).r, ref, 1e-12);
    checks += 2;
  }
  /* Trilinear with a round footprint of 4 texels: level 2 alone. */
  texture l2 = tex_bitmap(&lv[2]);
  for (int i = 0; i < 20; i++) {
    double u = rng_uniform(&r), v = rng_uniform(&r);
    texture tt = filtered(lv, n, TEX_FILTER_TRILINEAR, (tex_footprint){4.0 / 64, 0, 0, 4.0 / 32});
    assert_near(tex_eval(&tt, u, v).r, tex_eval(&l2, u, v).r, 1e-12);
    checks++;
  }
  /* EWA on level 0 (minor radius at most 1 texel): the average with
   * weights exp(-2 q) - exp(-2) over the texel centres with q < 1, where
   * q = |J^-1 d|^2 for the offset d from the point in texels and J the
   * footprint's Jacobian in texels; summed here over a window by brute
   * force. It is not the bilinear value (the ellipse spans several texels). */
  const tex_footprint fps[2] = {{3.0 / 64, 0, 0, 0.5 / 32}, {1.5 / 64, 1.5 / 32, -0.4 / 64, 0.4 / 32}};
  int differs = 0;
  for (int f = 0; f < 2; f++) {
    double j00 = fps[f].dudx * 64, j01 = fps[f].dudy * 64, j10 = fps[f].dvdx * 32, j11 = fps[f].dvdy * 32;
    double det = j00 * j11 - j01 * j10;
    for (int i = 0; i < 10; i++) {
      double u = 0.2 + 0.6 * rng_uniform(&r), v = 0.2 + 0.6 * rng_uniform(&r);
      double x = u * 64 - 0.5, y = v * 32 - 0.5, sw = 0.0, sv = 0.0;
      for (int ty = (int)y - 6; ty <= (int)y + 6; ty++)
        for (int tx = (int)x - 6; tx <= (int)x + 6; tx++) {
          double dx = tx - x, dy = ty - y;
          double a = (j11 * dx - j01 * dy) / det, b = (-j10 * dx + j00 * dy) / det;
          double q = a * a + b * b;
          if (q >= 1.0) continue;
          double w = exp(-2.0 * q) - exp(-2.0);
          sw += w, sv += w * img.data[3 * (ty * 64 + tx)];
        }
      texture te = filtered(lv, n, TEX_FILTER_EWA, fps[f]);
      double got = tex_eval(&te, u, v).r;
      assert_near(got, sv / sw, 1e-6);
      differs += fabs(got - tex_eval(&plain, u, v).r) > 1e-3;
      checks++;
    }
  }
  assert_true(differs >= 15);
  checks++;
  /* A constant image gives its value at every level and footprint. */
  lmc_image grey = {64, 32, 3, calloc(64 * 32 * 3, sizeof(float))};
  for (int k = 0; k < 64 * 32 * 3; k++) grey.data[k] = 0.75f;
  int ng;
  lmc_image *lg = build_levels(&grey, &ng);
  for (int f = 0; f < 2; f++) {
    texture te = filtered(lg, ng, TEX_FILTER_EWA, fps[f]);
    texture tt = filtered(lg, ng, TEX_FILTER_TRILINEAR, (tex_footprint){7.0 / 64, 0, 1.0 / 64, 3.0 / 32});
    assert_near(tex_eval(&te, rng_uniform(&r), rng_uniform(&r)).g, 0.75, 1e-6);
    assert_near(tex_eval(&tt, rng_uniform(&r), rng_uniform(&r)).b, 0.75, 1e-6);
    checks += 2;
  }
  free_levels(lg, ng);
  free(grey.data);
  /* The mean of the lookups at uniform points is the image mean, for
   * footprints of every size and shape (4 standard errors). */
  const tex_footprint shapes[4] = {
      {0.5 / 64, 0, 0, 0.5 / 32}, {5.0 / 64, 0, 0, 5.0 / 32}, {9.0 / 64, 1.0 / 32, 0, 0.5 / 32},
      {30.0 / 64, 40.0 / 32, -20.0 / 64, 10.0 / 32}};
  double m = image_mean_r(&img);
  for (int f = 0; f < 2; f++)
    for (int k = 0; k < 4; k++) {
      texture t = filtered(lv, n, f == 0 ? TEX_FILTER_EWA : TEX_FILTER_TRILINEAR, shapes[k]);
      const int N = 20000;
      double s1 = 0.0, s2 = 0.0;
      for (int i = 0; i < N; i++) {
        double val = tex_eval(&t, rng_uniform(&r), rng_uniform(&r)).r;
        s1 += val, s2 += val * val;
      }
      double mean = s1 / N, se = sqrt(fmax(s2 / N - mean * mean, 1e-30) / N);
      if (!(fabs(mean - m) < 4.0 * se))
        print_error("filter %d footprint %d: mean %g, image %g, se %g\n", f, k, mean, m, se);
      assert_true(fabs(mean - m) < 4.0 * se);
      checks++;
    }
  free_levels(lv, n);
  free(img.data);
  assert_int_equal(checks, 2 + 40 + 20 + 20 + 1 + 4 + 8);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_constant),
      cmocka_unit_test(test_bitmap_lookup),
      cmocka_unit_test(test_checkerboard),
      cmocka_unit_test(test_wrap_nearest),
      cmocka_unit_test(test_mip_levels),
      cmocka_unit_test(test_filtered_lookup),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
