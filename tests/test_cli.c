/*
 * test_cli.c: the `lmc` command line as a user runs it.
 *
 * Runs the built binary (LMC_BINARY) on the small analytic scene and checks
 * exit statuses, messages, flag syntax (--flag value and --flag=value),
 * determinism for a fixed seed and thread count, --resolution, `compare`
 * against metrics computed here, that SIGINT still leaves a valid image,
 * and that black scenes are said to be black (exit 2 under --strict).
 */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "test_util.h"
#include "run_lmc.h"
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "render/image.h"
#include "render/vec3.h"

#define SCENE "data/analytic/diffuse_sphere.xml"
#define TMP LMC_TEST_TMP "/lmc_test_cli"

/* Runs `lmc ARGS` through the shell; stdout and stderr go to files that
 * out/err_text read back. Returns the exit status. */
static char out_text[65536], err_text[65536];

static int run_lmc(const char *args) {
  return run_lmc_in(TMP, args, out_text, sizeof out_text, err_text, sizeof err_text);
}

static int setup(void **state) {
  (void)state;
  mkdir(TMP, 0755);
  return 0;
}

static void test_help_lists_every_flag(void **state) {
  (void)state;
  assert_int_equal(run_lmc("--help"), 0);
  assert_non_null(strstr(out_text, "render"));
  assert_non_null(strstr(out_text, "compare"));
  assert_int_equal(run_lmc("render --help"), 0);
  static const char *flags[] = {"-o", "--integrator", "--spp", "--time", "--threads", "--seed",
                                "--maxdepth", "--resolution", "-D", "--sampler"};
  int found = 0;
  for (size_t i = 0; i < sizeof flags / sizeof flags[0]; i++) {
    if (!strstr(out_text, flags[i])) fail_msg("render --help does not mention %s", flags[i]);
    found++;
  }
  assert_int_equal(found, 10);
  /* Every other command answers --help with its usage on stdout, exit 0. */
  static const char *cmds[] = {"compare", "merge", "convert"};
  int helped = 0;
  for (size_t i = 0; i < sizeof cmds / sizeof cmds[0]; i++) {
    char args[64];
    snprintf(args, sizeof args, "%s --help", cmds[i]);
    assert_int_equal(run_lmc(args), 0);
    char usage[64];
    snprintf(usage, sizeof usage, "usage: lmc %s", cmds[i]);
    if (!strstr(out_text, usage)) fail_msg("lmc %s --help printed: %s", cmds[i], out_text);
    helped++;
  }
  assert_int_equal(helped, 3);
}

static void test_bad_flags_exit_2_naming_the_flag(void **state) {
  (void)state;
  static const struct {
    const char *args, *needle;
  } cases[] = {
      {"render " SCENE " --bogus", "--bogus"},
      {"render " SCENE " --spp abc", "--spp"},
      {"render " SCENE " --spp=-3", "--spp"},
      {"render " SCENE " --integrator=foo", "foo"},
      {"render " SCENE " --resolution 10by10", "--resolution"},
      {"render " SCENE " --threads", "--threads"},
      {"render " SCENE " --sampler halton", "--sampler"},
      {"render " SCENE " -D novalue", "-D"},
      {"render no/such/scene.xml", "no/such/scene.xml"},
      {"frobnicate", "frobnicate"},
      {"render", "no scene"},
      {"render " SCENE " --states tree", "--states"},
      {"render " SCENE " --lmc-states=none", "--lmc-states"},
      {"render " SCENE " --small-step cauchy", "--small-step"},
      {"render " SCENE " --chains 0", "--chains"},
      {"render " SCENE " --roughness-threshold=-1", "--roughness-threshold"},
      {"render " SCENE " --largestep-scale x2", "--largestep-scale"},
      {"render " SCENE " --h2mc-sigma 0", "--h2mc-sigma"},
      {"render " SCENE " --spectra cubic", "--spectra"},
  };
  int n = 0;
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    int rc = run_lmc(cases[i].args);
    if (rc != 2) fail_msg("lmc %s: exit %d, expected 2 (stderr: %s)", cases[i].args, rc, err_text);
    if (!strstr(err_text, cases[i].needle))
      fail_msg("lmc %s: stderr does not name '%s': %s", cases[i].args, cases[i].needle, err_text);
    n++;
  }
  assert_int_equal(n, 19);
}

