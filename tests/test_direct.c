/*
 * test_direct.c: the direct illumination integrator (integrator_direct.c,
 * Mitsuba's `direct`), which must give pt --maxdepth 2's image in
 * expectation.
 *
 *  - The box: a closed diffuse box lit by an area light under its ceiling
 *    and a point light, with a rough conductor sphere (glossy: MIS matters)
 *    and a smooth plastic cube (a delta lobe beside a diffuse one). Much of
 *    its light is indirect. direct with the default counts against pt
 *    --maxdepth 2: the image mean and the means of its four quadrants
 *    (luminance, region_stats.h) agree within Z_EQUAL combined standard
 *    errors, each standard error from the spread of RUNS renders of
 *    independent seeds; full pt lies many standard errors above.
 *  - The same with emitterSamples 4 and bsdfSamples 2 set in the scene's
 *    <integrator type="direct">, and with one strategy alone (1, 0 and
 *    0, 1 as flags): each still pt --maxdepth 2's image.
 *  - The emitting box (tests/data/analytic/emitting_box.xml: walls of
 *    albedo 0.5 emitting 0.5 all round): every pixel is exactly 0.5 + 0.25
 *    = 0.75 by direct, and 0.25 with hideEmitters (the light the walls
 *    cast stays).
 *  - <integrator type="direct"> selects direct with its parameters, with
 *    no warning (strictNormals accepted silently), in the library and in
 *    the binary; the binary's --integrator direct and its flags.
 *  - Bad input: a negative emitterSamples, bsdfSamples or shadingSamples,
 *    or both counts 0, is an error naming the file and the line; the
 *    binary exits 2 on it and on --emitter-samples 0 --bsdf-samples 0.
 * Fixed seeds; each test counts its checks and asserts the count.
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
#include <sys/stat.h>
#include <sys/wait.h>

#include "lmc/mcmc.h"
#include "region_stats.h"
#include "render/integrators/integrator.h"
#include "render/io/io.h"
#include "test_util.h"
#include "run_lmc.h"
#include "load_scene.h"

#define TMP LMC_TEST_TMP "/lmc_test_direct"
#define GRID 2
#define NSTAT (GRID * GRID + 1) /* the quadrants, then the whole image */
#define RUNS 16                 /* independent renders per estimate */
#define SPP 16
#define Z_EQUAL 4.5             /* agreement: within this many combined standard errors */
#define Z_APART 20.0            /* full pt: at least this many above */

/* The box of the first test; %s is the integrator block. */
static const char *box_xml =
    "<scene version=\"0.6.0\">\n"
    "%s\n"
    "  <sensor type=\"perspective\">\n"
    "    <float name=\"fov\" value=\"70\"/>\n"
    "    <transform name=\"toWorld\"><lookat origin=\"0, 0, 0.9\" target=\"0, -0.1, -1\" "
    "up=\"0, 1, 0\"/></transform>\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" "
    "value=\"24\"/><rfilter type=\"box\"/></film>\n"
    "  </sensor>\n"
    "  <shape type=\"cube\"><boolean name=\"flipNormals\" value=\"true\"/>\n"
    "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.7, 0.6, 0.5\"/></bsdf>"
    "</shape>\n"
    "  <shape type=\"rectangle\">\n"
    "    <transform name=\"toWorld\"><scale value=\"0.3\"/><rotate x=\"1\" angle=\"90\"/>"
    "<translate x=\"0\" y=\"0.99\" z=\"-0.2\"/></transform>\n"
    "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf>\n"
    "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"6, 6, 5\"/></emitter>\n"
    "  </shape>\n"
    "  <shape type=\"sphere\"><point name=\"center\" x=\"-0.45\" y=\"-0.6\" z=\"-0.4\"/>"
    "<float name=\"radius\" value=\"0.35\"/>\n"
    "    <bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"0.15\"/></bsdf></shape>\n"
    "  <shape type=\"cube\">\n"
    "    <transform name=\"toWorld\"><scale value=\"0.25\"/><rotate y=\"1\" angle=\"30\"/>"
    "<translate x=\"0.45\" y=\"-0.75\" z=\"-0.3\"/></transform>\n"
    "    <bsdf type=\"plastic\"><rgb name=\"diffuseReflectance\" value=\"0.2, 0.4, 0.7\"/>"
    "</bsdf>\n"
    "  </shape>\n"
    "  <emitter type=\"point\"><point name=\"position\" x=\"0.5\" y=\"0.5\" z=\"0.3\"/>"
    "<rgb name=\"intensity\" value=\"0.6, 0.6, 0.6\"/></emitter>\n"
    "</scene>\n";

