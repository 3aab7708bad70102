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

#include "render/io/io.h"
#include "render/path.h"
#include "test_util.h"

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

static int rel_equal(double a, double b, double tol) {
  return fabs(a - b) <= tol * fmax(fabs(a), fabs(b)) || (a == 0.0 && b == 0.0);
}

/* Result of a central-difference check over many paths. */
typedef struct fd_stats {
  int paths_by_type[6];
  int comps_by_type[6];
  int paths, components, passed, skipped_topology;
  int nontrivial; /* components whose derivative is not negligible (|fd| > 1e-3 f) */
} fd_stats;

/* Checks the gradient of the current path of vs (already evaluated into
 * ev with want_grad) against central differences. */
static void fd_check(const scene *sc, path_scratch *ps, const render_settings *rs, path_vec_sampler *vs,
                     const path_eval *ev0, fd_stats *st) {
  int n = ev0->n_coords;
  path_coord coords[512];
  if (n > 512) return;
  memcpy(coords, ev0->coords, (size_t)n * sizeof *coords);
  uint64_t topo = ev0->topology;
  double f0 = ev0->lum;
  st->paths++;
  for (int k = 0; k < n; k++) {
    if (!coords[k].diff) continue;
    double *slot = &vs->u[coords[k].stream][coords[k].pos];
    double u = *slot;
    /* Central differences at steps h, h/2 (Richardson extrapolation,
     * error O(h^4)) for h = 1e-4, 1e-5, 1e-6, 1e-7; the estimate used is
     * the one that agrees best with the next smaller h (light-triangle and
     * envmap remaps stretch u by 1 / width, so no single h suits all
     * coordinates). The topology must be the same at every point used. */
    double rich[4][4];
    int same = 1;
    double hk = 1e-4;
    for (int lev = 0; lev < 4 && same; lev++, hk *= 0.1) {
      const double steps[4] = {hk, -hk, 0.5 * hk, -0.5 * hk};
      double y[4][4];
      for (int e = 0; e < 4; e++) {
        path_eval ev;
        *slot = u + steps[e];
        if (*slot < 0.0 || *slot >= 1.0) {
          same = 0;
          break;
        }
        path_vec_sampler_rewind(vs);
        path_eval_pt(sc, rs, &vs->base, 0, ps, &ev, NULL);
        same = same && ev.topology == topo;
        y[0][e] = ev.lum;
        y[1][e] = ev.value.r;
        y[2][e] = ev.value.g;
        y[3][e] = ev.value.b;
      }
      if (!same) break;
      for (int q = 0; q < 4; q++) {
        double d1 = (y[q][0] - y[q][1]) / (2.0 * hk), d2 = (y[q][2] - y[q][3]) / hk;
        rich[lev][q] = (4.0 * d2 - d1) / 3.0;
      }
    }
    *slot = u;
    if (!same) {
      st->skipped_topology++;
      continue;
    }
    double fd[4];
    for (int q = 0; q < 4; q++) {
      int best = 0;
      for (int lev = 1; lev < 3; lev++)
        if (fabs(rich[lev][q] - rich[lev + 1][q]) < fabs(rich[best][q] - rich[best + 1][q]))
          best = lev;
      fd[q] = rich[best][q];
    }
    double ad[4] = {coords[k].dlum, coords[k].drgb.r, coords[k].drgb.g, coords[k].drgb.b};
    for (int q = 0; q < 4; q++) {
      double err = fabs(fd[q] - ad[q]);
      int ok = err <= 1e-4 * fabs(fd[q]) || err <= 1e-6 * f0;
      st->components++;
      st->passed += ok;
      st->nontrivial += fabs(fd[q]) > 1e-3 * f0;
      if (!ok && st->components - st->passed < 10)
        print_message("coord %d (stream %d pos %d) comp %d: ad %.10g fd %.10g f %.6g\n", k,
                      coords[k].stream, coords[k].pos, q, ad[q], fd[q], f0);
    }
  }
}


/* Runs both checks on one scene; `need` lists the classes that must occur. */
static void check_scene(const char *file, int n_value, int n_grad, unsigned need) {
  scene *sc;
  lmc_error err;
  if (scene_load_xml(file, NULL, 0, &sc, &err) != LMC_OK) {
    print_error("%s: %s\n", file, err.msg);
    fail();
  }
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
    rgb L = pt_li(sc, &rs, &vs.base, org, dir, &cnt);
    if (!rel_equal(L.r, ev.value.r, 1e-9) || !rel_equal(L.g, ev.value.g, 1e-9) ||
        !rel_equal(L.b, ev.value.b, 1e-9)) {
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
  fd_stats st = {0};
  int tries = 0;
  while (st.paths < n_grad && tries < 200 * n_grad) {
    tries++;
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_pt(sc, &rs, &vs.base, 1, ps, &ev, NULL);
    if (!ev.grad_ok) continue;
    unsigned cls = classify(&ev);
    int before = st.components;
    fd_check(sc, ps, &rs, &vs, &ev, &st);
    for (int t = 0; t < TYPE_COUNT; t++)
      if (cls & (1u << t)) {
        st.paths_by_type[t]++;
        st.comps_by_type[t] += st.components - before;
      }
  }
  print_message("%s: gradient: %d paths, %d components (%d non-trivial), %d passed (%.4f%%), "
                "%d skipped (topology)\n",
                file, st.paths, st.components, st.nontrivial, st.passed,
                st.components ? 100.0 * st.passed / st.components : 0.0, st.skipped_topology);
  for (int t = 0; t < TYPE_COUNT; t++)
    print_message("    %-12s %6d paths %7d components\n", type_names[t], st.paths_by_type[t],
                  st.comps_by_type[t]);
  assert_int_equal(st.paths, n_grad);
  assert_true(st.nontrivial > st.components / 10);
  assert_true(st.passed >= 0.999 * st.components);
  for (int t = 0; t < TYPE_COUNT; t++)
    if (need & (1u << t)) {
      assert_true(st.paths_by_type[t] >= 10);
      assert_true(st.comps_by_type[t] >= 100);
    }
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
