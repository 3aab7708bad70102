/*
 * image.c: float images (image.h) and what the format readers and writers
 * in io/ share: allocation, the channel conversion, the size limits, the
 * sRGB curve and the writers' temporary names. The formats are in io/:
 * image_read.c dispatches on the file's first bytes, image_png.c,
 * image_jpeg.c and image_exr.c read and write them.
 *
 * Images are row-major, top row first, channels interleaved (image.h).
 *
 * The sRGB transfer function (IEC 61966-2-1):
 *   to linear:  c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055)^2.4
 *   to sRGB:    l <= 0.0031308 ? 12.92 l : 1.055 l^(1/2.4) - 0.055
 */
#define _POSIX_C_SOURCE 200809L

#include "render/image.h"
#include "render/vec3.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

lmc_status image_init(lmc_image *img, int width, int height, int channels, lmc_error *err) {
  img->width = img->height = img->channels = 0;
  img->data = NULL;
  if (width <= 0 || height <= 0 || channels <= 0 || channels > 4)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "invalid image size %d x %d x %d", width,
                         height, channels);
  size_t n = (size_t)width * (size_t)height * (size_t)channels;
  if (n / (size_t)width / (size_t)height != (size_t)channels || n > SIZE_MAX / sizeof(float))
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "image too large");
  img->data = calloc(n, sizeof(float));
  if (!img->data) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for an image");
  img->width = width;
  img->height = height;
  img->channels = channels;
  return LMC_OK;
}

void image_free(lmc_image *img) {
  if (!img) return;
  free(img->data);
  img->data = NULL;
  img->width = img->height = img->channels = 0;
}

static int image__cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

void image_rel_error(const lmc_image *img, const lmc_image *ref, double *OUT_rel) {
  size_t n = (size_t)img->width * (size_t)img->height;
  for (size_t p = 0; p < n; p++) {
    const float *I = img->data + 3 * p, *R = ref->data + 3 * p;
    OUT_rel[p] = 0.0;
    for (int c = 0; c < 3; c++) {
      double d = (double)I[c] - (double)R[c];
      OUT_rel[p] += d * d / ((double)R[c] * R[c] + 0.01) / 3.0;
    }
  }
}

lmc_status image_error(const lmc_image *img, const lmc_image *ref, lmc_image_error *OUT,
                       lmc_error *err) {
  memset(OUT, 0, sizeof *OUT);
  if (img->width != ref->width || img->height != ref->height || img->channels != 3 ||
      ref->channels != 3)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "images of %dx%d and %dx%d compared",
                         img->width, img->height, ref->width, ref->height);
  size_t n = (size_t)img->width * (size_t)img->height;
  double *rel = malloc((n > 0 ? n : 1) * sizeof *rel);
  if (!rel) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory comparing images");
  double lum_i = 0.0, lum_r = 0.0;
  image_rel_error(img, ref, rel);
  for (size_t p = 0; p < n; p++) {
    const float *I = img->data + 3 * p, *R = ref->data + 3 * p;
    for (int c = 0; c < 3; c++) {
      double d = (double)I[c] - (double)R[c];
      OUT->mse += d * d;
    }
    OUT->relmse += rel[p];
    lum_i += rgb_luminance(rgb_make(I[0], I[1], I[2]));
    lum_r += rgb_luminance(rgb_make(R[0], R[1], R[2]));
  }
  OUT->mse /= 3.0 * (double)(n > 0 ? n : 1);
  OUT->relmse /= (double)(n > 0 ? n : 1);
  size_t drop = n / 1000;
  qsort(rel, n, sizeof *rel, image__cmp_double);
  for (size_t p = 0; p + drop < n; p++) OUT->relmse_trimmed += rel[p];
  OUT->relmse_trimmed /= (double)(n - drop > 0 ? n - drop : 1);
  free(rel);
  OUT->mean_ratio = lum_r != 0.0 ? lum_i / lum_r : (lum_i == 0.0 ? 1.0 : INFINITY);
  return LMC_OK;
}

lmc_status image_to_rgb(lmc_image *img, lmc_error *err) {
  if (img->channels == 3) return LMC_OK;
  size_t n = (size_t)img->width * (size_t)img->height;
  float *d = malloc(n * 3 * sizeof(float) + 1);
  if (!d) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory converting an image");
  int c = img->channels;
  for (size_t i = 0; i < n; i++) {
    if (c < 3) {
      /* grey (and grey+alpha): replicate */
      d[3 * i] = d[3 * i + 1] = d[3 * i + 2] = img->data[c * i];
    } else {
      for (int k = 0; k < 3; k++) d[3 * i + k] = img->data[c * i + k];
    }
  }
  free(img->data);
  img->data = d;
  img->channels = 3;
  return LMC_OK;
}

lmc_status image_select_channel(lmc_image *img, int channel, lmc_error *err) {
  int c = img->channels;
  int has_alpha = c == 2 || c == 4;
  if (channel == 3 && !has_alpha)
    return lmc_error_set(err, LMC_EUNSUPPORTED, NULL, 0, "the image has no alpha channel");
  /* The source channel: alpha is the last; grey images have one colour. */
  int src = channel == 3 ? c - 1 : c < 3 ? 0 : channel;
  size_t n = (size_t)img->width * (size_t)img->height;
  float *d = malloc(n * 3 * sizeof(float) + 1);
  if (!d) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory converting an image");
  for (size_t i = 0; i < n; i++) d[3 * i] = d[3 * i + 1] = d[3 * i + 2] = img->data[c * i + src];
  free(img->data);
  img->data = d;
  img->channels = 3;
  return LMC_OK;
}

lmc_status image_check_size(const char *path, const char *format, long long width,
                            long long height, lmc_error *err) {
  if (width <= IMAGE_MAX_SIDE && height <= IMAGE_MAX_SIDE && width * height <= IMAGE_MAX_PIXELS)
    return LMC_OK;
  return lmc_error_set(err, LMC_EUNSUPPORTED, path, 0,
                       "%s image of %lld x %lld pixels is too large "
                       "(at most %d a side and %ld in all)",
                       format, width, height, IMAGE_MAX_SIDE, IMAGE_MAX_PIXELS);
}

double srgb_to_linear(double v) {
  if (v <= 0.04045) return v / 12.92;
  return pow((v + 0.055) / 1.055, 2.4);
}

double linear_to_srgb(double v) {
  if (v <= 0.0031308) return 12.92 * v;
  return 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

/* "<path>.tmp-<pid>-<n>": unique per process and call. */
void image_temp_name(const char *path, char *buf, size_t size) {
  static unsigned counter;
  unsigned n;
#pragma omp atomic capture
  n = counter++;
  snprintf(buf, size, "%s.tmp-%ld-%u", path, (long)getpid(), n);
}

