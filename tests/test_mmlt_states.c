/*
 * test_mmlt_states.c: the mmlt states' target with derivatives
 * (mmlt_states.c) on a small built-in scene with a tent filter (so the
 * film grows by a margin of 1 pixel and the adapter's raster mapping is
 * exercised), for every path length 1 .. 5:
 *
 *  - the value of a state evaluated without its gradient (mmlt's plain
 *    code) equals the value evaluated with it (path_eval_bdpt behind the
 *    layout adapter): f, RGB and raster position, to 1e-9 relative. This
 *    is what lets chains mix both evaluations of one state;
 *  - the gradient, in the state's own coordinates (after the adapter's
 *    index mapping and chain rule), against central differences of the
 *    plain f: Richardson-extrapolated differences at h = 1e-5 .. 1e-7,
 *    compared only where they converge (the three estimates agree to
 *    1e-3), which leaves out coordinates across a discontinuity.
 * Counts of compared values are asserted, per length.
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

#include "lmc/states/mmlt_states.h"
#include "lmc/mcmc.h"
#include "lmc/states/states.h"
#include "load_scene.h"
#include "render/io/io.h"
#include "render/integrators/path.h"
#include "test_util.h"

static const char *scene_xml =
    "<scene version=\"0.6.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"45\"/>\n"
    "    <transform name=\"toWorld\"><lookat origin=\"0, 2, 5\" target=\"0, 0.5, 0\" up=\"0, 1, 0\"/></transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"24\"/>"
    "<rfilter type=\"tent\"/></film>\n"
    "  </sensor>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/><scale x=\"4\" y=\"1\" z=\"4\"/></transform>\n"
    "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6, 0.5, 0.4\"/></bsdf>\n"
    "  </shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"0.8\" y=\"0.6\" z=\"0.2\"/><float name=\"radius\" value=\"0.6\"/>\n"
    "    <bsdf type=\"roughconductor\"><string name=\"material\" value=\"Au\"/>"
    "<string name=\"distribution\" value=\"ggx\"/><float name=\"alpha\" value=\"0.2\"/></bsdf>\n"
    "  </shape>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/><scale x=\"0.5\" y=\"1\" z=\"0.5\"/>"
    "<translate x=\"0.3\" y=\"3\" z=\"0.5\"/></transform>\n"
    "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"20, 18, 15\"/></emitter>\n"
    "    <bsdf type=\"diffuse\"/>\n" /* (an emitter's default BSDF is black) */
    "  </shape>\n"
    "  <emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.2, 0.25, 0.3\"/></emitter>\n"
    "</scene>\n";

#define KMAX 5

typedef struct fixture {
  scene *sc;
} fixture;

static int setup(void **state) {
  fixture *fx = calloc(1, sizeof *fx);
  const char *env = getenv("LMC_TEST_SCENE"); /* any scene instead (for diagnosis) */
  fx->sc = env ? try_load_scene(env) : try_load_scene_text(scene_xml, "bdpt_target");
  if (!fx->sc) return -1;
  *state = fx;
  return 0;
}

static int teardown(void **state) {
  fixture *fx = *state;
  scene_destroy(fx->sc);
  free(fx);
  return 0;
}

/* A state as a vector sampler over the target's layout (every stream filled
 * to its block size). */
static void fill_state(path_vec_sampler *vs, const mc_target *T) {
  path_vec_sampler_clear(vs);
  for (int k = 0; k < LMC_STREAM_COUNT; k++) {
    vs->base.use_stream(&vs->base, k);
    for (int j = 0; j < T->stream_dim[k]; j++) sampler_next(&vs->base);
  }
  path_vec_sampler_rewind(vs);
}

/* f of the state in vs with coordinate i (state index) set to u. */
static double f_at(const mc_target *T, void *scratch, path_vec_sampler *vs, int i, double u) {
  int k = 0, off = 0;
  while (i >= off + T->stream_dim[k]) off += T->stream_dim[k++];
  double old = vs->u[k][i - off];
  vs->u[k][i - off] = u;
  path_vec_sampler_rewind(vs);
  mc_value v;
  T->eval(T, scratch, &vs->base, &v, NULL, NULL);
  vs->u[k][i - off] = old;
  path_vec_sampler_rewind(vs);
  return v.f;
}

