/*
 * test_bump.c: Mitsuba's bump map: the slope of a displacement texture
 * (tex_lum_gradient), a triangle's uv tangents (mesh_uv_tangents) and the
 * tilted shading frame (bsdf_shading_frame), in doubles and in duals.
 *
 * What is checked:
 *   - the slope of a bitmap against central differences of the luminance
 *     of tex_eval, at random points away from texel edges (where the
 *     bilinear interpolant is smooth), with uv scale and offset; constant
 *     and checkerboard textures have slope 0;
 *   - uv tangents: p0 + dpdu (u - u0) + dpdv (v - v0) gives back the
 *     other two corners, for random triangles and uv; a degenerate uv
 *     triangle gives two unit tangents orthogonal to the face; none
 *     without texture coordinates;
 *   - the frame: a flat displacement leaves the normal alone; a ramp of
 *     slope k along u on the plane z = 0 (dpdu = x, dpdv = y) tilts it to
 *     (-k, 0, 1) / sqrt(1 + k^2), exactly as the surface z = k u would
 *     be; the normal is unit and on the geometric side; an anisotropic
 *     ward's frame keeps n and turns x to follow dpdu;
 *   - duals: tex_lum_gradient_ad and bsdf_shading_frame_ad give the plain
 *     values (relative 1e-12) and derivatives in tu, tv and the normal
 *     that agree with central differences of the plain functions.
 * Fixed seeds; each test counts its checks and asserts the count.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "test_util.h"

#include "render/bsdf/bsdf.h"
#include "render/bsdf/bsdf_ad.h"
#include "render/mesh.h"
#include "render/rng.h"

#define SQRT1_2 0.70710678118654752440

/* A 7 x 5 RGB image of smooth-ish random values. */
static float g_px[7 * 5 * 3];
static lmc_image g_img = {7, 5, 3, g_px};

static void init_image(void) {
  rng r;
  rng_seed(&r, 31, 2);
  for (int i = 0; i < 7 * 5 * 3; i++) g_px[i] = (float)rng_uniform(&r);
}

static double lum_at(const texture *t, double u, double v) {
  return rgb_luminance(tex_eval(t, u, v));
}

/* Distance of a texel coordinate from the nearest texel edge (centres at
 * half-integers: the interpolant has kinks where x - 1/2 is an integer). */
static double edge_dist(double uv, double scale, double offset, int size) {
  double x = (uv * scale + offset) * size - 0.5;
  return fabs(x - floor(x + 0.5));
}

static void test_slope(void **state) {
  (void)state;
  init_image();
  texture t = tex_bitmap(&g_img);
  t.uscale = 1.7, t.vscale = 0.6, t.uoffset = 0.3, t.voffset = -0.2;
  rng r;
  rng_seed(&r, 5, 1);
  int checked = 0;
  const double h = 1e-6;
  while (checked < 500) {
    double u = 3.0 * rng_uniform(&r) - 1.0, v = 3.0 * rng_uniform(&r) - 1.0;
    if (edge_dist(u, t.uscale, t.uoffset, 7) < 0.01 || edge_dist(v, t.vscale, t.voffset, 5) < 0.01)
      continue;
    double du, dv;
    tex_lum_gradient(&t, u, v, &du, &dv);
    double fu = (lum_at(&t, u + h, v) - lum_at(&t, u - h, v)) / (2 * h);
    double fv = (lum_at(&t, u, v + h) - lum_at(&t, u, v - h)) / (2 * h);
    if (fabs(du - fu) > 1e-6 * fmax(1.0, fabs(fu)) || fabs(dv - fv) > 1e-6 * fmax(1.0, fabs(fv)))
      fail_msg("slope at (%g, %g): (%.9g, %.9g), differences (%.9g, %.9g)", u, v, du, dv, fu, fv);
    checked++;
  }
  /* Constant and checkerboard: flat. */
  texture c = tex_constant(rgb_make(0.2, 0.5, 0.9)), k = tex_checkerboard(rgb_gray(0.4), rgb_gray(0.2));
  double du, dv;
  tex_lum_gradient(&c, 0.3, 0.7, &du, &dv);
  assert_true(du == 0.0 && dv == 0.0);
  tex_lum_gradient(&k, 0.3, 0.7, &du, &dv);
  assert_true(du == 0.0 && dv == 0.0);
  checked += 2;
  assert_int_equal(checked, 502);
}

