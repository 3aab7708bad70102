/*
 * test_mlt.c: path-space MLT (--integrator mlt: the path states of
 * lmc/states/path_states.c on the MCMC driver, the mutations and
 * perturbations of lmc/path).
 *
 * What is checked:
 * - tests/data/analytic/emitting_box.xml, whose every pixel has
 *   expectation 1 - 2^-8 exactly: the image mean of R = 6 seeds (each with
 *   its own bootstrap), and each quadrant's, lies within 8 of their
 *   standard errors of it
 *   (P(|t_5| > 8) = 5e-4 per check), with the chains rendering every path
 *   (--direct mcmc) and with pt rendering the paths of one and two
 *   segments (--direct separate, the chains from three); every render
 *   makes its budget of spp mutations per pixel (up to whole rounds), and
 *   its statistics count the moves proposed and accepted; and with the
 *   primary-sample step (--pss-mutation on) among the moves, and with
 *   HSLT's half-vector perturbation (--hslt on), each of which must
 *   change the image (the box's contribution is nearly flat, so the
 *   moves' exactness is test_perturb's and test_mut_hslt's to check).
 * - Determinism under --spp: the same seed gives a bit-identical film with
 *   1 and 2 threads, with HSLT among the moves too; another seed a
 *   different one.
 * - A plane under a directional light alone, every pixel rho / pi E cos:
 *   the mean of R seeds within 8 standard errors, no warning, --strict.
 * - A scene's <integrator type="mlt"> selects mlt; Mitsuba's mutation
 *   flags reach mlt's own; the manifold perturbation is warned about.
 * Each test counts its checks and asserts the count.
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
#include "load_scene.h"
#include "render/io/io.h"
#include "render/options.h"
#include "test_util.h"

#define RUNS 6

static render_settings settings(const scene *s, int64_t spp, uint64_t seed, int threads,
                                const char *direct) {
  render_settings rs = s->settings;
  snprintf(rs.integrator, sizeof rs.integrator, "mlt");
  rs.spp = spp;
  rs.set |= SET_SPP;
  rs.time_limit = 0.0;
  rs.threads = threads;
  rs.seed = seed;
  rs.quiet = 1;
  lmc_error err;
  assert_int_equal(mcmc_set(&rs, "bootstrap", "16384", &err), LMC_OK);
  assert_int_equal(mcmc_set(&rs, "direct", direct, &err), LMC_OK);
  return rs;
}

static double image_mean(const film *f) {
  lmc_image img;
  lmc_error err;
  assert_int_equal(film_develop(f, &img, &err), LMC_OK);
  double s = 0.0;
  for (int i = 0; i < img.width * img.height * 3; i++) s += img.data[i];
  s /= img.width * img.height * 3;
  image_free(&img);
  return s;
}

/* The mean of quadrant q (0 .. 3: left/right, top/bottom) of the image. */
static double quadrant_mean(const film *f, int q) {
  lmc_image img;
  lmc_error err;
  assert_int_equal(film_develop(f, &img, &err), LMC_OK);
  int w2 = img.width / 2, h2 = img.height / 2, x0 = (q & 1) * w2, y0 = (q >> 1) * h2;
  double s = 0.0;
  for (int y = y0; y < y0 + h2; y++)
    for (int x = x0; x < x0 + w2; x++)
      for (int c = 0; c < 3; c++) s += img.data[((size_t)y * img.width + x) * 3 + c];
  image_free(&img);
  return s / (3.0 * w2 * h2);
}

