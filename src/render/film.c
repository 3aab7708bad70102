/*
 * film.c: accumulation buffers and reconstruction filters.
 *
 * Filters are separable, w(dx, dy) = g(dx) g(dy) / norm^2 with the 1-D
 * profile g of Mitsuba's rfilters:
 *   box       g = 1 on [-0.5, 0.5)
 *   tent      g = 1 - |x| on [-1, 1]
 *   gaussian  g = exp(-x^2 / (2 s^2)) - exp(-r^2 / (2 s^2)) on [-r, r],
 *             s = 0.5, r = 4 s = 2.
 * filter_sample draws offsets with exactly this density, so camera-ray
 * estimates (filter importance sampling) and splats estimate the same pixel
 * values. The Gaussian is sampled by inverting its exact cdf: a table gives
 * the cell, then safeguarded Newton steps on the closed-form cdf.
 */
#include "render/film.h"

#include "render/dist.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render/warp.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Unnormalised Gaussian profile and its integral from -r to x. */
static double filter__gauss(const film_filter *f, double x) {
  if (fabs(x) > f->radius) return 0.0;
  double s2 = 2.0 * f->stddev * f->stddev;
  return fmax(0.0, exp(-x * x / s2) - exp(-f->radius * f->radius / s2));
}

static double filter__gauss_cdf_raw(const film_filter *f, double x) {
  double s = f->stddev, r = f->radius;
  double c = exp(-r * r / (2.0 * s * s));
  double k = s * sqrt(M_PI / 2.0);
  return k * (erf(x / (s * sqrt(2.0))) - erf(-r / (s * sqrt(2.0)))) - c * (x + r);
}

void filter_init(film_filter *f, filter_type type) {
  memset(f, 0, sizeof *f);
  f->type = type;
  switch (type) {
    case FILTER_BOX:
      f->radius = 0.5;
      f->norm1d = 1.0;
      break;
    case FILTER_TENT:
      f->radius = 1.0;
      f->norm1d = 1.0;
      break;
    case FILTER_GAUSSIAN:
      f->stddev = 0.5;
      f->radius = 4.0 * f->stddev;
      f->norm1d = filter__gauss_cdf_raw(f, f->radius);
      for (int i = 0; i <= FILTER_TABLE_SIZE; i++) {
        double x = -f->radius + 2.0 * f->radius * i / FILTER_TABLE_SIZE;
        f->cdf[i] = filter__gauss_cdf_raw(f, x) / f->norm1d;
      }
      f->cdf[FILTER_TABLE_SIZE] = 1.0;
      break;
  }
}

static double filter__eval1d(const film_filter *f, double x) {
  switch (f->type) {
    case FILTER_BOX:
      return (x >= -0.5 && x < 0.5) ? 1.0 : 0.0;
    case FILTER_TENT:
      return fmax(0.0, 1.0 - fabs(x));
    case FILTER_GAUSSIAN:
      return filter__gauss(f, x) / f->norm1d;
  }
  return 0.0;
}

double filter_eval(const film_filter *f, double dx, double dy) {
  return filter__eval1d(f, dx) * filter__eval1d(f, dy);
}

/* Inverts the Gaussian's cdf at u. */
static double filter__gauss_sample(const film_filter *f, double u) {
  int lo = 0, hi = FILTER_TABLE_SIZE;
  while (hi - lo > 1) {
    int mid = (lo + hi) / 2;
    if (f->cdf[mid] <= u) lo = mid;
    else hi = mid;
  }
  double cell = 2.0 * f->radius / FILTER_TABLE_SIZE;
  double a = -f->radius + lo * cell, b = a + cell;
  double t = (f->cdf[hi] > f->cdf[lo]) ? (u - f->cdf[lo]) / (f->cdf[hi] - f->cdf[lo]) : 0.5;
  double x = a + t * cell;
  /* Newton on F(x) - u with the density as derivative, kept inside [a, b]. */
  for (int it = 0; it < 20; it++) {
    double fx = filter__gauss_cdf_raw(f, x) / f->norm1d - u;
    double d = filter__gauss(f, x) / f->norm1d;
    if (fx > 0.0) b = x;
    else a = x;
    double nx = d > 0.0 ? x - fx / d : 0.5 * (a + b);
    if (!(nx > a && nx < b)) nx = 0.5 * (a + b);
    if (fabs(nx - x) < 1e-14) {
      x = nx;
      break;
    }
    x = nx;
  }
  return x;
}

