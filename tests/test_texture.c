/*
 * test_texture.c: the textures of src/render/texture.c.
 *
 * What is checked: constants; the bitmap lookup of Mitsuba (pixel centres
 * at half-integers, bilinear weights, repeat wrapping on both axes and for
 * negative and large coordinates, v = 0 at the top row without a flip, the
 * uv scale and offset, grey and RGBA images) and its mean (cached or not);
 * the checkerboard's parity rule (truncation toward zero, squares of 1/2,
 * color0 when both parities agree), its defaults and its mean. Each test
 * counts its checks and asserts the count.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "test_util.h"

#include "render/bsdf/texture.h"


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

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_constant),
      cmocka_unit_test(test_bitmap_lookup),
      cmocka_unit_test(test_checkerboard),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