/* Occurrences of needle in hay. */
static int count_of(const char *hay, const char *needle) {
  int n = 0;
  for (const char *p = hay; (p = strstr(p, needle)) != NULL; p += strlen(needle)) n++;
  return n;
}

/* An image that cannot be right says so, in every integrator: a scene
 * without an emitter and one whose only emitter lmc lacks each get the
 * warning once, naming the scene, and render (exit 0, an image written);
 * under --strict they exit 2 before rendering (no image). A lit scene
 * whose camera sees nothing lit renders black with a warning (MCMC: b = 0
 * after the bootstrap) and exits 2 under --strict; a scene without
 * warnings renders under --strict as without it. */
static void test_black_scenes_warn(void **state) {
  (void)state;
  static const char *const integrators[] = {"pt", "bdpt", "pssmlt", "mmlt", "lmc", "h2mc"};
  static const struct {
    const char *scene, *needle;
  } cases[] = {
      {"data/warn/no_emitter.xml", "the scene has no emitter: the image will be black"},
      {"data/warn/unsupported_emitter.xml", "no emitter left: the scene's 1 emitter was ignored"},
  };
  int checks = 0;
  for (size_t i = 0; i < sizeof integrators / sizeof integrators[0]; i++) {
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
      char args[1024];
      remove(TMP "/black.exr");
      snprintf(args, sizeof args, "render %s --integrator %s --spp 2 -q -o " TMP "/black.exr",
               cases[k].scene, integrators[i]);
      int rc = run_lmc(args);
      struct stat sb;
      if (rc != 0 || count_of(err_text, cases[k].needle) != 1 ||
          !strstr(err_text, cases[k].scene) || stat(TMP "/black.exr", &sb) != 0)
        fail_msg("lmc %s: exit %d, expected 0, the warning once and an image; stderr: %s", args,
                 rc, err_text);
      remove(TMP "/black.exr");
      strncat(args, " --strict", sizeof args - strlen(args) - 1);
      rc = run_lmc(args);
      if (rc != 2 || count_of(err_text, cases[k].needle) != 1 || !strstr(err_text, "--strict") ||
          stat(TMP "/black.exr", &sb) == 0)
        fail_msg("lmc %s: exit %d, expected 2, the warning once and no image; stderr: %s", args,
                 rc, err_text);
      checks += 2;
    }
    /* Lit, but the camera sees nothing lit. */
    char args[1024];
    snprintf(args, sizeof args,
             "render data/warn/dark_view.xml --integrator %s --spp 2 -q -o " TMP "/black.exr",
             integrators[i]);
    int rc = run_lmc(args);
    const char *said = i < 2 ? "the image is black" : "b = 0";
    if (rc != 0 || !strstr(err_text, said))
      fail_msg("lmc %s: exit %d, expected 0 and '%s'; stderr: %s", args, rc, said, err_text);
    strncat(args, " --strict", sizeof args - strlen(args) - 1);
    rc = run_lmc(args);
    if (rc != 2 || !strstr(err_text, "--strict"))
      fail_msg("lmc %s: exit %d, expected 2; stderr: %s", args, rc, err_text);
    checks += 2;
  }
  /* No warning: --strict changes nothing. */
  assert_int_equal(run_lmc("render " SCENE " --spp 2 -q --strict -o " TMP "/black.exr"), 0);
  assert_int_equal(count_of(err_text, "warning"), 0);
  checks++;
  assert_int_equal(checks, 6 * 6 + 1);
}

/* Media: pt, bdpt and pssmlt (without the jumps) render them without a
 * word; every other integrator or setting warns once (naming the medium's
 * file and line) and renders, or exits 2 without an image under --strict. */
