/*
 * analytic_check.h: rendering the analytic scenes (tests/data/analytic)
 * with an MCMC integrator and checking image means against their exact
 * values over independent seeds; shared by test_mcmc_analytic.c (which
 * states the statistics) and test_mmlt_moves_slow.c. The flags below set
 * the renders' options. Include after <cmocka.h>.
 */
#ifndef LMC_TESTS_ANALYTIC_CHECK_H
#define LMC_TESTS_ANALYTIC_CHECK_H

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lmc/mcmc.h"
#include "load_scene.h"
#include "render/io/io.h"
#include "test_util.h"

#define RUNS 6
static int g_checks;
static int g_even; /* --allocate even for the renders of check_scene */
static int g_direct; /* --direct separate for the renders (the CLI's default; 0: mcmc) */
static int g_mcmc_empty; /* the scene has no path for MCMC (all of it is pt's direct light) */
static const char *g_states; /* --states for the renders (NULL: the integrator's) */
static int g_delayed; /* --delayed on (lmc, h2mc: delayed acceptance; h2mc's default) */
static const char *g_jump; /* mmlt's --technique-jump (NULL: not given) */
static const char *g_perturb; /* mmlt's --path-mutations (NULL: not given) */

static inline render_settings settings(const scene *s, const char *integrator, int64_t spp,
                                uint64_t seed, int threads) {
  render_settings rs = s->settings;
  snprintf(rs.integrator, sizeof rs.integrator, "%s", integrator);
  rs.spp = spp;
  rs.set |= SET_SPP;
  rs.time_limit = 0.0;
  rs.threads = threads;
  rs.seed = seed;
  rs.quiet = 1;
  lmc_error err;
  assert_int_equal(mcmc_set(&rs, "bootstrap", "16384", &err), LMC_OK);
  assert_int_equal(mcmc_set(&rs, "allocate", g_even ? "even" : "b", &err), LMC_OK);
  assert_int_equal(mcmc_set(&rs, "direct", g_direct ? "separate" : "mcmc", &err), LMC_OK);
  if (g_states) assert_int_equal(mcmc_set(&rs, "states", g_states, &err), LMC_OK);
  assert_int_equal(mcmc_set(&rs, "delayed", g_delayed ? "on" : "off", &err), LMC_OK);
  if (g_jump) assert_int_equal(mcmc_set(&rs, "technique-jump", g_jump, &err), LMC_OK);
  if (g_perturb) assert_int_equal(mcmc_set(&rs, "path-mutations", g_perturb, &err), LMC_OK);
  return rs;
}

/* Group of pixel (x, y): 0 environment, 1 + the mesh index of an object,
 * -1 mixed (probes at the corners and centre disagree). */
static inline int pixel_group(const scene *s, int x, int y) {
  static const double off[5][2] = {{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}, {1.0, 1.0}, {0.5, 0.5}};
  int g = -2;
  for (int k = 0; k < 5; k++) {
    vec3 o, d;
    camera_generate_ray(&s->cam, x + off[k][0], y + off[k][1], &o, &d);
    surface_hit h;
    int gk = scene_intersect(s, o, d, 0.0, INFINITY, &h) ? 1 + h.mesh : 0;
    if (g == -2) g = gk;
    else if (g != gk) return -1;
  }
  return g;
}

/* Renders R seeds and checks the per-group channel means against expect
 * (NULL entries: group not checked). */
#define MAX_GROUPS 3
static inline void check_scene(const char *file, const char *integrator, int64_t spp, const rgb *expect,
                        int n_groups, double extra_tol) {
  scene *s = load_analytic_scene(file);
  assert_true(n_groups <= MAX_GROUPS);
  double sum[MAX_GROUPS][3] = {{0}}, sum2[MAX_GROUPS][3] = {{0}};
  for (int r = 0; r < RUNS; r++) {
    render_settings rs = settings(s, integrator, spp, 100 + (uint64_t)r, 2);
    film f;
    render_stats st;
    lmc_error err;
    lmc_error_clear(&err);
    assert_int_equal(mcmc_render_run(s, &rs, &f, &st, &err), LMC_OK);
    /* Whatever the allocation among mmlt's lengths, the budget is spp
     * mutations per pixel, up to whole rounds of every chain. */
    int64_t want = spp * (int64_t)s->cam.width * s->cam.height;
    if (g_mcmc_empty) {
      /* Nothing for the chains to render: b = 0 and no mutation made. */
      assert_true(st.mcmc_b == 0.0 && st.samples == 0);
    } else {
      if (!(st.samples >= want && st.samples < want + want / 10))
        fprintf(stderr, "  %s %s: %lld mutations for a budget of %lld\n", file, integrator,
                (long long)st.samples, (long long)want);
      assert_true(st.samples >= want && st.samples < want + want / 10);
    }
    lmc_image img;
    assert_int_equal(film_develop(&f, &img, &err), LMC_OK);
    double gs[MAX_GROUPS][3] = {{0}};
    int gn[MAX_GROUPS] = {0};
    for (int y = 0; y < img.height; y++)
      for (int x = 0; x < img.width; x++) {
        int g = n_groups == 1 ? 0 : pixel_group(s, x, y);
        if (g < 0 || g >= n_groups) continue;
        const float *p = img.data + 3 * ((size_t)y * img.width + x);
        for (int c = 0; c < 3; c++) gs[g][c] += p[c];
        gn[g]++;
      }
    for (int g = 0; g < n_groups; g++) {
      assert_true(gn[g] > 50);
      for (int c = 0; c < 3; c++) {
        double m = gs[g][c] / gn[g];
        sum[g][c] += m;
        sum2[g][c] += m * m;
      }
    }
    image_free(&img);
    film_free(&f);
  }
  for (int g = 0; g < n_groups; g++) {
    double e[3] = {expect[g].r, expect[g].g, expect[g].b};
    for (int c = 0; c < 3; c++) {
      double mean = sum[g][c] / RUNS;
      double var = fmax(0.0, (sum2[g][c] - RUNS * mean * mean) / (RUNS - 1));
      double se = sqrt(var / RUNS);
      fprintf(stderr, "  %s %s group %d channel %d: mean %.5f (exact %.5f), SE %.2g\n", file,
              integrator, g, c, mean, e[c], se);
      /* A group with no variance at all (pure environment) must be exact to rounding. */
      assert_near(mean, e[c], 8.0 * se + extra_tol * e[c] + 1e-9 * e[c]);
      g_checks++;
    }
  }
  scene_destroy(s);
}

/* One render of `file` with seed 7, 4 mutations per pixel, one thread,
 * under the flags set now (a film to compare). */
static inline void render_seed7(const char *file, const char *integrator, film *OUT_f) {
  scene *s = load_analytic_scene(file);
  render_stats st;
  lmc_error err;
  render_settings rs = settings(s, integrator, 4, 7, 1);
  assert_int_equal(mcmc_render_run(s, &rs, OUT_f, &st, &err), LMC_OK);
  scene_destroy(s);
}

/* Two films differ somewhere (a flag changed what the chains did); frees both. */
static inline void assert_films_differ(film *a, film *b) {
  size_t n = 3 * (size_t)a->width * (size_t)a->height;
  assert_true(memcmp(a->splat, b->splat, n * sizeof *a->splat) != 0);
  film_free(a);
  film_free(b);
}

#endif