static void test_emitting_box(void **state) {
  (void)state;
  int checks = 0;
  scene *s = load_analytic_scene("emitting_box.xml");
  const double exact = 1.0 - 1.0 / 256.0;
  /* The third: every path with the primary-sample step among the moves;
   * the fourth with HSLT's half-vector perturbation among them. */
  const char *direct[4] = {"mcmc", "separate", "mcmc", "mcmc"};
  for (int d = 0; d < 4; d++) {
    double sum = 0.0, sum2 = 0.0, qs[4] = {0}, qs2[4] = {0};
    static double q0_first; /* quadrant 0's sum with d = 0: the step must change it */
    for (int r = 0; r < RUNS; r++) {
      render_settings rs = settings(s, 16, 100 + (uint64_t)r, 2, direct[d]);
      if (d >= 2) {
        lmc_error err;
        assert_int_equal(mcmc_set(&rs, d == 2 ? "pss-mutation" : "hslt", "on", &err), LMC_OK);
      }
      film f;
      render_stats st;
      lmc_error err;
      lmc_error_clear(&err);
      assert_int_equal(mcmc_render_run(s, &rs, &f, &st, &err), LMC_OK);
      int64_t want = 16 * (int64_t)s->cam.width * s->cam.height;
      assert_true(st.samples >= want && st.samples < want + want / 10);
      double m = image_mean(&f);
      sum += m, sum2 += m * m;
      for (int q = 0; q < 4; q++) {
        double mq = quadrant_mean(&f, q);
        qs[q] += mq, qs2[q] += mq * mq;
      }
      film_free(&f);
    }
    if (d == 0) q0_first = qs[0];
    if (d >= 2) assert_true(qs[0] != q0_first); /* the step did move the chains */
    /* Where the chains put the light (the total is b's): each quadrant's
     * mean within 8 of its standard errors of the exact value. */
    for (int q = 0; q < 4; q++) {
      double mq = qs[q] / RUNS;
      double seq = sqrt(fmax(0.0, (qs2[q] - RUNS * mq * mq) / (RUNS - 1)) / RUNS);
      assert_true(seq > 0.0);
      assert_near(mq, exact, 8.0 * seq);
      checks++;
    }
    double mean = sum / RUNS, se = sqrt(fmax(0.0, (sum2 - RUNS * mean * mean) / (RUNS - 1)) / RUNS);
    fprintf(stderr, "  emitting box, --direct %s%s: mean %.5f (exact %.5f), SE %.2g\n", direct[d],
            d == 2 ? " --pss-mutation on" : d == 3 ? " --hslt on" : "", mean, exact, se);
    assert_true(se > 0.0);
    assert_near(mean, exact, 8.0 * se);
    checks += 2;
  }
  scene_destroy(s);
  assert_int_equal(checks, 4 * (2 + 4));
}

static int films_equal(const film *a, const film *b) {
  size_t n = (size_t)a->width * a->height * 3;
  return a->width == b->width && a->height == b->height &&
         memcmp(a->splat, b->splat, n * sizeof *a->splat) == 0 &&
         memcmp(a->sum, b->sum, n * sizeof *a->sum) == 0;
}

static void test_determinism(void **state) {
  (void)state;
  scene *s = load_analytic_scene("emitting_box.xml");
  int checks = 0;
  /* mlt's default moves, then with HSLT's among them. */
  for (int hslt = 0; hslt < 2; hslt++) {
    film f[4];
    const uint64_t seed[4] = {3, 3, 3, 4};
    const int threads[4] = {2, 2, 1, 2};
    for (int i = 0; i < 4; i++) {
      render_settings rs = settings(s, 8, seed[i], threads[i], "separate");
      render_stats st;
      lmc_error err;
      if (hslt) assert_int_equal(mcmc_set(&rs, "hslt", "on", &err), LMC_OK);
      assert_int_equal(mcmc_render_run(s, &rs, &f[i], &st, &err), LMC_OK);
    }
    assert_true(films_equal(&f[0], &f[1]));  /* same seed, same threads */
    assert_true(films_equal(&f[0], &f[2]));  /* 1 vs 2 threads */
    assert_false(films_equal(&f[0], &f[3])); /* another seed differs */
    checks += 3;
    for (int i = 0; i < 4; i++) film_free(&f[i]);
  }
  assert_int_equal(checks, 6);
  scene_destroy(s);
}

/* A diffuse plane facing the camera under a directional light alone: every
 * pixel is rho / pi E cos theta = 0.5 / pi * 0.8, and mlt (every path
 * through its light walk: no walk hits the light) renders it, with no
 * warning, under --strict too. RUNS seeds, the mean within 8 standard
 * errors. */
