/*
 * region_stats.h: per-region mean luminance of an image, and the mean and
 * standard error of such statistics over independent runs (region_runs),
 * and their agreement with a reference's (region_agree). The MCMC
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

/* The settings of an agreement run: `integrator` at spp samples (or
 * mutations) per pixel, 2 threads, quiet, no time limit, and for the MCMC
 * integrators the default adaptive bootstrap to 3% (its error is part of
 * the runs' spread). Flags beyond these are the caller's (mcmc_set). */
static inline render_settings region_settings(const scene *s, const char *integrator,
                                              int64_t spp) {
  render_settings rs = s->settings;
  snprintf(rs.integrator, sizeof rs.integrator, "%s", integrator);
  rs.spp = spp;
  rs.set |= SET_SPP;
  lmc_error err;
  assert_int_equal(mcmc_set(&rs, "bootstrap-error", "0.03", &err), LMC_OK);
  rs.time_limit = 0.0;
  rs.threads = 2;
  rs.quiet = 1;
  return rs;
}

/* The grid^2 + 1 statistics of region_means over `runs` renders of s with
 * *rs (its integrator and flags set by the caller), seeds seed0, seed0 +
 * 1, ...: their means into OUT_mean, their standard errors into OUT_se. */
static inline void region_runs(const scene *s, const render_settings *rs, int runs,
                               uint64_t seed0, int grid, double *OUT_mean, double *OUT_se) {
  int n = grid * grid + 1;
  double sum[n], sum2[n];
  for (int k = 0; k < n; k++) sum[k] = sum2[k] = 0.0;
  for (int r = 0; r < runs; r++) {
    render_settings one = *rs;
    one.seed = seed0 + (uint64_t)r;
    region_stats_render(s, &one, grid, sum, sum2);
  }
  region_mean_se(n, runs, sum, sum2, OUT_mean, OUT_se);
}

/* Asserts every statistic m[k] (region_runs') within z_max sqrt(se^2 +
 * ref_se^2) of ref[k], the runs' spread not zero unless both agree
 * exactly; prints the image means and the largest |difference| / SE under
 * `what`. Returns the number of checks, grid^2 + 1. */
static inline int region_agree(const char *what, int grid, const double *m, const double *se,
                               const double *ref, const double *ref_se, double z_max) {
  int n = grid * grid + 1;
  double worst = 0.0;
  for (int k = 0; k < n; k++) {
    double sd = sqrt(se[k] * se[k] + ref_se[k] * ref_se[k]);
    double z = fabs(m[k] - ref[k]) / fmax(sd, 1e-300);
    if (z > worst) worst = z;
    if (k == n - 1)
      fprintf(stderr, "  %s: image mean %.5f +- %.2g, reference %.5f +- %.2g\n", what, m[k],
              se[k], ref[k], ref_se[k]);
    assert_true(sd > 0.0 || m[k] == ref[k]); /* independent runs differ */
    if (!(fabs(m[k] - ref[k]) <= z_max * sd))
      fail_msg("%s: statistic %d is %.6g, the reference's %.6g: %.2f of their SE (at most %.1f)",
               what, k, m[k], ref[k], z, z_max);
  }
  fprintf(stderr, "  %s: largest |difference| / SE over the regions %.2f\n", what, worst);
  return n;
}

#endif
