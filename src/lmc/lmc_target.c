/*
 * lmc_target.c: the scene as an mc_target for LMC: path_eval_pt
 * (render/path.h) over the camera stream, with the gradient of the
 * luminance of its contribution per primary sample coordinate.
 *
 * f(u) = W H lum(L(u)): the film position (coordinates 0, 1) is uniform
 * over [0, W) x [0, H) (path.h), so W H L(u) is an unbiased estimate of
 * the whole image's sum. With a box filter (radius 1/2) every splat lands
 * in its own pixel; a wider filter would lose the parts of border splats
 * that fall off the film (pssmlt grows its film by the filter radius;
 * path_eval_pt does not).
 *
 * The gradient: path_eval reports, for every number drawn, its stream,
 * position and d lum / du; the coordinate is stream_offset + position.
 * Numbers drawn past the stream's block have no coordinate of the state
 * (the chain gave them a fresh uniform, chain.h) and no gradient entry.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/integrator_lmc.h"
#include "render/path.h"

typedef struct lmc_target_scratch {
  path_scratch *ps;
  int64_t rays;
  int64_t grad_evals;
} lmc_target_scratch;

static void *lmc__scratch_create(const mc_target *t) {
  (void)t;
  lmc_target_scratch *sc = calloc(1, sizeof *sc);
  if (!sc) return NULL;
  lmc_error err;
  if (path_scratch_create(&sc->ps, &err) != LMC_OK) {
    free(sc);
    return NULL;
  }
  return sc;
}

static void lmc__scratch_destroy(void *scratch) {
  lmc_target_scratch *sc = scratch;
  if (!sc) return;
  path_scratch_destroy(sc->ps);
  free(sc);
}

static int64_t lmc__scratch_rays(const void *scratch) {
  return ((const lmc_target_scratch *)scratch)->rays;
}

int64_t lmc_target_scratch_grad_evals(const void *scratch) {
  return scratch ? ((const lmc_target_scratch *)scratch)->grad_evals : 0;
}

static int lmc__eval(const mc_target *t, void *scratch, lmc_sampler *smp, mc_value *OUT_value,
                     double *OUT_grad, int *OUT_grad_ok) {
  const lmc_scene_target *st = t->ctx;
  lmc_target_scratch *sc = scratch;
  sampler_use_stream(smp, LMC_STREAM_CAMERA);
  path_eval pe;
  if (path_eval_pt(st->s, &st->rs, smp, OUT_grad != NULL, sc->ps, &pe, &sc->rays) != LMC_OK)
    return -1;
  /* The contribution, scaled to an estimate of the image sum. */
  rgb c = rgb_scale(pe.value, st->area);
  double f = rgb_luminance(c);
  if (!rgb_isfinite(c) || !(f > 0.0) || !isfinite(f)) {
    c = rgb_zero();
    f = 0.0;
  }
  OUT_value->value = c;
  OUT_value->f = f;
  OUT_value->rx = pe.rx;
  OUT_value->ry = pe.ry;
  if (!OUT_grad) return 0;
  /* The gradient of f per coordinate of the state. */
  sc->grad_evals++;
  memset(OUT_grad, 0, (size_t)t->dim * sizeof(double));
  *OUT_grad_ok = 0;
  if (!(f > 0.0) || !pe.grad_ok) return 0;
  int ok = 0;
  for (int i = 0; i < pe.n_coords; i++) {
    const path_coord *pc = &pe.coords[i];
    if (!pc->diff || pc->stream < 0 || pc->stream >= LMC_STREAM_COUNT) continue;
    if (pc->pos >= t->stream_dim[pc->stream]) continue;
    int idx = mc_target_stream_offset(t, pc->stream) + pc->pos;
    double d = pc->dlum * st->area;
    if (!isfinite(d)) return 0; /* no usable gradient at this state */
    OUT_grad[idx] += d;
    ok = 1;
  }
  *OUT_grad_ok = ok;
  return 0;
}

void lmc_target_init(mc_target *OUT_target, lmc_scene_target *ctx, const scene *s,
                     const render_settings *rs, int unbounded) {
  memset(OUT_target, 0, sizeof *OUT_target);
  ctx->s = s;
  ctx->rs = *rs;
  ctx->area = (double)s->cam.width * (double)s->cam.height;
  int bounces = rs->maxdepth >= 0 ? rs->maxdepth : unbounded;
  OUT_target->stream_dim[LMC_STREAM_CAMERA] = PT_DIMS_CAMERA + PT_DIMS_PER_BOUNCE * (bounces + 1);
  OUT_target->dim = OUT_target->stream_dim[LMC_STREAM_CAMERA];
  OUT_target->ctx = ctx;
  OUT_target->eval = lmc__eval;
  OUT_target->scratch_create = lmc__scratch_create;
  OUT_target->scratch_destroy = lmc__scratch_destroy;
  OUT_target->scratch_rays = lmc__scratch_rays;
}

int lmc_target_length_of_key(int key) {
  if (key <= PT_DIMS_CAMERA) return 1;
  return (key - 1 - PT_DIMS_CAMERA) / PT_DIMS_PER_BOUNCE + 2;
}