static void test_media_warn(void **state) {
  (void)state;
  static const char *const integrators[] = {
      "pt", "bdpt", "pssmlt --direct mcmc", "direct", "pssmlt --direct mcmc --technique-jump 0.2",
      "lmc", "mlt"};
  static const char *const needle = "data/media/slab.xml:27: integrator";
  int checks = 0;
  for (size_t i = 0; i < sizeof integrators / sizeof integrators[0]; i++) {
    char args[1024];
    struct stat sb;
    remove(TMP "/media.exr");
    snprintf(args, sizeof args,
             "render data/media/slab.xml --integrator %s --spp 2 -q -o " TMP "/media.exr",
             integrators[i]);
    int rc = run_lmc(args), warned = i > 2;
    if (rc != 0 || count_of(err_text, needle) != warned || stat(TMP "/media.exr", &sb) != 0)
      fail_msg("lmc %s: exit %d, expected 0, %d warning(s) and an image; stderr: %s", args, rc,
               warned, err_text);
    remove(TMP "/media.exr");
    strncat(args, " --strict", sizeof args - strlen(args) - 1);
    rc = run_lmc(args);
    if (rc != (warned ? 2 : 0) || (stat(TMP "/media.exr", &sb) == 0) == warned)
      fail_msg("lmc %s: exit %d, expected %d; stderr: %s", args, rc, warned ? 2 : 0, err_text);
    checks += 2;
  }
  assert_int_equal(checks, 14);
}

/* Reads an EXR written by the CLI; fails the test when it cannot. */
static lmc_image read_exr(const char *path) {
  lmc_image img = {0};
  lmc_error err;
  lmc_error_clear(&err);
  if (image_read_exr(path, &img, &err)) fail_msg("cannot read %s: %s", path, err.msg);
  return img;
}

/* A malformed scene: exit 2, and the message names the file and the line. */
static void test_malformed_scene_names_file_and_line(void **state) {
  (void)state;
  FILE *f = fopen(TMP "/bad.xml", "w");
  assert_non_null(f);
  fputs("<?xml version=\"1.0\"?>\n<scene version=\"0.6.0\">\n  <shape type=\"sphere\">\n"
        "    <float name=\"radius\" value=\"1.2.3\"/>\n  </shape>\n</scene>\n",
        f);
  fclose(f);
  assert_int_equal(run_lmc("render " TMP "/bad.xml -q"), 2);
  if (!strstr(err_text, "bad.xml:4")) fail_msg("no file:line in: %s", err_text);
  f = fopen(TMP "/bad.xml", "w");
  assert_non_null(f);
  fputs("<scene version=\"0.6.0\">\n  <shape type=\"sphere\">\n</scene>\n", f);
  fclose(f);
  assert_int_equal(run_lmc("render " TMP "/bad.xml -q"), 2);
  if (!strstr(err_text, "bad.xml:3")) fail_msg("no file:line in: %s", err_text);
}

static void test_flag_syntax_and_determinism(void **state) {
  (void)state;
  assert_int_equal(run_lmc("render " SCENE " --spp 4 --threads 2 --seed 3 -q -o " TMP "/a.exr"), 0);
  assert_non_null(strstr(out_text, TMP "/a.exr"));
  assert_non_null(strstr(out_text, TMP "/a.png"));
  assert_int_equal(run_lmc("render " SCENE " --spp=4 --threads=2 --seed=3 --quiet --output=" TMP "/b.exr"), 0);
  lmc_image a = read_exr(TMP "/a.exr"), b = read_exr(TMP "/b.exr");
  assert_int_equal(a.width, 40);
  assert_int_equal(a.height, 30);
  assert_int_equal(a.width * a.height * a.channels, b.width * b.height * b.channels);
  assert_memory_equal(a.data, b.data, sizeof(float) * (size_t)(a.width * a.height * a.channels));
  /* A different seed gives a different image (the test is not vacuous). */
  assert_int_equal(run_lmc("render " SCENE " --spp 4 --threads 2 --seed 4 -q -o " TMP "/c.exr"), 0);
  lmc_image c = read_exr(TMP "/c.exr");
  assert_true(memcmp(a.data, c.data, sizeof(float) * (size_t)(a.width * a.height * 3)) != 0);
  image_free(&a);
  image_free(&b);
  image_free(&c);
  /* bdpt too: its light-tracing splats are merged in thread order. */
  assert_int_equal(run_lmc("render " SCENE " --integrator bdpt --spp 2 --threads 2 -q -o " TMP "/d.exr"), 0);
  assert_int_equal(run_lmc("render " SCENE " --integrator=bdpt --spp=2 --threads=2 -q -o " TMP "/e.exr"), 0);
  lmc_image d = read_exr(TMP "/d.exr"), e = read_exr(TMP "/e.exr");
  assert_memory_equal(d.data, e.data, sizeof(float) * (size_t)(d.width * d.height * 3));
  image_free(&d);
  image_free(&e);
}

