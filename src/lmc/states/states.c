/*
 * states.c: helpers of the primary-sample state spaces that several MCMC
 * integrators share (states.h).
 */
#include "lmc/states/states.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* The small-step factor for the coordinate that picks an area light's
 * triangle (mmlt, pssmlt and lmc). light_sample_le and light_sample_li choose the triangle
 * with their first position number u1 and reuse u1 inside its cell, so
 * d(point)/d(u1) grows with the triangle count: on the 16384-triangle
 * sphere light of ring-caustics a step of 1/1024 moves the point about 60
 * degrees round the sphere and, through the new normal's frame, the
 * emitted direction anywhere (of light-tracing proposals that touch only
 * u1 by 0.003, 99.5% of the f-weight came back black). Scaling that
 * coordinate's steps by 1 / (largest triangle count of an area light)
 * keeps them within about a cell; larger moves of the point are left to
 * large steps. 1 when no area light has more than one triangle. */
double mc_light_u1_scale(const scene *s) {
  int64_t n_max = 1;
  for (int i = 0; i < s->n_lights; i++) {
    const light *l = &s->lights[i];
    if (l->type != LIGHT_AREA || l->mesh < 0) continue;
    int64_t n = s->meshes[l->mesh].n_triangles;
    if (n > n_max) n_max = n;
  }
  return 1.0 / (double)n_max;
}

void mc_pt_step_scale(const scene *s, int dim, int media, double *OUT_scale) {
  double u1_scale = mc_light_u1_scale(s);
  int lead = media ? PT_DIMS_MEDIA : 0;
  for (int i = 0; i < dim; i++) OUT_scale[i] = 1.0;
  for (int i = PT_DIMS_CAMERA + lead + 1; i < dim; i += PT_DIMS_PER_BOUNCE + lead)
    OUT_scale[i] = u1_scale;
}

rgb mc_mmlt_contribution(const scene *s, const render_settings *rs, int k, int n, double margin,
                         double area, lmc_sampler *smp, bdpt_vertex *cam, bdpt_vertex *lp,
                         render_counters *cnt, double *OUT_rx, double *OUT_ry) {
  /* The strategy (s, t) from the technique coordinate, and the light sample
   * of s = 1. */
  sampler_use_stream(smp, LMC_STREAM_CONNECT);
  int idx = (int)(sampler_next(smp) * n);
  if (idx >= n) idx = n - 1;
  int tt = k == 1 ? 2 : idx + 1, ss = k + 1 - tt;
  double uc[BDPT_DIMS_CONNECT];
  for (int i = 0; i < BDPT_DIMS_CONNECT; i++) uc[i] = sampler_next(smp);

  /* The two subpaths, just long enough for (s, t). */
  sampler_use_stream(smp, LMC_STREAM_CAMERA);
  double u0 = sampler_next(smp), u1 = sampler_next(smp);
  double rx = -margin + u0 * (s->cam.width + 2.0 * margin);
  double ry = -margin + u1 * (s->cam.height + 2.0 * margin);
  *OUT_rx = rx, *OUT_ry = ry;
  int nc = bdpt_camera_subpath(s, rs, smp, rx, ry, tt, cam, cnt);
  if (nc < tt) return rgb_zero();
  if (ss > 0) {
    sampler_use_stream(smp, LMC_STREAM_LIGHT);
    int nl = bdpt_light_subpath(s, rs, smp, ss, lp, cnt);
    if (nl < ss) return rgb_zero();
  }

  return mc_mmlt_connect(s, cam, tt, lp, ss, uc, n, area, cnt, OUT_rx, OUT_ry);
}

rgb mc_mmlt_connect(const scene *s, const bdpt_vertex *cam, int tt, const bdpt_vertex *lp,
                    int ss, const double *uc, int n, double area, render_counters *cnt,
                    double *IO_rx, double *IO_ry) {
  /* The strategy's MIS-weighted contribution, times n_k. */
  double prx = *IO_rx, pry = *IO_ry;
  rgb c = bdpt_connect(s, cam, tt, lp, ss, uc, &prx, &pry, NULL, cnt);
  if (tt != 1) return rgb_scale(c, area * n);
  *IO_rx = prx, *IO_ry = pry;
  return rgb_scale(c, (double)n);
}

double mc_mmlt_expected(const scene *s, const render_settings *rs, int k, double margin,
                        double area, lmc_sampler *smp, bdpt_vertex *cam, bdpt_vertex *lp,
                        render_counters *cnt) {
  sampler_use_stream(smp, LMC_STREAM_CONNECT);
  (void)sampler_next(smp); /* the technique */
  double uc[BDPT_DIMS_CONNECT];
  for (int i = 0; i < BDPT_DIMS_CONNECT; i++) uc[i] = sampler_next(smp);
  /* Subpaths long enough for every strategy (their prefixes are those of
   * the shorter ones: the streams' layout is per vertex). */
  sampler_use_stream(smp, LMC_STREAM_CAMERA);
  double u0 = sampler_next(smp), u1 = sampler_next(smp);
  double rx = -margin + u0 * (s->cam.width + 2.0 * margin);
  double ry = -margin + u1 * (s->cam.height + 2.0 * margin);
  int t_max = k + 1, s_max = k == 1 ? 0 : k;
  int nc = bdpt_camera_subpath(s, rs, smp, rx, ry, t_max, cam, cnt);
  int nl = 0;
  if (s_max > 0) {
    sampler_use_stream(smp, LMC_STREAM_LIGHT);
    nl = bdpt_light_subpath(s, rs, smp, s_max, lp, cnt);
  }
  double sum = 0.0;
  for (int tt = k == 1 ? 2 : 1; tt <= t_max; tt++) {
    int ss = k + 1 - tt;
    if (nc < tt || nl < ss) continue;
    double prx = rx, pry = ry;
    rgb c = bdpt_connect(s, cam, tt, lp, ss, uc, &prx, &pry, NULL, cnt);
    if (tt != 1) c = rgb_scale(c, area);
    double f = rgb_luminance(c);
    if (rgb_isfinite(c) && f > 0.0 && isfinite(f)) sum += f;
  }
  return sum;
}


