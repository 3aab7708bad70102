/*
 * test_path_grad.c: the differentiable path sampler (render/integrators/path.h) on a
 * small built-in scene: a diffuse floor and sphere, a rough metal sphere,
 * a rectangular area light, a point light and a constant sky, so that
 * every kind of vertex and emitter of pt_li occurs.
 *
 *  - value agreement: for the same numbers path_eval_pt returns pt_li's
 *    radiance (to 1e-9 relative), i.e. the layout and the estimator are
 *    the same;
 *  - gradient: d luminance / du and d rgb / du against central differences
 *    with Richardson-extrapolated central differences (the best converged of
 *    h = 1e-4 ... 1e-7) wherever the topology hash is the same at u + h
 *    and u - h;
 *  - the same two checks for path_eval_bdpt: random strategies (s, t) of
 *    every length up to maxdepth against bdpt_connect (value and, for
 *    t = 1, splat position), and their gradients (for t = 1 also d rx/du,
 *    d ry/du), counted per group of strategies (s = 0, s = 1, t = 1,
 *    s, t >= 2).
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

static const char *scene_xml =
    "<scene version=\"0.6.0\">\n"
    "  <integrator type=\"path\"><integer name=\"maxDepth\" value=\"5\"/></integrator>\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"45\"/>\n"
    "    <transform name=\"toWorld\"><lookat origin=\"0, 2, 5\" target=\"0, 0.5, 0\" up=\"0, 1, 0\"/></transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"24\"/>"
    "<rfilter type=\"box\"/></film>\n"
    "  </sensor>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/><scale x=\"4\" y=\"1\" z=\"4\"/></transform>\n"
    "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6, 0.5, 0.4\"/></bsdf>\n"
    "  </shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"-0.8\" y=\"0.6\" z=\"0\"/><float name=\"radius\" value=\"0.6\"/>\n"
    "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.3, 0.7, 0.3\"/></bsdf>\n"
    "  </shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0.8\" y=\"0.6\" z=\"0.2\"/><float name=\"radius\" value=\"0.6\"/>\n"
    "    <bsdf type=\"roughconductor\"><string name=\"material\" value=\"Au\"/>"
    "<string name=\"distribution\" value=\"ggx\"/><float name=\"alpha\" value=\"0.2\"/></bsdf>\n"
    "  </shape>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/><scale x=\"0.5\" y=\"1\" z=\"0.5\"/>"
    "<translate x=\"0.3\" y=\"3\" z=\"0.5\"/></transform>\n"
    "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"20, 18, 15\"/></emitter>\n"
    "  </shape>\n"
    "  <emitter type=\"point\"><point name=\"position\" x=\"-2\" y=\"2.5\" z=\"2\"/>"
    "<rgb name=\"intensity\" value=\"6, 6, 8\"/></emitter>\n"
    "  <emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.2, 0.25, 0.3\"/></emitter>\n"
    "</scene>\n";

typedef struct fixture {
  scene *sc;
  path_scratch *ps;
} fixture;

static int setup(void **state) {
  fixture *fx = calloc(1, sizeof *fx);
  fx->sc = try_load_scene_text(scene_xml, "path_grad");
  if (!fx->sc) return -1;
  lmc_error err;
  if (path_scratch_create(&fx->ps, &err) != LMC_OK) return -1;
  *state = fx;
  return 0;
}

static int teardown(void **state) {
  fixture *fx = *state;
  path_scratch_destroy(fx->ps);
  scene_destroy(fx->sc);
  free(fx);
  return 0;
}

/* For the same numbers, path_eval_pt gives pt_li's value. */
static void test_pt_value_matches_pt_li(void **state) {
  fixture *fx = *state;
  render_settings rs = fx->sc->settings;
  rs.rrdepth = 3; /* exercise Russian roulette within maxdepth 5 */
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 7, NULL);
  int n = 3000, nonzero = 0, mismatched = 0;
  for (int i = 0; i < n; i++) {
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_pt(fx->sc, &rs, &vs.base, 0, fx->ps, &ev, NULL);

    /* The same numbers through pt_li. */
    path_vec_sampler_rewind(&vs);
    double u0 = sampler_next(&vs.base), u1 = sampler_next(&vs.base);
    vec3 org, dir;
    camera_generate_ray(&fx->sc->cam, u0 * fx->sc->cam.width, u1 * fx->sc->cam.height, &org, &dir);
    render_counters cnt = {0};
    rgb L = pt_li(fx->sc, &rs, &vs.base, org, dir, NULL, &cnt);
    assert_int_equal(vs.pos[LMC_STREAM_CAMERA], ev.n_coords);
    assert_near(ev.rx, u0 * fx->sc->cam.width, 0.0);
    if (!pg_rgb_rel_equal(L, ev.value, 1e-9)) {
      mismatched++;
      print_message("path %d: pt_li (%.17g %.17g %.17g) path_eval_pt (%.17g %.17g %.17g)\n", i,
                    L.r, L.g, L.b, ev.value.r, ev.value.g, ev.value.b);
    }
    if (!rgb_is_black(L)) nonzero++;
  }
  path_vec_sampler_free(&vs);
  print_message("value agreement: %d paths, %d non-zero, %d mismatched\n", n, nonzero, mismatched);
  assert_int_equal(mismatched, 0);
  assert_true(nonzero > n / 4);
}

