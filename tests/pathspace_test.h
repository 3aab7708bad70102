/*
 * pathspace_test.h: what the tests of path-space MLT's states and moves
 * (test_pathspace.c, test_perturb.c) share: the path space of paths up
 * to kmax segments, relative closeness, and the check of a path's caches
 * against a fresh evaluation (their scenes, XML text, load with
 * load_scene.h's try_load_scene_text). Include after <cmocka.h>.
 */
#ifndef LMC_TESTS_PATHSPACE_TEST_H
#define LMC_TESTS_PATHSPACE_TEST_H

#include <math.h>
#include <stdio.h>

#include "chi2.h"
#include "lmc/path/pathspace.h"
#include "load_scene.h"
#include "render/io/io.h"

/* The path space of sc's paths of 1 .. kmax segments. */
static inline void ps_test_context(const scene *sc, int kmax, ps_context *ctx) {
  render_settings rs = sc->settings;
  rs.maxdepth = kmax;
  rs.mindepth = -1;
  ps_context_init(ctx, sc, &rs);
}

static inline int rel_close(double a, double b, double tol) {
  if (!isfinite(a) || !isfinite(b)) return 0;
  return fabs(a - b) <= tol * fmax(fabs(a), fabs(b)) || (a == 0.0 && b == 0.0);
}

static inline int rgb_close(rgb a, rgb b, double tol) {
  return rel_close(a.r, b.r, tol) && rel_close(a.g, b.g, tol) && rel_close(a.b, b.b, tol);
}

/* Whether every cache of y equals a fresh evaluation of a copy (tmp):
 * factors, geometry terms and densities to 1e-12, delta flags, the raster
 * point to 1e-9, f to 1e-9 (when not 0). Prints the first difference. */
static inline int ps_test_caches_fresh(const ps_context *ctx, const ps_path *y, ps_path *tmp) {
  *tmp = *y;
  ps_eval(ctx, tmp);
  for (int i = 0; i <= y->k; i++) {
    const ps_vertex *a = &y->x[i], *b = &tmp->x[i];
    int ok = rgb_close(a->fac, b->fac, 1e-12) && rel_close(a->g, b->g, 1e-12) &&
             rel_close(a->pdf_cam, b->pdf_cam, 1e-12) &&
             rel_close(a->pdf_light, b->pdf_light, 1e-12) && a->delta == b->delta;
    if (!ok) {
      fprintf(stderr,
              "vertex %d of %d: pdf_cam %.17g / %.17g, pdf_light %.17g / %.17g, g %.17g / %.17g\n",
              i, y->k, a->pdf_cam, b->pdf_cam, a->pdf_light, b->pdf_light, a->g, b->g);
      return 0;
    }
  }
  if (!(fabs(y->rx - tmp->rx) <= 1e-9 && fabs(y->ry - tmp->ry) <= 1e-9)) return 0;
  if (y->lum > 0.0 && !rgb_close(y->f, tmp->f, 1e-9)) {
    fprintf(stderr, "partial f %.17g, scratch %.17g\n", y->lum, tmp->lum);
    return 0;
  }
  return 1;
}

/* The one-step invariance test's statistic (test_pathspace.c states it):
 * per bin b, D_b = sum of w (1_b(y) - 1_b(x)) and V_b = sum of its
 * squares over the weighted samples x moved once to y; z_b^2 = D_b^2 / V_b
 * against chi^2(1), at the Sidak level for the bins with moves. */
#define PS_INV_MAX_BINS 512

typedef struct ps_inv {
  double D[PS_INV_MAX_BINS], V[PS_INV_MAX_BINS];
  double min_p; /* smallest p-value over the bins (ps_inv_finish) */
  double level; /* the Sidak level 1 - (1 - 1e-3)^(1 / bins) */
  int bins;     /* bins with moves */
  int samples;  /* samples counted (the caller's) */
  int moved;    /* samples whose bin changed */
} ps_inv;

/* One sample of weight w moved from bin b0 to bin b1. */
static inline void ps_inv_add(ps_inv *s, double w, int b0, int b1) {
  if (b0 == b1) return;
  s->moved++;
  s->D[b1] += w, s->D[b0] -= w;
  s->V[b1] += w * w, s->V[b0] += w * w;
}

/* The bin of path x among (length) x (a cols x rows grid of the raster):
 * the perturbations move paths by a few pixels. */
static inline int ps_inv_raster_bin(const scene *sc, const ps_path *x, int cols, int rows) {
  int cx = (int)(x->rx * cols / sc->cam.width), cy = (int)(x->ry * rows / sc->cam.height);
  cx = cx < 0 ? 0 : cx >= cols ? cols - 1 : cx;
  cy = cy < 0 ? 0 : cy >= rows ? rows - 1 : cy;
  return ((x->k - 1) * rows + cy) * cols + cx;
}

static inline void ps_inv_finish(ps_inv *s) {
  s->min_p = 1.0;
  s->bins = 0;
  for (int b = 0; b < PS_INV_MAX_BINS; b++) {
    if (!(s->V[b] > 0.0)) continue;
    s->bins++;
    double p = chi2_gamma_q(0.5, 0.5 * s->D[b] * s->D[b] / s->V[b]);
    if (p < s->min_p) s->min_p = p;
  }
  s->level = chi2_sidak(1e-3, s->bins > 0 ? s->bins : 1);
}

#endif