static void test_resolution_override(void **state) {
  (void)state;
  assert_int_equal(run_lmc("render " SCENE " --spp 1 --resolution=20x10 -q -o " TMP "/r.exr"), 0);
  lmc_image r = read_exr(TMP "/r.exr");
  assert_int_equal(r.width, 20);
  assert_int_equal(r.height, 10);
  image_free(&r);
  /* -o OUT.png: the EXR beside it as OUT.exr, the PNG a PNG. */
  remove(TMP "/p.exr");
  assert_int_equal(run_lmc("render " SCENE " --spp 1 --resolution=20x10 -q -o " TMP "/p.png"), 0);
  lmc_image p = read_exr(TMP "/p.exr");
  assert_int_equal(p.width, 20);
  image_free(&p);
  FILE *f = fopen(TMP "/p.png", "rb");
  assert_non_null(f);
  unsigned char magic[4] = {0};
  assert_int_equal(fread(magic, 1, 4, f), 4);
  fclose(f);
  assert_memory_equal(magic, "\x89PNG", 4);
}

static double metric(const char *name) {
  char key[64];
  snprintf(key, sizeof key, "%s: ", name);
  const char *p = strstr(out_text, key);
  if (!p) fail_msg("compare printed no '%s' line: %s", name, out_text);
  return strtod(p + strlen(key), NULL);
}

static void test_compare_metrics(void **state) {
  (void)state;
  /* Two 2x1 images with known differences. */
  lmc_image I, R, S;
  lmc_error err;
  assert_int_equal(image_init(&I, 2, 1, 3, &err), LMC_OK);
  assert_int_equal(image_init(&R, 2, 1, 3, &err), LMC_OK);
  assert_int_equal(image_init(&S, 3, 1, 3, &err), LMC_OK);
  const float iv[6] = {1.0f, 2.0f, 0.5f, 0.0f, 0.25f, 1.0f};
  const float rv[6] = {1.0f, 1.0f, 1.0f, 0.1f, 0.25f, 2.0f};
  memcpy(I.data, iv, sizeof iv);
  memcpy(R.data, rv, sizeof rv);
  assert_int_equal(image_write_exr(TMP "/I.exr", &I, &err), LMC_OK);
  assert_int_equal(image_write_exr(TMP "/R.exr", &R, &err), LMC_OK);
  assert_int_equal(image_write_exr(TMP "/S.exr", &S, &err), LMC_OK);
  double mse = 0.0, rel = 0.0, li = 0.0, lr = 0.0;
  for (int k = 0; k < 6; k++) {
    double d = (double)iv[k] - rv[k];
    mse += d * d / 6.0;
    rel += d * d / ((double)rv[k] * rv[k] + 0.01) / 6.0;
  }
  for (int p = 0; p < 2; p++) {
    li += rgb_luminance(rgb_make(iv[3 * p], iv[3 * p + 1], iv[3 * p + 2]));
    lr += rgb_luminance(rgb_make(rv[3 * p], rv[3 * p + 1], rv[3 * p + 2]));
  }
  assert_int_equal(run_lmc("compare " TMP "/I.exr " TMP "/R.exr --heatmap=" TMP "/h.png"), 0);
  assert_near(metric("mse"), mse, 1e-7 * mse);
  assert_near(metric("relmse"), rel, 1e-7 * rel);
  assert_near(metric("relmse_trimmed"), rel, 1e-7 * rel); /* 2 pixels: none dropped */
  assert_near(metric("mean_ratio"), li / lr, 1e-7);
  lmc_image h = {0};
  assert_int_equal(image_read(TMP "/h.png", 0, &h, &err), LMC_OK);
  assert_int_equal(h.width, 2);
  image_free(&h);
  /* Identical images: zero error. */
  assert_int_equal(run_lmc("compare " TMP "/R.exr " TMP "/R.exr"), 0);
  assert_near(metric("mse"), 0.0, 0.0);
  assert_near(metric("mean_ratio"), 1.0, 1e-12);
  /* The trimmed relative MSE drops the largest 0.1% of pixel errors: on
   * 2000 pixels, the 2 outliers. */
  {
    lmc_image A, B;
    assert_int_equal(image_init(&A, 2000, 1, 3, &err), LMC_OK);
    assert_int_equal(image_init(&B, 2000, 1, 3, &err), LMC_OK);
    double full = 0.0, kept = 0.0;
    for (int p = 0; p < 2000; p++) {
      double r = 0.5 + 0.25 * (p % 7), v = p == 17 || p == 1500 ? 100.0 : r * (1.0 + 0.01 * (p % 5));
      double e = 0.0;
      for (int c = 0; c < 3; c++) {
        B.data[3 * p + c] = (float)r;
        A.data[3 * p + c] = (float)v;
        double d = (double)(float)v - (double)(float)r;
        e += d * d / ((double)(float)r * (float)r + 0.01) / 3.0;
      }
      full += e / 2000.0;
      if (p != 17 && p != 1500) kept += e / 1998.0;
    }
    assert_int_equal(image_write_exr(TMP "/A.exr", &A, &err), LMC_OK);
    assert_int_equal(image_write_exr(TMP "/B.exr", &B, &err), LMC_OK);
    assert_int_equal(run_lmc("compare " TMP "/A.exr " TMP "/B.exr"), 0);
    assert_near(metric("relmse"), full, 1e-6 * full);
    assert_near(metric("relmse_trimmed"), kept, 1e-6 * kept);
    assert_true(kept < 1e-3 * full);
    image_free(&A);
    image_free(&B);
  }
  /* Different sizes: exit 2. */
  assert_int_equal(run_lmc("compare " TMP "/I.exr " TMP "/S.exr"), 2);
  assert_non_null(strstr(err_text, "3x1"));
  image_free(&I);
  image_free(&R);
  image_free(&S);
}

