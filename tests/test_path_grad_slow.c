/*
 * test_path_grad_slow.c: the differentiable path sampler on whole scenes:
 * scenes/ring-caustics (rough gold, diffuse floor, area light, constant
 * sky), scenes/ring-caustics-glass (rough glass), scenes/cornell-box
 * (smooth glass: delta vertices) and the torus scene of ../shared
 * (envmap, phong, textured floor, rough glass; skipped when absent).
 *
 * Per scene: path_eval_pt equals pt_li for the same numbers (1e-9
 * relative) on thousands of random paths; then, on paths with a non-zero
 * value, every continuous coordinate's derivative of the luminance and of
 * the three colour channels is compared with central differences (Richardson-extrapolated, the best converged of h = 1e-4 ... 1e-7)
 * wherever the topology hash is the same at u + h and u - h. Pass: relative
 * error under 1e-4 or absolute error under 1e-6 |f|; at least 99.9% of the
 * components must pass. Paths are classified by the lobes and emitters
 * they use, and the test asserts how many paths and components each class
 * had, so it cannot pass on nothing.
 *
 * Then the same for the bidirectional strategies (path_eval_bdpt against
 * bdpt_connect, and its gradients), counted per group of strategies
 * (s = 0, s = 1, t = 1 with its raster derivatives, s, t >= 2) and per
 * class (check_bdpt).
 *
 * Last, Hessians of the luminance (PATH_WANT_HESS) against central
 * differences of the gradient, unidirectional and per group of strategies
 * (check_hessian).
 */
#include <float.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "render/io/io.h"
#include "render/integrators/path.h"
#include "test_util.h"
#include "path_grad_util.h"
#include "load_scene.h"

enum { TYPE_DIFFUSE, TYPE_GLOSSY, TYPE_DELTA, TYPE_GLASS, TYPE_ENV, TYPE_DIRECT, TYPE_COUNT };
static const char *type_names[TYPE_COUNT] = {"diffuse", "glossy", "delta", "glass", "environment", "direct"};

/* The classes a path belongs to (a path can be in several). */
static unsigned classify(const path_eval *ev) {
  unsigned t = 0;
  if (ev->flags & PATH_LOBE_DIFFUSE) t |= 1u << TYPE_DIFFUSE;
  if (ev->flags & PATH_LOBE_GLOSSY) t |= 1u << TYPE_GLOSSY;
  if (ev->flags & PATH_LOBE_DELTA) t |= 1u << TYPE_DELTA;
  if (ev->flags & PATH_LOBE_TRANSMISSION) t |= 1u << TYPE_GLASS;
  if (ev->flags & PATH_EMIT_INFINITE) t |= 1u << TYPE_ENV;
  if (!(ev->flags & (PATH_LOBE_DIFFUSE | PATH_LOBE_GLOSSY | PATH_LOBE_DELTA))) t |= 1u << TYPE_DIRECT;
  return t;
}

/* Paths and components checked, per class of path. */
typedef struct class_count {
  int paths_by_type[TYPE_COUNT];
  int comps_by_type[TYPE_COUNT];
} class_count;

/* The bidirectional strategies on one scene: path_eval_bdpt equals
 * bdpt_connect for the same numbers (value, and the splat position for
 * t = 1) on random strategies of every length up to maxdepth, until each
 * group of strategies (s = 0, s = 1, t = 1, s, t >= 2) has BD_VALUE
 * non-zero paths (or BD_TRIES tries; at least BD_VALUE / 3 are required);
 * then BD_GRAD paths with a gradient per group are checked
 * against central differences, with the rules of the unidirectional part
 * (99.9% of components within 1e-4 relative or 1e-6 |f| absolute; raster
 * derivatives within 1e-6 of the film's size) per scene, 99.5% per group;
 * paths with a subnormal f are not checked (counted). The counts of paths
 * and components per group and per class are asserted. */
enum { BD_VALUE = 300, BD_GRAD = 100, BD_TRIES = 150000 };

