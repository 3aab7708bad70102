/*
 * test_plugin_integrator.c: an integrator defined outside src/lmc, run
 * through the MCMC driver (method.h): the interface is proven by a client
 * that is not one of ours.
 *
 * The client is an independence sampler over whole BDPT samples: its only
 * kernel is the large step on the bdpt states (space.h), which proposes a
 * fresh BDPT sample and moves to one of its strategies in proportion to
 * its contribution (chain.h). It is registered at run time
 * (mc_method_register) and has one file's worth of code: a table, a run
 * that counts what the driver asks of it, and its kernels.
 *
 * On the analytic scenes (tests/data/analytic, test_analytic.c), the
 * furnace (every pixel exactly 1) and the diffuse sphere (covered pixels
 * 0.5 L, the background L, L = (1, 2, 4)), R = 6 seeds give the group means'
 * mean and standard error SE; each must lie within 8 SE of the exact
 * value (P(|t_5| > 8) = 5e-4 per check, 9 checks). The driver must call
 * create, set_chains, chain_kernels once per chain, report and destroy,
 * and make spp mutations per pixel (up to 10% of whole rounds). A second
 * registration under the same name, and one without chain_kernels, fail.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/mcmc.h"
#include "lmc/driver/method.h"
#include "load_scene.h"
#include "render/io/io.h"
#include "test_util.h"

#define RUNS 6
static int g_checks;

/* --- the client integrator ----------------------------------------------------- */

typedef struct indep_run {
  int n_chains;      /* from set_chains */
  int kernel_calls;  /* chain_kernels calls */
  int reports;
} indep_run;

static indep_run g_last; /* what the last run counted, kept at destroy */

static lmc_status indep_create(void **OUT_run, const mc_method_setup *setup, lmc_error *err) {
  if (setup->space->n_fam < 1)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "indep: a space without families");
  indep_run *run = calloc(1, sizeof *run);
  if (!run) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "indep: out of memory");
  *OUT_run = run;
  return LMC_OK;
}

static void indep_destroy(void *run) {
  g_last = *(indep_run *)run;
  free(run);
}

static lmc_status indep_set_chains(void *run, int n, const int *family, lmc_error *err) {
  (void)family, (void)err;
  ((indep_run *)run)->n_chains = n;
  return LMC_OK;
}

static int indep_chain_kernels(void *run, const mc_method_setup *setup, int i,
                               const mc_space_family *F, mc_kernel *k, double *p) {
  (void)setup, (void)i, (void)F;
  ((indep_run *)run)->kernel_calls++;
  k[0] = mc_kernel_large();
  p[0] = 1.0;
  return 1;
}

static void indep_report(void *run, mc_chain *const *chains, int n, double seconds,
                         const mc_counts *counts) {
  (void)counts;
  (void)chains, (void)n, (void)seconds;
  ((indep_run *)run)->reports++;
}

static const mc_method indep_method = {
    .name = "indep-bdpt",
    .default_states = MCMC_STATES_BDPT,
    .create = indep_create,
    .destroy = indep_destroy,
    .set_chains = indep_set_chains,
    .chain_kernels = indep_chain_kernels,
    .report = indep_report,
};

/* --- the checks ------------------------------------------------------------------ */

/* 1 when every probe of pixel (x, y) hits an object, 0 when none does,
 * -1 mixed. */
static int pixel_group(const scene *s, int x, int y) {
  static const double off[5][2] = {{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}, {1.0, 1.0}, {0.5, 0.5}};
  int g = -2;
  for (int q = 0; q < 5; q++) {
    vec3 o, d;
    camera_generate_ray(&s->cam, x + off[q][0], y + off[q][1], &o, &d);
    surface_hit h;
    int gq = scene_intersect(s, o, d, 0.0, INFINITY, &h) ? 1 : 0;
    if (g == -2) g = gq;
    else if (g != gq) return -1;
  }
  return g;
}