static void test_pt_gradient_matches_fd(void **state) {
  fixture *fx = *state;
  render_settings rs = fx->sc->settings;
  rs.rrdepth = 3;
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 11, NULL);
  pg_fd_stats st = {0};
  int tries = 0;
  while (st.paths < 300 && tries < 20000) {
    tries++;
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_pt(fx->sc, &rs, &vs.base, 1, fx->ps, &ev, NULL);
    if (!ev.grad_ok) continue;
    /* The gradient is reported for exactly the continuous coordinates a
     * path uses: those of the last bounce when it stops at maxdepth are not. */
    int bounces = (ev.n_coords - 2) / PT_DIMS_PER_BOUNCE;
    int dead = rs.maxdepth >= 0 && bounces >= rs.maxdepth;
    assert_int_equal(ev.n_diff, 2 + 4 * (bounces - dead));
    assert_near(ev.coords[0].drx, fx->sc->cam.width, 0.0);
    pg_fd_check(fx->sc, fx->ps, &rs, &vs, PG_PT, &ev, &st);
  }
  path_vec_sampler_free(&vs);
  print_message("gradient: %d paths, %d components (%d non-trivial), %d passed, %d skipped "
                "(topology)\n",
                st.paths, st.components, st.nontrivial, st.passed, st.skipped_topology);
  assert_int_equal(st.paths, 300);
  assert_true(st.components > 3000);
  assert_true(st.nontrivial > st.components / 4);
  /* Extrapolated central differences have truncation error ~h^4 and
   * rounding ~1e-16 f / h at the chosen h; what remains are paths within h
   * of a discontinuity the topology hash does not see. */
  assert_true(st.passed >= 0.995 * st.components);
}

/* For the same numbers, path_eval_bdpt gives bdpt_connect's MIS-weighted
 * value (and, for t = 1, its splat position), over random strategies of
 * every length up to maxdepth. */