static void check_bdpt(const char *file, const scene *sc, path_scratch *ps,
                       const render_settings *rs, unsigned need) {
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 314, NULL);
  rng r;
  rng_seed(&r, 27, 5);
  int maxdepth = rs->maxdepth >= 0 ? rs->maxdepth : 8;

  /* Value agreement with bdpt_connect. Groups are visited in turn (the
   * strategy drawn within its group), each until it has BD_VALUE non-zero
   * paths or BD_TRIES evaluations: light tracing on a sky-lit scene is
   * non-zero for ~0.2% of its paths. */
  int n = 0, mismatched = 0, nonzero[PG_GROUPS] = {0}, tried[PG_GROUPS] = {0};
  for (int i = 0;; i = (i + 1) % PG_GROUPS) {
    int done = 1;
    for (int g = 0; g < PG_GROUPS; g++) done = done && (nonzero[g] >= BD_VALUE || tried[g] >= BD_TRIES);
    if (done) break;
    if (nonzero[i] >= BD_VALUE || tried[i] >= BD_TRIES) continue;
    pg_strategy st = pg_random_strategy(&r, maxdepth);
    while (pg_group(st) != i) st = pg_random_strategy(&r, maxdepth);
    tried[i]++;
    n++;
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_bdpt(sc, rs, &vs.base, st.s, st.t, 0, ps, &ev, NULL);
    double rx, ry;
    rgb L = pg_bdpt_reference(sc, rs, &vs, st, &rx, &ry);
    int ok = pg_rgb_rel_equal(L, ev.value, 1e-9);
    if (st.t == 1 && !rgb_is_black(L))
      ok = ok && pg_rel_equal(rx, ev.rx, 1e-9) && pg_rel_equal(ry, ev.ry, 1e-9);
    if (!ok) {
      if (mismatched < 5)
        print_message("(s,t) = (%d,%d): bdpt_connect (%.17g %.17g %.17g) at (%g %g), "
                      "path_eval_bdpt (%.17g %.17g %.17g) at (%g %g)\n",
                      st.s, st.t, L.r, L.g, L.b, rx, ry, ev.value.r, ev.value.g, ev.value.b,
                      ev.rx, ev.ry);
      mismatched++;
    }
    nonzero[i] += !rgb_is_black(L);
  }
  print_message("%s: bdpt value: %d paths, %d mismatched; non-zero per group: %d %d %d %d\n", file,
                n, mismatched, nonzero[0], nonzero[1], nonzero[2], nonzero[3]);
  assert_int_equal(mismatched, 0);
  for (int g = 0; g < PG_GROUPS; g++) assert_true(nonzero[g] >= BD_VALUE / 3);

  /* Gradients against central differences, per group and class. */
  pg_fd_stats st = {0};
  class_count cc = {{0}, {0}};
  int paths[PG_GROUPS] = {0}, comps[PG_GROUPS] = {0}, nontriv[PG_GROUPS] = {0};
  int pass[PG_GROUPS] = {0};
  int gtried[PG_GROUPS] = {0}, subnormal = 0;
  for (int g = 0;; g = (g + 1) % PG_GROUPS) {
    int done = 1;
    for (int k = 0; k < PG_GROUPS; k++) done = done && (paths[k] >= BD_GRAD || gtried[k] >= BD_TRIES);
    if (done) break;
    if (paths[g] >= BD_GRAD || gtried[g] >= BD_TRIES) continue;
    pg_strategy sg = pg_random_strategy(&r, maxdepth);
    while (pg_group(sg) != g) sg = pg_random_strategy(&r, maxdepth);
    gtried[g]++;
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_bdpt(sc, rs, &vs.base, sg.s, sg.t, 1, ps, &ev, NULL);
    if (!ev.grad_ok) continue;
    /* A subnormal f (the torus scene has paths of ~1e-320) keeps only a few
     * significant bits, so differences cannot resolve a relative error of
     * 1e-4: such paths are counted, not checked. */
    if (ev.lum < DBL_MIN) {
      subnormal++;
      continue;
    }
    assert_int_equal(ev.n_diff, pg_bdpt_n_diff(sg));
    unsigned cls = classify(&ev);
    pg_fd_stats before = st;
    pg_fd_check(sc, ps, rs, &vs, sg, &ev, &st);
    paths[g]++;
    comps[g] += st.components - before.components;
    nontriv[g] += st.nontrivial - before.nontrivial;
    pass[g] += st.passed - before.passed;
    for (int t = 0; t < TYPE_COUNT; t++)
      if (cls & (1u << t)) {
        cc.paths_by_type[t]++;
        cc.comps_by_type[t] += st.components - before.components;
      }
  }
  print_message("%s: bdpt gradient: %d paths, %d components (%d non-trivial, %d raster), "
                "%d passed (%.4f%%; of the failures %d with unconverged differences), "
                "%d skipped (topology), %d subnormal paths not checked\n",
                file, st.paths, st.components, st.nontrivial, st.raster, st.passed,
                st.components ? 100.0 * st.passed / st.components : 0.0, st.failed_unconverged,
                st.skipped_topology, subnormal);
  for (int g = 0; g < PG_GROUPS; g++)
    print_message("    %-22s %5d paths %7d components (%d non-trivial, %d passed)\n",
                  pg_group_name(g), paths[g], comps[g], nontriv[g], pass[g]);
  for (int t = 0; t < TYPE_COUNT; t++)
    print_message("    %-12s %6d paths %7d components\n", type_names[t], cc.paths_by_type[t],
                  cc.comps_by_type[t]);
  for (int g = 0; g < PG_GROUPS; g++) {
    assert_int_equal(paths[g], BD_GRAD);
    assert_true(comps[g] >= 5 * BD_GRAD);
    assert_true(nontriv[g] >= comps[g] / 10);
    /* The 99.9% rule holds per scene (below); per group at least 99.5%
     * (the torus' light tracing has a few very steep paths where the
     * difference quotients do not converge). */
    assert_true(pass[g] >= 0.995 * comps[g]);
  }
  assert_true(st.raster >= 2 * BD_GRAD);
  assert_true(st.passed >= 0.999 * st.components);
  for (int t = 0; t < TYPE_COUNT; t++)
    if (need & (1u << t)) {
      assert_true(cc.paths_by_type[t] >= 10);
      assert_true(cc.comps_by_type[t] >= 100);
    }
  path_vec_sampler_free(&vs);
}

