/*
 * film.h: the film (accumulation buffers) and its reconstruction filter.
 *
 * Two buffers with separate normalisations:
 *  - `sum`/`count`: camera-ray estimates, each into the pixel it was taken
 *    for (the film position is drawn from the filter around the pixel
 *    centre, so no weights are needed: filter importance sampling). Pixel
 *    value = sum / count.
 *  - `splat`: contributions that land anywhere on the film (light tracing,
 *    MCMC), spread over nearby pixels with the filter's weights.
 *    Pixel value = splat * splat_scale.
 * The image is the sum of the two. Both are sums of doubles, merged in a
 * fixed order, so a render is repeatable.
 *
 * Filters (Mitsuba's rfilter): box (radius 0.5), tent (radius 1), gaussian
 * (stddev 0.5, truncated at 4 stddev), each normalised to integrate to one.
 */
#ifndef LMC_RENDER_FILM_H
#define LMC_RENDER_FILM_H

#include <stdint.h>

#include "render/error.h"
#include "render/image.h"
#include "render/vec3.h"

typedef enum filter_type { FILTER_BOX = 0, FILTER_TENT, FILTER_GAUSSIAN } filter_type;

#define FILTER_TABLE_SIZE 64

typedef struct film_filter {
  filter_type type;
  double radius;
  double stddev;
  /* gaussian: tabulated 1-D cdf for sampling */
  double cdf[FILTER_TABLE_SIZE + 1];
  double norm1d;
} film_filter;

void filter_init(film_filter *f, filter_type type);
/* Normalised 2-D weight at offset (dx, dy) from a pixel centre. */
double filter_eval(const film_filter *f, double dx, double dy);
/* Samples an offset with density filter_eval. */
void filter_sample(const film_filter *f, double u1, double u2, double *dx, double *dy);

/* A list of splats in the order they were made (render.c gives each row
 * of the image its own list and replays the lists in row order, so the
 * sums do not depend on which thread rendered which row). */
typedef struct film_splat_rec {
  double rx, ry;
  rgb v;
} film_splat_rec;
typedef struct film_splat_log {
  film_splat_rec *rec; /* owned */
  int64_t n, cap;
  int64_t lost;        /* splats that could not be recorded (out of memory) */
} film_splat_log;

typedef struct film {
  int width, height;
  double *sum;      /* 3 per pixel */
  double *count;    /* 1 per pixel */
  double *splat;    /* 3 per pixel */
  double splat_scale;
  film_splat_log *log; /* borrowed; when set, film_splat appends to it instead */
  /* The per-pixel standard error (film_error_init; NULL without): every
   * complete pass of pt or bdpt is an independent estimate of the image
   * (its camera sample of each pixel plus its light subpaths' splats), so
   * the sums of the passes' pixel values and of their squares give each
   * pixel's variance. pass_val holds the current pass's camera samples,
   * splat_prev the splats before it (3 per pixel each). */
  double *esum, *esum2, *pass_val, *splat_prev;
  double epasses; /* complete passes summed (a double: summed over ranks) */
  /* A variance to add to each value's (3 per pixel; NULL: none; owned):
   * the MCMC chains' part of the image, set by their driver (mcmc_error.c),
   * beside the direct pass's passes in esum. */
  double *evar;
} film;

lmc_status film_init(film *f, int width, int height, lmc_error *err);
void film_free(film *f);
void film_clear(film *f);
/* Adds a camera-ray estimate to pixel (x, y). */
static inline void film_add(film *f, int x, int y, rgb v) {
  double *s = f->sum + 3 * ((int64_t)y * f->width + x);
  s[0] += v.r;
  s[1] += v.g;
  s[2] += v.b;
  f->count[(int64_t)y * f->width + x] += 1.0;
}
/* Spreads v around raster point (rx, ry) with the filter's weights (or,
 * when f->log is set, appends the splat to the log). Non-finite v is ignored. */
void film_splat(film *f, const film_filter *filter, double rx, double ry, rgb v);
/* Splats every record of the log into f in order, then empties the log. */
void film_splat_log_replay(film *f, const film_filter *filter, film_splat_log *log);
void film_splat_log_free(film_splat_log *log);
/* dst += src (same size; the error's sums too when both have them). */
void film_merge(film *dst, const film *src);
/* Collective (dist.h): every rank's sum, count and splat buffers added in
 * rank order into rank 0's f (the others' f unchanged); splat_scale is
 * left to the caller. */
void film_sum_to_root(film *f);
/* Whether the film carries an error (film_error_init, or evar). */
static inline int film_has_error(const film *f) { return f->esum || f->evar; }
/* Adds the error's buffers to f (film.esum ...). */
lmc_status film_error_init(film *f, lmc_error *err);
/* The end of a complete pass whose camera samples are in f->pass_val:
 * each pixel's value in the pass, pass_val + (the pass's splats) *
 * splat_norm, added to the sums. */
void film_error_pass(film *f, double splat_norm);
/* The standard error of each pixel's value into `pixels` (width * height
 * * 3 floats): the variance of the passes' mean, s^2 / n with s^2 their
 * sample variance (infinity with fewer than two passes), plus evar when
 * set; infinity when the film has neither. */
void film_error_develop_to(const film *f, float *pixels);

/* The image: sum / count + splat * splat_scale (out is initialised here). */
lmc_status film_develop(const film *f, lmc_image *out, lmc_error *err);
/* The same pixels into `pixels` (room for width * height * 3 floats, caller's):
 * for a caller that develops the same film again and again. */
void film_develop_to(const film *f, float *pixels);

#endif
