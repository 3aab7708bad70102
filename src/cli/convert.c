/*
 * convert.c: `lmc convert IN.exr OUT.png`: the sRGB preview of a linear image.
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

/* --- lmc convert ---------------------------------------------------------------- */

int lmc_cmd_convert(int argc, char **argv) {
  const char *paths[2] = {NULL, NULL};
  int n = 0;
  lmc_exposure exposure = {0, 0.0};
  lmc_args a = {argc, 2, argv, NULL};
  for (a.i = 2; a.i < argc; a.i++) {
    const char *v;
    if (lmc_flag_is(&a, "--exposure")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_exposure(v, &exposure)) return EXIT_BADINPUT;
    } else if (lmc_flag_is(&a, "--help") || lmc_flag_is(&a, "-h")) {
      printf("usage: lmc convert IN.exr OUT.png [--exposure STOPS|auto]\n"
             "writes an sRGB PNG preview of a linear image: radiance times 2^STOPS\n"
             "(default 0), clamped, with the sRGB curve; 'auto' maps the 99th\n"
             "percentile of luminance to white\n");
      return EXIT_OK;
    } else if (argv[a.i][0] == '-') {
      fprintf(stderr, "lmc: unknown flag '%s' (usage: lmc convert IN.exr OUT.png [--exposure STOPS|auto])\n",
              argv[a.i]);
      return EXIT_BADINPUT;
    } else if (n < 2) {
      paths[n++] = argv[a.i];
    } else {
      fprintf(stderr, "lmc convert: too many arguments\n");
      return EXIT_BADINPUT;
    }
  }
  if (n != 2) {
    fprintf(stderr, "usage: lmc convert IN.exr OUT.png [--exposure STOPS|auto]\n");
    return EXIT_BADINPUT;
  }
  lmc_image img = {0};
  lmc_error err;
  lmc_error_clear(&err);
  char msg[2048];
  int status = EXIT_OK;
  /* A PNG or JPEG input is sRGB-encoded: decoded to linear first, so that
   * converting a preview gives it back. */
  if (image_read(paths[0], 1, &img, &err) || image_to_rgb(&img, &err)) {
    status = EXIT_BADINPUT;
  } else if (image_write_png(paths[1], &img, lmc_exposure_scale(&exposure, &img), &err)) {
    status = EXIT_FAIL;
  }
  if (status != EXIT_OK) {
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
  } else {
    printf("wrote %s\n", paths[1]);
  }
  image_free(&img);
  return status;
}