static char out_text[1 << 14], err_text[1 << 15];

static int run_lmc(const char *args) {
  return run_lmc_in(TMP, args, out_text, sizeof out_text, err_text, sizeof err_text);
}

static void write_text(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
}

/* The box with integrator block `block` at path. */
static void write_box(const char *path, const char *block) {
  static char xml[8192];
  snprintf(xml, sizeof xml, box_xml, block);
  write_text(path, xml);
}

/* Settings for integrator `name` (maxdepth: -1 unbounded) at SPP. */
static render_settings settings(const char *name, int maxdepth) {
  render_settings rs = render_settings_default();
  snprintf(rs.integrator, sizeof rs.integrator, "%s", name);
  rs.maxdepth = maxdepth;
  rs.spp = SPP;
  rs.set |= SET_SPP | SET_MAXDEPTH;
  rs.threads = 2;
  rs.quiet = 1;
  return rs;
}

/* Sets one of direct's flags in rs. */
static void set_flag(render_settings *rs, const char *name, const char *value) {
  lmc_error err;
  lmc_error_clear(&err);
  assert_int_equal(mcmc_set(rs, name, value, &err), LMC_OK);
}

/* The NSTAT statistics' means and standard errors over RUNS renders of
 * seeds seed0, seed0 + 1, ... */
static void estimate(const scene *s, render_settings rs, uint64_t seed0, double *OUT_mean,
                     double *OUT_se) {
  double sum[NSTAT] = {0}, sum2[NSTAT] = {0};
  for (int r = 0; r < RUNS; r++) {
    rs.seed = seed0 + (uint64_t)r;
    region_stats_render(s, &rs, GRID, sum, sum2);
  }
  region_mean_se(NSTAT, RUNS, sum, sum2, OUT_mean, OUT_se);
}

/* Asserts that every statistic of a and b agrees within Z_EQUAL combined
 * standard errors (printing them); the number of comparisons. */
static int assert_agree(const char *what, const double *ma, const double *sa, const double *mb,
                        const double *sb) {
  int checks = 0;
  for (int k = 0; k < NSTAT; k++) {
    double se = sqrt(sa[k] * sa[k] + sb[k] * sb[k]), z = (ma[k] - mb[k]) / se;
    fprintf(stderr, "  %-26s %-8s %.5f +- %.5f vs pt2 %.5f +- %.5f: z %+.2f\n", what,
            k == GRID * GRID ? "image" : (const char *[]){"quad 0", "quad 1", "quad 2", "quad 3"}[k],
            ma[k], sa[k], mb[k], sb[k], z);
    assert_true(se > 0.0);
    assert_le(fabs(z), Z_EQUAL);
    checks++;
  }
  return checks;
}

static int setup(void **state) {
  (void)state;
  mkdir(TMP, 0755);
  return 0;
}

/* (a) direct = pt --maxdepth 2 on the box; full pt lies far above. */
static void test_box_default(void **state) {
  (void)state;
  const char *path = TMP "/box.xml";
  write_box(path, "");
  scene *s = load_scene(path);
  double md[NSTAT], sd[NSTAT], mp[NSTAT], sp[NSTAT], mf[NSTAT], sf[NSTAT];
  estimate(s, settings("direct", -1), 1000, md, sd);
  estimate(s, settings("pt", 2), 2000, mp, sp);
  estimate(s, settings("pt", -1), 3000, mf, sf);
  int checks = assert_agree("direct (1, 1)", md, sd, mp, sp);
  /* Indirect light: full pt far above, in the image and every quadrant. */
  for (int k = 0; k < NSTAT; k++) {
    double z = (mf[k] - md[k]) / sqrt(sd[k] * sd[k] + sf[k] * sf[k]);
    if (k == GRID * GRID)
      fprintf(stderr, "  full pt image %.5f +- %.5f: %.1f%% above direct, z %.1f\n", mf[k], sf[k],
              100.0 * (mf[k] / md[k] - 1.0), z);
    assert_true(z > Z_APART);
    checks++;
  }
  scene_destroy(s);
  assert_int_equal(checks, 2 * NSTAT);
}