/* --- the chains' scratch ---------------------------------------------------- */

static void *states__scratch_create(const mc_target *t) {
  (void)t;
  return calloc(1, sizeof(mc_states_scratch));
}

static void states__scratch_destroy(void *scratch) {
  mc_states_scratch *sc = scratch;
  if (!sc) return;
  path_scratch_destroy(sc->ps);
  free(sc);
}

static int64_t states__scratch_rays(const void *scratch) {
  const mc_states_scratch *sc = scratch;
  return sc->cnt.rays + sc->rays_d;
}

static void states__scratch_counts(const void *scratch, mc_counts *OUT) {
  const mc_states_scratch *sc = scratch;
  OUT->grad_evals += sc->counts.grad_evals;
  OUT->hess_evals += sc->counts.hess_evals;
  OUT->nan_samples += sc->counts.nan_samples + sc->cnt.nan_samples;
}

static void *states__workspace_create(const mc_target *t) {
  (void)t;
  path_scratch *ps = NULL;
  lmc_error err;
  return path_scratch_create(&ps, &err) == LMC_OK ? ps : NULL;
}

static void states__workspace_destroy(void *ws) { path_scratch_destroy(ws); }

static void states__scratch_bind(void *scratch, void *ws) {
  ((mc_states_scratch *)scratch)->bound = ws;
}

void mc_states_use_scratch(mc_target *T) {
  T->scratch_create = states__scratch_create;
  T->scratch_destroy = states__scratch_destroy;
  T->scratch_rays = states__scratch_rays;
  T->scratch_counts = states__scratch_counts;
  T->workspace_create = states__workspace_create;
  T->workspace_destroy = states__workspace_destroy;
  T->scratch_bind = states__scratch_bind;
}

path_scratch *mc_states_scratch_path(mc_states_scratch *sc) {
  if (sc->bound) return sc->bound;
  if (!sc->ps) {
    lmc_error err;
    if (path_scratch_create(&sc->ps, &err) != LMC_OK) return NULL;
  }
  return sc->ps;
}

double mc_states_value(mc_value *v, rgb c, double rx, double ry, int64_t *nan_samples) {
  v->rx = rx;
  v->ry = ry;
  if (!rgb_isfinite(c)) {
    (*nan_samples)++;
    c = rgb_zero();
  }
  double f = rgb_luminance(c);
  if (!(f > 0.0) || !isfinite(f)) {
    f = 0.0;
    c = rgb_zero();
  }
  v->value = c;
  v->f = v->f_large = f;
  return f;
}

int mc_states_hessian(const path_eval *pe, int nd, const int *coord, const double *m,
                      double scale, int *OUT_hn, int *OUT_hidx, double *OUT_hess) {
  int keep[MC_HESS_MAX], hn = 0;
  for (int j = 0; j < nd && j < MC_HESS_MAX; j++)
    if (coord[j] >= 0) keep[hn] = j, OUT_hidx[hn++] = coord[j];
  int q = 0;
  for (int x = 0; x < hn; x++)
    for (int y = x; y < hn; y++) {
      int ja = keep[x], jb = keep[y];
      double h = pe->hlum[(size_t)ja * nd - (size_t)ja * (size_t)(ja - 1) / 2 + (size_t)(jb - ja)];
      h *= scale * m[ja] * m[jb];
      if (!isfinite(h)) return 0;
      OUT_hess[q++] = h;
    }
  *OUT_hn = hn;
  return 1;
}

/* --- the film adapter ----------------------------------------------------- */

static double states__adapter_next(lmc_sampler *self) {
  mc_film_adapter *a = (mc_film_adapter *)self;
  int p = a->pos[a->stream]++;
  if (a->stream == LMC_STREAM_CONNECT && p < a->skip) return 0.5; /* drawn and unused */
  double u = sampler_next(a->inner);
  if (a->stream == LMC_STREAM_CAMERA && p < 2)
    return p == 0 ? (-a->r + u * (a->W + 2.0 * a->r)) / a->W : (-a->r + u * (a->H + 2.0 * a->r)) / a->H;
  return u;
}

static void states__adapter_use_stream(lmc_sampler *self, int stream) {
  mc_film_adapter *a = (mc_film_adapter *)self;
  a->stream = stream;
  sampler_use_stream(a->inner, stream);
}

void mc_film_adapter_init(mc_film_adapter *a, lmc_sampler *inner, int stream, int skip, double r,
                          double W, double H) {
  memset(a, 0, sizeof *a);
  a->base.next = states__adapter_next;
  a->base.use_stream = states__adapter_use_stream;
  a->inner = inner;
  a->stream = stream;
  a->skip = skip;
  a->r = r, a->W = W, a->H = H;
}

double mc_film_adapter_factor(const mc_film_adapter *a, int k, int pos) {
  if (k != LMC_STREAM_CAMERA || pos >= 2) return 1.0;
  return pos == 0 ? (a->W + 2.0 * a->r) / a->W : (a->H + 2.0 * a->r) / a->H;
}
