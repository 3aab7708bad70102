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

/* --channel error: per pixel the expected squared relative error
 * se^2 / (I^2 + 0.01), averaged over the channels (the quantity lmc
 * compare's heat map shows of the true error), as a false-colour PNG. */
static int lmc_convert_error(const char *in, const char *out, const lmc_image *img,
                             lmc_error *err) {
  lmc_image se = {0};
  if (image_read_exr_layer(in, "error", &se, err)) return EXIT_BADINPUT;
  size_t n = (size_t)img->width * (size_t)img->height;
  double *e = se.channels == 3 && se.width == img->width && se.height == img->height
                  ? malloc(n * sizeof *e)
                  : NULL;
  int status = EXIT_OK;
  if (!e) {
    lmc_error_set(err, LMC_EINVAL, in, 0, "its error channels do not match its image");
    status = EXIT_BADINPUT;
  } else {
    for (size_t p = 0; p < n; p++) {
      e[p] = 0.0;
      for (int c = 0; c < 3; c++) {
        double s = se.data[3 * p + c], v = img->data[3 * p + c];
        e[p] += s * s / (v * v + 0.01) / 3.0;
      }
    }
    if (lmc_write_heat_png(out, img->width, img->height, e, err)) status = EXIT_FAIL;
  }
  free(e);
  image_free(&se);
  return status;
}

int lmc_cmd_convert(int argc, char **argv) {
  const char *paths[2] = {NULL, NULL};
  int n = 0;
  lmc_exposure exposure = {0, 0.0};
  int error_channel = 0;
  lmc_args a = {argc, 2, argv, NULL};
  for (a.i = 2; a.i < argc; a.i++) {
    const char *v;
    if (lmc_flag_is(&a, "--exposure")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_exposure(v, &exposure)) return EXIT_BADINPUT;
    } else if (lmc_flag_is(&a, "--channel")) {
      if (!(v = lmc_flag_value(&a))) return EXIT_BADINPUT;
      if (strcmp(v, "error") != 0 && strcmp(v, "rgb") != 0) {
        fprintf(stderr, "lmc: flag --channel: '%s' is neither rgb nor error\n", v);
        return EXIT_BADINPUT;
      }
      error_channel = strcmp(v, "error") == 0;
    } else if (lmc_flag_is(&a, "--help") || lmc_flag_is(&a, "-h")) {
      printf("usage: lmc convert IN.exr OUT.png [--exposure STOPS|auto] [--channel rgb|error]\n"
             "writes an sRGB PNG preview of a linear image: radiance times 2^STOPS\n"
             "(default 0), clamped, with the sRGB curve; 'auto' maps the 99th\n"
             "percentile of luminance to white. --channel error: the image's own\n"
             "standard error (lmc render --error on) as a false-colour map of\n"
             "the expected squared relative error, the scale of lmc compare's\n"
             "heat map (1e-4 dark blue to 1 red)\n");
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
  } else if (error_channel) {
    status = lmc_convert_error(paths[0], paths[1], &img, &err);
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

