/*
 * test_bdpt_invert.c: the inverse of BDPT's subpaths (integrator.h:
 * bdpt_invert_camera_subpath, bdpt_invert_light_subpath,
 * bdpt_invert_connect, bdpt_resplit), on tests/data/invert/mixed.xml, with
 * every kind of vertex the walks make: a glossy phong floor, a rough gold
 * sphere, a rough glass sphere (absolute directions when rough), a smooth
 * glass sphere (delta lobes, total internal reflection), a plastic box
 * (delta coating and diffuse base on one surface), a diffuse sphere, an
 * area light of two triangles, a point light and a constant environment.
 * Russian roulette from the second segment on.
 *
 * What is checked:
 *   - subpaths: numbers u, walked (camera and light, with and without
 *     absolute directions), inverted at every prefix of m >= 2 vertices and
 *     walked again with at most m vertices, give the same m vertices (type,
 *     light, position to 1e-7 of the scene's radius, delta flag);
 *   - strategies: full paths made by BDPT's connections, re-split at every
 *     other strategy (s', t') of their length (bdpt_resplit) and inverted,
 *     are walked again by that strategy's subpaths: the camera subpath of
 *     t' vertices, the light subpath of s' (or for s' = 1 the light sample
 *     of the connect numbers) land on the path's vertices; a re-split that
 *     does not invert must have a step whose direction BSDF sampling
 *     cannot reach (a smooth lobe's density below 1e-12 there);
 *   - both on the project's ring scenes and Cornell box and on the LMC
 *     paper's torus (../shared; skipped when absent);
 *   - every strategy's MIS weight at once (bdpt_mis_weights) equals
 *     bdpt_mis_weight on each re-split (1e-9), and they sum to 1;
 *   - the inverse is the posterior of u given the vertices: numbers that
 *     made at least m vertices, the part that shaped them replaced by the
 *     inverse (the rest kept), are uniform coordinate by coordinate
 *     (chi-square, 20 cells, Sidak level of an overall 1%); a negative
 *     control that puts Russian roulette's number anywhere in [0, 1) fails.
 * Each test counts its checks and asserts the count.
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

#include "chi2.h"
#include "render/bsdf/bsdf_model.h"
#include "render/integrators/integrator.h"
#include "render/io/io.h"
#include "render/rng.h"
#include "arr_sampler.h"
#include "test_util.h"
#include "load_scene.h"


enum { MAXV = 7, DIM_CAM = 2 + BDPT_DIMS_PER_VERTEX * MAXV, DIM_LIGHT = BDPT_DIMS_LIGHT_START +
                                                                            BDPT_DIMS_PER_VERTEX * MAXV };

static scene *g_sc;
static render_settings g_rs;

static int setup(void **state) {
  (void)state;
  g_sc = try_load_scene(LMC_SOURCE_DIR "/tests/data/invert/mixed.xml");
  if (!g_sc) return -1;
  g_rs = render_settings_default();
  g_rs.maxdepth = MAXV;
  g_rs.rrdepth = 2;
  return 0;
}

static int teardown(void **state) {
  (void)state;
  scene_destroy(g_sc);
  return 0;
}

static int walk_camera(const double *u, int max_v, const bdpt_param *par, bdpt_vertex *path) {
  render_counters cnt = {0};
  arr_smp a = arr_at(u + 2, DIM_CAM - 2);
  return bdpt_camera_subpath_p(g_sc, &g_rs, &a.base, u[0] * g_sc->cam.width,
                               u[1] * g_sc->cam.height, max_v, par, path, &cnt);
}

static int walk_light(const double *u, int max_v, const bdpt_param *par, bdpt_vertex *path) {
  render_counters cnt = {0};
  arr_smp a = arr_at(u, DIM_LIGHT);
  return bdpt_light_subpath_p(g_sc, &g_rs, &a.base, max_v, par, path, &cnt);
}

/* Inverts the first m vertices of a subpath into u (camera: film first). */
static int invert(int is_cam, const bdpt_vertex *path, int m, const bdpt_param *par, rng *g,
                  double *u) {
  if (!is_cam) return bdpt_invert_light_subpath(g_sc, &g_rs, par, path, m, g, u);
  double rx, ry;
  if (!bdpt_invert_camera_subpath(g_sc, &g_rs, par, path, m, g, &rx, &ry, u + 2)) return 0;
  u[0] = rx / g_sc->cam.width;
  u[1] = ry / g_sc->cam.height;
  return 1;
}