static void test_bdpt_value_matches_bdpt_connect(void **state) {
  fixture *fx = *state;
  render_settings rs = fx->sc->settings;
  rs.rrdepth = 3;
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 17, NULL);
  rng r;
  rng_seed(&r, 5, 1);
  /* Most light subpaths start on the sky and leave this open scene, so
   * strategies with s >= 2 or t = 1 are rarely non-zero: draw until every
   * group has 100 non-zero paths (about 30000 paths, 1 s). */
  int n = 0, mismatched = 0, nonzero[PG_GROUPS] = {0}, tried[PG_GROUPS] = {0};
  for (int i = 0; i < 100000; i++) {
    int done = 1;
    for (int g = 0; g < PG_GROUPS; g++) done = done && nonzero[g] >= 100;
    if (done) break;
    pg_strategy st = pg_random_strategy(&r, rs.maxdepth);
    if (nonzero[pg_group(st)] >= 100) continue;
    n++;
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_bdpt(fx->sc, &rs, &vs.base, st.s, st.t, 0, fx->ps, &ev, NULL);
    double rx, ry;
    rgb L = pg_bdpt_reference(fx->sc, &rs, &vs, st, &rx, &ry);
    int ok = pg_rgb_rel_equal(L, ev.value, 1e-9);
    if (st.t == 1 && !rgb_is_black(L))
      ok = ok && pg_rel_equal(rx, ev.rx, 1e-9) && pg_rel_equal(ry, ev.ry, 1e-9);
    if (!ok) {
      mismatched++;
      print_message("path %d (s,t) = (%d,%d): bdpt_connect (%.17g %.17g %.17g) at (%g %g), "
                    "path_eval_bdpt (%.17g %.17g %.17g) at (%g %g)\n",
                    i, st.s, st.t, L.r, L.g, L.b, rx, ry, ev.value.r, ev.value.g, ev.value.b,
                    ev.rx, ev.ry);
    }
    tried[pg_group(st)]++;
    nonzero[pg_group(st)] += !rgb_is_black(L);
  }
  path_vec_sampler_free(&vs);
  print_message("bdpt value agreement: %d paths, %d mismatched\n", n, mismatched);
  for (int g = 0; g < PG_GROUPS; g++)
    print_message("    %-22s %5d paths, %5d non-zero\n", pg_group_name(g), tried[g], nonzero[g]);
  assert_int_equal(mismatched, 0);
  /* Every kind of strategy contributed often enough to mean something. */
  for (int g = 0; g < PG_GROUPS; g++) assert_true(nonzero[g] >= 100);
}

/* Gradients of bidirectional strategies against central differences, per
 * group of strategies; for t = 1 also the splat's raster position. */
static void test_bdpt_gradient_matches_fd(void **state) {
  fixture *fx = *state;
  render_settings rs = fx->sc->settings;
  rs.rrdepth = 3;
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 23, NULL);
  rng r;
  rng_seed(&r, 9, 3);
  pg_fd_stats st = {0};
  int paths[PG_GROUPS] = {0}, comps[PG_GROUPS] = {0};
  int tries = 0;
  while (st.paths < 300 && tries < 200000) {
    tries++;
    pg_strategy sg = pg_random_strategy(&r, rs.maxdepth);
    if (paths[pg_group(sg)] >= 75) continue; /* 75 paths per group */
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_bdpt(fx->sc, &rs, &vs.base, sg.s, sg.t, 1, fx->ps, &ev, NULL);
    if (!ev.grad_ok) continue;
    /* Exactly the continuous coordinates got a tangent slot. */
    assert_int_equal(ev.n_diff, pg_bdpt_n_diff(sg));
    assert_int_equal(ev.length, sg.s + sg.t - 1);
    int before = st.components;
    pg_fd_check(fx->sc, fx->ps, &rs, &vs, sg, &ev, &st);
    paths[pg_group(sg)]++;
    comps[pg_group(sg)] += st.components - before;
  }
  path_vec_sampler_free(&vs);
  print_message("bdpt gradient: %d paths, %d components (%d non-trivial, %d raster), %d passed, "
                "%d skipped (topology)\n",
                st.paths, st.components, st.nontrivial, st.raster, st.passed,
                st.skipped_topology);
  for (int g = 0; g < PG_GROUPS; g++)
    print_message("    %-22s %5d paths, %6d components\n", pg_group_name(g), paths[g], comps[g]);
  assert_int_equal(st.paths, 300);
  assert_true(st.components > 3000);
  assert_true(st.nontrivial > st.components / 4);
  assert_true(st.raster >= 200);
  for (int g = 0; g < PG_GROUPS; g++) {
    assert_int_equal(paths[g], 75);
    assert_true(comps[g] >= 500);
  }
  assert_true(st.passed >= 0.995 * st.components);
}