static double filter__sample1d(const film_filter *f, double u) {
  switch (f->type) {
    case FILTER_BOX:
      return u - 0.5;
    case FILTER_TENT:
      return warp_interval_to_tent(u);
    case FILTER_GAUSSIAN:
      return filter__gauss_sample(f, u);
  }
  return 0.0;
}

void filter_sample(const film_filter *f, double u1, double u2, double *dx, double *dy) {
  *dx = filter__sample1d(f, u1);
  *dy = filter__sample1d(f, u2);
}

lmc_status film_init(film *f, int width, int height, lmc_error *err) {
  memset(f, 0, sizeof *f);
  if (width <= 0 || height <= 0)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "film size %dx%d is empty", width, height);
  size_t n = (size_t)width * (size_t)height;
  f->sum = calloc(3 * n, sizeof(double));
  f->count = calloc(n, sizeof(double));
  f->splat = calloc(3 * n, sizeof(double));
  if (!f->sum || !f->count || !f->splat) {
    film_free(f);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for a %dx%d film", width, height);
  }
  f->width = width;
  f->height = height;
  f->splat_scale = 1.0;
  return LMC_OK;
}

void film_free(film *f) {
  if (!f) return;
  free(f->sum);
  free(f->count);
  free(f->splat);
  f->sum = f->count = f->splat = NULL;
  free(f->esum);
  free(f->esum2);
  free(f->pass_val);
  free(f->splat_prev);
  f->esum = f->esum2 = f->pass_val = f->splat_prev = NULL;
  free(f->evar);
  f->evar = NULL;
}

lmc_status film_error_init(film *f, lmc_error *err) {
  size_t n = 3 * (size_t)f->width * (size_t)f->height;
  f->esum = calloc(n, sizeof(double));
  f->esum2 = calloc(n, sizeof(double));
  f->pass_val = calloc(n, sizeof(double));
  f->splat_prev = calloc(n, sizeof(double));
  f->epasses = 0.0;
  if (!f->esum || !f->esum2 || !f->pass_val || !f->splat_prev)
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the error of a %dx%d film",
                         f->width, f->height);
  return LMC_OK;
}

void film_error_pass(film *f, double splat_norm) {
  if (!f->esum) return;
  size_t n = 3 * (size_t)f->width * (size_t)f->height;
  for (size_t i = 0; i < n; i++) {
    double x = f->pass_val[i] + (f->splat[i] - f->splat_prev[i]) * splat_norm;
    f->splat_prev[i] = f->splat[i];
    f->esum[i] += x;
    f->esum2[i] += x * x;
  }
  f->epasses += 1.0;
}

void film_error_develop_to(const film *f, float *pixels) {
  size_t n = 3 * (size_t)f->width * (size_t)f->height;
  double m = f->epasses;
  if (!film_has_error(f) || (f->esum && m < 2.0)) {
    for (size_t i = 0; i < n; i++) pixels[i] = INFINITY;
    return;
  }
  for (size_t i = 0; i < n; i++) {
    double var = 0.0;
    if (f->esum) {
      double mean = f->esum[i] / m;
      double s2 = (f->esum2[i] - m * mean * mean) / (m - 1.0);
      var = s2 > 0.0 ? s2 / m : 0.0;
    }
    if (f->evar) var += f->evar[i];
    pixels[i] = (float)sqrt(var);
  }
}

void film_clear(film *f) {
  size_t n = (size_t)f->width * (size_t)f->height;
  memset(f->sum, 0, 3 * n * sizeof(double));
  memset(f->count, 0, n * sizeof(double));
  memset(f->splat, 0, 3 * n * sizeof(double));
  if (f->esum) {
    memset(f->esum, 0, 3 * n * sizeof(double));
    memset(f->esum2, 0, 3 * n * sizeof(double));
    f->epasses = 0.0;
  }
}