static void check_scene(const char *file, const rgb *expect, int n_groups) {
  scene *s = load_analytic_scene(file);
  const int64_t spp = 16;
  double sum[2][3] = {{0}}, sum2[2][3] = {{0}};
  for (int r = 0; r < RUNS; r++) {
    render_settings rs = s->settings;
    lmc_error err;
    snprintf(rs.integrator, sizeof rs.integrator, "indep-bdpt");
    rs.spp = spp;
    rs.set |= SET_SPP;
    rs.time_limit = 0.0;
    rs.threads = 2;
    rs.seed = 300 + (uint64_t)r;
    assert_int_equal(mcmc_set(&rs, "bootstrap", "16384", &err), LMC_OK);
    rs.quiet = 0; /* (the report is called only when not quiet) */
    assert_int_equal(mcmc_set(&rs, "direct", "mcmc", &err), LMC_OK);
    film f;
    render_stats st;
    lmc_error_clear(&err);
    memset(&g_last, 0, sizeof g_last);
    assert_int_equal(mcmc_render_run(s, &rs, &f, &st, &err), LMC_OK);
    assert_true(g_last.n_chains > 0);
    assert_int_equal(g_last.kernel_calls, g_last.n_chains);
    assert_int_equal(g_last.reports, 1);
    int64_t want = spp * (int64_t)s->cam.width * s->cam.height;
    assert_true(st.samples >= want && st.samples < want + want / 10);
    lmc_image img;
    assert_int_equal(film_develop(&f, &img, &err), LMC_OK);
    double gs[2][3] = {{0}};
    int gn[2] = {0, 0};
    for (int y = 0; y < img.height; y++)
      for (int x = 0; x < img.width; x++) {
        int g = n_groups == 1 ? 0 : pixel_group(s, x, y);
        if (g < 0) continue;
        const float *p = img.data + 3 * ((size_t)y * img.width + x);
        for (int c = 0; c < 3; c++) gs[g][c] += p[c];
        gn[g]++;
      }
    for (int g = 0; g < n_groups; g++) {
      assert_true(gn[g] > 50);
      for (int c = 0; c < 3; c++) {
        double m = gs[g][c] / gn[g];
        sum[g][c] += m, sum2[g][c] += m * m;
      }
    }
    image_free(&img);
    film_free(&f);
  }
  for (int g = 0; g < n_groups; g++) {
    double e[3] = {expect[g].r, expect[g].g, expect[g].b};
    for (int c = 0; c < 3; c++) {
      double mean = sum[g][c] / RUNS;
      double se = sqrt(fmax(0.0, (sum2[g][c] - RUNS * mean * mean) / (RUNS - 1)) / RUNS);
      fprintf(stderr, "  %s indep-bdpt group %d channel %d: mean %.5f (exact %.5f), SE %.2g\n",
              file, g, c, mean, e[c], se);
      assert_near(mean, e[c], 8.0 * se + 1e-9 * e[c]);
      g_checks++;
    }
  }
  scene_destroy(s);
}

static void test_register(void **state) {
  (void)state;
  lmc_error err;
  assert_false(mcmc_is_integrator("indep-bdpt"));
  assert_int_equal(mc_method_register(&indep_method, &err), LMC_OK);
  assert_true(mcmc_is_integrator("indep-bdpt"));
  assert_int_not_equal(mc_method_register(&indep_method, &err), LMC_OK);
  mc_method bad = {.name = "no-kernels"};
  assert_int_not_equal(mc_method_register(&bad, &err), LMC_OK);
  assert_false(mcmc_is_integrator("no-kernels"));
  g_checks += 5;
}

static void test_analytic(void **state) {
  (void)state;
  rgb one = rgb_gray(1.0);
  rgb e[2] = {rgb_make(1.0, 2.0, 4.0), rgb_make(0.5, 1.0, 2.0)};
  check_scene("furnace.xml", &one, 1);
  check_scene("diffuse_sphere.xml", e, 2);
}

static void test_count(void **state) {
  (void)state;
  assert_int_equal(g_checks, 5 + 3 + 6);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_register),
      cmocka_unit_test(test_analytic),
      cmocka_unit_test(test_count),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
