/*
 * compare.c: `lmc compare IMAGE.exr REF.exr`: error metrics, one `name: value` per line, and a heat map.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"

/* --- lmc compare ---------------------------------------------------------------- */

/* A false-colour ramp (dark blue - cyan - yellow - red) for t in [0, 1]. */
static rgb lmc_heat_color(double t) {
  static const double stops[5][3] = {
      {0.05, 0.05, 0.25}, {0.0, 0.45, 0.85}, {0.1, 0.85, 0.75}, {0.95, 0.9, 0.1}, {0.85, 0.1, 0.05}};
  t = fmin(1.0, fmax(0.0, t)) * 4.0;
  int i = (int)t;
  if (i >= 4) i = 3;
  double f = t - i;
  return rgb_make(stops[i][0] + f * (stops[i + 1][0] - stops[i][0]),
                  stops[i][1] + f * (stops[i + 1][1] - stops[i][1]),
                  stops[i][2] + f * (stops[i + 1][2] - stops[i][2]));
}

/* IMAGE's own error (channels error.R, G, B, from `lmc render --error on`)
 * against the true error I - R: how many values lie within one and two
 * estimated standard errors, over the values with a finite, positive one
 * (a pixel of zero spread, such as the bare environment, says nothing). */
static void lmc_print_coverage(const char *path, const lmc_image *img, const lmc_image *ref) {
  lmc_image se = {0};
  lmc_error err;
  lmc_error_clear(&err);
  if (image_read_exr_layer(path, "error", &se, &err) || se.channels != 3 ||
      se.width != img->width || se.height != img->height) {
    image_free(&se);
    return;
  }
  size_t n = 3 * (size_t)img->width * (size_t)img->height;
  long long used = 0, in1 = 0, in2 = 0;
  for (size_t i = 0; i < n; i++) {
    double e = se.data[i], d = fabs((double)img->data[i] - (double)ref->data[i]);
    if (!(e > 0.0) || !isfinite(e)) continue;
    used++;
    in1 += d <= e;
    in2 += d <= 2.0 * e;
  }
  image_free(&se);
  printf("error_values: %lld\n", used);
  if (used > 0)
    printf("coverage_1se: %.6g\ncoverage_2se: %.6g\n", (double)in1 / (double)used,
           (double)in2 / (double)used);
}

lmc_status lmc_write_heat_png(const char *path, int width, int height, const double *e,
                              lmc_error *err) {
  lmc_image hm = {0};
  lmc_status st = image_init(&hm, width, height, 3, err);
  if (st) return st;
  for (size_t p = 0; p < (size_t)width * (size_t)height; p++) {
    double t = (log10(fmax(e[p], 1e-4)) + 4.0) / 4.0;
    rgb col = lmc_heat_color(t);
    hm.data[3 * p] = (float)srgb_to_linear(col.r);
    hm.data[3 * p + 1] = (float)srgb_to_linear(col.g);
    hm.data[3 * p + 2] = (float)srgb_to_linear(col.b);
  }
  st = image_write_png(path, &hm, 1.0, err);
  image_free(&hm);
  return st;
}

int lmc_cmd_compare(int argc, char **argv) {
  const char *paths[2] = {NULL, NULL}, *heatmap = NULL;
  int n_paths = 0;
  lmc_args a = {argc, 2, argv, NULL};
  for (a.i = 2; a.i < argc; a.i++) {
    if (lmc_flag_is(&a, "--heatmap")) {
      if (!(heatmap = lmc_flag_value(&a))) return EXIT_BADINPUT;
    } else if (lmc_flag_is(&a, "--help") || lmc_flag_is(&a, "-h")) {
      printf("usage: lmc compare IMAGE.exr REFERENCE.exr [--heatmap ERR.png]\n"
             "prints mse, relmse (mean of (I-R)^2 / (R^2 + 0.01)), relmse_trimmed\n"
             "(the same without the 0.1%% of pixels with the largest error) and\n"
             "mean_ratio (mean luminance of IMAGE over REFERENCE); exit 2 if the\n"
             "sizes differ. When IMAGE has channels error.R, G, B (lmc render\n"
             "--error on), also how often |I - R| lies within one and two of\n"
             "them (coverage_1se, coverage_2se; 0.68 and 0.95 for normal errors)\n"
             "over error_values values of positive error\n");
      return EXIT_OK;
    } else if (argv[a.i][0] == '-') {
      fprintf(stderr, "lmc: unknown flag '%s' (see lmc compare --help)\n", argv[a.i]);
      return EXIT_BADINPUT;
    } else if (n_paths < 2) {
      paths[n_paths++] = argv[a.i];
    } else {
      fprintf(stderr, "lmc compare: too many arguments\n");
      return EXIT_BADINPUT;
    }
  }
  if (n_paths != 2) {
    fprintf(stderr, "usage: lmc compare IMAGE.exr REFERENCE.exr [--heatmap ERR.png]\n");
    return EXIT_BADINPUT;
  }
  lmc_image img[2] = {{0}, {0}};
  lmc_error err;
  lmc_error_clear(&err);
  char msg[2048];
  for (int k = 0; k < 2; k++) {
    if (image_read(paths[k], 0, &img[k], &err) || image_to_rgb(&img[k], &err)) {
      lmc_error_format(&err, msg, sizeof msg);
      fprintf(stderr, "lmc: %s\n", msg);
      image_free(&img[0]);
      image_free(&img[1]);
      return EXIT_BADINPUT;
    }
  }
  if (img[0].width != img[1].width || img[0].height != img[1].height) {
    fprintf(stderr, "lmc: %s is %dx%d but %s is %dx%d\n", paths[0], img[0].width, img[0].height,
            paths[1], img[1].width, img[1].height);
    image_free(&img[0]);
    image_free(&img[1]);
    return EXIT_BADINPUT;
  }

  size_t n = (size_t)img[0].width * (size_t)img[0].height;
  lmc_image_error ie;
  if (image_error(&img[0], &img[1], &ie, &err)) {
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
    image_free(&img[0]);
    image_free(&img[1]);
    return EXIT_FAIL;
  }
  printf("mse: %.9g\nrelmse: %.9g\nrelmse_trimmed: %.9g\nmean_ratio: %.9g\n", ie.mse, ie.relmse,
         ie.relmse_trimmed, ie.mean_ratio);
  lmc_print_coverage(paths[0], &img[0], &img[1]);

  /* The heatmap: per-pixel relative error, log scale from 1e-4 to 1. */
  int status = EXIT_OK;
  if (heatmap) {
    double *e = malloc(n * sizeof *e);
    if (e) image_rel_error(&img[0], &img[1], e);
    if (!e) {
      lmc_error_set(&err, LMC_ENOMEM, NULL, 0, "out of memory");
      status = EXIT_FAIL;
    } else if (lmc_write_heat_png(heatmap, img[0].width, img[0].height, e, &err)) {
      status = EXIT_FAIL;
    }
    free(e);
    if (status != EXIT_OK) {
      lmc_error_format(&err, msg, sizeof msg);
      fprintf(stderr, "lmc: %s\n", msg);
    }
  }
  image_free(&img[0]);
  image_free(&img[1]);
  return status;
}