static int rel_equal(double a, double b, double tol) {
  return fabs(a - b) <= tol * fmax(fabs(a), fabs(b)) || (a == 0.0 && b == 0.0);
}

static void test_values_and_gradients(void **state) {
  fixture *fx = *state;
  render_settings rs = fx->sc->settings;
  rs.maxdepth = KMAX;
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 5, NULL);
  int total_nonzero = 0;
  for (int len = 1; len <= KMAX; len++) {
    mc_mmlt_states ctx;
    mc_target T;
    lmc_error err;
    assert_int_equal(mc_mmlt_states_init(&T, &ctx, fx->sc, &rs, len, &err), LMC_OK);
    void *scratch = T.scratch_create(&T);
    assert_non_null(scratch);
    double *grad = malloc((size_t)T.dim * sizeof(double));
    int nonzero = 0, mismatched = 0, compared = 0, passed = 0, with_grad = 0;
    for (int n = 0; n < 20000 && nonzero < 150; n++) {
      fill_state(&vs, &T);
      mc_value a, b;
      T.eval(&T, scratch, &vs.base, &a, NULL, NULL);
      path_vec_sampler_rewind(&vs);
      int ok = 0;
      T.eval(&T, scratch, &vs.base, &b, grad, &ok);
      path_vec_sampler_rewind(&vs);
      if (!(a.f > 0.0) && !(b.f > 0.0)) continue;
      nonzero++;
      if (!rel_equal(a.f, b.f, 1e-9) || !rel_equal(a.value.r, b.value.r, 1e-9) ||
          fabs(a.rx - b.rx) > 1e-9 || fabs(a.ry - b.ry) > 1e-9) {
        mismatched++;
        print_message("length %d: plain f %.17g at (%g, %g), gradient eval %.17g at (%g, %g)\n",
                      len, a.f, a.rx, a.ry, b.f, b.rx, b.ry);
        continue;
      }
      if (!ok) continue;
      with_grad++;
      /* Every coordinate against Richardson-extrapolated central differences. */
      for (int i = 0; i < T.dim; i++) {
        int k = 0, off = 0;
        while (i >= off + T.stream_dim[k]) off += T.stream_dim[k++];
        double u = vs.u[k][i - off];
        double est[3];
        int valid = 1;
        for (int e = 0; e < 3; e++) {
          double h = 1e-5 * pow(0.1, e);
          if (u - 2 * h < 0.0 || u + 2 * h >= 1.0) valid = 0;
          if (!valid) break;
          double d1 = (f_at(&T, scratch, &vs, i, u + h) - f_at(&T, scratch, &vs, i, u - h)) / (2 * h);
          double d2 = (f_at(&T, scratch, &vs, i, u + 2 * h) - f_at(&T, scratch, &vs, i, u - 2 * h)) /
                      (4 * h);
          est[e] = (4.0 * d1 - d2) / 3.0;
        }
        if (!valid) continue;
        double scale = fmax(fabs(est[1]), 1e-6 * a.f);
        if (fabs(est[0] - est[1]) > 1e-3 * scale || fabs(est[2] - est[1]) > 1e-3 * scale) continue;
        compared++;
        if (fabs(grad[i] - est[1]) <= 1e-3 * fmax(fabs(est[1]), 1e-5 * a.f))
          passed++;
        else
          print_message("length %d coordinate %d: gradient %.10g, differences %.10g (f %g)\n", len,
                        i, grad[i], est[1], a.f);
      }
    }
    print_message("length %d: %d contributing states, %d value mismatches, %d with a gradient, "
                  "%d of %d derivatives agree\n",
                  len, nonzero, mismatched, with_grad, passed, compared);
    assert_int_equal(mismatched, 0);
    if (len >= 2) { /* the light faces away from the camera: length 1 is black */
      assert_true(nonzero >= 30);
      assert_true(compared >= 10 * len);
      assert_true(passed >= 0.99 * compared);
    }
    total_nonzero += nonzero;
    free(grad);
    T.scratch_destroy(scratch);
    mc_mmlt_states_free(&ctx);
  }
  assert_true(total_nonzero >= 150);
  path_vec_sampler_free(&vs);
}

