/*
 * distribution.h: piecewise-constant distributions in 1 and 2 dimensions,
 * each with sample, pdf and invert (the inverse of sample), as pbrt's
 * PiecewiseConstant1D/2D. Used for area-light triangles, light selection
 * and environment-map importance sampling.
 *
 * A 1-D distribution over n cells of [0,1): pdf(x) = f[i] / (integral),
 * i = floor(x * n). When all f are zero it falls back to uniform.
 */
#ifndef LMC_RENDER_DISTRIBUTION_H
#define LMC_RENDER_DISTRIBUTION_H

#include "render/error.h"

typedef struct distrib1d {
  int n;
  double *func; /* n values (non-negative) */
  double *cdf;  /* n + 1 values, cdf[0] = 0, cdf[n] = 1 */
  double integral; /* sum(func) / n */
  int *guide;      /* n cutpoints: guide[k] = the cell of u = k / n (Chen and Asau 1974) */
} distrib1d;

lmc_status distrib1d_init(distrib1d *d, const double *f, int n, lmc_error *err);
void distrib1d_free(distrib1d *d);
/* Continuous sample in [0,1); *pdf is the density, *index the cell. */
double distrib1d_sample_cont(const distrib1d *d, double u, double *pdf, int *index);
/* Discrete sample of a cell with probability func[i] / sum; *pmf is that probability.
 * *u_remap (may be NULL) is u rescaled to [0,1) inside the chosen cell. */
int distrib1d_sample_discrete(const distrib1d *d, double u, double *pmf, double *u_remap);
double distrib1d_pmf(const distrib1d *d, int index);
/* The inverse of sample_discrete: the u that picks cell index with
 * *u_remap = u_remap (u_remap in [0, 1)); -1 when the cell has probability 0. */
double distrib1d_invert_discrete(const distrib1d *d, int index, double u_remap);
double distrib1d_pdf_cont(const distrib1d *d, double x);
/* The u that sample_cont maps to x. */
double distrib1d_invert_cont(const distrib1d *d, double x);

typedef struct distrib2d {
  int nu, nv;
  distrib1d *conditional; /* nv rows, each over u */
  distrib1d marginal;     /* over v */
} distrib2d;

/* f has nv rows of nu values. */
lmc_status distrib2d_init(distrib2d *d, const double *f, int nu, int nv, lmc_error *err);
void distrib2d_free(distrib2d *d);
/* Sample (u, v) in [0,1)^2 with density *pdf (with respect to the unit square). */
void distrib2d_sample(const distrib2d *d, double u0, double u1, double out[2], double *pdf);
double distrib2d_pdf(const distrib2d *d, double u, double v);
void distrib2d_invert(const distrib2d *d, double u, double v, double out[2]);

#endif