/* Vertex a and b agree: kind, light, position, lobe. */
static void assert_same_vertex(const bdpt_vertex *a, const bdpt_vertex *b) {
  assert_int_equal(a->type == BDPT_VERTEX_CAMERA, b->type == BDPT_VERTEX_CAMERA);
  int far = a->type == BDPT_VERTEX_LIGHT &&
            (a->light < 0 || light_is_infinite(&g_sc->lights[a->light]));
  if (far) {
    assert_near(v3_len(v3_sub(a->dir, b->dir)), 0.0, 1e-7);
  } else {
    assert_near(v3_len(v3_sub(a->p, b->p)), 0.0, 1e-7 * g_sc->radius);
  }
}

static const bdpt_param g_abs = {100, 0.05};

/* ---- Subpaths ------------------------------------------------------------------ */

/* Round trips of subpaths from `iters` numbers per kind and
 * parametrization; returns the prefixes checked, *OUT_deltas the delta
 * vertices among them. */
static long subpath_round_trips(int iters, long *OUT_deltas) {
  long checks = 0, prefixes = 0, deltas = 0;
  for (int is_cam = 0; is_cam < 2; is_cam++)
    for (int pa = 0; pa < 2; pa++) {
      const bdpt_param *par = pa ? &g_abs : NULL;
      rng g;
      rng_seed(&g, 7, (uint64_t)(2 * is_cam + pa));
      for (int it = 0; it < iters; it++) {
        double u[DIM_LIGHT], v[DIM_LIGHT];
        for (int i = 0; i < DIM_LIGHT; i++) u[i] = rng_uniform(&g);
        bdpt_vertex p[MAXV + 1], q[MAXV + 1];
        int n = is_cam ? walk_camera(u, MAXV, par, p) : walk_light(u, MAXV, par, p);
        for (int m = 2; m <= n; m++) {
          for (int i = 0; i < DIM_LIGHT; i++) v[i] = rng_uniform(&g);
          if (!invert(is_cam, p, m, par, &g, v)) {
            print_error("%s subpath: prefix %d of %d does not invert\n",
                        is_cam ? "camera" : "light", m, n);
            fail();
          }
          int n2 = is_cam ? walk_camera(v, m, par, q) : walk_light(v, m, par, q);
          assert_int_equal(n2, m);
          for (int i = 0; i < m; i++) assert_same_vertex(&p[i], &q[i]);
          /* The lobes (the last vertex has not scattered in the new walk). */
          for (int i = 1; i < m - 1; i++) {
            assert_int_equal(p[i].delta, q[i].delta);
            deltas += p[i].delta;
          }
          checks += m;
          prefixes++;
        }
      }
    }
  print_message("subpaths: %ld prefixes, %ld vertices, %ld delta vertices\n", prefixes, checks,
                deltas);
  *OUT_deltas = deltas;
  return prefixes;
}

static void test_subpath_round_trip(void **state) {
  (void)state;
  long deltas, prefixes = subpath_round_trips(3000, &deltas);
  assert_true(prefixes > 4000 && deltas > 100);
}

/* ---- Strategies ------------------------------------------------------------------ */

/* Why a re-split subpath did not invert: a step whose direction its BSDF's
 * sampler cannot reach, which must be a smooth lobe's tail of density
 * below 1e-12: there the numbers would lie within 1e-16 of the square's
 * edge, where doubles cannot resolve them (a Beckmann slope beyond about
 * 6 has erfc below 1e-16), or beyond a sampler's clamp. Returns 1 when
 * that is the reason. */