/* The LMC reference implementation's torus scenes render unmodified (with
 * their own settings but a small film), giving a finite, lit image. */
static void test_torus_renders_unmodified(void **state) {
  (void)state;
  const char *names[2] = {"lmc.xml", "h2mc.xml"};
  char path[1024], args[2048];
  int rendered = 0;
  for (int k = 0; k < 2; k++) {
    snprintf(path, sizeof path, "%s/scenes/torus/%s", LMC_SHARED_DIR, names[k]);
    if (access(path, R_OK) != 0) skip();
    snprintf(args, sizeof args, "render '%s' --spp 2 --resolution 64x48 -q -o " TMP "/torus.exr", path);
    int rc = run_lmc(args);
    if (rc != 0) fail_msg("lmc %s: exit %d: %s", args, rc, err_text);
    lmc_image img = read_exr(TMP "/torus.exr");
    assert_int_equal(img.width, 64);
    double sum = 0.0;
    for (int i = 0; i < 64 * 48 * 3; i++) {
      assert_true(isfinite(img.data[i]));
      sum += img.data[i];
    }
    assert_true(sum > 0.0);
    image_free(&img);
    rendered++;
  }
  assert_int_equal(rendered, 2);
}

/* merge averages, with weights when given; convert writes a PNG of the same
 * size. */