static void test_directional(void **state) {
  (void)state;
  const char *path = LMC_TEST_TMP "/lmc_test_mlt_sun.xml";
  FILE *fp = fopen(path, "w");
  assert_non_null(fp);
  fprintf(fp, "<scene version=\"0.6.0\">\n"
              "<integrator type=\"mlt\"><integer name=\"maxDepth\" value=\"2\"/></integrator>\n"
              "<sensor type=\"perspective\"><float name=\"fov\" value=\"30\"/>"
              "<film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/>"
              "<integer name=\"height\" value=\"12\"/><rfilter type=\"box\"/></film></sensor>\n"
              "<shape type=\"rectangle\"><transform name=\"toWorld\"><rotate y=\"1\" angle=\"180\"/>"
              "<translate z=\"2\"/></transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
              "value=\"0.5\"/></bsdf></shape>\n"
              "<emitter type=\"directional\"><vector name=\"direction\" x=\"0.6\" y=\"0\" "
              "z=\"0.8\"/><rgb name=\"irradiance\" value=\"1\"/></emitter>\n"
              "</scene>\n");
  fclose(fp);
  scene *s = NULL;
  lmc_error err;
  lmc_error_clear(&err);
  int before = lmc_warning_count();
  assert_int_equal(scene_load_xml(path, NULL, 0, &s, &err), LMC_OK);
  const double exact = 0.5 / 3.14159265358979323846 * 0.8;
  double sum = 0.0, sum2 = 0.0;
  for (int r = 0; r < RUNS; r++) {
    render_settings rs = settings(s, 8, 11 + r, 2, "mcmc");
    rs.strict = 1;
    film f;
    render_stats st;
    lmc_error_clear(&err);
    assert_int_equal(mcmc_render_run(s, &rs, &f, &st, &err), LMC_OK);
    double m = image_mean(&f);
    sum += m, sum2 += m * m;
    film_free(&f);
  }
  assert_int_equal(lmc_warning_count() - before, 0);
  double mean = sum / RUNS, se = sqrt(fmax(0.0, (sum2 - RUNS * mean * mean) / (RUNS - 1)) / RUNS);
  fprintf(stderr, "  directional light: mean %.5f (exact %.5f), SE %.2g\n", mean, exact, se);
  assert_true(se > 0.0);
  assert_near(mean, exact, 8.0 * se);
  scene_destroy(s);
}

/* A scene's <integrator type="mlt"> (Mitsuba's path-space MLT) selects
 * mlt; its mutation flags (Mitsuba's names, the manifold perturbation's
 * among them) become mlt's, without a warning. */
static void test_scene_integrator(void **state) {
  (void)state;
  const char *path = LMC_TEST_TMP "/lmc_test_mlt.xml";
  static const char *const flags[4][2] = {{"bidirectionalMutation", "bidir-mutation"},
                                          {"lensPerturbation", "lens-perturbation"},
                                          {"multiChainPerturbation", "multichain-perturbation"},
                                          {"causticPerturbation", "caustic-perturbation"}};
  for (int manifold = 0; manifold < 2; manifold++) {
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "<scene version=\"0.6.0\">\n<integrator type=\"mlt\">");
    for (int j = 0; j < 4; j++)
      fprintf(f, "<boolean name=\"%s\" value=\"%s\"/>", flags[j][0], j % 2 ? "false" : "true");
    fprintf(f, "<boolean name=\"manifoldPerturbation\" value=\"%s\"/>", manifold ? "true" : "false");
    fprintf(f, "</integrator>\n"
               "<sensor type=\"perspective\"><film type=\"hdrfilm\"/></sensor>\n"
               "<shape type=\"rectangle\"><emitter type=\"area\"><rgb name=\"radiance\" "
               "value=\"1\"/></emitter></shape>\n"
               "</scene>\n");
    fclose(f);
    scene *s = NULL;
    lmc_error err;
    lmc_error_clear(&err);
    int before = lmc_warning_count();
    assert_int_equal(scene_load_xml(path, NULL, 0, &s, &err), LMC_OK);
    assert_string_equal(s->settings.integrator, "mlt");
    render_settings rs;
    assert_int_equal(mcmc_scene_settings(s, &rs, &err), LMC_OK);
    assert_int_equal(lmc_warning_count() - before, 0);
    for (int j = 0; j < 4; j++) {
      const char *v = lmc_opt_value(&rs, flags[j][1]);
      assert_non_null(v);
      assert_string_equal(v, j % 2 ? "off" : "on");
    }
    const char *mv = lmc_opt_value(&rs, "manifold-perturbation");
    assert_non_null(mv);
    assert_string_equal(mv, manifold ? "on" : "off");
    scene_destroy(s);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_emitting_box),
      cmocka_unit_test(test_determinism),
      cmocka_unit_test(test_directional),
      cmocka_unit_test(test_scene_integrator),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