/* Prints and asserts what a Hessian check covered. */
static void hess_report(const char *what, const pg_hess_stats *st, int paths) {
  print_message("%s Hessian: %d paths, %d entries (%d non-trivial, %d of them off the diagonal), "
                "%d passed, %d coordinates skipped (topology), %d unconverged, %d value/gradient "
                "mismatches\n",
                what, st->paths, st->entries, st->nontrivial, st->offdiag, st->passed,
                st->skipped_topology, st->unconverged, st->mismatched);
  assert_int_equal(st->paths, paths);
  assert_int_equal(st->mismatched, 0);
  assert_true(st->unconverged <= st->entries / 50);
  assert_true(st->entries > 20 * paths);
  assert_true(st->nontrivial > st->entries / 10);
  assert_true(st->offdiag > st->nontrivial / 4);
  /* As for the gradient: what fails are paths within h of a discontinuity
   * the topology hash does not see. */
  assert_true(st->passed >= 0.995 * st->entries);
}

/* Hessians of unidirectional paths (PATH_WANT_HESS) against central
 * differences of their gradients. */
static void test_pt_hessian_matches_fd(void **state) {
  fixture *fx = *state;
  render_settings rs = fx->sc->settings;
  rs.rrdepth = 3;
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 31, NULL);
  pg_hess_stats st = {0};
  int tries = 0;
  while (st.paths < 100 && tries < 20000) {
    tries++;
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_pt(fx->sc, &rs, &vs.base, PATH_WANT_HESS, fx->ps, &ev, NULL);
    if (!ev.grad_ok) continue;
    assert_true(ev.hess_ok);
    pg_hess_check(fx->sc, fx->ps, &rs, &vs, PG_PT, &ev, &st);
  }
  path_vec_sampler_free(&vs);
  hess_report("pt", &st, 100);
}

/* Long paths (up to 24 bounces, no roulette): a second-order arena keeps
 * every dual of the evaluation, more than its first size (4096) here, so
 * the evaluator grows it and evaluates again; the Hessians still match the
 * differences. Counts: at least 5 paths of 16+ segments, every one with its
 * Hessian. */
static void test_pt_hessian_long_paths(void **state) {
  fixture *fx = *state;
  render_settings rs = fx->sc->settings;
  rs.maxdepth = 24;
  rs.rrdepth = 1000;
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 47, NULL);
  pg_hess_stats st = {0};
  int tries = 0, long_paths = 0;
  while (long_paths < 5 && tries < 200000) {
    tries++;
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_pt(fx->sc, &rs, &vs.base, PATH_WANT_HESS, fx->ps, &ev, NULL);
    if (!ev.grad_ok || ev.length < 16 || ev.n_diff > AD_H_CAPACITY) continue;
    assert_true(ev.hess_ok);
    long_paths++;
    pg_hess_check(fx->sc, fx->ps, &rs, &vs, PG_PT, &ev, &st);
  }
  path_vec_sampler_free(&vs);
  print_message("long paths: %d of 16+ segments in %d tries, the arena grown to %zu duals\n",
                long_paths, tries, fx->ps->arena2_duals);
  assert_int_equal(long_paths, 5);
  assert_true(fx->ps->arena2_duals > PATH__ARENA2_DUALS);
  hess_report("pt, long paths", &st, 5);
}

/* Whether two evaluations of one path agree bit for bit: value, gradient
 * and (both present or both absent) Hessian. */
static int same_eval(const path_eval *a, const path_eval *b) {
  if (memcmp(&a->value, &b->value, sizeof a->value) || a->grad_ok != b->grad_ok ||
      a->hess_ok != b->hess_ok || a->n_coords != b->n_coords || a->n_diff != b->n_diff)
    return 0;
  for (int i = 0; i < a->n_coords; i++)
    if (memcmp(&a->coords[i].dlum, &b->coords[i].dlum, sizeof a->coords[i].dlum)) return 0;
  size_t nh = (size_t)a->n_diff * (size_t)(a->n_diff + 1) / 2;
  return !a->hess_ok || memcmp(a->hlum, b->hlum, nh * sizeof *a->hlum) == 0;
}

/* Chains share a thread's path scratch (their arenas), so what a scratch
 * evaluated before must not change an evaluation: paths evaluated with
 * their Hessians in one scratch, first 10 long ones (16+ segments, which
 * grow its second-order arena) and then 60 of any length, agree bit for
 * bit with the same paths evaluated in a fresh scratch each. */
