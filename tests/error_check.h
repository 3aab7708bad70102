/*
 * error_check.h: renders of the Cornell box with `lmc render --error on`
 * and the checks of their per-pixel standard error against the spread of
 * renders of other seeds; shared by test_error.c (pt, bdpt) and
 * test_error_mcmc.c (pssmlt, mmlt). Define TMP (a scratch folder) and
 * include after <cmocka.h>.
 *
 * K renders of the Cornell box at 80x60 with seeds 1 .. K, each of spp
 * passes (or mutations per pixel), are independent estimates of the same
 * image; so
 *  - agreement: for every pixel value, the spread of the K renders (the
 *    sample variance, K - 1 degrees of freedom) and the mean of the K
 *    estimated variances (error^2) are two unbiased estimates of the same
 *    variance. Their difference summed over the values is tested with the
 *    standard error of that sum from the pixels' own spread (pixels taken
 *    as independent: each has its own random streams; bdpt's splats and
 *    the chains tie them a little), |z| <= 4;
 *  - coverage: each render against the mean of the other K - 1 (whose own
 *    variance is 1 / (K - 1) of one render's, so the bound is widened by
 *    sqrt(1 + 1 / (K - 1))): the share of values within one estimated
 *    standard error, and within two, bounded by the caller or printed;
 *  - `lmc compare` prints the same coverage for one render against an EXR
 *    of the others' mean, computed here independently;
 *  - values of zero spread (the black background around the box, 28% of
 *    the image) are left out and counted, and must not differ between
 *    renders.
 * Counts of values and renders checked are asserted.
 */
#ifndef LMC_TESTS_ERROR_CHECK_H
#define LMC_TESTS_ERROR_CHECK_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include "render/image.h"
#include "test_util.h"

#define CBOX "../scenes/cornell-box/scene.xml"
#define K 12
#define EW 80
#define EH 60

static char out_text[1 << 14], err_text[1 << 14];

/* `lmc ARGS` (under timeout); its exit status, stdout in out_text, stderr
 * in err_text. */
static int run_lmc(const char *args) {
  char cmd[2048];
  snprintf(cmd, sizeof cmd, "timeout 120 '%s' %s > " TMP "/out.txt 2> " TMP "/err.txt",
           LMC_BINARY, args);
  int rc = system(cmd);
  slurp_text(TMP "/out.txt", out_text, sizeof out_text);
  slurp_text(TMP "/err.txt", err_text, sizeof err_text);
  if (rc == -1 || !WIFEXITED(rc)) return -1;
  return WEXITSTATUS(rc);
}

/* `lmc render CBOX ARGS -q -o TMP/OUT`. */
static int render(const char *args, const char *out) {
  char cmd[1024];
  snprintf(cmd, sizeof cmd, "render '%s' %s -q -o '" TMP "/%s'", CBOX, args, out);
  return run_lmc(cmd);
}

static void read_layer(const char *name, const char *layer, lmc_image *img) {
  char path[1024];
  snprintf(path, sizeof path, TMP "/%s", name);
  lmc_error err;
  lmc_error_clear(&err);
  if (image_read_exr_layer(path, layer, img, &err))
    fail_msg("%s (layer %s): %s", path, layer ? layer : "-", err.msg);
  assert_int_equal(img->channels, 3);
  assert_int_equal(img->width, EW);
  assert_int_equal(img->height, EH);
}

/* A test's setup: the scratch folder TMP. */
static int error_check_setup(void **state) {
  (void)state;
  mkdir(TMP, 0755);
  return 0;
}

/* K renders of integ (spp passes or mutations per pixel; `extra`: more
 * flags) and the checks above; check_coverage bounds the coverage. */