/* Hessians (PATH_WANT_HESS) on one scene against central differences of
 * the gradient (pg_hess_check): HS_PT unidirectional paths, then HS_BD
 * paths per group of bidirectional strategies; the rules of test_path_grad
 * (99.5% of the entries within 1e-4 relative or 1e-6 |f| absolute, at
 * most 2% without converged differences, the
 * second-order pass's value and gradient bit for bit the first-order
 * pass's), and the counts asserted per group. Subnormal f are skipped as
 * for the gradient. */
enum { HS_PT = 60, HS_BD = 20, HS_TRIES = 150000 };

static void check_hessian(const char *file, const scene *sc, path_scratch *ps,
                          const render_settings *rs) {
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 71, NULL);
  rng r;
  rng_seed(&r, 17, 1);
  int maxdepth = rs->maxdepth < 0 ? 8 : rs->maxdepth;
  pg_hess_stats st[PG_GROUPS + 1] = {{0}};
  int tries[PG_GROUPS + 1] = {0};
  for (int g = 0; g <= PG_GROUPS; g++) {
    int want = g == PG_GROUPS ? HS_PT : HS_BD;
    while (st[g].paths < want && tries[g] < HS_TRIES) {
      tries[g]++;
      pg_strategy sg = PG_PT;
      if (g < PG_GROUPS) {
        sg = pg_random_strategy(&r, maxdepth);
        if (pg_group(sg) != g) continue;
      }
      path_vec_sampler_clear(&vs);
      path_eval ev;
      pg_eval(sc, rs, &vs, sg, PATH_WANT_HESS, ps, &ev);
      if (!ev.grad_ok || ev.lum < DBL_MIN) continue;
      assert_true(ev.hess_ok);
      pg_hess_check(sc, ps, rs, &vs, sg, &ev, &st[g]);
    }
    print_message("%s: Hessian, %-22s %3d paths, %6d entries (%d non-trivial, %d off the "
                  "diagonal), %d passed (%.3f%%), %d skipped (topology), %d unconverged\n",
                  file, g == PG_GROUPS ? "unidirectional" : pg_group_name(g), st[g].paths,
                  st[g].entries, st[g].nontrivial, st[g].offdiag, st[g].passed,
                  st[g].entries ? 100.0 * st[g].passed / st[g].entries : 0.0,
                  st[g].skipped_topology, st[g].unconverged);
    assert_int_equal(st[g].paths, want);
    assert_true(st[g].unconverged <= st[g].entries / 50);
    assert_int_equal(st[g].mismatched, 0);
    assert_true(st[g].entries >= 5 * want);
    assert_true(st[g].nontrivial >= st[g].entries / 20);
    assert_true(st[g].passed >= 0.995 * st[g].entries);
  }
  path_vec_sampler_free(&vs);
}