static void test_merge_and_convert(void **state) {
  (void)state;
  lmc_image A, B;
  lmc_error err;
  assert_int_equal(image_init(&A, 3, 2, 3, &err), LMC_OK);
  assert_int_equal(image_init(&B, 3, 2, 3, &err), LMC_OK);
  for (int i = 0; i < 18; i++) {
    A.data[i] = (float)i;
    B.data[i] = (float)(3 * i + 1);
  }
  assert_int_equal(image_write_exr(TMP "/mA.exr", &A, &err), LMC_OK);
  assert_int_equal(image_write_exr(TMP "/mB.exr", &B, &err), LMC_OK);
  assert_int_equal(run_lmc("merge " TMP "/mA.exr " TMP "/mB.exr -o " TMP "/mM.exr"), 0);
  lmc_image M = read_exr(TMP "/mM.exr");
  int checked = 0;
  for (int i = 0; i < 18; i++, checked++) assert_near(M.data[i], 0.5 * (i + 3 * i + 1), 1e-5);
  assert_int_equal(checked, 18);
  /* Weighted: A with weight 3, B with 1 (the flag as --weight=W too). */
  assert_int_equal(
      run_lmc("merge --weight 3 " TMP "/mA.exr --weight=1 " TMP "/mB.exr -o " TMP "/mW.exr"), 0);
  lmc_image W = read_exr(TMP "/mW.exr");
  for (int i = 0; i < 18; i++, checked++) assert_near(W.data[i], 0.75 * i + 0.25 * (3 * i + 1), 1e-5);
  assert_int_equal(checked, 36);
  image_free(&W);
  /* A weight must be positive and followed by an image. */
  assert_int_equal(run_lmc("merge --weight 0 " TMP "/mA.exr -o " TMP "/mX.exr"), 2);
  assert_non_null(strstr(err_text, "--weight"));
  assert_int_equal(run_lmc("merge " TMP "/mA.exr --weight 2 -o " TMP "/mX.exr"), 2);
  assert_non_null(strstr(err_text, "--weight"));
  assert_int_equal(run_lmc("convert " TMP "/mM.exr " TMP "/mM.png --exposure 0.01"), 0);
  lmc_image P = {0};
  assert_int_equal(image_read(TMP "/mM.png", 0, &P, &err), LMC_OK);
  assert_int_equal(P.width, 3);
  assert_int_equal(P.height, 2);
  /* A PNG converted again at exposure 0 gives the same bytes back (its
   * sRGB is decoded first, not encoded twice). */
  assert_int_equal(run_lmc("convert " TMP "/mM.png " TMP "/mM2.png"), 0);
  lmc_image P2 = {0};
  assert_int_equal(image_read(TMP "/mM2.png", 0, &P2, &err), LMC_OK);
  assert_int_equal(P2.width * P2.height * P2.channels, 18);
  int same = 0;
  for (int i = 0; i < 18; i++) same += fabsf(P2.data[i] - P.data[i]) <= 0.5f / 255.0f;
  assert_int_equal(same, 18);
  image_free(&P2);
  /* Different sizes cannot be merged. */
  lmc_image C;
  assert_int_equal(image_init(&C, 2, 2, 3, &err), LMC_OK);
  assert_int_equal(image_write_exr(TMP "/mC.exr", &C, &err), LMC_OK);
  assert_int_equal(run_lmc("merge " TMP "/mA.exr " TMP "/mC.exr -o " TMP "/mX.exr"), 2);
  image_free(&A);
  image_free(&B);
  image_free(&C);
  image_free(&M);
  image_free(&P);
}

/* The sRGB byte of a linear value times 2^stops, computed here from the
 * sRGB standard's curve (IEC 61966-2-1), independently of image.c. */
static int expected_byte(float v, double stops) {
  double x = (double)v * exp2(stops);
  if (!(x > 0.0)) x = 0.0;
  if (x > 1.0) x = 1.0;
  double s = x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
  return (int)floor(255.0 * s + 0.5);
}

/* Bytes of a PNG (read without decoding) against expected_byte of img's
 * values at `stops`: returns the number of channel values checked. */
static int check_png_bytes(const char *png, const lmc_image *img, double stops) {
  lmc_image P = {0};
  lmc_error err;
  lmc_error_clear(&err);
  if (image_read(png, 0, &P, &err)) fail_msg("cannot read %s: %s", png, err.msg);
  assert_int_equal(P.width, img->width);
  assert_int_equal(P.height, img->height);
  int n = 0;
  for (int i = 0; i < img->width * img->height * 3; i++, n++) {
    int got = (int)floor(P.data[i] * 255.0f + 0.5f), want = expected_byte(img->data[i], stops);
    if (got != want)
      fail_msg("%s: value %d (linear %g, %g stops): byte %d, expected %d", png, i, img->data[i],
               stops, got, want);
  }
  image_free(&P);
  return n;
}

/* --exposure STOPS: radiance times 2^STOPS, clamped, with the sRGB curve
 * (lmc convert and lmc render); auto: the 99th percentile of luminance
 * maps to white; bad values exit 2 naming the flag. */