static void spread_check(const char *integ, const char *extra, int spp, int check_coverage) {
  const size_t n = 3 * (size_t)EW * EH;
  lmc_image img[K], se[K];
  for (int k = 0; k < K; k++) {
    char args[512], out[64];
    snprintf(args, sizeof args,
             "--integrator %s --resolution %dx%d --spp %d --seed %d --threads 2 --error on %s",
             integ, EW, EH, spp, k + 1, extra);
    snprintf(out, sizeof out, "err_%s_%d.exr", integ, k);
    if (render(args, out) != 0) fail_msg("lmc render %s: %s", args, err_text);
    read_layer(out, NULL, &img[k]);
    read_layer(out, "error", &se[k]);
  }

  /* Agreement of the two variance estimates, value by value; the three
   * values of a pixel come from the same paths, so their differences are
   * summed per pixel before the spread of the sum is taken. */
  double sum_d = 0.0, sum_d2 = 0.0, sum_emp = 0.0, sum_est = 0.0;
  long used = 0, flat = 0;
  for (size_t p = 0; p < n / 3; p++) {
    double dp = 0.0;
    for (size_t i = 3 * p; i < 3 * p + 3; i++) {
      double m = 0.0, est = 0.0;
      for (int k = 0; k < K; k++) m += img[k].data[i] / (double)K;
      for (int k = 0; k < K; k++) est += (double)se[k].data[i] * se[k].data[i] / K;
      double emp = 0.0;
      for (int k = 0; k < K; k++) emp += pow(img[k].data[i] - m, 2.0) / (K - 1);
      if (!(est > 0.0)) {
        flat++;
        assert_true(emp < 1e-12); /* no spread estimated where the renders differ */
        continue;
      }
      dp += emp - est;
      sum_emp += emp, sum_est += est;
      used++;
    }
    sum_d += dp, sum_d2 += dp * dp;
  }
  double z = sum_d / sqrt(sum_d2);
  fprintf(stderr, "  %s: %ld values (%ld of zero spread), variance across seeds / estimated %.4f, z %.2f\n",
          integ, used, flat, sum_emp / sum_est, z);
  assert_int_equal(used + flat, (long)n);
  assert_true(used >= (long)(0.6 * n)); /* (the box fills 72% of the image) */
  assert_le(fabs(z), 4.0);

  /* Coverage against the mean of the other renders. */
  long in1 = 0, in2 = 0, total = 0;
  const double widen = sqrt(1.0 + 1.0 / (K - 1));
  lmc_image ref;
  assert_int_equal(image_init(&ref, EW, EH, 3, NULL), LMC_OK);
  for (int k = 0; k < K; k++) {
    long in1_k = 0, total_k = 0;
    for (size_t i = 0; i < n; i++) {
      double m = 0.0;
      for (int j = 0; j < K; j++)
        if (j != k) m += img[j].data[i] / (double)(K - 1);
      ref.data[i] = (float)m;
      double e = se[k].data[i];
      if (!(e > 0.0) || !isfinite(e)) continue;
      double d = fabs(img[k].data[i] - m);
      in1 += d <= widen * e, in2 += d <= 2.0 * widen * e, total++;
      in1_k += d <= e, total_k++;
    }
    if (k == 0) {
      /* lmc compare's coverage of render 0 against the same mean (its
       * plain bound, without the widening). */
      lmc_error err;
      lmc_error_clear(&err);
      assert_int_equal(image_write_exr(TMP "/err_ref.exr", &ref, &err), LMC_OK);
      char cmd[256];
      snprintf(cmd, sizeof cmd, "compare '" TMP "/err_%s_0.exr' '" TMP "/err_ref.exr'", integ);
      assert_int_equal(run_lmc(cmd), 0);
      const char *c1 = strstr(out_text, "coverage_1se: ");
      const char *nv = strstr(out_text, "error_values: ");
      assert_non_null(c1);
      assert_non_null(nv);
      assert_int_equal(atol(nv + 14), total_k);
      assert_near(atof(c1 + 14), (double)in1_k / (double)total_k, 1e-5);
    }
  }
  image_free(&ref);
  double c1 = (double)in1 / total, c2 = (double)in2 / total;
  fprintf(stderr, "  %s: %ld values in %d renders: %.4f within one standard error, %.4f within two\n",
          integ, total, K, c1, c2);
  /* (a render may see no spread where the others do: all its passes alike) */
  assert_true(total <= K * used && total >= (long)(0.95 * K * used));
  if (check_coverage) {
    assert_true(c1 >= 0.60 && c1 <= 0.75);
    assert_true(c2 >= 0.90 && c2 <= 0.98);
  }
  for (int k = 0; k < K; k++) image_free(&img[k]), image_free(&se[k]);
}

#endif
