/*
 * merge.c: `lmc merge A.exr B.exr ... -o OUT.exr`: the (weighted) mean of independent renders.
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

/* --- lmc merge ------------------------------------------------------------------ */

/* Averages renders of the same scene made with different seeds: equal
 * weights, or the weights given with --weight (inverse variances, for
 * renders of unequal effort). */
int lmc_cmd_merge(int argc, char **argv) {
  static const char usage[] = "usage: lmc merge [--weight W] A.exr [--weight W] B.exr ... -o OUT.exr";
  const char *out = NULL;
  lmc_image acc = {0}, img = {0};
  lmc_error err;
  lmc_error_clear(&err);
  char msg[2048];
  int n = 0, status = EXIT_OK, weight_pending = 0;
  double weight = 1.0, total = 0.0;
  lmc_args a = {argc, 2, argv, NULL};
  for (a.i = 2; a.i < argc && status == EXIT_OK; a.i++) {
    const char *v;
    if (lmc_flag_is(&a, "-o") || lmc_flag_is(&a, "--output")) {
      if (!(out = lmc_flag_value(&a))) status = EXIT_BADINPUT;
      continue;
    }
    if (lmc_flag_is(&a, "--weight")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_double("--weight", v, 1e-9, 1e9, &weight))
        status = EXIT_BADINPUT;
      weight_pending = 1;
      continue;
    }
    if (lmc_flag_is(&a, "--help") || lmc_flag_is(&a, "-h")) {
      printf("%s\n"
             "writes the per-pixel weighted mean of the images (all the same size) to\n"
             "OUT.exr, for independent renders of one scene. --weight W applies to the\n"
             "image after it (default 1): give renders of unequal effort weights in\n"
             "inverse proportion to their variance, e.g. their sample counts\n",
             usage);
      image_free(&acc);
      return EXIT_OK;
    }
    if (argv[a.i][0] == '-') {
      fprintf(stderr, "lmc: unknown flag '%s' (%s)\n", argv[a.i], usage);
      status = EXIT_BADINPUT;
      continue;
    }
    double w = weight;
    weight = 1.0;
    weight_pending = 0;
    if (image_read(argv[a.i], 0, &img, &err) || image_to_rgb(&img, &err)) {
      lmc_error_format(&err, msg, sizeof msg);
      fprintf(stderr, "lmc: %s\n", msg);
      status = EXIT_BADINPUT;
    } else if (n == 0) {
      acc = img;
      memset(&img, 0, sizeof img);
      n = 1;
      total = w;
    } else if (img.width != acc.width || img.height != acc.height) {
      fprintf(stderr, "lmc: %s is %dx%d, the first image %dx%d\n", argv[a.i], img.width,
              img.height, acc.width, acc.height);
      status = EXIT_BADINPUT;
    } else {
      /* Running weighted mean, in place. */
      n++;
      total += w;
      float f = (float)(w / total);
      for (size_t k = 0; k < (size_t)acc.width * acc.height * 3; k++)
        acc.data[k] += (img.data[k] - acc.data[k]) * f;
    }
    image_free(&img);
  }
  if (status == EXIT_OK && weight_pending) {
    fprintf(stderr, "lmc: flag --weight: no image after it\n");
    status = EXIT_BADINPUT;
  }
  if (status == EXIT_OK && (n < 1 || !out)) {
    fprintf(stderr, "%s\n", usage);
    status = EXIT_BADINPUT;
  }
  if (status == EXIT_OK && image_write_exr(out, &acc, &err)) {
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
    status = EXIT_FAIL;
  }
  if (status == EXIT_OK) printf("wrote %s (weighted mean of %d images, total weight %g)\n", out, n, total);
  image_free(&acc);
  return status;
}

