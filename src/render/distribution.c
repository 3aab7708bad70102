/*
 * distribution.c: piecewise-constant distributions in one and two
 * dimensions, each with sample, pdf and invert.
 *
 * The 1-D model. n non-negative values f[0..n-1] define a step function on
 * [0,1) whose cell i is [i/n, (i+1)/n). Its integral is
 *
 *     I = sum_i f[i] / n,
 *
 * the density is p(x) = f[floor(x n)] / I, and the cumulative distribution
 * at the cell boundaries is cdf[i] = sum_{j<i} f[j] / (n I), with cdf[0] = 0
 * and cdf[n] = 1 exactly. Sampling inverts the (piecewise-linear) CDF:
 * find the cell i with cdf[i] <= u < cdf[i+1], then
 *
 *     x = (i + (u - cdf[i]) / (cdf[i+1] - cdf[i])) / n,
 *
 * and invert is the CDF itself, u = cdf[i] + (x n - i) (cdf[i+1] - cdf[i]).
 * Cells with f = 0 have zero width in u and are never chosen (trailing
 * empty cells get cdf = 1 exactly so roundoff cannot select them). When
 * every f is zero the distribution falls back to uniform: func becomes all
 * ones and I = 1, so pdf, pmf and sampling stay consistent with each other.
 *
 * The 2-D model (pbrt's PiecewiseConstant2D, Mitsuba's envmap tables): nv
 * rows of nu values; the marginal over rows has the row integrals as its
 * function, and each row has its own conditional over u. The density with
 * respect to the unit square is
 *
 *     p(u, v) = p_marg(v) p_cond(u | v),
 *
 * written as a product (not as f / I_marg) so that an all-zero row, whose
 * conditional fell back to uniform, still has density 0: its marginal
 * weight is 0. Sampling uses u1 for the row (v) and u0 inside the row (u).
 */
#include "render/distribution.h"
#include "render/warp.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The largest double below 1: remapped samples must stay in [0,1). */
#define DISTRIB_ONE_MINUS_EPS (1.0 - DBL_EPSILON / 2.0)

/* The cutpoint table: guide[k] is the cell that contains u = k / n, found
 * by one walk over the cdf. A search for u starts at guide[floor(u n)] and
 * steps forward, so it finds the same cell as a binary search in an
 * expected O(1) steps (the cdf of a triangle mesh is too large for the
 * cache, and a binary search misses it at every step). */
static void distrib1d__build_guide(distrib1d *d) {
  int i = 0;
  for (int k = 0; k < d->n; k++) {
    double u = (double)k / d->n;
    while (i + 1 < d->n && d->cdf[i + 1] <= u) i++;
    d->guide[k] = i;
  }
}

lmc_status distrib1d_init(distrib1d *d, const double *f, int n, lmc_error *err) {
  d->n = 0;
  d->func = NULL;
  d->cdf = NULL;
  d->guide = NULL;
  d->integral = 0.0;
  if (n < 1) return lmc_error_set(err, LMC_EINVAL, NULL, 0, "distribution with %d cells", n);
  for (int i = 0; i < n; i++)
    if (!(f[i] >= 0.0) || !isfinite(f[i]))
      return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                           "distribution value %d is %g (must be finite and non-negative)", i,
                           f[i]);
  /* One block: func (n), cdf (n + 1), guide (n ints). */
  double *blk = malloc((2 * (size_t)n + 1) * sizeof(double) + (size_t)n * sizeof(int));
  if (!blk)
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for a distribution of %d cells",
                         n);
  d->func = blk;
  d->cdf = blk + n;
  d->guide = (int *)(blk + 2 * (size_t)n + 1);
  d->n = n;

  /* Running sum of f / n gives the unnormalised CDF. */
  double sum = 0.0;
  d->cdf[0] = 0.0;
  for (int i = 0; i < n; i++) {
    d->func[i] = f[i];
    sum += f[i] / n;
    d->cdf[i + 1] = sum;
  }

  /* An all-zero (or underflowing) function becomes uniform. */
  if (!(sum > 0.0) || !isfinite(sum)) {
    for (int i = 0; i < n; i++) {
      d->func[i] = 1.0;
      d->cdf[i] = (double)i / n;
    }
    d->cdf[n] = 1.0;
    d->integral = 1.0;
    distrib1d__build_guide(d);
    return LMC_OK;
  }

  /* Normalise; pin the end (and trailing empty cells) to exactly 1. */
  d->integral = sum;
  for (int i = 1; i < n; i++) d->cdf[i] /= sum;
  d->cdf[n] = 1.0;
  for (int i = n - 1; i > 0 && d->func[i] == 0.0; i--) d->cdf[i] = 1.0;
  distrib1d__build_guide(d);
  return LMC_OK;
}

void distrib1d_free(distrib1d *d) {
  if (!d) return;
  free(d->func); /* the block */
  memset(d, 0, sizeof *d);
}

/* The cell i in [0, n-1] with cdf[i] <= u < cdf[i+1] (the largest i with
 * cdf[i] <= u, so zero-width cells are skipped). */
static int distrib1d__find(const distrib1d *d, double u) {
  int k = (int)(u * d->n);
  if (k < 0) k = 0;
  if (k >= d->n) k = d->n - 1;
  int i = d->guide[k];
  while (i > 0 && d->cdf[i] > u) i--; /* u * n rounded up to k */
  while (i + 1 < d->n && d->cdf[i + 1] <= u) i++;
  return i;
}

