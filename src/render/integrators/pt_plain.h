/*
 * pt_plain.h: the plain side of the path tracer's walk (pt_generic.h) for
 * integrator_pt.c (pt_li, the walk without media) and
 * integrator_pt_media.c (pt_li_media, through media): its context, and
 * the macros pt_generic.h asks for, on the sampler and Embree. Compiled
 * apart, the walk without media keeps none of the media's branches (a
 * tenth of pt's time on the Cornell box when they shared one function).
 * The includer defines PT_MEDIA_CODE first. Not a header: no include
 * guard; each of the two files includes it once.
 */
#include "render/integrators/integrator.h"

/* What pt_li's walk reads: the scene, the settings, the sampler (r: its
 * inline independent stream, or NULL), the counters, and the camera ray's
 * differentials (or NULL) with room for the first hit's filtered BSDF. */
typedef struct pt__ctx {
  const scene *s;
  const render_settings *rs;
  lmc_sampler *smp;
  rng *r;
  render_counters *cnt;
  const ray_diff *rd;
  bsdf filtered;
} pt__ctx;

/* The next number of the sampler: drawn inline for the independent sampler
 * (the same number, without the indirect call). */
static inline double pt__next(pt__ctx *c) {
  return c->r ? rng_uniform(c->r) : sampler_next(c->smp);
}

/* The camera hit h (from org) reads its filtered textures over its
 * footprint: h's BSDF becomes a copy that carries it. */
static void pt__footprint(pt__ctx *c, surface_hit *h, vec3 org) {
  tex_footprint fp;
  if (h->bsdf && bsdf_is_tex_filtered(h->bsdf) &&
      scene_tex_footprint(c->s, h, org, c->rd->dx, c->rd->dy, &fp))
    h->bsdf = bsdf_with_footprint(h->bsdf, &fp, &c->filtered);
}

/* The free flight of the walk (render_fly, its transmittance and density
 * unused here). */
static inline int pt__fly(pt__ctx *c, vec3 org, vec3 dir, double tmin, int *med, double u_ch,
                          double u_t, surface_hit *h, vec3 *vp, rgb *fw) {
  rgb T;
  double pdf;
  return render_fly(c->s, c->cnt, org, dir, tmin, med, u_ch, u_t, h, vp, &T, &pdf, fw);
}

#define R_DUAL 0
#include "render/real.h"
#define PT_CTX pt__ctx *c
#define PT_SCENE (c->s)
#define PT_RS (c->rs)
#define PT_ARENA
#define PT_HIT surface_hit
#define PT_LI light_li_sample
#define PT_INTERSECT(org, dir, tmin, h) render_trace(c->s, c->cnt, (org), (dir), (tmin), (h))
#define PT_BLOCKED(p, wi, lp, dist) render_blocked(c->s, c->cnt, (p), (wi), (lp), (dist))
#define PT_DRAW(diff) pt__next(c)
#define PT_TOPO(x) ((void)0)
#define PT_LE_INFINITE(l, dir, pdf) light_le_pdf_infinite((l), c->s, (dir), (pdf))
#define PT_PDF_INFINITE(l, dir, ref, pdf) (pdf)
#define PT_PDF_LI(l, ref, w, p, n) light_pdf_li((l), c->s, (ref), (w), (p), (n))
#define PT_SAMPLE_LI(l, ref, u1, u2, ls) light_sample_li((l), c->s, (ref), (u1), (u2), (ls))
#define PT_MIS(a, b) mis_power((a), (b))
#define PT_SCALE_C(col, w) rgb_scale((col), (w))
#define PT_ADD(L, beta, contrib, emit, lobes, length) ((L) = rgb_fma((L), (beta), (contrib)))
#define PT_RR_Q(beta, eta) fmin(0.95, rgb_max(beta) * (eta))
#define PT_LOBE(flags) 0u
#define PT_FOOTPRINT(h, depth, org) \
  ((depth) == 1 && c->rd ? pt__footprint(c, &(h), (org)) : (void)0)
#define PT_MEDIA_ON 1
#define PT_TRANSMIT(at, w, sample, cur, T) \
  render_transmittance(c->s, c->cnt, (at), (w), (sample).p, (sample).dist, (cur), (T))
#define PT_FLY(org, dir, tmin, med, u_ch, u_t, h, vp, fw) \
  pt__fly(c, (org), (dir), (tmin), (med), (u_ch), (u_t), (h), (vp), (fw))
#define PT_MEDIUM_AFTER(h, cur, dir) scene_medium_after(c->s, (h), (cur), (dir))
#include "render/integrators/pt_generic.h"

/* The walk along (org, dir). */
static rgb pt__li(const scene *s, const render_settings *rs, lmc_sampler *smp, vec3 org,
                  vec3 dir, const ray_diff *rd, render_counters *cnt) {
  pt__ctx c;
  c.s = s, c.rs = rs, c.smp = smp, c.r = sampler_indep_rng(smp), c.cnt = cnt;
  c.rd = rd;
  return pt__walk(&c, org, dir, NULL, NULL);
}