static void test_exposure(void **state) {
  (void)state;
  /* 10 x 10 grey pixels 0.01, 0.02, ..., 1.00 times a ramp per channel. */
  lmc_image G;
  lmc_error err;
  assert_int_equal(image_init(&G, 10, 10, 3, &err), LMC_OK);
  for (int i = 0; i < 100; i++)
    for (int c = 0; c < 3; c++) G.data[3 * i + c] = (float)((i + 1) * 0.01);
  G.data[0] = 0.0f;                 /* black */
  G.data[1] = 0.002f;               /* the curve's linear segment */
  G.data[2] = 3.0f;                 /* clamped at every exposure >= -1 */
  G.data[4] = -1.0f;                /* negative: 0 */
  assert_int_equal(image_write_exr(TMP "/x.exr", &G, &err), LMC_OK);
  static const char *stops[] = {"0", "1", "-1", "2.5", "-3.25"};
  int checked = 0;
  for (size_t k = 0; k < sizeof stops / sizeof stops[0]; k++) {
    char args[256];
    snprintf(args, sizeof args, "convert " TMP "/x.exr " TMP "/x.png --exposure %s", stops[k]);
    assert_int_equal(run_lmc(args), 0);
    checked += check_png_bytes(TMP "/x.png", &G, atof(stops[k]));
  }
  /* The default is 0 stops, and --exposure=VALUE is the same flag. */
  assert_int_equal(run_lmc("convert " TMP "/x.exr " TMP "/x.png"), 0);
  checked += check_png_bytes(TMP "/x.png", &G, 0.0);
  assert_int_equal(run_lmc("convert " TMP "/x.exr " TMP "/x.png --exposure=1"), 0);
  checked += check_png_bytes(TMP "/x.png", &G, 1.0);
  assert_int_equal(checked, 7 * 300);

  /* auto: pure grey 0.01 .. 1.00 (pixel i: (i + 1) / 100): the 99th
   * percentile of the 100 luminances (the 99th smallest, 0.99) maps to 1. */
  lmc_image A;
  assert_int_equal(image_init(&A, 10, 10, 3, &err), LMC_OK);
  for (int i = 0; i < 300; i++) A.data[i] = (float)((i / 3 + 1) * 0.01);
  assert_int_equal(image_write_exr(TMP "/auto.exr", &A, &err), LMC_OK);
  assert_int_equal(run_lmc("convert " TMP "/auto.exr " TMP "/auto.png --exposure auto"), 0);
  checked = check_png_bytes(TMP "/auto.png", &A, -log2(0.99f));
  assert_int_equal(checked, 300);

  /* lmc render writes its PNG with the same mapping of its own EXR. */
  assert_int_equal(run_lmc("render " SCENE " --spp 2 -q --exposure -1.5 -o " TMP "/xr.exr"), 0);
  lmc_image R = read_exr(TMP "/xr.exr");
  assert_int_equal(check_png_bytes(TMP "/xr.png", &R, -1.5), 40 * 30 * 3);
  image_free(&R);

  /* Bad values: exit 2, naming the flag. */
  static const char *bad[] = {"convert " TMP "/x.exr " TMP "/y.png --exposure bright",
                              "convert " TMP "/x.exr " TMP "/y.png --exposure 65",
                              "convert " TMP "/x.exr " TMP "/y.png --exposure",
                              "render " SCENE " -q --exposure nan",
                              "render " SCENE " -q --exposure=Auto"};
  int refused = 0;
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
    int rc = run_lmc(bad[k]);
    if (rc != 2) fail_msg("lmc %s: exit %d, expected 2 (stderr: %s)", bad[k], rc, err_text);
    if (!strstr(err_text, "--exposure")) fail_msg("lmc %s: stderr: %s", bad[k], err_text);
    refused++;
  }
  assert_int_equal(refused, 5);
  image_free(&G);
  image_free(&A);
}

/* SIGINT during a long render: exit 130 within seconds, and the image of
 * what was rendered is written and valid. */
static void test_interrupt_writes_image(void **state) {
  (void)state;
  unlink(TMP "/int.exr");
  pid_t pid = fork();
  assert_true(pid >= 0);
  if (pid == 0) {
    freopen("/dev/null", "w", stdout);
    freopen("/dev/null", "w", stderr);
    execl(LMC_BINARY, LMC_BINARY, "render", SCENE, "--spp", "100000000", "-q", "-o", TMP "/int.exr",
          (char *)NULL);
    _exit(127);
  }
  struct timespec ts = {1, 0};
  nanosleep(&ts, NULL);
  kill(pid, SIGINT);
  int status = 0, waited = 0;
  for (int i = 0; i < 100; i++) { /* up to 10 s */
    if (waitpid(pid, &status, WNOHANG) == pid) {
      waited = 1;
      break;
    }
    struct timespec t = {0, 100000000};
    nanosleep(&t, NULL);
  }
  if (!waited) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    fail_msg("lmc did not stop within 10 s of SIGINT");
  }
  assert_true(WIFEXITED(status));
  assert_int_equal(WEXITSTATUS(status), 130);
  lmc_image img = read_exr(TMP "/int.exr");
  double sum = 0.0;
  int finite = 0;
  for (int i = 0; i < img.width * img.height * 3; i++) {
    finite += isfinite(img.data[i]) != 0;
    sum += img.data[i];
  }
  assert_int_equal(finite, img.width * img.height * 3);
  /* The background alone (L = 1, 2, 4) makes the mean clearly positive. */
  assert_true(sum / (img.width * img.height * 3) > 0.5);
  image_free(&img);
}

