/*
 * mut_lenssub.c: Veach's lens subpath mutation (Veach 1997, section
 * 11.4.4); mut_lenssub.h states the move and its density. The walk is
 * done here one vertex at a time (mut_perturb_trace), choosing each
 * vertex's lobe kind first: smooth (stop) with P_smooth, else one of its
 * delta lobes with that lobe's probability, which is what pathspace.c's
 * camera-side density of the next vertex carries.
 */
#include "lmc/path/mut_lenssub.h"

#include <math.h>
#include <string.h>

#include "lmc/path/mut_perturb.h"

void mut_lenssub_init(mut_lenssub *ml, const ps_context *ctx) {
  ml->ctx = ctx;
  ml->test_smooth_power = 1.0;
}

int mut_lenssub_m(const ps_context *ctx, const ps_path *x) {
  int k = x->k, m = 1;
  while (m < k && (!ps_connectible(x, m) || ps_glossy(ctx, x, m))) m++;
  if (m >= k || !ps_connectible(x, m + 1)) return 0;
  return m;
}

/* The delta lobes of surface vertex v from wo (unit, world): their
 * directions and probabilities (at most two distinct: lmc's delta models
 * pick their lobe by u_lobe against a threshold, pathspace.c). */
static int ml__delta_lobes(const bdpt_vertex *v, vec3 wo, vec3 OUT_dir[2], double OUT_prob[2]) {
  const surface_hit *h = &v->hit;
  vec3 wo_l = frame_to_local(&h->sh, wo);
  if (!(v3_dot(wo, h->ng) * wo_l.z > 0.0)) return -1;
  static const double u_lobes[2] = {0.0, 1.0 - 1e-9};
  int n = 0;
  for (int j = 0; j < 2; j++) {
    bsdf_sample bs;
    if (!bsdf_sample_f(h->bsdf, h->tu, h->tv, wo_l, u_lobes[j], 0.5, 0.5, TRANSPORT_RADIANCE, &bs))
      continue;
    if (!(bs.flags & BSDF_DELTA) || !(bs.pdf > 0.0)) continue;
    vec3 wi = v3_normalize(frame_to_world(&h->sh, bs.wi));
    if (n == 1 && v3_len2(v3_sub(wi, OUT_dir[0])) < 1e-12) continue;
    OUT_dir[n] = wi;
    OUT_prob[n++] = bs.pdf;
  }
  return n;
}

double mut_lenssub_smooth_prob(const bdpt_vertex *v, vec3 wo) {
  vec3 dir[2];
  double prob[2];
  int n = ml__delta_lobes(v, wo, dir, prob);
  if (n < 0) return 0.0;
  double p = 1.0;
  for (int j = 0; j < n; j++) p -= prob[j];
  return p > 0.0 ? p : 0.0;
}

double mut_lenssub_density(const mut_lenssub *ml, const ps_path *p) {
  int m = mut_lenssub_m(ml->ctx, p);
  if (m == 0) return 0.0;
  double d = 1.0;
  for (int i = 1; i <= m; i++) d *= p->x[i].pdf_cam;
  double ps = mut_lenssub_smooth_prob(&p->x[m].v, ps_dir(p, m, m - 1));
  return d * (ml->test_smooth_power == 1.0 ? ps : pow(ps, ml->test_smooth_power));
}

/* The new lens subpath into v[0 .. *OUT_m] (at most mmax surface
 * vertices); 0 when the walk leaves the scene or runs too long. */
static int ml__walk(const ps_context *ctx, rng *r, int mmax, bdpt_vertex *v, int *OUT_m,
                    int64_t *rays) {
  const camera *cam = &ctx->sc->cam;
  double rx = rng_uniform(r) * cam->width, ry = rng_uniform(r) * cam->height;
  if (!mut_perturb_first_hit(ctx, rx, ry, &v[0], &v[1], rays)) return 0;
  for (int i = 1;; i++) {
    vec3 wo = v3_normalize(v3_sub(v[i - 1].p, v[i].p)), dir[2];
    double prob[2];
    if (ps_glossy_vertex(ctx, &v[i])) {
      /* A G vertex: on through its BSDF's sample. */
      if (i + 1 > mmax || !mut_perturb_sample_dir(&v[i], wo, TRANSPORT_RADIANCE, r, &dir[0]))
        return 0;
      v[i].delta = 0;
      if (!mut_perturb_trace(ctx, &v[i], dir[0], TRANSPORT_RADIANCE, &v[i + 1], rays)) return 0;
      continue;
    }
    int n = ml__delta_lobes(&v[i], wo, dir, prob);
    if (n < 0) return 0;
    double u = rng_uniform(r), ps = 1.0;
    for (int j = 0; j < n; j++) ps -= prob[j];
    if (u < ps) {
      v[i].delta = 0;
      *OUT_m = i;
      return 1;
    }
    /* A delta lobe, in proportion to its probability. */
    int j = n > 1 && u >= ps + prob[0] ? 1 : 0;
    if (i + 1 > mmax) return 0;
    v[i].delta = 1;
    if (!mut_perturb_trace(ctx, &v[i], dir[j], TRANSPORT_RADIANCE, &v[i + 1], rays)) return 0;
  }
}

int mut_lenssub_propose(const mut_lenssub *ml, rng *r, const ps_path *x, ps_path *OUT_y,
                        double *OUT_ratio, int64_t *rays) {
  const ps_context *ctx = ml->ctx;
  *OUT_ratio = 0.0;
  int m = mut_lenssub_m(ctx, x), k = x->k;
  if (m == 0) return 0;
  int mmax = ctx->kmax - (k - m), m2;
  bdpt_vertex v[PS_MAX_VERTICES];
  if (mmax < 1 || !ml__walk(ctx, r, mmax, v, &m2, rays)) return 0;
  int k2 = k - m + m2;
  if (k2 < ctx->kmin || k2 > ctx->kmax) return 0;
  ps_path *y = OUT_y;
  y->k = k2;
  for (int i = 0; i <= m2; i++) y->x[i].v = v[i];
  for (int i = m + 1; i <= k; i++) y->x[i - m + m2] = x->x[i];
  ps_eval(ctx, y);
  if (mut_lenssub_m(ctx, y) != m2) return 0; /* (not reachable back: no proposal) */
  if (rays) (*rays)++;
  if (ps_edge_blocked(ctx, y, m2)) {
    y->f = rgb_zero();
    y->lum = 0.0;
  }
  double t_fwd = mut_lenssub_density(ml, y);
  if (!(t_fwd > 0.0)) return 0;
  if (!(y->lum > 0.0) || !(x->lum > 0.0)) return 1;
  double ratio = y->lum * mut_lenssub_density(ml, x) / (x->lum * t_fwd);
  *OUT_ratio = isfinite(ratio) ? ratio : 0.0;
  return 1;
}