/* One triangle with texture coordinates, as a mesh of its own. */
typedef struct tri_mesh {
  mesh m;
  float p[9 + 3], uv[6];
  uint32_t idx[3];
} tri_mesh;

static void make_tri(tri_mesh *t, rng *r, int with_uv) {
  memset(t, 0, sizeof *t);
  for (int i = 0; i < 9; i++) t->p[i] = (float)(4.0 * rng_uniform(r) - 2.0);
  for (int i = 0; i < 6; i++) t->uv[i] = (float)(2.0 * rng_uniform(r) - 0.5);
  t->idx[0] = 0, t->idx[1] = 1, t->idx[2] = 2;
  t->m.n_vertices = 3;
  t->m.n_triangles = 1;
  t->m.p = t->p;
  t->m.uv = with_uv ? t->uv : NULL;
  t->m.idx = t->idx;
}

static void test_uv_tangents(void **state) {
  (void)state;
  rng r;
  rng_seed(&r, 8, 3);
  int checks = 0;
  for (int k = 0; k < 200; k++) {
    tri_mesh t;
    make_tri(&t, &r, 1);
    vec3 p[3] = {mesh_position(&t.m, 0), mesh_position(&t.m, 1), mesh_position(&t.m, 2)};
    vec3 dpdu, dpdv;
    assert_true(mesh_uv_tangents(&t.m, 0, p[0], p[1], p[2], &dpdu, &dpdv));
    for (int i = 1; i < 3; i++) {
      double du = (double)t.uv[2 * i] - t.uv[0], dv = (double)t.uv[2 * i + 1] - t.uv[1];
      vec3 q = v3_add(p[0], v3_add(v3_scale(dpdu, du), v3_scale(dpdv, dv)));
      double err = v3_len(v3_sub(q, p[i]));
      if (err > 1e-9 * (1.0 + v3_len(dpdu) + v3_len(dpdv)))
        fail_msg("triangle %d corner %d off by %g (|dpdu| %g, |dpdv| %g)", k, i, err, v3_len(dpdu),
                 v3_len(dpdv));
      checks++;
    }
  }
  /* Degenerate uv (all corners at one uv): unit tangents in the face. */
  tri_mesh t;
  make_tri(&t, &r, 1);
  for (int i = 0; i < 6; i++) t.uv[i] = 0.5f;
  vec3 p[3] = {mesh_position(&t.m, 0), mesh_position(&t.m, 1), mesh_position(&t.m, 2)};
  vec3 n = v3_normalize(v3_cross(v3_sub(p[1], p[0]), v3_sub(p[2], p[0]))), dpdu, dpdv;
  assert_true(mesh_uv_tangents(&t.m, 0, p[0], p[1], p[2], &dpdu, &dpdv));
  assert_true(fabs(v3_len(dpdu) - 1.0) < 1e-12 && fabs(v3_len(dpdv) - 1.0) < 1e-12);
  assert_true(fabs(v3_dot(dpdu, n)) < 1e-12 && fabs(v3_dot(dpdv, n)) < 1e-12);
  t.m.uv = NULL;
  assert_false(mesh_uv_tangents(&t.m, 0, p[0], p[1], p[2], &dpdu, &dpdv));
  checks += 3;
  assert_int_equal(checks, 2 * 200 + 3);
}

