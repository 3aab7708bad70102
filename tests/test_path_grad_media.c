/*
 * test_path_grad_media.c: the differentiable path sampler's unidirectional
 * estimator (path_eval_pt) through participating media, on two scenes of
 * tests/data/media: furnace.xml (fogs behind an index-matched boundary and
 * inside a glass sphere, in a box of emitting walls: free flights across
 * boundaries, shadow rays through them to an area light) and
 * rough_glass_fog.xml (a fog no shape encloses, a rough glass sphere of
 * fog, a point light: transmittance along shadow rays to a delta light,
 * phase functions with g 0 and 0.6).
 *
 *  - value agreement: for the same numbers path_eval_pt gives pt_li_media's
 *    radiance to 1e-9 relative (the pieces' lengths are the distances
 *    between the re-evaluated boundary hits, Embree's t on the plain side)
 *    and consumes the same count of numbers (two more per bounce);
 *  - gradient: d luminance / du and d rgb / du against Richardson-
 *    extrapolated central differences (path_grad_util.h's pg_fd_check)
 *    wherever the topology is the same at u + h and u - h; the flights'
 *    distance numbers are among the coordinates, and paths with a
 *    scattering point and with a boundary crossed are counted.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "render/integrators/path_internal.h" /* (the arena's size) */
#include "render/io/io.h"
#include "render/integrators/path.h"
#include "test_util.h"
#include "path_grad_util.h"
#include "load_scene.h"

static const char *const scenes[2] = {"data/media/furnace.xml", "data/media/rough_glass_fog.xml"};

typedef struct fixture {
  scene *sc[2];
  path_scratch *ps;
} fixture;

static int setup(void **state) {
  fixture *fx = calloc(1, sizeof *fx);
  for (int i = 0; i < 2; i++) {
    fx->sc[i] = try_load_scene(scenes[i]);
    if (!fx->sc[i] || fx->sc[i]->n_media == 0) return -1;
  }
  lmc_error err;
  if (path_scratch_create(&fx->ps, &err) != LMC_OK) return -1;
  *state = fx;
  return 0;
}

static int teardown(void **state) {
  fixture *fx = *state;
  path_scratch_destroy(fx->ps);
  for (int i = 0; i < 2; i++) scene_destroy(fx->sc[i]);
  free(fx);
  return 0;
}

/* The scene's settings for these checks: paths of at most 6 segments,
 * Russian roulette from the third. */
static render_settings settings_of(const scene *sc) {
  render_settings rs = sc->settings;
  rs.maxdepth = 6;
  rs.rrdepth = 3;
  return rs;
}

/* For the same numbers, path_eval_pt gives pt_li_media's value. */
static void test_value_matches_pt_li_media(void **state) {
  fixture *fx = *state;
  int checked = 0;
  for (int q = 0; q < 2; q++) {
    const scene *sc = fx->sc[q];
    render_settings rs = settings_of(sc);
    path_vec_sampler vs;
    path_vec_sampler_init(&vs, 17 + (uint64_t)q, NULL);
    int n = 3000, nonzero = 0, mismatched = 0;
    for (int i = 0; i < n; i++) {
      path_vec_sampler_clear(&vs);
      path_eval ev;
      path_eval_pt(sc, &rs, &vs.base, 0, fx->ps, &ev, NULL);
      path_vec_sampler_rewind(&vs);
      double u0 = sampler_next(&vs.base), u1 = sampler_next(&vs.base);
      vec3 org, dir;
      camera_generate_ray(&sc->cam, u0 * sc->cam.width, u1 * sc->cam.height, &org, &dir);
      render_counters cnt = {0};
      rgb L = pt_li_media(sc, &rs, &vs.base, org, dir, NULL, &cnt);
      assert_int_equal(vs.pos[LMC_STREAM_CAMERA], ev.n_coords);
      if (!pg_rgb_rel_equal(L, ev.value, 1e-9)) {
        mismatched++;
        print_message("%s path %d: pt_li_media (%.17g %.17g %.17g) path_eval_pt (%.17g %.17g "
                      "%.17g)\n",
                      scenes[q], i, L.r, L.g, L.b, ev.value.r, ev.value.g, ev.value.b);
      }
      nonzero += !rgb_is_black(L);
      checked++;
    }
    path_vec_sampler_free(&vs);
    print_message("%s: %d paths, %d non-zero, %d mismatched\n", scenes[q], n, nonzero,
                  mismatched);
    assert_int_equal(mismatched, 0);
    assert_true(nonzero > n / 4);
  }
  assert_int_equal(checked, 6000);
}

/* Whether the path of vs (just evaluated) scattered in a medium: a
 * flight's distance number (the second of a bounce) is a coordinate with
 * a derivative that moves the value. */
static int flight_coords(const path_eval *ev) {
  int n = 0;
  for (int i = 0; i < ev->n_coords; i++) {
    const path_coord *pc = &ev->coords[i];
    int in_bounce = (pc->pos - PT_DIMS_CAMERA) % (PT_DIMS_PER_BOUNCE + PT_DIMS_MEDIA);
    n += pc->diff && pc->pos >= PT_DIMS_CAMERA && in_bounce == 1 && pc->dlum != 0.0;
  }
  return n;
}

static void test_gradient_matches_fd(void **state) {
  fixture *fx = *state;
  for (int q = 0; q < 2; q++) {
    const scene *sc = fx->sc[q];
    render_settings rs = settings_of(sc);
    path_vec_sampler vs;
    path_vec_sampler_init(&vs, 23 + (uint64_t)q, NULL);
    pg_fd_stats st = {0};
    int tries = 0, with_flight = 0;
    while (st.paths < 200 && tries < 20000) {
      tries++;
      path_vec_sampler_clear(&vs);
      path_eval ev;
      path_eval_pt(sc, &rs, &vs.base, 1, fx->ps, &ev, NULL);
      if (!ev.grad_ok) continue;
      with_flight += flight_coords(&ev) > 0;
      pg_fd_check(sc, fx->ps, &rs, &vs, PG_PT, &ev, &st);
    }
    path_vec_sampler_free(&vs);
    print_message("%s: %d paths (%d with a flight's derivative), %d components (%d non-trivial), "
                  "%d passed, %d skipped (topology)\n",
                  scenes[q], st.paths, with_flight, st.components, st.nontrivial, st.passed,
                  st.skipped_topology);
    assert_int_equal(st.paths, 200);
    assert_true(with_flight > 50);
    assert_true(st.components > 2000);
    assert_true(st.nontrivial > st.components / 4);
    assert_true(st.passed >= 0.995 * st.components);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_value_matches_pt_li_media),
      cmocka_unit_test(test_gradient_matches_fd),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