/* (b) emitterSamples 4, bsdfSamples 2 from the scene; each strategy alone. */
static void test_box_counts(void **state) {
  (void)state;
  const char *path = TMP "/box_counts.xml";
  write_box(path, "  <integrator type=\"direct\"><integer name=\"emitterSamples\" value=\"4\"/>"
                  "<integer name=\"bsdfSamples\" value=\"2\"/></integrator>");
  scene *s = load_scene(path);
  render_settings rs;
  lmc_error err;
  lmc_error_clear(&err);
  assert_int_equal(mcmc_scene_settings(s, &rs, &err), LMC_OK);
  assert_string_equal(rs.integrator, "direct");
  direct_settings ds;
  assert_int_equal(direct_read_settings(&rs, &ds, &err), LMC_OK);
  assert_int_equal(ds.emitter_samples, 4);
  assert_int_equal(ds.bsdf_samples, 2);
  int checks = 1;
  rs.spp = SPP, rs.set |= SET_SPP, rs.threads = 2, rs.quiet = 1;

  double mp[NSTAT], sp[NSTAT], m[NSTAT], se[NSTAT];
  estimate(s, settings("pt", 2), 4000, mp, sp);
  estimate(s, rs, 5000, m, se);
  checks += assert_agree("direct (4, 2) from XML", m, se, mp, sp);
  /* One strategy alone: light samples only here; BSDF samples only below,
   * where the box has no point light (no BSDF sample meets a point: pt
   * finds it by its light samples alone, as direct with some). */
  render_settings lo = settings("direct", -1);
  set_flag(&lo, "emitter-samples", "2");
  set_flag(&lo, "bsdf-samples", "0");
  estimate(s, lo, 6000, m, se);
  checks += assert_agree("direct (2, 0)", m, se, mp, sp);
  scene_destroy(s);

  /* BSDF samples alone, in the box without its point light. */
  static char xml[8192];
  snprintf(xml, sizeof xml, box_xml, "");
  char *pl = strstr(xml, "  <emitter type=\"point\">");
  assert_non_null(pl);
  strcpy(pl, "</scene>\n");
  write_text(TMP "/box_area.xml", xml);
  s = load_scene(TMP "/box_area.xml");
  render_settings bo = settings("direct", -1);
  set_flag(&bo, "emitter-samples", "0");
  set_flag(&bo, "bsdf-samples", "3");
  estimate(s, settings("pt", 2), 7000, mp, sp);
  estimate(s, bo, 8000, m, se);
  checks += assert_agree("direct (0, 3), area light", m, se, mp, sp);
  scene_destroy(s);
  assert_int_equal(checks, 1 + 3 * NSTAT);
}

/* The emitting box: exactly 0.75 everywhere, 0.25 with the walls hidden. */
static void test_emitting_box(void **state) {
  (void)state;
  scene *s = load_scene("data/analytic/emitting_box.xml");
  int checks = 0;
  for (int hide = 0; hide < 2; hide++) {
    render_settings rs = settings("direct", -1);
    if (hide) set_flag(&rs, "hide-emitters", "on");
    double m[NSTAT], se[NSTAT], want = hide ? 0.25 : 0.75;
    estimate(s, rs, 9000 + 100 * (uint64_t)hide, m, se);
    for (int k = 0; k < NSTAT; k++) {
      if (k == GRID * GRID)
        fprintf(stderr, "  emitting box, hide-emitters %s: %.6f +- %.6f (exact %.2f)\n",
                hide ? "on" : "off", m[k], se[k], want);
      /* (a uniform diffuse hemisphere of light: the estimate's spread may
       * be tiny, never zero with light samples of the box's faces) */
      assert_le(fabs(m[k] - want), Z_EQUAL * se[k] + 1e-9);
      checks++;
    }
  }
  scene_destroy(s);
  assert_int_equal(checks, 2 * NSTAT);
}

/* (c) <integrator type="direct"> selects it, with no warning. */
static void test_scene_selects(void **state) {
  (void)state;
  const char *path = TMP "/box_select.xml";
  write_box(path, "  <integrator type=\"direct\"><boolean name=\"hideEmitters\" value=\"true\"/>"
                  "<boolean name=\"strictNormals\" value=\"true\"/>"
                  "<integer name=\"shadingSamples\" value=\"3\"/>"
                  "<integer name=\"bsdfSamples\" value=\"5\"/></integrator>");
  int checks = 0;
  int w0 = lmc_warning_count();
  scene *s = load_scene(path);
  render_settings rs;
  lmc_error err;
  lmc_error_clear(&err);
  assert_int_equal(mcmc_scene_settings(s, &rs, &err), LMC_OK);
  assert_int_equal(lmc_warning_count(), w0), checks++;
  assert_string_equal(rs.integrator, "direct"), checks++;
  direct_settings ds;
  assert_int_equal(direct_read_settings(&rs, &ds, &err), LMC_OK);
  /* shadingSamples sets the count not given on its own. */
  assert_int_equal(ds.emitter_samples, 3), checks++;
  assert_int_equal(ds.bsdf_samples, 5), checks++;
  assert_int_equal(ds.hide_emitters, 1), checks++;
  scene_destroy(s);

  /* The binary: the scene's integrator, no warning; --integrator direct
   * with its flags on a scene of pt's. */
  char args[1024];
  snprintf(args, sizeof args, "render %s --spp 2 --resolution 8x6 -q -o " TMP "/sel.exr", path);
  int rc = run_lmc(args);
  if (rc != 0) print_error("%s\n", err_text);
  assert_int_equal(rc, 0), checks++;
  assert_non_null(strstr(err_text, "lmc: direct 8x6")), checks++;
  assert_null(strstr(err_text, "not supported")), checks++;
  assert_null(strstr(err_text, "warning")), checks++;
  snprintf(args, sizeof args,
           "render data/analytic/emitting_box.xml --integrator direct --emitter-samples 2 "
           "--bsdf-samples=0 --hide-emitters on --sampler sobol --spp 2 --resolution 8x6 -q "
           "-o " TMP "/flags.exr");
  rc = run_lmc(args);
  if (rc != 0) print_error("%s\n", err_text);
  assert_int_equal(rc, 0), checks++;
  assert_non_null(strstr(err_text, "lmc: direct 8x6")), checks++;
  assert_int_equal(checks, 11);
}

