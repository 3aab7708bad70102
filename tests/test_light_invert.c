/*
 * test_light_invert.c: the inverses of the emitters' samplers
 * (light_invert_le, light_invert_li, light_disk_invert) and of the film
 * sample (camera_invert), on the scene of light_scene.h (one light of each
 * kind, an area light of four triangles of unequal areas, envmaps with
 * black regions).
 *
 * Every sampler here is a bijection between the numbers it reads and what
 * it makes, so the inverses are checked by round trips both ways, with u
 * away from the square's edges:
 *   - u -> sample -> invert (random r for unread numbers) gives u back to
 *     1e-9 for every number the sampler reads, and r for the others;
 *   - re-sampling from the inverted numbers gives the same point (1e-9 of
 *     the scene's radius) and direction (1e-9);
 *   - an area-light point inverts into its own triangle's cell of u1 (the
 *     discrete choice, distrib1d_invert_discrete), and points of a light
 *     facing away from ref, directions outside a spot's cone and an
 *     envmap's black region are refused.
 * Each test counts its checks and asserts the count.
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

#include "light_scene.h"
#include "render/camera.h"
#include "render/rng.h"
#include "render/warp.h"

static double inner(rng *r) { return 1e-3 + (1.0 - 2e-3) * rng_uniform(r); }

/* Which of the four numbers light_sample_le reads, per light kind. */
static int le_reads(light_type t, int i) {
  switch (t) {
  case LIGHT_AREA:
  case LIGHT_CONSTANT:
  case LIGHT_ENVMAP:
    return 1;
  case LIGHT_POINT:
  case LIGHT_SPOT:
    return i >= 2;
  case LIGHT_DIRECTIONAL:
    return i < 2;
  }
  return 0;
}

static void test_le_round_trip(void **state) {
  (void)state;
  long checks = 0;
  for (int li = 0; li < N_LIGHTS; li++) {
    const light *l = L(li);
    rng g;
    rng_seed(&g, 41, (uint64_t)li);
    int done = 0;
    for (int i = 0; i < 3000; i++) {
      double u[4] = {inner(&g), inner(&g), inner(&g), inner(&g)};
      light_le_sample a;
      if (!light_sample_le(l, g_scene, u[0], u[1], u[2], u[3], &a)) continue;
      /* The sample names its triangle (the discrete choice u1 made). */
      int64_t tri = a.tri;
      assert_int_equal(tri, l->type == LIGHT_AREA
                                ? distrib1d_sample_discrete(&l->tri_dist, u[0], NULL, NULL)
                                : -1);
      double r[4] = {rng_uniform(&g), rng_uniform(&g), rng_uniform(&g), rng_uniform(&g)};
      double v[4];
      assert_true(light_invert_le(l, g_scene, a.p, a.dir, tri, r, v));
      for (int k = 0; k < 4; k++) {
        assert_true(v[k] >= 0.0 && v[k] < 1.0);
        assert_near(v[k], le_reads(l->type, k) ? u[k] : r[k], 1e-9);
      }
      light_le_sample b;
      assert_true(light_sample_le(l, g_scene, v[0], v[1], v[2], v[3], &b));
      assert_near(v3_len(v3_sub(a.p, b.p)), 0.0, 1e-9 * g_scene->radius);
      assert_near(v3_len(v3_sub(a.dir, b.dir)), 0.0, 1e-9);
      checks += 6;
      done++;
    }
    if (done < 1000) {
      print_error("light %d: %d of 3000 emissions\n", li, done);
      fail();
    }
  }
  print_message("emission round trips: %ld checks over %d lights\n", checks, N_LIGHTS);
  assert_true(checks >= 6L * 1000 * N_LIGHTS);
}