static int refused_in_tail(const bdpt_vertex *path, int n) {
  const double r[4] = {0.3, 0.6, 0.2, 0.8};
  for (int i = 1; i < n - 1; i++) {
    const surface_hit *h = &path[i].hit;
    vec3 wi = path[i + 1].type == BDPT_VERTEX_LIGHT && path[i + 1].light < 0
                  ? v3_neg(path[i + 1].dir)
                  : v3_normalize(v3_sub(path[i + 1].p, path[i].p));
    vec3 wo_l = frame_to_local(&h->sh, path[i].wo), wi_l = frame_to_local(&h->sh, wi);
    double u[3];
    if (bsdf_invert(h->bsdf, h->tu, h->tv, wo_l, wi_l, path[i].delta, r, u)) continue;
    double pdf = bsdf_pdf(h->bsdf, h->tu, h->tv, wo_l, wi_l);
    if (path[i].delta || !(pdf < 1e-12)) {
      print_error("vertex %d (bsdf %s, delta %d) refused at density %g\n", i,
                  h->bsdf->model->name, path[i].delta, pdf);
      return 0;
    }
    return 1;
  }
  print_error("a subpath of %d vertices refused with every step invertible\n", n);
  return 0;
}

/* Full paths from `iters` BDPT samples re-split at every other strategy,
 * inverted and walked again; returns the paths, *OUT_by_s the re-splits
 * by s' (0, 1, 2, more). */