/* The gradient of the state in vs with coordinate i set to u (to OUT). */
static int grad_at(const mc_target *T, void *scratch, path_vec_sampler *vs, int i, double u,
                   double *OUT) {
  int k = 0, off = 0;
  while (i >= off + T->stream_dim[k]) off += T->stream_dim[k++];
  double old = vs->u[k][i - off];
  vs->u[k][i - off] = u;
  path_vec_sampler_rewind(vs);
  mc_value v;
  int ok = 0;
  T->eval(T, scratch, &vs->base, &v, OUT, &ok);
  vs->u[k][i - off] = old;
  path_vec_sampler_rewind(vs);
  return ok;
}

/* eval_hess: the same f and gradient as eval, the Hessian against central
 * differences of the gradient (Richardson-extrapolated, entries whose
 * differences have not converged skipped and counted), and local_coords
 * (H2MC's moved set) holding every coordinate the gradient and Hessian
 * touch and never the technique coordinate. */
static void test_hessian(void **state) {
  fixture *fx = *state;
  render_settings rs = fx->sc->settings;
  rs.maxdepth = KMAX;
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 11, NULL);
  int total_compared = 0, total_passed = 0;
  for (int len = 2; len <= KMAX; len++) {
    mc_mmlt_states ctx;
    mc_target T;
    lmc_error err;
    assert_int_equal(mc_mmlt_states_init(&T, &ctx, fx->sc, &rs, len, &err), LMC_OK);
    assert_non_null(T.eval_hess);
    assert_non_null(T.local_coords);
    void *scratch = T.scratch_create(&T);
    size_t hsz = (size_t)MC_HESS_MAX * (MC_HESS_MAX + 1) / 2;
    double *grad = malloc((size_t)T.dim * sizeof(double)), *g1 = malloc((size_t)T.dim * sizeof(double));
    double *gp = malloc((size_t)T.dim * sizeof(double)), *gm = malloc((size_t)T.dim * sizeof(double));
    double *hess = malloc(hsz * sizeof(double));
    int *hidx = malloc(MC_HESS_MAX * sizeof(int)), *loc = malloc((size_t)T.dim * sizeof(int));
    int off_conn = mc_target_stream_offset(&T, LMC_STREAM_CONNECT);
    int with_hess = 0, compared = 0, passed = 0, unconverged = 0, outside = 0;
    for (int n = 0; n < 20000 && with_hess < 40; n++) {
      fill_state(&vs, &T);
      mc_value a, b;
      int ok_a = 0, ok_b = 0, hn = 0, hok = 0;
      T.eval(&T, scratch, &vs.base, &a, g1, &ok_a);
      path_vec_sampler_rewind(&vs);
      T.eval_hess(&T, scratch, &vs.base, 0, &b, grad, &ok_b, &hn, hidx, hess, &hok);
      path_vec_sampler_rewind(&vs);
      if (!(a.f > 0.0)) continue;
      assert_true(rel_equal(a.f, b.f, 1e-12));
      assert_int_equal(ok_a, ok_b);
      for (int i = 0; i < T.dim; i++) assert_true(rel_equal(g1[i], grad[i], 1e-12));
      if (!hok) continue;
      with_hess++;
      /* The moved set. */
      double uvec[512];
      assert_true(T.dim <= 512);
      for (int k = 0, q = 0; k < LMC_STREAM_COUNT; k++)
        for (int j = 0; j < T.stream_dim[k]; j++) uvec[q++] = vs.u[k][j];
      int nl = T.local_coords(&T, uvec, 0, loc);
      char in[512] = {0};
      for (int q = 0; q < nl; q++) in[loc[q]] = 1;
      assert_false(in[off_conn]);
      for (int i = 0; i < T.dim; i++) outside += grad[i] != 0.0 && !in[i];
      for (int q = 0; q < hn; q++) outside += !in[hidx[q]];
      /* Column b of the Hessian from differences of the gradient along hidx[b]. */
      for (int cb = 0; cb < hn; cb++) {
        int j = hidx[cb];
        int k = 0, off = 0;
        while (j >= off + T.stream_dim[k]) off += T.stream_dim[k++];
        double u = vs.u[k][j - off];
        double h = 1e-6;
        if (u - h < 0.0 || u + h >= 1.0) continue;
        if (!grad_at(&T, scratch, &vs, j, u + h, gp) || !grad_at(&T, scratch, &vs, j, u - h, gm))
          continue;
        double gp2[512], gm2[512];
        if (!grad_at(&T, scratch, &vs, j, u + h / 2, gp2) || !grad_at(&T, scratch, &vs, j, u - h / 2, gm2))
          continue;
        for (int ca = 0; ca <= cb; ca++) {
          int i = hidx[ca];
          double d1 = (gp[i] - gm[i]) / (2 * h), d2 = (gp2[i] - gm2[i]) / h;
          double hv = hess[(size_t)ca * hn - (size_t)ca * (size_t)(ca - 1) / 2 + (size_t)(cb - ca)];
          double scale = fmax(fmax(fabs(d2), fabs(hv)), 1e-4 * a.f);
          if (fabs(d1 - d2) > 1e-3 * scale) {
            unconverged++;
            continue;
          }
          compared++;
          if (fabs(hv - d2) <= 1e-3 * scale + 2.0 * fabs(d1 - d2))
            passed++;
          else
            print_message("length %d: H[%d][%d] %.10g, differences %.10g (f %g)\n", len, i, j, hv,
                          d2, a.f);
        }
      }
    }
    print_message("length %d: %d states with a Hessian, %d of %d entries agree (%d unconverged), "
                  "%d derivatives outside the moved set\n",
                  len, with_hess, passed, compared, unconverged, outside);
    assert_true(with_hess >= 20);
    assert_int_equal(outside, 0);
    assert_true(compared >= 50 * len);
    assert_true(passed >= 0.99 * compared);
    total_compared += compared, total_passed += passed;
    free(grad), free(g1), free(gp), free(gm), free(hess), free(hidx), free(loc);
    T.scratch_destroy(scratch);
    mc_mmlt_states_free(&ctx);
  }
  assert_true(total_compared > 0 && total_passed >= 0.99 * total_compared);
  path_vec_sampler_free(&vs);
}

