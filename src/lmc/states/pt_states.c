/*
 * pt_states.c: the pt states (--states pt): a state is the camera stream
 * of pt_li (render/integrators/integrator.h), the unidirectional path tracer with
 * next-event estimation, as in Kelemen, Szirmay-Kalos, Antal and Csonka
 * 2002. One family over every length.
 *
 * Layout. The first two coordinates pick the raster point uniformly over
 * the film grown by the filter radius r, rx = -r + u0 (W + 2r) (so border
 * pixels get what filter importance sampling gives them in pt); the rest
 * drive the path tracer, PT_DIMS_PER_BOUNCE per bounce, for maxdepth
 * bounces or MC_PT_UNBOUNDED when the depth is unbounded (numbers drawn
 * past the block are fresh uniforms, chain.h). The contribution of a state
 * is A L(u), A = (W + 2r)(H + 2r), an estimate of the whole image; f is
 * its luminance.
 *
 * Derivatives. Without a gradient, f comes from pt_li; with one, from
 * path_eval_pt (render/integrators/path.h), the same estimator in duals (the same
 * value to rounding). path_eval_pt reads the film position as u W; a
 * sampler adapter hands it (-r + u (W + 2r)) / W, and the gradient of the
 * two film numbers gets the chain-rule factor (W + 2r) / W (and H's).
 * There is no Hessian on these states (h2mc refuses them).
 *
 * Step scales: next-event estimation's light-position number of every
 * bounce picks a light triangle (mc_pt_step_scale, states.h).
 *
 * Media: on a scene with participating media (unless rs.no_media) f comes
 * from pt_li_media, each bounce's numbers led by its flight's
 * PT_DIMS_MEDIA, and the gradient from path_eval_pt through them (the
 * flight's distance number u_t a continuous coordinate, its channel
 * number a discrete one).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/driver/space.h"
#include "lmc/states/states.h"
#include "render/integrators/path.h"

#define MC_PT_UNBOUNDED 16 /* bounces kept in the state when maxdepth is -1 */

typedef struct pts__ctx {
  const scene *s;
  render_settings rs;  /* depths as the chains render them */
  double margin, area; /* r, (W + 2r)(H + 2r) */
  double *step_scale;  /* owned */
  int media;           /* through the scene's media (pt_li_media, path_eval_pt's media walk) */
  int per_bounce;      /* numbers per bounce: PT_DIMS_PER_BOUNCE (+ PT_DIMS_MEDIA) */
  mc_space_family fam;
} pts__ctx;

typedef mc_states_scratch pts__scratch;

/* f with its gradient over the state's coordinates. */
static int pts__eval_grad(const mc_target *t, pts__scratch *sc, lmc_sampler *smp,
                          mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok) {
  const pts__ctx *st = t->ctx;
  path_scratch *ps = mc_states_scratch_path(sc);
  if (!ps) return -1;
  mc_film_adapter a;
  mc_film_adapter_init(&a, smp, LMC_STREAM_CAMERA, 0, st->margin, st->s->cam.width,
                       st->s->cam.height);
  path_eval pe;
  if (path_eval_pt(st->s, &st->rs, &a.base, 1, ps, &pe, &sc->rays_d) != LMC_OK) return -1;
  sc->counts.grad_evals++;
  double f = mc_states_value(OUT_value, rgb_scale(pe.value, st->area), pe.rx, pe.ry,
                             &sc->counts.nan_samples);
  memset(OUT_grad, 0, (size_t)t->dim * sizeof(double));
  if (!(f > 0.0) || !pe.grad_ok) return 0;
  int ok = 0;
  for (int i = 0; i < pe.n_coords; i++) {
    const path_coord *pc = &pe.coords[i];
    if (!pc->diff || pc->stream != LMC_STREAM_CAMERA || pc->pos >= t->dim) continue;
    double d = pc->dlum * st->area * mc_film_adapter_factor(&a, pc->stream, pc->pos);
    if (!isfinite(d)) return 0; /* no usable gradient at this state */
    OUT_grad[pc->pos] += d;
    ok = 1;
  }
  *OUT_grad_ok = ok;
  return 0;
}