static void test_frame(void **state) {
  (void)state;
  int checks = 0;
  const vec3 x = v3(1, 0, 0), y = v3(0, 1, 0), z = v3(0, 0, 1);
  bsdf b;
  bsdf_init_defaults(&b, "diffuse");
  /* Unbumped, and bumped by a constant: the frame of n. */
  frame f = bsdf_shading_frame(&b, 0.3, 0.4, x, y, z, z);
  assert_true(f.n.x == 0.0 && f.n.y == 0.0 && f.n.z == 1.0);
  b.bumped = 1;
  b.bump = tex_constant(rgb_gray(0.7));
  f = bsdf_shading_frame(&b, 0.3, 0.4, v3(2, 0, 0), v3(0, 3, 0), z, z);
  assert_true(v3_len(v3_sub(f.n, z)) < 1e-15);
  checks += 2;
  /* A ramp: grey texels 0, 1, 2, 3 along u (one row): inside, the
   * luminance rises by 1 per texel, slope k = 4 (texels per unit u) times
   * the u scale. */
  float ramp[4 * 3];
  for (int i = 0; i < 12; i++) ramp[i] = (float)(i / 3);
  lmc_image img = {4, 1, 3, ramp};
  b.bump = tex_bitmap(&img);
  const double scales[3] = {1.0, 0.5, 2.0};
  for (int s = 0; s < 3; s++) {
    b.bump.uscale = scales[s];
    double k = 4.0 * scales[s];
    for (int side = 0; side < 2; side++) {
      /* Between the centres of texels 1 and 2 (u' = 0.45 .. 0.55). */
      double u = 0.5 / scales[s];
      vec3 ng = side ? v3_neg(z) : z;
      f = bsdf_shading_frame(&b, u, 0.5, x, y, z, ng);
      vec3 want = v3_scale(v3(-k, 0.0, 1.0), 1.0 / sqrt(1.0 + k * k));
      if (side) want = v3_neg(want);
      if (v3_len(v3_sub(f.n, want)) > 1e-12)
        fail_msg("ramp k = %g side %d: n (%g %g %g), want (%g %g %g)", k, side, f.n.x, f.n.y,
                 f.n.z, want.x, want.y, want.z);
      assert_true(fabs(v3_len(f.n) - 1.0) < 1e-12 && v3_dot(f.n, ng) > 0.0);
      assert_true(fabs(v3_dot(f.s, f.n)) < 1e-12 && fabs(v3_dot(f.t, f.n)) < 1e-12);
      checks++;
    }
  }
  /* An anisotropic ward without a bump: the normal kept, x along dpdu
   * made orthogonal to it. */
  bsdf w;
  bsdf_init_defaults(&w, "ward");
  w.alpha_u = 0.1, w.alpha_v = 0.3;
  assert_true(bsdf_is_anisotropic(&w) && bsdf_needs_tangents(&w));
  f = bsdf_shading_frame(&w, 0.3, 0.4, v3(1.0, 1.0, 0.3), y, z, z);
  assert_true(v3_len(v3_sub(f.n, z)) < 1e-15);
  assert_true(v3_len(v3_sub(f.s, v3(SQRT1_2, SQRT1_2, 0.0))) < 1e-15);
  assert_true(v3_len(v3_sub(f.t, v3(-SQRT1_2, SQRT1_2, 0.0))) < 1e-15);
  w.alpha_v = w.alpha_u;
  assert_false(bsdf_is_anisotropic(&w) || bsdf_needs_tangents(&w));
  checks += 5;
  assert_int_equal(checks, 2 + 3 * 2 + 5);
}

/* Duals against the plain functions: values and derivatives by central
 * differences, with the 5 variables tu, tv and the normal's (x, y, z). */
static double g_buf[1 << 14];

static void plain_frame(const bsdf *b, const double *x, vec3 dpdu, vec3 dpdv, vec3 ng,
                        double out[9]) {
  frame f = bsdf_shading_frame(b, x[0], x[1], dpdu, dpdv, v3_normalize(v3(x[2], x[3], x[4])), ng);
  const vec3 ax[3] = {f.n, f.s, f.t};
  for (int k = 0; k < 3; k++) out[3 * k] = ax[k].x, out[3 * k + 1] = ax[k].y, out[3 * k + 2] = ax[k].z;
}

