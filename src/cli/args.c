/*
 * args.c: flag parsing and the preview's exposure, for every command (cli.h).
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

/* --- flag parsing ------------------------------------------------------------ */

/* Matches argv[i] against a flag name (with or without "=value"). */
int lmc_flag_is(lmc_args *a, const char *name) {
  const char *arg = a->argv[a->i];
  size_t n = strlen(name);
  if (strncmp(arg, name, n) != 0) return 0;
  if (arg[n] == '\0') {
    a->inline_value = NULL;
    return 1;
  }
  if (arg[n] == '=') {
    a->inline_value = arg + n + 1;
    return 1;
  }
  return 0;
}

/* The value of the current flag, from "=value" or the next argument. */
const char *lmc_flag_value(lmc_args *a) {
  if (a->inline_value) return a->inline_value;
  if (a->i + 1 >= a->argc) {
    fprintf(stderr, "lmc: flag %s needs a value\n", a->argv[a->i]);
    return NULL;
  }
  return a->argv[++a->i];
}

/* s as a whole finite number in [lo, hi]: 1 and *out, else 0 (silent). */
int lmc_number_in(const char *s, double lo, double hi, double *out) {
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (errno || end == s || *end != '\0' || !isfinite(v) || v < lo || v > hi) return 0;
  *out = v;
  return 1;
}

int lmc_parse_double(const char *flag, const char *s, double lo, double hi, double *out) {
  if (lmc_number_in(s, lo, hi, out)) return 1;
  fprintf(stderr, "lmc: flag %s: '%s' is not a number in [%g, %g]\n", flag, s, lo, hi);
  return 0;
}

int lmc_parse_exposure(const char *s, lmc_exposure *out) {
  if (strcmp(s, "auto") == 0) {
    out->is_auto = 1;
    out->stops = 0.0;
    return 1;
  }
  if (!lmc_number_in(s, -64.0, 64.0, &out->stops)) {
    fprintf(stderr, "lmc: flag --exposure: '%s' is neither a number of stops in [-64, 64] nor 'auto'\n",
            s);
    return 0;
  }
  out->is_auto = 0;
  return 1;
}

double lmc_preview_scale(const lmc_image *img) {
  size_t n = (size_t)img->width * (size_t)img->height;
  float *lum = malloc(n * sizeof(float));
  if (!lum || n == 0) {
    free(lum);
    return 1.0;
  }
  size_t k = 0;
  for (size_t i = 0; i < n; i++) {
    const float *p = img->data + 3 * i;
    double l = rgb_luminance(rgb_make(p[0], p[1], p[2]));
    if (isfinite(l) && l > 0.0) lum[k++] = (float)l;
  }
  double scale = 1.0;
  if (k > 0) {
    /* Partial selection of the percentile (nth element by quickselect). */
    size_t target = (size_t)(0.99 * (double)(k - 1));
    size_t lo = 0, hi = k - 1;
    while (lo < hi) {
      float pivot = lum[(lo + hi) / 2];
      size_t i = lo, j = hi;
      while (i <= j) {
        while (lum[i] < pivot) i++;
        while (lum[j] > pivot) j--;
        if (i <= j) {
          float t = lum[i];
          lum[i] = lum[j];
          lum[j] = t;
          i++;
          if (j == 0) break;
          j--;
        }
      }
      if (target <= j) hi = j;
      else if (target >= i) lo = i;
      else break;
    }
    double p = lum[target];
    if (p > 0.0 && isfinite(p)) scale = 1.0 / p;
  }
  free(lum);
  return scale;
}

/* The factor the preview multiplies radiance by. */
double lmc_exposure_scale(const lmc_exposure *e, const lmc_image *img) {
  return e->is_auto ? lmc_preview_scale(img) : exp2(e->stops);
}