static int pts__eval(const mc_target *t, void *scratch, lmc_sampler *smp, mc_value *OUT_value,
                     double *OUT_grad, int *OUT_grad_ok) {
  const pts__ctx *st = t->ctx;
  pts__scratch *sc = scratch;
  if (OUT_grad_ok) *OUT_grad_ok = 0;
  sampler_use_stream(smp, LMC_STREAM_CAMERA);
  if (OUT_grad) return pts__eval_grad(t, sc, smp, OUT_value, OUT_grad, OUT_grad_ok);
  /* f alone: pt_li in plain numbers. */
  double r = st->margin;
  double u0 = sampler_next(smp), u1 = sampler_next(smp);
  double rx = -r + u0 * (st->s->cam.width + 2.0 * r);
  double ry = -r + u1 * (st->s->cam.height + 2.0 * r);
  vec3 org, dir;
  camera_generate_ray(&st->s->cam, rx, ry, &org, &dir);
  rgb L = st->media ? pt_li_media(st->s, &st->rs, smp, org, dir, NULL, &sc->cnt)
                    : pt_li(st->s, &st->rs, smp, org, dir, NULL, &sc->cnt);
  mc_states_value(OUT_value, rgb_scale(L, st->area), rx, ry, &sc->cnt.nan_samples);
  return 0;
}

/* The path length of a state whose deepest differentiated coordinate is
 * `last`: its bounce + 2, or 1 for the film position. */
static int pts__length_of(const mc_space_family *F, int label, int last) {
  (void)label;
  const pts__ctx *c = F->target.ctx;
  if (last < 0) return -1;
  if (last < PT_DIMS_CAMERA) return 1;
  return (last - PT_DIMS_CAMERA) / c->per_bounce + 2;
}

static void pts__destroy(mc_space *sp) {
  pts__ctx *c = sp->ctx;
  if (c) free(c->step_scale);
  free(c);
}

lmc_status mc_space_pt_create(mc_space *OUT, const scene *s, const render_settings *rs,
                              lmc_error *err) {
  pts__ctx *c = calloc(1, sizeof *c);
  if (!c) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the pt states");
  c->s = s;
  c->rs = *rs;
  c->margin = s->filter.radius;
  c->area = (s->cam.width + 2.0 * c->margin) * (s->cam.height + 2.0 * c->margin);
  c->media = render_media_on(s, rs);
  c->per_bounce = PT_DIMS_PER_BOUNCE + (c->media ? PT_DIMS_MEDIA : 0);
  int bounces = rs->maxdepth >= 0 ? rs->maxdepth : MC_PT_UNBOUNDED;
  mc_target *T = &c->fam.target;
  T->stream_dim[LMC_STREAM_CAMERA] = PT_DIMS_CAMERA + c->per_bounce * (bounces + 1);
  T->dim = T->stream_dim[LMC_STREAM_CAMERA];
  T->ctx = c;
  T->eval = pts__eval;
  mc_states_use_scratch(T);
  c->step_scale = malloc((size_t)T->dim * sizeof(double));
  if (!c->step_scale) {
    free(c);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the pt states");
  }
  mc_pt_step_scale(s, T->dim, c->media, c->step_scale);
  T->step_scale = c->step_scale;
  c->fam.length = 0;
  c->fam.technique = -1;
  c->fam.length_of = pts__length_of;
  OUT->name = "pt";
  OUT->n_fam = 1;
  OUT->fam = &c->fam;
  OUT->kmin = rs->mindepth > 1 ? rs->mindepth : 1;
  OUT->kmax = rs->maxdepth;
  OUT->pool_large = 1;
  OUT->destroy = pts__destroy;
  OUT->ctx = c;
  return LMC_OK;
}