/* Runs both checks on one scene; `need` lists the classes that must occur. */
static void check_scene(const char *file, int n_value, int n_grad, unsigned need) {
  scene *sc = load_scene(file);
  lmc_error err;
  path_scratch *ps;
  assert_int_equal(path_scratch_create(&ps, &err), LMC_OK);
  render_settings rs = sc->settings;
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 99, NULL);

  /* Value agreement with pt_li. */
  int nonzero = 0, mismatched = 0;
  for (int i = 0; i < n_value; i++) {
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_pt(sc, &rs, &vs.base, 0, ps, &ev, NULL);
    path_vec_sampler_rewind(&vs);
    double u0 = sampler_next(&vs.base), u1 = sampler_next(&vs.base);
    vec3 org, dir;
    camera_generate_ray(&sc->cam, u0 * sc->cam.width, u1 * sc->cam.height, &org, &dir);
    render_counters cnt = {0};
    rgb L = pt_li(sc, &rs, &vs.base, org, dir, NULL, &cnt);
    if (!pg_rgb_rel_equal(L, ev.value, 1e-9)) {
      if (mismatched < 5)
        print_message("path %d: pt_li (%.17g %.17g %.17g) path_eval_pt (%.17g %.17g %.17g)\n", i,
                      L.r, L.g, L.b, ev.value.r, ev.value.g, ev.value.b);
      mismatched++;
    }
    nonzero += !rgb_is_black(L);
  }
  print_message("%s: value: %d paths, %d non-zero, %d mismatched\n", file, n_value, nonzero,
                mismatched);
  assert_int_equal(mismatched, 0);
  assert_true(nonzero > n_value / 10);

  /* Gradients against central differences, per class of path. */
  pg_fd_stats st = {0};
  class_count cc = {{0}, {0}};
  int tries = 0;
  while (st.paths < n_grad && tries < 200 * n_grad) {
    tries++;
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_pt(sc, &rs, &vs.base, 1, ps, &ev, NULL);
    if (!ev.grad_ok) continue;
    unsigned cls = classify(&ev);
    int before = st.components;
    pg_fd_check(sc, ps, &rs, &vs, PG_PT, &ev, &st);
    for (int t = 0; t < TYPE_COUNT; t++)
      if (cls & (1u << t)) {
        cc.paths_by_type[t]++;
        cc.comps_by_type[t] += st.components - before;
      }
  }
  print_message("%s: gradient: %d paths, %d components (%d non-trivial), %d passed (%.4f%%), "
                "%d skipped (topology)\n",
                file, st.paths, st.components, st.nontrivial, st.passed,
                st.components ? 100.0 * st.passed / st.components : 0.0, st.skipped_topology);
  for (int t = 0; t < TYPE_COUNT; t++)
    print_message("    %-12s %6d paths %7d components\n", type_names[t], cc.paths_by_type[t],
                  cc.comps_by_type[t]);
  assert_int_equal(st.paths, n_grad);
  assert_true(st.nontrivial > st.components / 10);
  assert_true(st.passed >= 0.999 * st.components);
  for (int t = 0; t < TYPE_COUNT; t++)
    if (need & (1u << t)) {
      assert_true(cc.paths_by_type[t] >= 10);
      assert_true(cc.comps_by_type[t] >= 100);
    }
  check_bdpt(file, sc, ps, &rs, need);
  check_hessian(file, sc, ps, &rs);
  path_vec_sampler_free(&vs);
  path_scratch_destroy(ps);
  scene_destroy(sc);
}

static void test_ring_caustics(void **state) {
  (void)state;
  check_scene(LMC_SOURCE_DIR "/scenes/ring-caustics/scene.xml", 3000, 1500,
              1u << TYPE_DIFFUSE | 1u << TYPE_GLOSSY | 1u << TYPE_ENV);
}

static void test_ring_caustics_glass(void **state) {
  (void)state;
  check_scene(LMC_SOURCE_DIR "/scenes/ring-caustics-glass/scene.xml", 3000, 1500,
              1u << TYPE_DIFFUSE | 1u << TYPE_GLASS | 1u << TYPE_ENV);
}

static void test_cornell_box(void **state) {
  (void)state;
  check_scene(LMC_SOURCE_DIR "/scenes/cornell-box/scene.xml", 3000, 1000,
              1u << TYPE_DIFFUSE | 1u << TYPE_DELTA | 1u << TYPE_GLASS);
}

static void test_torus(void **state) {
  (void)state;
  const char *file = LMC_SHARED_DIR "/scenes/torus/lmc.xml";
  if (access(file, R_OK) != 0) {
    print_message("%s absent: skipped\n", file);
    skip();
  }
  check_scene(file, 3000, 1500, 1u << TYPE_DIFFUSE | 1u << TYPE_GLOSSY | 1u << TYPE_ENV);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_ring_caustics),
      cmocka_unit_test(test_ring_caustics_glass),
      cmocka_unit_test(test_cornell_box),
      cmocka_unit_test(test_torus),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