static void test_duals(void **state) {
  (void)state;
  init_image();
  ad_arena A;
  assert_int_equal(ad_arena_init(&A, g_buf, sizeof g_buf / sizeof g_buf[0], 5), 0);
  bsdf models[3];
  bsdf_init_defaults(&models[0], "diffuse");
  models[0].bumped = 1;
  models[0].bump = tex_bitmap(&g_img);
  models[0].bump.uscale = 1.3;
  bsdf_init_defaults(&models[1], "ward");
  models[1].alpha_u = 0.1, models[1].alpha_v = 0.3;
  models[2] = models[1];
  models[2].bumped = 1;
  models[2].bump = models[0].bump;
  const size_t mark = ad_arena_mark(&A);
  rng r;
  rng_seed(&r, 77, 4);
  int checked = 0, points = 0;
  const double h = 1e-6;
  while (points < 600) {
    const bsdf b = models[points % 3];
    double x[5] = {rng_uniform(&r), rng_uniform(&r), 0.3 * rng_uniform(&r) - 0.15,
                   0.3 * rng_uniform(&r) - 0.15, 1.0};
    if (edge_dist(x[0], 1.3, 0.0, 7) < 0.01 || edge_dist(x[1], 1.0, 0.0, 5) < 0.01) continue;
    vec3 dpdu = v3(1.0, 0.2, 0.1), dpdv = v3(-0.1, 0.8, 0.3), ng = v3(0, 0, 1);
    ad_arena_rewind(&A, mark);
    ad xs[5];
    for (int i = 0; i < 5; i++) xs[i] = ad_var(&A, x[i], i);
    /* The slope in duals. */
    ad gu, gv;
    tex_lum_gradient_ad(&A, &models[0].bump, xs[0], xs[1], &gu, &gv);
    double pu, pv;
    tex_lum_gradient(&models[0].bump, x[0], x[1], &pu, &pv);
    assert_true(fabs(gu.v - pu) <= 1e-12 * fmax(1.0, fabs(pu)));
    assert_true(fabs(gv.v - pv) <= 1e-12 * fmax(1.0, fabs(pv)));
    /* The frame in duals. */
    adv3 n = adv3_normalize(&A, adv3_make(xs[2], xs[3], xs[4]));
    ad_frame fa = bsdf_shading_frame_ad(&A, &b, xs[0], xs[1], dpdu, dpdv, n, ng);
    assert_true(ad_arena_ok(&A));
    double v0[9];
    plain_frame(&b, x, dpdu, dpdv, ng, v0);
    const ad *na[9] = {&fa.n.x, &fa.n.y, &fa.n.z, &fa.s.x, &fa.s.y, &fa.s.z, &fa.t.x, &fa.t.y, &fa.t.z};
    for (int c = 0; c < 9; c++) assert_true(fabs(na[c]->v - v0[c]) <= 1e-12);
    for (int j = 0; j < 5; j++) {
      double xp[5], xm[5], vp[9], vm[9];
      memcpy(xp, x, sizeof xp);
      memcpy(xm, x, sizeof xm);
      xp[j] += h, xm[j] -= h;
      plain_frame(&b, xp, dpdu, dpdv, ng, vp);
      plain_frame(&b, xm, dpdu, dpdv, ng, vm);
      for (int c = 0; c < 9; c++) {
        double fd = (vp[c] - vm[c]) / (2 * h), d = na[c]->d[j];
        if (fabs(d - fd) > 1e-6 * fmax(1.0, fabs(fd)))
          fail_msg("point %d: dn[%d]/dx[%d] = %.9g, differences %.9g", points, c, j, d, fd);
        checked++;
      }
    }
    points++;
  }
  assert_int_equal(checked, 600 * 5 * 9);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_slope),
      cmocka_unit_test(test_uv_tangents),
      cmocka_unit_test(test_frame),
      cmocka_unit_test(test_duals),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