double distrib1d_sample_cont(const distrib1d *d, double u, double *pdf, int *index) {
  int i = distrib1d__find(d, u);
  /* Position inside the cell: the fraction of its CDF rise below u. */
  double width = d->cdf[i + 1] - d->cdf[i];
  double du = width > 0.0 ? (u - d->cdf[i]) / width : 0.0;
  if (du < 0.0) du = 0.0;
  if (du > DISTRIB_ONE_MINUS_EPS) du = DISTRIB_ONE_MINUS_EPS;
  if (pdf) *pdf = d->func[i] / d->integral;
  if (index) *index = i;
  double x = (i + du) / d->n;
  return x < 1.0 ? x : DISTRIB_ONE_MINUS_EPS;
}

int distrib1d_sample_discrete(const distrib1d *d, double u, double *pmf, double *u_remap) {
  int i = distrib1d__find(d, u);
  double width = d->cdf[i + 1] - d->cdf[i];
  if (pmf) *pmf = width > 0.0 ? d->func[i] / (d->integral * d->n) : 0.0;
  if (u_remap) {
    double r = width > 0.0 ? (u - d->cdf[i]) / width : 0.0;
    if (r < 0.0) r = 0.0;
    if (r > DISTRIB_ONE_MINUS_EPS) r = DISTRIB_ONE_MINUS_EPS;
    *u_remap = r;
  }
  return i;
}

double distrib1d_invert_discrete(const distrib1d *d, int index, double u_remap) {
  if (index < 0 || index >= d->n) return -1.0;
  double lo = d->cdf[index], hi = d->cdf[index + 1];
  if (!(hi > lo)) return -1.0;
  return warp_uniform_in(lo, hi, u_remap);
}

double distrib1d_pmf(const distrib1d *d, int index) {
  if (index < 0 || index >= d->n) return 0.0;
  return d->func[index] / (d->integral * d->n);
}

/* Cell of x in [0,1), clamped to [0, n-1]. */
static int distrib1d__cell(const distrib1d *d, double x) {
  double t = floor(x * d->n);
  if (!(t >= 0.0)) return 0;
  if (t > d->n - 1) return d->n - 1;
  return (int)t;
}

double distrib1d_pdf_cont(const distrib1d *d, double x) {
  if (!(x >= 0.0 && x <= 1.0)) return 0.0;
  return d->func[distrib1d__cell(d, x)] / d->integral;
}

double distrib1d_invert_cont(const distrib1d *d, double x) {
  if (!(x > 0.0)) return 0.0;
  if (x >= 1.0) return 1.0;
  int i = distrib1d__cell(d, x);
  /* u = cdf[i] + (x n - i) (cdf[i+1] - cdf[i]) */
  double t = x * d->n - i;
  return d->cdf[i] + t * (d->cdf[i + 1] - d->cdf[i]);
}

lmc_status distrib2d_init(distrib2d *d, const double *f, int nu, int nv, lmc_error *err) {
  d->nu = 0;
  d->nv = 0;
  d->conditional = NULL;
  d->marginal.n = 0;
  d->marginal.func = d->marginal.cdf = NULL;
  if (nu < 1 || nv < 1)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "2-D distribution of %d x %d cells", nu, nv);
  d->conditional = calloc((size_t)nv, sizeof(distrib1d));
  double *row_integral = malloc((size_t)nv * sizeof(double));
  if (!d->conditional || !row_integral) {
    free(d->conditional);
    free(row_integral);
    d->conditional = NULL;
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for a %d x %d distribution", nu,
                         nv);
  }
  d->nu = nu;
  d->nv = nv;

  /* One conditional per row; the marginal weighs rows by their integral
   * (taken from f itself, before any uniform fallback of the row). */
  lmc_status st = LMC_OK;
  for (int j = 0; j < nv; j++) {
    const double *row = f + (size_t)j * (size_t)nu;
    st = distrib1d_init(&d->conditional[j], row, nu, err);
    if (st) break;
    double s = 0.0;
    for (int i = 0; i < nu; i++) s += row[i] / nu;
    row_integral[j] = s;
  }
  if (!st) st = distrib1d_init(&d->marginal, row_integral, nv, err);
  free(row_integral);
  if (st) {
    distrib2d_free(d);
    return st;
  }
  return LMC_OK;
}

void distrib2d_free(distrib2d *d) {
  if (!d) return;
  if (d->conditional)
    for (int j = 0; j < d->nv; j++) distrib1d_free(&d->conditional[j]);
  free(d->conditional);
  d->conditional = NULL;
  distrib1d_free(&d->marginal);
  d->nu = d->nv = 0;
}

void distrib2d_sample(const distrib2d *d, double u0, double u1, double out[2], double *pdf) {
  /* Choose the row with u1, then the position inside it with u0. */
  double pdf_v, pdf_u;
  int row;
  out[1] = distrib1d_sample_cont(&d->marginal, u1, &pdf_v, &row);
  out[0] = distrib1d_sample_cont(&d->conditional[row], u0, &pdf_u, NULL);
  if (pdf) *pdf = pdf_v * pdf_u;
}

double distrib2d_pdf(const distrib2d *d, double u, double v) {
  if (!(u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0)) return 0.0;
  int row = distrib1d__cell(&d->marginal, v);
  return distrib1d_pdf_cont(&d->marginal, v) * distrib1d_pdf_cont(&d->conditional[row], u);
}

void distrib2d_invert(const distrib2d *d, double u, double v, double out[2]) {
  int row = distrib1d__cell(&d->marginal, v);
  out[1] = distrib1d_invert_cont(&d->marginal, v);
  out[0] = distrib1d_invert_cont(&d->conditional[row], u);
}