static long strategy_round_trips(int iters, long OUT_by_s[4]) {
  rng g;
  rng_seed(&g, 11, 0);
  long paths = 0, splits = 0, refused = 0, weights = 0, by_s[4] = {0};
  for (int it = 0; it < iters; it++) {
    double uc[DIM_CAM], ul[DIM_LIGHT], ux[BDPT_DIMS_CONNECT];
    for (int i = 0; i < DIM_CAM; i++) uc[i] = rng_uniform(&g);
    for (int i = 0; i < DIM_LIGHT; i++) ul[i] = rng_uniform(&g);
    for (int i = 0; i < BDPT_DIMS_CONNECT; i++) ux[i] = rng_uniform(&g);
    bdpt_vertex cam[MAXV + 1], lp[MAXV + 1];
    int nc = walk_camera(uc, MAXV, NULL, cam), nl = walk_light(ul, MAXV, NULL, lp);
    /* One strategy with a contribution makes the full path. */
    int t = 2 + (int)(rng_uniform(&g) * (nc - 1)), s = (int)(rng_uniform(&g) * (nl + 1));
    if (t > nc) continue;
    if (s + t - 1 > MAXV || s + t < 3) continue;
    render_counters cnt = {0};
    double rx, ry;
    bdpt_vertex x[2 * MAXV + 2];
    if (s == 1) {
      /* The connect numbers' light sample is the path's last vertex. */
      double pmf, ur;
      int li = scene_sample_light(g_sc, ux[0], &pmf, &ur);
      light_li_sample ls;
      if (rgb_is_black(bdpt_connect(g_sc, cam, t, lp, 1, ux, &rx, &ry, NULL, &cnt))) continue;
      assert_true(light_sample_li(&g_sc->lights[li], g_sc, cam[t - 1].p, ux[1], ux[2], &ls));
      memset(&lp[0], 0, sizeof lp[0]);
      lp[0].type = BDPT_VERTEX_LIGHT;
      lp[0].light = li;
      lp[0].p = ls.p;
      lp[0].n = ls.n;
      lp[0].dir = v3_neg(ls.wi);
      lp[0].hit.prim = ls.tri;
    } else if (rgb_is_black(bdpt_connect(g_sc, cam, t, lp, s, NULL, &rx, &ry, NULL, &cnt))) {
      continue;
    }
    int k = s + t - 1;
    for (int i = 0; i < t; i++) x[i] = cam[i];
    for (int j = 0; j < s; j++) x[k - j] = lp[j];
    if (s > 0) x[t - 1].delta = x[t].delta = 0;
    paths++;
    /* Every strategy's MIS weight at once equals the ratio walk's on each
     * re-split, and the weights sum to one. */
    {
      double wa[2 * MAXV + 3], sum = 0.0;
      bdpt_vertex sc2[2 * MAXV + 3], c2[2 * MAXV + 2], l2[2 * MAXV + 2];
      bdpt_mis_weights(g_sc, x, k, sc2, wa);
      for (int t2 = 1; t2 <= k + 1; t2++) {
        int s2 = k + 1 - t2;
        sum += wa[t2];
        if (!(wa[t2] > 0.0)) continue;
        bdpt_resplit(g_sc, x, k, s2, t2, c2, l2);
        bdpt_path_pdfs(g_sc, c2, t2, l2, s2);
        double w1 = bdpt_mis_weight(g_sc, c2, t2, l2, s2, NULL);
        assert_near(wa[t2], w1, 1e-9 * fmax(1.0, w1));
        weights++;
      }
      assert_near(sum, 1.0, 1e-9);
    }
    /* Every other strategy with a camera subpath of two or more vertices. */
    for (int t2 = 2; t2 <= k + 1; t2++) {
      int s2 = k + 1 - t2;
      if (s2 == s) continue;
      /* A camera walk ends only on area and infinite lights. */
      if (s2 == 0 && x[k].type == BDPT_VERTEX_LIGHT && x[k].light >= 0 &&
          (light_is_delta(&g_sc->lights[x[k].light]) ||
           g_sc->lights[x[k].light].type == LIGHT_DIRECTIONAL))
        continue;
      if (s2 >= 1 && !(x[t2 - 1].type != BDPT_VERTEX_SURFACE || !x[t2 - 1].delta)) continue;
      if (s2 >= 2 && x[t2].delta) continue; /* a connection needs smooth ends */
      bdpt_vertex c2[MAXV + 2], l2[MAXV + 2], c3[MAXV + 2], l3[MAXV + 2];
      bdpt_resplit(g_sc, x, k, s2, t2, c2, l2);
      if (s2 >= 1 && c2[t2 - 1].type == BDPT_VERTEX_SURFACE && bsdf_is_delta(c2[t2 - 1].hit.bsdf))
        continue;
      if (s2 >= 2 && l2[s2 - 1].type == BDPT_VERTEX_SURFACE && bsdf_is_delta(l2[s2 - 1].hit.bsdf))
        continue;
      double vc[DIM_CAM], vl[DIM_LIGHT], vx[BDPT_DIMS_CONNECT];
      for (int i = 0; i < DIM_LIGHT; i++) vl[i] = rng_uniform(&g);
      for (int i = 0; i < DIM_CAM; i++) vc[i] = rng_uniform(&g);
      /* A direction deep in a clamped tail of a sampler (a connection's
       * direction that BSDF sampling cannot reach) is refused. */
      if (!invert(1, c2, t2, NULL, &g, vc)) {
        assert_true(refused_in_tail(c2, t2));
        refused++;
        continue;
      }
      assert_int_equal(walk_camera(vc, t2, NULL, c3), t2);
      for (int i = 0; i < t2; i++) assert_same_vertex(&x[i], &c3[i]);
      if (s2 >= 2) {
        if (!invert(0, l2, s2, NULL, &g, vl)) {
          assert_true(refused_in_tail(l2, s2));
          refused++;
          continue;
        }
        assert_int_equal(walk_light(vl, s2, NULL, l3), s2);
        for (int j = 0; j < s2; j++) assert_same_vertex(&x[k - j], &l3[j]);
      } else if (s2 == 1) {
        assert_true(bdpt_invert_connect(g_sc, &c2[t2 - 1], &x[k], &g, vx));
        double pmf, ur;
        int li = scene_sample_light(g_sc, vx[0], &pmf, &ur);
        light_li_sample ls;
        assert_true(light_sample_li(&g_sc->lights[li], g_sc, x[t2 - 1].p, vx[1], vx[2], &ls));
        assert_near(v3_len(v3_sub(ls.wi, v3_normalize(v3_sub(x[k].p, x[t2 - 1].p)))), 0.0, 1e-7);
      }
      splits++;
      by_s[s2 < 3 ? s2 : 3]++;
    }
  }
  print_message("strategies: %ld paths, %ld re-splits (s' = 0: %ld, 1: %ld, 2: %ld, >2: %ld), "
                "%ld refused; %ld MIS weights compared\n",
                paths, splits, by_s[0], by_s[1], by_s[2], by_s[3], refused, weights);
  assert_true(weights > 2 * paths);
  for (int i = 0; i < 4; i++) OUT_by_s[i] = by_s[i];
  return paths;
}

static void test_strategies(void **state) {
  (void)state;
  long by_s[4];
  assert_true(strategy_round_trips(8000, by_s) > 600);
  for (int i = 0; i < 4; i++) assert_true(by_s[i] > 50);
}

/* The same round trips on the project's scenes and the LMC paper's torus
 * (../shared, skipped when absent). */