/* Appends a splat to a log, growing it geometrically (a log is reused, so
 * it stops growing once it holds a row's worth of splats). */
static void film__log_add(film_splat_log *log, double rx, double ry, rgb v) {
  if (log->n == log->cap) {
    int64_t cap = log->cap ? 2 * log->cap : 256;
    film_splat_rec *r = realloc(log->rec, (size_t)cap * sizeof *r);
    if (!r) {
      log->lost++;
      return;
    }
    log->rec = r;
    log->cap = cap;
  }
  film_splat_rec *r = &log->rec[log->n++];
  r->rx = rx;
  r->ry = ry;
  r->v = v;
}

void film_splat_log_replay(film *f, const film_filter *filter, film_splat_log *log) {
  for (int64_t i = 0; i < log->n; i++)
    film_splat(f, filter, log->rec[i].rx, log->rec[i].ry, log->rec[i].v);
  log->n = 0;
}

void film_splat_log_free(film_splat_log *log) {
  if (!log) return;
  free(log->rec);
  log->rec = NULL;
  log->n = log->cap = 0;
}

void film_splat(film *f, const film_filter *filter, double rx, double ry, rgb v) {
  if (!rgb_isfinite(v)) return;
  if (f->log) {
    film__log_add(f->log, rx, ry, v);
    return;
  }
  int x0 = (int)floor(rx - 0.5 - filter->radius), x1 = (int)ceil(rx - 0.5 + filter->radius);
  int y0 = (int)floor(ry - 0.5 - filter->radius), y1 = (int)ceil(ry - 0.5 + filter->radius);
  if (x0 < 0) x0 = 0;
  if (y0 < 0) y0 = 0;
  if (x1 > f->width - 1) x1 = f->width - 1;
  if (y1 > f->height - 1) y1 = f->height - 1;
  for (int y = y0; y <= y1; y++) {
    double wy = filter__eval1d(filter, (y + 0.5) - ry);
    if (wy == 0.0) continue;
    for (int x = x0; x <= x1; x++) {
      double w = wy * filter__eval1d(filter, (x + 0.5) - rx);
      if (w == 0.0) continue;
      double *s = f->splat + 3 * ((int64_t)y * f->width + x);
      s[0] += w * v.r;
      s[1] += w * v.g;
      s[2] += w * v.b;
    }
  }
}

void film_merge(film *dst, const film *src) {
  size_t n = (size_t)dst->width * (size_t)dst->height;
  for (size_t i = 0; i < 3 * n; i++) {
    dst->sum[i] += src->sum[i];
    dst->splat[i] += src->splat[i];
  }
  for (size_t i = 0; i < n; i++) dst->count[i] += src->count[i];
  if (dst->esum && src->esum) {
    for (size_t i = 0; i < 3 * n; i++) dst->esum[i] += src->esum[i], dst->esum2[i] += src->esum2[i];
    dst->epasses += src->epasses;
  }
}

void film_sum_to_root(film *f) {
  size_t n = (size_t)f->width * (size_t)f->height;
  dist_sum_to_root(f->sum, 3 * n);
  dist_sum_to_root(f->count, n);
  dist_sum_to_root(f->splat, 3 * n);
  if (f->esum) {
    dist_sum_to_root(f->esum, 3 * n);
    dist_sum_to_root(f->esum2, 3 * n);
    dist_sum_to_root(&f->epasses, 1);
  }
}

void film_develop_to(const film *f, float *pixels) {
  size_t n = (size_t)f->width * (size_t)f->height;
  for (size_t i = 0; i < n; i++) {
    double c = f->count[i];
    for (int k = 0; k < 3; k++) {
      double v = (c > 0.0 ? f->sum[3 * i + k] / c : 0.0) + f->splat[3 * i + k] * f->splat_scale;
      pixels[3 * i + k] = (float)v;
    }
  }
}

lmc_status film_develop(const film *f, lmc_image *out, lmc_error *err) {
  lmc_status st = image_init(out, f->width, f->height, 3, err);
  if (st) return st;
  film_develop_to(f, out->data);
  return LMC_OK;
}
