/*
 * test_path_grad.c: the differentiable path sampler (render/path.h) on a
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
 *    and u - h.
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
  char path[64];
} fixture;

static int setup(void **state) {
  fixture *fx = calloc(1, sizeof *fx);
  snprintf(fx->path, sizeof fx->path, "/tmp/lmc_test_path_grad_%d.xml", (int)getpid());
  FILE *f = fopen(fx->path, "w");
  if (!f) return -1;
  fputs(scene_xml, f);
  fclose(f);
  lmc_error err;
  if (scene_load_xml(fx->path, NULL, 0, &fx->sc, &err) != LMC_OK) {
    fprintf(stderr, "%s\n", err.msg);
    return -1;
  }
  if (path_scratch_create(&fx->ps, &err) != LMC_OK) return -1;
  *state = fx;
  return 0;
}

static int teardown(void **state) {
  fixture *fx = *state;
  path_scratch_destroy(fx->ps);
  scene_destroy(fx->sc);
  remove(fx->path);
  free(fx);
  return 0;
}

static int rel_equal(double a, double b, double tol) {
  return fabs(a - b) <= tol * fmax(fabs(a), fabs(b)) || (a == 0.0 && b == 0.0);
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
    rgb L = pt_li(fx->sc, &rs, &vs.base, org, dir, &cnt);
    assert_int_equal(vs.pos[LMC_STREAM_CAMERA], ev.n_coords);
    assert_near(ev.rx, u0 * fx->sc->cam.width, 0.0);
    if (!rel_equal(L.r, ev.value.r, 1e-9) || !rel_equal(L.g, ev.value.g, 1e-9) ||
        !rel_equal(L.b, ev.value.b, 1e-9)) {
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

/* Result of a central-difference check over many paths. */
typedef struct fd_stats {
  int paths, components, passed, skipped_topology;
  int nontrivial; /* components whose derivative is not negligible (|fd| > 1e-3 f) */
} fd_stats;

/* Checks the gradient of the current path of vs (already evaluated into
 * ev with want_grad) against central differences. */
static void fd_check(fixture *fx, const render_settings *rs, path_vec_sampler *vs,
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
        path_eval_pt(fx->sc, rs, &vs->base, 0, fx->ps, &ev, NULL);
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

static void test_pt_gradient_matches_fd(void **state) {
  fixture *fx = *state;
  render_settings rs = fx->sc->settings;
  rs.rrdepth = 3;
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 11, NULL);
  fd_stats st = {0};
  int tries = 0;
  while (st.paths < 300 && tries < 20000) {
    tries++;
    path_vec_sampler_clear(&vs);
    path_eval ev;
    path_eval_pt(fx->sc, &rs, &vs.base, 1, fx->ps, &ev, NULL);
    if (!ev.grad_ok) continue;
    /* The gradient is reported for exactly the continuous coordinates. */
    assert_int_equal(ev.n_diff, 2 + 4 * ((ev.n_coords - 2) / PT_DIMS_PER_BOUNCE));
    assert_near(ev.coords[0].drx, fx->sc->cam.width, 0.0);
    fd_check(fx, &rs, &vs, &ev, &st);
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

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_pt_value_matches_pt_li),
      cmocka_unit_test(test_pt_gradient_matches_fd),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