static void test_time_limit(void **state) {
  (void)state;
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  assert_int_equal(run_lmc("render " SCENE " --time 1 -q -o " TMP "/t.exr"), 0);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  double secs = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
  assert_true(secs < 10.0);
  assert_non_null(strstr(err_text, "time limit"));
  lmc_image img = read_exr(TMP "/t.exr");
  assert_int_equal(img.width, 40);
  image_free(&img);
}

/* --reference: a relmse line at each snapshot and one for the final
 * image, which is lmc compare's relmse of the written EXR (to the 6
 * digits printed); a missing reference or one of another size exits 2
 * naming the flag. */
static void test_render_reference(void **state) {
  (void)state;
  const char *ref = LMC_SOURCE_DIR "/scenes/ring-caustics/reference.exr";
  char args[2048];
  snprintf(args, sizeof args,
           "render '" LMC_SOURCE_DIR "/scenes/ring-caustics/scene.xml' --time 1.3 --snapshot 0.4 "
           "--reference '%s' -q -o " TMP "/ref_run.exr",
           ref);
  if (run_lmc(args) != 0) fail_msg("lmc %s: %s", args, err_text);
  int snapshots = 0, finals = 0;
  double final_rel = -1.0;
  for (const char *p = err_text; (p = strstr(p, "lmc: ")) != NULL; p++) {
    const char *r = strstr(p, ": relmse ");
    const char *eol = strchr(p, '\n');
    if (!r || (eol && r > eol)) continue;
    double v = strtod(r + 9, NULL);
    assert_true(isfinite(v) && v >= 0.0);
    if (!strncmp(p + 5, "final image", 11)) {
      finals++;
      final_rel = v;
    } else {
      snapshots++;
    }
  }
  print_message("--reference: %d snapshot lines, final relmse %g\n", snapshots, final_rel);
  assert_true(snapshots >= 1);
  assert_int_equal(finals, 1);
  snprintf(args, sizeof args, "compare " TMP "/ref_run.exr '%s'", ref);
  assert_int_equal(run_lmc(args), 0);
  double rel = metric("relmse");
  assert_true(fabs(rel - final_rel) <= 1e-5 * rel);

  snprintf(args, sizeof args,
           "render '" LMC_SOURCE_DIR "/scenes/ring-caustics/scene.xml' --spp 1 --reference "
           TMP "/no_such.exr -q -o " TMP "/ref_bad.exr");
  assert_int_equal(run_lmc(args), 2);
  assert_non_null(strstr(err_text, "--reference"));
  assert_non_null(strstr(err_text, "no_such.exr"));
  snprintf(args, sizeof args,
           "render '" LMC_SOURCE_DIR "/scenes/ring-caustics/scene.xml' --spp 1 --resolution 64x48 "
           "--reference '%s' -q -o " TMP "/ref_bad.exr",
           ref);
  assert_int_equal(run_lmc(args), 2);
  assert_non_null(strstr(err_text, "320x240"));
  assert_non_null(strstr(err_text, "64x48"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_help_lists_every_flag),
      cmocka_unit_test(test_bad_flags_exit_2_naming_the_flag),
      cmocka_unit_test(test_black_scenes_warn),
      cmocka_unit_test(test_media_warn),
      cmocka_unit_test(test_malformed_scene_names_file_and_line),
      cmocka_unit_test(test_flag_syntax_and_determinism),
      cmocka_unit_test(test_resolution_override),
      cmocka_unit_test(test_compare_metrics),
      cmocka_unit_test(test_render_reference),
      cmocka_unit_test(test_merge_and_convert),
      cmocka_unit_test(test_exposure),
      cmocka_unit_test(test_torus_renders_unmodified),
      cmocka_unit_test(test_interrupt_writes_image),
      cmocka_unit_test(test_time_limit),
  };
  return cmocka_run_group_tests(tests, setup, NULL);
}