/* Bad counts: errors at their file and line; the binary exits 2. */
static void test_bad_counts(void **state) {
  (void)state;
  static const struct {
    const char *params;
    int line; /* of the offending element: the integrator's is 2, its parameters' 3 */
    const char *needle;
  } cases[] = {
      {"<integer name=\"emitterSamples\" value=\"-1\"/>", 3, "emitterSamples"},
      {"<integer name=\"bsdfSamples\" value=\"-2\"/>", 3, "bsdfSamples"},
      {"<integer name=\"shadingSamples\" value=\"-1\"/>", 3, "shadingSamples"},
      {"<integer name=\"emitterSamples\" value=\"0\"/><integer name=\"bsdfSamples\" value=\"0\"/>",
       2, "both 0"},
      {"<integer name=\"shadingSamples\" value=\"0\"/>", 2, "both 0"},
  };
  const int n = (int)(sizeof cases / sizeof cases[0]);
  int checks = 0;
  lmc_warn_set_quiet(1);
  for (int i = 0; i < n; i++) {
    char block[512], path[256];
    snprintf(block, sizeof block, "  <integrator type=\"direct\">\n    %s\n  </integrator>",
             cases[i].params);
    snprintf(path, sizeof path, TMP "/bad%d.xml", i);
    write_box(path, block);
    /* (the box's first line is <scene>: the block starts on line 2) */
    scene *s = NULL;
    lmc_error err;
    lmc_error_clear(&err);
    assert_int_equal(scene_load_xml(path, NULL, 0, &s, &err), LMC_EPARSE);
    assert_null(s);
    fprintf(stderr, "  %s:%d: %s\n", err.file, err.line, err.msg);
    assert_non_null(strstr(err.file, "bad"));
    assert_int_equal(err.line, cases[i].line);
    assert_non_null(strstr(err.msg, cases[i].needle));
    checks++;
    /* The binary: exit 2 with file:line. */
    char args[1024], where[300];
    snprintf(args, sizeof args, "render %s --spp 1 -q -o " TMP "/bad.exr", path);
    assert_int_equal(run_lmc(args), 2);
    snprintf(where, sizeof where, "bad%d.xml:%d", i, cases[i].line);
    if (!strstr(err_text, where)) fail_msg("no '%s' in: %s", where, err_text);
    checks++;
  }
  lmc_warn_set_quiet(0);
  /* Both counts 0 by flags, and a negative flag. */
  static const char *const flags[] = {"--emitter-samples 0 --bsdf-samples 0",
                                      "--emitter-samples -1", "--bsdf-samples x"};
  for (int i = 0; i < 3; i++) {
    char args[1024];
    snprintf(args, sizeof args,
             "render data/analytic/emitting_box.xml --integrator direct %s --spp 1 "
             "--resolution 4x4 -q -o " TMP "/bad.exr",
             flags[i]);
    assert_int_equal(run_lmc(args), 2);
    assert_non_null(strstr(err_text, i == 2 ? "--bsdf-samples" : "--emitter-samples"));
    checks++;
  }
  assert_int_equal(checks, 2 * n + 3);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_box_default),   cmocka_unit_test(test_box_counts),
      cmocka_unit_test(test_emitting_box),  cmocka_unit_test(test_scene_selects),
      cmocka_unit_test(test_bad_counts),
  };
  return cmocka_run_group_tests(tests, setup, NULL);
}