/* mc_mmlt_expected is, state by state, the mean over the strategies of
 * mc_mmlt_contribution with the technique coordinate set to each
 * strategy in turn (so its expectation is b_k exactly). */
static void test_expected_is_mean_over_techniques(void **state) {
  fixture *fx = *state;
  render_settings rs = fx->sc->settings;
  rs.maxdepth = KMAX;
  rs.mindepth = -1;
  double r = fx->sc->filter.radius;
  double area = (fx->sc->cam.width + 2 * r) * (fx->sc->cam.height + 2 * r);
  path_vec_sampler vs;
  path_vec_sampler_init(&vs, 9, NULL);
  bdpt_vertex cam[BDPT_MAX_VERTICES], lp[BDPT_MAX_VERTICES];
  render_counters cnt = {0};
  int nonzero = 0, checked = 0;
  for (int k = 1; k <= KMAX; k++) {
    int n = k == 1 ? 1 : k + 1;
    for (int j = 0; j < 3000; j++) {
      path_vec_sampler_clear(&vs);
      double e = mc_mmlt_expected(fx->sc, &rs, k, r, area, &vs.base, cam, lp, &cnt);
      double mean = 0.0;
      for (int i = 0; i < n; i++) {
        path_vec_sampler_rewind(&vs);
        vs.u[LMC_STREAM_CONNECT][0] = (i + 0.5) / n;
        double rx, ry;
        rgb c = mc_mmlt_contribution(fx->sc, &rs, k, n, r, area, &vs.base, cam, lp, &cnt, &rx, &ry);
        double f = rgb_luminance(c);
        mean += (f > 0.0 && isfinite(f) ? f : 0.0) / n;
      }
      checked++;
      nonzero += e > 0.0;
      if (!(fabs(e - mean) <= 1e-9 * fmax(e, mean)))
        print_message("length %d sample %d: expected %.17g, mean over techniques %.17g\n", k, j, e, mean);
      assert_true(fabs(e - mean) <= 1e-9 * fmax(e, mean));
    }
  }
  print_message("%d states, %d contributing\n", checked, nonzero);
  assert_int_equal(checked, 3000 * KMAX);
  assert_true(nonzero >= 1000);
  path_vec_sampler_free(&vs);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_values_and_gradients),
      cmocka_unit_test(test_expected_is_mean_over_techniques),
      cmocka_unit_test(test_hessian),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
