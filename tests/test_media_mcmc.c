/*
 * test_media_mcmc.c: the MCMC integrators through participating media
 * (issue 59, part 2): pssmlt, mmlt and lmc render the media scenes
 * of tests/data/media whose pixel values are known exactly, and the
 * integrators and settings that do not render media yet say so.
 *
 *  slab.xml            an absorbing slab in front of a uniform emitter:
 *                      L exp(-sigma_a) (paths of one segment);
 *  single_scatter.xml  single scattering of a directional light through a
 *                      slab: sigma_s p(0) E exp(-sigma_t) (two segments);
 *  furnace.xml         a closed emitting box of fogs that do not absorb:
 *                      exactly L (every length).
 * The slab and the single scattering run with --direct mcmc (the chains
 * render every length); the furnace with the default --direct separate
 * (pt renders one and two segments through the media, the chains the
 * rest), so both halves and their seam are checked, by pssmlt on the bdpt
 * and the pt states, by mmlt on the mmlt states and by lmc on the pt
 * states.
 *
 * Variance: an MCMC image's pixels are tied by the chains and scaled by
 * the bootstrap's b, so the spread over the pixels says nothing of the
 * image mean's error. Each scene is rendered R = 6 times with independent
 * seeds (each with its own bootstrap); the mean over the runs of each
 * channel's image mean must lie within t_5(0.9995) = 6.87 standard errors
 * (their spread over the runs / sqrt(R)) of the exact value, plus the
 * scene's stated geometric error: 6 configurations x 3 channels = 18
 * checks, a false alarm about 2e-2 at most (the channels of a scene are not
 * independent). The control: the slab rendered with the media ignored
 * (render_settings.no_media) must fail the same check. Fixed seeds;
 * checks counted. Also: the same image with 1 and 2 threads.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lmc/mcmc.h"
#include "render/integrators/integrator.h"
#include "render/io/io.h"
#include "load_scene.h"
#include "test_util.h"

#define RUNS 6
#define T_5 6.87 /* Student's t with 5 degrees of freedom, two-sided 0.001 */

static int g_checks;

/* The image mean of each channel over RUNS renders of path by integrator
 * (on `states`, NULL: its own; spp mutations per pixel, --direct
 * `direct`, media ignored when no_media) into mean[3], its standard error
 * into se[3]. */
static void runs(const char *path, const char *integrator, const char *states, int64_t spp,
                 const char *direct, int no_media, double mean[3], double se[3]) {
  scene *s = load_scene(path);
  assert_true(s->n_media > 0);
  double sum[3] = {0}, sum2[3] = {0};
  for (int r = 0; r < RUNS; r++) {
    render_settings rs = s->settings;
    snprintf(rs.integrator, sizeof rs.integrator, "%s", integrator);
    lmc_error err;
    assert_int_equal(mcmc_set(&rs, "direct", direct, &err), LMC_OK);
    if (states) assert_int_equal(mcmc_set(&rs, "states", states, &err), LMC_OK);
    assert_int_equal(mcmc_renders_media(&rs), 1);
    rs.spp = spp;
    rs.set |= SET_SPP;
    rs.time_limit = 0.0;
    rs.threads = 2;
    rs.seed = 300 + (uint64_t)r;
    rs.quiet = 1;
    rs.no_media = no_media;
    film f;
    render_stats st;
    assert_int_equal(mcmc_render_run(s, &rs, &f, &st, &err), LMC_OK);
    assert_int_equal(st.nan_samples, 0);
    lmc_image img;
    assert_int_equal(film_develop(&f, &img, &err), LMC_OK);
    int n = img.width * img.height;
    for (int c = 0; c < 3; c++) {
      double m = 0.0;
      for (int i = 0; i < n; i++) m += img.data[3 * i + c];
      m /= n;
      sum[c] += m, sum2[c] += m * m;
    }
    image_free(&img);
    film_free(&f);
  }
  for (int c = 0; c < 3; c++) {
    mean[c] = sum[c] / RUNS;
    se[c] = sqrt(fmax(0.0, (sum2[c] - RUNS * mean[c] * mean[c]) / (RUNS - 1)) / RUNS);
  }
  scene_destroy(s);
}

/* 1 when every channel's mean lies within T_5 SE + rel_tol of expect. */
static int agrees(const char *what, const double mean[3], const double se[3], rgb expect,
                  double rel_tol) {
  const double ex[3] = {expect.r, expect.g, expect.b};
  int ok = 1;
  for (int c = 0; c < 3; c++) {
    double z = fabs(mean[c] - ex[c]) / fmax(se[c], 1e-300);
    printf("%s channel %d: mean %.6f over %d runs, exact %.6f, SE %.2e (%.2f SE)\n", what, c,
           mean[c], RUNS, ex[c], se[c], z);
    ok = ok && se[c] > 0.0 && fabs(mean[c] - ex[c]) <= T_5 * se[c] + rel_tol * ex[c];
  }
  return ok;
}

static void test_slab(void **state) {
  (void)state;
  rgb ex = rgb_make(2.0 * exp(-0.5), 3.0 * exp(-1.0), 4.0 * exp(-2.0));
  double m[3], se[3];
  runs("data/media/slab.xml", "pssmlt", NULL, 64, "mcmc", 0, m, se);
  assert_true(agrees("slab", m, se, ex, 1e-4));
  g_checks += 3;
  /* The control: through the slab as if it were empty. */
  runs("data/media/slab.xml", "pssmlt", NULL, 64, "mcmc", 1, m, se);
  assert_false(agrees("slab, media ignored (control)", m, se, ex, 1e-4));
}

