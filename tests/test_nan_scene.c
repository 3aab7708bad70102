/*
 * test_nan_scene.c: NaN quarantine through the command line (issue 6).
 *
 * tests/data/nan/scene.xml textures a diffuse quad with an image that holds
 * NaN and infinite texels, and lights the scene with an environment map
 * that has NaN, infinite and negative texels too. Both images are written
 * here at run time (into a private temporary folder) and passed with -D.
 *
 * What must hold, for pt and for bdpt:
 *  - the loader accepts the scene, warning with file and line about the
 *    texture (kept as it is) and the environment map (bad texels set to 0);
 *  - the render succeeds (exit 0), the bad texels do produce non-finite
 *    samples, and the count of dropped samples is printed at the end
 *    ("dropped N non-finite samples", N > 0);
 *  - every pixel of the EXR is finite, and the image is not black.
 */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "render/image.h"
#include "test_util.h"
#include "tmp_dir.h"

#define SCENE "data/nan/scene.xml"

static char tmp_dir[256];
static char err_text[65536];

/* Runs `lmc ARGS` with stderr into a file read back into err_text; returns
 * the exit status (-1 when it did not exit normally). */
static int run_lmc(const char *args) {
  char cmd[4096], err_path[512];
  snprintf(err_path, sizeof err_path, "%s/err.txt", tmp_dir);
  snprintf(cmd, sizeof cmd, "'%s' %s > /dev/null 2> '%s'", LMC_BINARY, args, err_path);
  int rc = system(cmd);
  err_text[0] = '\0';
  FILE *f = fopen(err_path, "rb");
  if (f) {
    size_t n = fread(err_text, 1, sizeof err_text - 1, f);
    err_text[n] = '\0';
    fclose(f);
  }
  if (rc == -1 || !WIFEXITED(rc)) return -1;
  return WEXITSTATUS(rc);
}

/* Writes an 8x8 RGB EXR: a grey ramp with n_texels texels replaced by the
 * n_bad values of `bad` in turn. */
static void write_image(const char *path, const float *bad, int n_bad, int n_texels) {
  lmc_image img;
  lmc_error err;
  assert_int_equal(image_init(&img, 8, 8, 3, &err), LMC_OK);
  for (int i = 0; i < 8 * 8 * 3; i++) img.data[i] = 0.2f + 0.6f * (float)(i % 8) / 8.0f;
  /* Bad texels on a diagonal, so they cover many pixels of the quad. */
  for (int k = 0; k < n_texels; k++) {
    int px = (k * 9) % 64;
    for (int c = 0; c < 3; c++) img.data[3 * px + c] = bad[k % n_bad];
  }
  assert_int_equal(image_write_exr(path, &img, &err), LMC_OK);
  image_free(&img);
}

static void render_and_check(const char *integrator) {
  char args[2048], out[512], msg[256];
  snprintf(out, sizeof out, "%s/%s.exr", tmp_dir, integrator);
  snprintf(args, sizeof args,
           "render " SCENE " --integrator %s --spp 8 --threads 2 -q -o '%s' -D texfile=%s/tex.exr "
           "-D envfile=%s/env.exr",
           integrator, out, tmp_dir, tmp_dir);
  int rc = run_lmc(args);
  if (rc != 0) fail_msg("lmc %s: exit %d: %s", args, rc, err_text);

  /* The loader's warnings name the file and the line of the filename. */
  if (!strstr(err_text, "scene.xml:24:") || !strstr(err_text, "NaN or infinite values"))
    fail_msg("no texture warning with file and line in: %s", err_text);
  if (!strstr(err_text, "scene.xml:39:") || !strstr(err_text, "set to 0"))
    fail_msg("no environment map warning with file and line in: %s", err_text);

  /* The count of dropped samples is printed, and it is not zero. */
  const char *d = strstr(err_text, "dropped ");
  long long dropped = -1;
  if (!d || sscanf(d, "dropped %lld non-finite samples", &dropped) != 1)
    fail_msg("no dropped-sample count in: %s", err_text);
  snprintf(msg, sizeof msg, "%s dropped %lld", integrator, dropped);
  print_message("%s\n", msg);
  assert_true(dropped > 0);

  /* No NaN or Inf reached the film. */
  lmc_image img = {0};
  lmc_error err;
  if (image_read_exr(out, &img, &err) != LMC_OK) fail_msg("cannot read %s: %s", out, err.msg);
  int64_t n = (int64_t)img.width * img.height * img.channels, bad = 0;
  double sum = 0.0;
  for (int64_t i = 0; i < n; i++) {
    if (!isfinite(img.data[i])) bad++;
    else sum += img.data[i];
  }
  assert_int_equal(img.width * img.height, 24 * 24);
  assert_int_equal(bad, 0);
  assert_true(sum > 0.0);
  image_free(&img);
}

static void test_pt_drops_and_counts(void **state) {
  (void)state;
  render_and_check("pt");
}

static void test_bdpt_drops_and_counts(void **state) {
  (void)state;
  render_and_check("bdpt");
}

static int setup(void **state) {
  (void)state;
  if (tmp_dir_make(tmp_dir, sizeof tmp_dir, "lmc-nan")) return -1;
  char path[512];
  const float tex_bad[] = {NAN, INFINITY, -INFINITY};
  snprintf(path, sizeof path, "%s/tex.exr", tmp_dir);
  write_image(path, tex_bad, 3, 12);
  const float env_bad[] = {NAN, INFINITY, -1.0f};
  snprintf(path, sizeof path, "%s/env.exr", tmp_dir);
  write_image(path, env_bad, 3, 6);
  return 0;
}

static int teardown(void **state) {
  (void)state;
  return tmp_dir_remove(tmp_dir);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_pt_drops_and_counts),
      cmocka_unit_test(test_bdpt_drops_and_counts),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