static void test_scenes(void **state) {
  (void)state;
  static const char *const files[] = {
      LMC_SOURCE_DIR "/scenes/ring-caustics/scene.xml",
      LMC_SOURCE_DIR "/scenes/ring-caustics-glass/scene.xml",
      LMC_SOURCE_DIR "/scenes/cornell-box/scene.xml", LMC_SHARED_DIR "/scenes/torus/lmc.xml"};
  scene *mixed = g_sc;
  int done = 0;
  for (int f = 0; f < 4; f++) {
    if (access(files[f], R_OK) != 0) {
      print_message("%s: absent, skipped\n", files[f]);
      continue;
    }
    g_sc = load_scene(files[f]);
    print_message("%s\n", files[f]);
    long deltas, by_s[4];
    assert_true(subpath_round_trips(400, &deltas) > 300);
    assert_true(strategy_round_trips(3000, by_s) > 30);
    scene_destroy(g_sc);
    done++;
  }
  g_sc = mixed;
  assert_true(done >= 3);
}

/* ---- The posterior ------------------------------------------------------------------ */

enum { NBIN = 20 };

/* Worst p-value over the coordinates of one stream after the
 * replacement; rr_anywhere: the negative control. */
static double posterior_worst_p(int is_cam, const bdpt_param *par, int m, int n_samples,
                                int rr_anywhere, uint64_t seed) {
  int dim = is_cam ? 2 + BDPT_DIMS_PER_VERTEX * (m - 1) : BDPT_DIMS_LIGHT_START +
                                                             BDPT_DIMS_PER_VERTEX * (m - 1);
  static double obs[DIM_LIGHT][NBIN];
  memset(obs, 0, sizeof obs);
  rng g;
  rng_seed(&g, seed, 1);
  for (int it = 0; it < n_samples; it++) {
    double u[DIM_LIGHT], v[DIM_LIGHT];
    for (int i = 0; i < DIM_LIGHT; i++) u[i] = rng_uniform(&g);
    bdpt_vertex p[MAXV + 1];
    int n = is_cam ? walk_camera(u, MAXV, par, p) : walk_light(u, MAXV, par, p);
    if (n >= m) {
      if (!invert(is_cam, p, m, par, &g, v)) return 0.0;
      if (rr_anywhere) {
        int first = is_cam ? 2 : BDPT_DIMS_LIGHT_START;
        for (int i = 1; i < m - 1; i++) v[first + BDPT_DIMS_PER_VERTEX * (i - 1) + 3] = rng_uniform(&g);
      }
      memcpy(u, v, (size_t)dim * sizeof u[0]);
    }
    for (int i = 0; i < dim; i++) obs[i][(int)(u[i] * NBIN)] += 1.0;
  }
  double worst = 1.0, expct[NBIN];
  for (int b = 0; b < NBIN; b++) expct[b] = (double)n_samples / NBIN;
  for (int i = 0; i < dim; i++) worst = fmin(worst, chi2_pvalue(obs[i], expct, NBIN, 5.0, NULL, NULL));
  return worst;
}

static void test_posterior(void **state) {
  (void)state;
  /* 8 runs of up to 2 + 4 * 4 = 18 coordinates each. */
  const int runs = 8, coords = 18;
  double level = chi2_sidak(0.01, runs * coords);
  int checked = 0;
  for (int is_cam = 0; is_cam < 2; is_cam++)
    for (int pa = 0; pa < 2; pa++)
      for (int mi = 0; mi < 2; mi++) {
        int m = mi ? 4 : 3;
        double p = posterior_worst_p(is_cam, pa ? &g_abs : NULL, m, 60000, 0,
                                     100 + (uint64_t)(4 * is_cam + 2 * pa + mi));
        if (!(p >= level)) {
          print_error("%s subpath, absolute %d, %d vertices: worst p %g below %g\n",
                      is_cam ? "camera" : "light", pa, m, p, level);
          fail();
        }
        checked++;
      }
  /* The negative control: roulette's number anywhere in [0, 1). */
  double pc = posterior_worst_p(1, NULL, 4, 60000, 1, 999);
  print_message("posterior: %d runs at level %.2e per coordinate; control p = %g\n", checked,
                level, pc);
  assert_int_equal(checked, runs);
  assert_true(pc < 1e-6);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_subpath_round_trip),
      cmocka_unit_test(test_strategies),
      cmocka_unit_test(test_scenes),
      cmocka_unit_test(test_posterior),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