static void test_single_scatter(void **state) {
  (void)state;
  double g = 0.3, p0 = (1.0 + g) / (4.0 * 3.14159265358979323846 * (1.0 - g) * (1.0 - g));
  rgb ex = rgb_make(0.3 * p0 * 1.0 * exp(-0.4), 0.6 * p0 * 2.0 * exp(-0.7),
                    1.2 * p0 * 3.0 * exp(-1.3));
  double m[3], se[3];
  runs("data/media/single_scatter.xml", "pssmlt", NULL, 64, "mcmc", 0, m, se);
  assert_true(agrees("single scatter", m, se, ex, 1e-4));
  g_checks += 3;
}

/* The furnace by pssmlt on the bdpt and the pt states, by mmlt on the
 * mmlt states (pssmlt there makes the same moves), and by lmc on the pt
 * states (Langevin steps through the fogs, path_eval_pt's gradient). */
static void test_furnace(void **state) {
  (void)state;
  static const char *const cfg[4][2] = {
      {"pssmlt", NULL}, {"pssmlt", "pt"}, {"mmlt", NULL}, {"lmc", "pt"}};
  for (int i = 0; i < 4; i++) {
    double m[3], se[3];
    char what[64];
    snprintf(what, sizeof what, "furnace, %s on %s states", cfg[i][0],
             cfg[i][1] ? cfg[i][1] : "its own");
    runs("data/media/furnace.xml", cfg[i][0], cfg[i][1], 64, "separate", 0, m, se);
    assert_true(agrees(what, m, se, rgb_make(1.0, 2.0, 3.0), 1e-9));
    g_checks += 3;
  }
}

/* Which MCMC settings render media: pssmlt and mmlt on the bdpt, mmlt
 * and pt states, lmc on the pt states; not with the inverse path
 * sampler's moves, not on the path states, and not h2mc or mlt yet. The scene's media are then
 * named in the warning (render_media_note), and not when the integrator
 * renders them. */
static void test_which_render_media(void **state) {
  (void)state;
  scene *s = load_scene("data/media/slab.xml");
  lmc_error err;
  int checks = 0;
  render_settings rs = s->settings;
  snprintf(rs.integrator, sizeof rs.integrator, "pssmlt");
  assert_int_equal(mcmc_renders_media(&rs), 1);
  int w0 = lmc_warning_count();
  assert_int_equal(render_media_note(s, "pssmlt", mcmc_renders_media(&rs)), 0);
  assert_int_equal(lmc_warning_count(), w0);
  checks++;
  static const char *const flags[5][2] = {{"states", "mmlt"},
                                           {"states", "pt"},
                                           {"states", "path"},
                                           {"technique-jump", "0.2"},
                                           {"path-mutations", "0.3"}};
  for (int i = 0; i < 5; i++) {
    render_settings r2 = rs;
    assert_int_equal(mcmc_set(&r2, flags[i][0], flags[i][1], &err), LMC_OK);
    assert_int_equal(mcmc_renders_media(&r2), i < 2);
    checks++;
  }
  static const char *const others[] = {"mmlt", "lmc", "h2mc", "mlt", "pt", "nosuch"};
  for (int i = 0; i < 6; i++) {
    render_settings r2 = s->settings;
    snprintf(r2.integrator, sizeof r2.integrator, "%s", others[i]);
    assert_int_equal(mcmc_renders_media(&r2), i == 0);
    checks++;
  }
  /* lmc on the pt states (gradients through media), not on its own bdpt
   * states. */
  render_settings r3 = s->settings;
  snprintf(r3.integrator, sizeof r3.integrator, "lmc");
  assert_int_equal(mcmc_set(&r3, "states", "pt", &err), LMC_OK);
  assert_int_equal(mcmc_renders_media(&r3), 1);
  assert_int_equal(mcmc_set(&r3, "states", "mmlt", &err), LMC_OK);
  assert_int_equal(mcmc_renders_media(&r3), 0);
  checks += 2;
  assert_int_equal(render_media_note(s, "lmc", 0), 1);
  assert_int_equal(lmc_warning_count(), w0 + 1);
  checks++;
  assert_int_equal(checks, 15);
  scene_destroy(s);
}

/* pssmlt through media makes the same image with 1 and 2 threads (the
 * chains' moves do not depend on the threads), and another seed another. */
static void test_threads(void **state) {
  (void)state;
  scene *s = load_scene("data/media/furnace.xml");
  lmc_image img[3];
  for (int k = 0; k < 3; k++) {
    render_settings rs = s->settings;
    snprintf(rs.integrator, sizeof rs.integrator, "pssmlt");
    rs.spp = 8;
    rs.set |= SET_SPP;
    rs.threads = k == 0 ? 1 : 2;
    rs.seed = k == 2 ? 78 : 77;
    rs.quiet = 1;
    film f;
    render_stats st;
    lmc_error err;
    assert_int_equal(mcmc_render_run(s, &rs, &f, &st, &err), LMC_OK);
    assert_int_equal(film_develop(&f, &img[k], &err), LMC_OK);
    film_free(&f);
  }
  size_t n = (size_t)img[0].width * img[0].height * 3;
  assert_memory_equal(img[0].data, img[1].data, n * sizeof(float));
  assert_memory_not_equal(img[0].data, img[2].data, n * sizeof(float));
  for (int k = 0; k < 3; k++) image_free(&img[k]);
  scene_destroy(s);
}

static void test_count(void **state) {
  (void)state;
  assert_int_equal(g_checks, 18);
}

int main(void) {
  lmc_warn_set_quiet(1);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_slab),    cmocka_unit_test(test_single_scatter),
      cmocka_unit_test(test_furnace), cmocka_unit_test(test_which_render_media),
      cmocka_unit_test(test_threads), cmocka_unit_test(test_count),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