static void test_li_round_trip(void **state) {
  (void)state;
  long checks = 0;
  for (int li = 0; li < N_LIGHTS; li++) {
    const light *l = L(li);
    /* Receivers below the area light, inside the spot's cone. */
    vec3 refs[2] = {v3(0.1, 0.05, 0.0), v3(-0.3, 0.2, 0.4)};
    if (l->type == LIGHT_SPOT) {
      refs[0] = v3_fma(l->pos, l->frm.n, 2.0);
      refs[1] = v3_fma(v3_fma(l->pos, l->frm.n, 3.0), l->frm.s, 0.5);
    }
    int reads = l->type == LIGHT_AREA || l->type == LIGHT_CONSTANT || l->type == LIGHT_ENVMAP;
    for (int ri = 0; ri < 2; ri++) {
      rng g;
      rng_seed(&g, 43, (uint64_t)(2 * li + ri));
      int done = 0;
      for (int i = 0; i < 1500; i++) {
        double u[2] = {inner(&g), inner(&g)};
        light_li_sample a;
        if (!light_sample_li(l, g_scene, refs[ri], u[0], u[1], &a)) continue;
        int64_t tri = a.tri;
        assert_int_equal(tri, l->type == LIGHT_AREA
                                  ? distrib1d_sample_discrete(&l->tri_dist, u[0], NULL, NULL)
                                  : -1);
        double r[2] = {rng_uniform(&g), rng_uniform(&g)}, v[2];
        assert_true(light_invert_li(l, g_scene, refs[ri], a.wi, a.p, tri, r, v));
        assert_near(v[0], reads ? u[0] : r[0], 1e-9);
        assert_near(v[1], reads ? u[1] : r[1], 1e-9);
        light_li_sample b;
        assert_true(light_sample_li(l, g_scene, refs[ri], v[0], v[1], &b));
        assert_near(v3_len(v3_sub(a.wi, b.wi)), 0.0, 1e-9);
        if (isfinite(a.dist)) assert_near(v3_len(v3_sub(a.p, b.p)), 0.0, 1e-9 * g_scene->radius);
        checks += 4;
        done++;
      }
      if (done < 500) {
        print_error("light %d ref %d: %d of 1500 samples\n", li, ri, done);
        fail();
      }
    }
  }
  print_message("direct-sampling round trips: %ld checks\n", checks);
  assert_true(checks >= 4L * 500 * 2 * N_LIGHTS);
}

/* The area light's discrete choice and the refusals. */
static void test_refusals(void **state) {
  (void)state;
  int checks = 0;
  const light *area = L(L_AREA);
  double r[4] = {0.25, 0.5, 0.75, 0.125}, v[4];
  /* Each triangle's points land in its own cell of u1. */
  for (int tri = 0; tri < area->tri_dist.n; tri++) {
    const mesh *m = &g_scene->meshes[area->mesh];
    const uint32_t *ix = m->idx + 3 * tri;
    vec3 c = v3_scale(v3_add(v3_add(mesh_position(m, ix[0]), mesh_position(m, ix[1])),
                             mesh_position(m, ix[2])),
                      1.0 / 3.0);
    assert_true(light_invert_le(area, g_scene, c, v3(0.0, 0.0, -1.0), tri, r, v));
    assert_true(v[0] >= area->tri_dist.cdf[tri] && v[0] < area->tri_dist.cdf[tri + 1]);
    assert_int_equal(distrib1d_sample_discrete(&area->tri_dist, v[0], NULL, NULL), tri);
    /* Seen from above (behind its emitting side) it is refused. */
    assert_false(light_invert_li(area, g_scene, v3(0.0, 0.0, 2.0), v3(0.0, 0.0, -1.0), c, tri, r,
                                 v));
    /* Emission upwards, into its back, too. */
    assert_false(light_invert_le(area, g_scene, c, v3(0.0, 0.0, 1.0), tri, r, v));
    checks += 5;
  }
  /* A spot's direction outside its cone. */
  const light *spot = L(L_SPOT);
  assert_false(light_invert_le(spot, g_scene, spot->pos, v3_neg(spot->frm.n), -1, r, v));
  /* A directional light's ray must travel its direction. */
  const light *dl = L(L_DIR);
  assert_false(light_invert_le(dl, g_scene, g_scene->center, v3_neg(dl->frm.n), -1, r, v));
  /* The envmap's black pixels (x 4-7, y >= 10 of the single-pixel and test maps): the
   * single-pixel map refuses every direction but its pixel's. */
  const light *one = L(L_ENV_ONE);
  assert_false(light_invert_li(one, g_scene, v3(0.0, 0.0, 0.0), v3(0.0, 1.0, 0.0), v3(0, 0, 0), -1,
                               r, v));
  checks += 3;
  assert_int_equal(checks, 5 * 4 + 3);
}

static void test_camera_invert(void **state) {
  (void)state;
  camera c;
  memset(&c, 0, sizeof c);
  assert_true(xform_lookat(v3(1.0, 2.0, 3.0), v3(0.0, 0.5, 0.0), v3(0.0, 1.0, 0.0), &c.to_world));
  assert_true(camera_set_fov(&c, 40.0, "x", 320, 240));
  rng g;
  rng_seed(&g, 47, 0);
  int checks = 0;
  for (int i = 0; i < 5000; i++) {
    double u1 = inner(&g), u2 = inner(&g), v1, v2;
    vec3 org, d;
    camera_generate_ray(&c, u1 * c.width, u2 * c.height, &org, &d);
    assert_true(camera_invert(&c, d, &v1, &v2));
    assert_near(v1, u1, 1e-9);
    assert_near(v2, u2, 1e-9);
    checks++;
  }
  /* Behind the camera: no film position. */
  assert_false(camera_invert(&c, v3_neg(c.forward), &(double){0}, &(double){0}));
  assert_int_equal(checks, 5000);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_le_round_trip),
      cmocka_unit_test(test_li_round_trip),
      cmocka_unit_test(test_refusals),
      cmocka_unit_test(test_camera_invert),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