static void test_hessian_independent_of_scratch(void **state) {
  fixture *fx = *state;
  render_settings rs = fx->sc->settings;
  rs.maxdepth = 24;
  lmc_error err;
  path_scratch *grown = NULL, *fresh = NULL;
  assert_int_equal(path_scratch_create(&grown, &err), LMC_OK);
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 53, NULL);
  int checked[2] = {0, 0}, want[2] = {10, 60}, tries = 0;
  for (int phase = 0; phase < 2; phase++) {
    rs.rrdepth = phase == 0 ? 1000 : 2;
    while (checked[phase] < want[phase] && tries < 400000) {
      tries++;
      path_vec_sampler_clear(&vs);
      path_eval a, b;
      path_eval_pt(fx->sc, &rs, &vs.base, PATH_WANT_HESS, grown, &a, NULL);
      if (!a.grad_ok || (phase == 0 && a.length < 16) || a.n_diff > AD_H_CAPACITY) continue;
      assert_true(a.hess_ok);
      /* (a's outputs stay in `grown` until its next evaluation.) */
      assert_int_equal(path_scratch_create(&fresh, &err), LMC_OK);
      path_vec_sampler_rewind(&vs);
      path_eval_pt(fx->sc, &rs, &vs.base, PATH_WANT_HESS, fresh, &b, NULL);
      assert_true(same_eval(&a, &b));
      path_scratch_destroy(fresh);
      checked[phase]++;
    }
  }
  print_message("%d long paths and %d others with their Hessian in %d tries; the shared arena "
                "grew to %zu duals\n", checked[0], checked[1], tries, grown->arena2_duals);
  assert_int_equal(checked[0], want[0]);
  assert_int_equal(checked[1], want[1]);
  assert_true(grown->arena2_duals > PATH__ARENA2_DUALS);
  path_vec_sampler_free(&vs);
  path_scratch_destroy(grown);
}

/* The same for bidirectional strategies, 25 paths per group. */
static void test_bdpt_hessian_matches_fd(void **state) {
  fixture *fx = *state;
  render_settings rs = fx->sc->settings;
  rs.rrdepth = 3;
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 37, NULL);
  rng r;
  rng_seed(&r, 13, 5);
  pg_hess_stats st = {0};
  int paths[PG_GROUPS] = {0}, entries[PG_GROUPS] = {0};
  int tries = 0;
  while (st.paths < 100 && tries < 200000) {
    tries++;
    pg_strategy sg = pg_random_strategy(&r, rs.maxdepth);
    if (paths[pg_group(sg)] >= 25) continue;
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_bdpt(fx->sc, &rs, &vs.base, sg.s, sg.t, PATH_WANT_HESS, fx->ps, &ev, NULL);
    if (!ev.grad_ok) continue;
    assert_true(ev.hess_ok);
    int before = st.entries;
    pg_hess_check(fx->sc, fx->ps, &rs, &vs, sg, &ev, &st);
    paths[pg_group(sg)]++;
    entries[pg_group(sg)] += st.entries - before;
  }
  path_vec_sampler_free(&vs);
  for (int g = 0; g < PG_GROUPS; g++)
    print_message("    %-22s %5d paths, %6d entries\n", pg_group_name(g), paths[g], entries[g]);
  hess_report("bdpt", &st, 100);
  for (int g = 0; g < PG_GROUPS; g++) {
    assert_int_equal(paths[g], 25);
    assert_true(entries[g] >= 200);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_pt_value_matches_pt_li),
      cmocka_unit_test(test_pt_gradient_matches_fd),
      cmocka_unit_test(test_bdpt_value_matches_bdpt_connect),
      cmocka_unit_test(test_bdpt_gradient_matches_fd),
      cmocka_unit_test(test_pt_hessian_matches_fd),
      cmocka_unit_test(test_pt_hessian_long_paths),
      cmocka_unit_test(test_hessian_independent_of_scratch),
      cmocka_unit_test(test_bdpt_hessian_matches_fd),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
