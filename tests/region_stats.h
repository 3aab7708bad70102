/*
 * region_stats.h: per-region mean luminance of an image, and the mean and
 * standard error of such statistics over independent runs. The MCMC
 * agreement tests compare integrators with these (the image mean plus a
 * grid x grid of region means). Include after <cmocka.h>: region_stats_render
 * asserts.
 */
#ifndef LMC_TESTS_REGION_STATS_H
#define LMC_TESTS_REGION_STATS_H

#include <math.h>

#include <stdio.h>

#include "lmc/mcmc.h"
#include "render/film.h"
#include "render/image.h"
#include "render/integrators/integrator.h"
#include "render/vec3.h"

/* OUT[g] for g < grid^2: mean luminance of region g (row-major);
 * OUT[grid^2]: mean luminance of the whole image. */
static inline void region_means(const lmc_image *img, int grid, double *OUT) {
  int n = grid * grid + 1, cnt[n];
  for (int k = 0; k < n; k++) OUT[k] = 0.0, cnt[k] = 0;
  for (int y = 0; y < img->height; y++)
    for (int x = 0; x < img->width; x++) {
      const float *p = img->data + 3 * ((size_t)y * img->width + x);
      double l = rgb_luminance(rgb_make(p[0], p[1], p[2]));
      int g = (y * grid / img->height) * grid + x * grid / img->width;
      OUT[g] += l, cnt[g]++;
      OUT[grid * grid] += l, cnt[grid * grid]++;
    }
  for (int k = 0; k < n; k++) OUT[k] /= cnt[k];
}

/* Mean and standard error of the mean of n statistics from sums over runs. */
static inline void region_mean_se(int n, int runs, const double *sum, const double *sum2,
                                  double *OUT_mean, double *OUT_se) {
  for (int k = 0; k < n; k++) {
    OUT_mean[k] = sum[k] / runs;
    OUT_se[k] = sqrt(fmax(0.0, (sum2[k] - runs * OUT_mean[k] * OUT_mean[k]) / (runs - 1)) / runs);
  }
}

/* Renders s with rs (an MCMC integrator or pt/bdpt) and adds the image's
 * grid^2 + 1 region means (region_means) and their squares to sum, sum2. */
static inline void region_stats_render(const scene *s, const render_settings *rs, int grid,
                                       double *sum, double *sum2) {
  film f;
  render_stats st;
  lmc_error err;
  lmc_error_clear(&err);
  lmc_status status = mcmc_is_integrator(rs->integrator) ? mcmc_render_run(s, rs, &f, &st, &err)
                                                         : render_run(s, rs, &f, &st, &err);
  if (status) fprintf(stderr, "%s\n", err.msg);
  assert_int_equal(status, LMC_OK);
  lmc_image img;
  assert_int_equal(film_develop(&f, &img, &err), LMC_OK);
  int n = grid * grid + 1;
  double reg[n];
  region_means(&img, grid, reg);
  for (int k = 0; k < n; k++) sum[k] += reg[k], sum2[k] += reg[k] * reg[k];
  image_free(&img);
  film_free(&f);
}

#endif
