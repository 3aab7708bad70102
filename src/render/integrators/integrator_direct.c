/*
 * integrator_direct.c: direct illumination only, Mitsuba 0.6's `direct`
 * integrator (src/integrators/direct/direct.cpp): the emitters the camera
 * sees, plus the light that reaches the first surface hit straight from an
 * emitter. In segments (integrator.h), the paths of length 1 and 2 and no
 * others: in expectation the image of pt with --maxdepth 2.
 *
 * At the camera ray's first hit x the light arriving straight from the
 * emitters is estimated by two strategies, each with its own count of
 * samples per pixel sample: n_L light samples (next-event estimation: an
 * emitter chosen by scene_sample_light, a direction by light_sample_li)
 * and n_B BSDF samples (a direction by bsdf_sample_f, traced to the
 * emitter it meets, if any). Multiple importance sampling (Veach and
 * Guibas 1995) joins them with the power heuristic over the sample counts,
 * as Mitsuba: a light sample with densities p_L (light) and p_B (BSDF) of
 * its direction is weighted
 *   w_L = (n_L p_L)^2 / ((n_L p_L)^2 + (n_B p_B)^2),
 * a BSDF sample symmetrically, and each strategy's sum is divided by its
 * own count: the estimate is
 *   sum_i w_L f Le |cos| / (n_L p_L) + sum_j w_B f Le |cos| / (n_B p_B).
 * A delta light (point, spot, directional) or a delta BSDF lobe has only
 * the one strategy that can make it: weight 1. With n_L = 0 the BSDF
 * samples have weight 1 alone, with n_B = 0 the light samples; both zero
 * is refused (direct_read_settings, and the loader).
 *
 * The rest follows pt (integrator_pt.c, pt_generic.h) line for line, so
 * the two agree in expectation, which tests/test_direct.c checks: the same
 * light choice and densities (light.c), the same BSDF evaluation and
 * sampling, Mitsuba's side rule for shading normals (a direction is used
 * only when the geometric and the shading frame put it on the same side:
 * Mitsuba's strictNormals, always on in lmc), the camera hit's filtered
 * textures read over its footprint, --mindepth and --maxdepth (0 or 1:
 * the emitters seen alone). No Russian roulette: the walk has no second
 * bounce.
 *
 * hideEmitters (--hide-emitters on) makes the emitters the camera sees
 * black, area lights and the environment alike (Mitsuba's; pt has no such
 * option); the light they send to surfaces stays. Mitsuba also hides the
 * environment behind its null BSDFs under hideEmitters; lmc's masks pass
 * light by a delta lobe of their own and are not singled out.
 *
 * Random numbers (stream LMC_STREAM_CAMERA, after the PT_DIMS_CAMERA for
 * the film position): per light sample 3 (light choice, point on the
 * light), then per BSDF sample 3 (lobe, direction), always taken, used or
 * not; sampler_layout_direct groups them for the Sobol sampler.
 */
#include <math.h>
#include <stddef.h>

#include "render/integrators/integrator.h"

static const direct_settings direct__defaults = {1, 1, 0};

static const lmc_opt direct__opts[] = {
    {"emitter-samples", LMC_OPT_INT, offsetof(direct_settings, emitter_samples), 0, 0, 4096,
     NULL, NULL, 0, "N", NULL,
     "light samples (next-event estimation) per pixel sample at the first hit (Mitsuba's "
     "emitterSamples)",
     NULL},
    {"bsdf-samples", LMC_OPT_INT, offsetof(direct_settings, bsdf_samples), 0, 0, 4096, NULL, NULL,
     0, "N", NULL,
     "BSDF samples per pixel sample at the first hit, joined with the light samples by MIS "
     "(Mitsuba's bsdfSamples; not both 0)",
     NULL},
    {"hide-emitters", LMC_OPT_CHOICE, offsetof(direct_settings, hide_emitters), 0, 0, 0,
     lmc_opt_off_on, NULL, 0, NULL, "off",
     "emitters seen directly by the camera are black; the light they cast stays (Mitsuba's "
     "hideEmitters)",
     NULL},
};

const lmc_opt_table direct_options = {"Direct illumination (--integrator direct)", direct__opts,
                                      (int)(sizeof direct__opts / sizeof direct__opts[0]),
                                      &direct__defaults, sizeof(direct_settings)};

/* The camera stream: the film pair, then groups of one (a light or lobe
 * choice) and two (a point on a light, a BSDF direction) in turn. */
const sampler_layout sampler_layout_direct = {
    .stream = {[LMC_STREAM_CAMERA] = {{2}, 1, {1, 2}, 2},
               [LMC_STREAM_LIGHT] = {{0}, 0, {2}, 1},
               [LMC_STREAM_CONNECT] = {{0}, 0, {2}, 1}}};

lmc_status direct_read_settings(const render_settings *rs, direct_settings *OUT,
                                lmc_error *err) {
  lmc_status st = lmc_opt_read(&direct_options, rs, OUT, err);
  if (st) return st;
  if (OUT->emitter_samples == 0 && OUT->bsdf_samples == 0)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                         "--integrator direct: --emitter-samples and --bsdf-samples are both 0 "
                         "(no strategy left to sample the light)");
  return LMC_OK;
}

/* What one estimate reads: the scene, the settings, the sampler (r: its
 * inline independent stream, or NULL) and the counters. */
typedef struct direct__ctx {
  const scene *s;
  const render_settings *rs;
  lmc_sampler *smp;
  rng *r;
  render_counters *cnt;
} direct__ctx;

static inline double direct__next(direct__ctx *c) {
  return c->r ? rng_uniform(c->r) : sampler_next(c->smp);
}


/* Whether paths of `length` segments are counted (--mindepth). */
static int direct__counts(const render_settings *rs, int length) {
  return rs->mindepth <= 0 || length >= rs->mindepth;
}

/* The light samples' sum at the hit h (wo_l: towards the camera, local),
 * each divided by n_L. */
static rgb direct__light_samples(direct__ctx *c, const direct_settings *ds, const surface_hit *h,
                                 vec3 wo_l) {
  const scene *s = c->s;
  const bsdf *b = h->bsdf;
  const int nl = ds->emitter_samples, nb = ds->bsdf_samples;
  const int can = !bsdf_is_delta(b) && s->n_lights > 0;
  rgb L = rgb_zero();
  for (int i = 0; i < nl; i++) {
    /* Take the sample's numbers, then choose a light and a point on it. */
    double u_light = direct__next(c), ul1 = direct__next(c), ul2 = direct__next(c);
    if (!can) continue;
    double pmf, u_rem;
    int li = scene_sample_light(s, u_light, &pmf, &u_rem);
    light_li_sample ls;
    if (li < 0 || !(pmf > 0.0) || !light_sample_li(&s->lights[li], s, h->p, ul1, ul2, &ls) ||
        !(ls.pdf > 0.0) || rgb_is_black(ls.li))
      continue;
    /* The BSDF there, on the side rule; then the shadow ray. */
    vec3 wi_l = frame_to_local(&h->sh, ls.wi);
    if (!(v3_dot(ls.wi, h->ng) * wi_l.z > 0.0)) continue;
    double pdf_b;
    rgb f = bsdf_eval_pdf(b, h->tu, h->tv, wo_l, wi_l, TRANSPORT_RADIANCE, &pdf_b);
    if (rgb_is_black(f) || render_blocked(c->s, c->cnt, h->p, ls.wi, ls.p, ls.dist)) continue;
    /* Weighted by the power heuristic over the counts. */
    double pdf_l = ls.pdf * pmf;
    double w = ls.delta ? 1.0 : mis_power((double)nl * pdf_l, (double)nb * pdf_b);
    L = rgb_add(L, rgb_scale(rgb_mul(f, ls.li), fabs(wi_l.z) * w / ((double)nl * pdf_l)));
  }
  return L;
}

/* The BSDF samples' sum at the hit h, each divided by n_B. */
static rgb direct__bsdf_samples(direct__ctx *c, const direct_settings *ds, const surface_hit *h,
                                vec3 wo_l) {
  const scene *s = c->s;
  const bsdf *b = h->bsdf;
  const int nl = ds->emitter_samples, nb = ds->bsdf_samples;
  rgb L = rgb_zero();
  for (int j = 0; j < nb; j++) {
    /* Sample a direction on the side rule. */
    double u_lobe = direct__next(c), ub1 = direct__next(c), ub2 = direct__next(c);
    bsdf_sample bs;
    if (!bsdf_sample_f(b, h->tu, h->tv, wo_l, u_lobe, ub1, ub2, TRANSPORT_RADIANCE, &bs)) continue;
    vec3 wi = frame_to_world(&h->sh, bs.wi);
    if (v3_dot(wi, h->ng) * bs.wi.z <= 0.0 || rgb_is_black(bs.weight)) continue;
    const int delta = (bs.flags & BSDF_DELTA) != 0;
    const double pdf_b = (double)nb * bs.pdf;

    /* Escaped: the infinite lights, each weighted against its own
     * light-sampling density. */
    surface_hit e;
    if (!render_trace(c->s, c->cnt, h->p, wi, scene_ray_eps(s, h->p), &e)) {
      for (int k = 0; k < s->n_infinite; k++) {
        int li = s->infinite_lights[k];
        double pdf_inf = 0.0;
        rgb le = light_le_pdf_infinite(&s->lights[li], s, wi, &pdf_inf);
        if (rgb_is_black(le)) continue;
        double w = delta ? 1.0 : mis_power(pdf_b, (double)nl * pdf_inf * scene_light_pmf(s, li));
        L = rgb_add(L, rgb_scale(rgb_mul(bs.weight, le), w / (double)nb));
      }
      continue;
    }

    /* Met an area light: its emission towards x. */
    if (e.light < 0) continue;
    const light *l = &s->lights[e.light];
    rgb le = light_le_area(l, e.ng, v3_neg(wi));
    if (rgb_is_black(le)) continue;
    double w = 1.0;
    if (!delta)
      w = mis_power(pdf_b, (double)nl * light_pdf_li(l, s, h->p, wi, e.p, e.ng) *
                               scene_light_pmf(s, e.light));
    L = rgb_add(L, rgb_scale(rgb_mul(bs.weight, le), w / (double)nb));
  }
  return L;
}

rgb direct_li(const scene *s, const render_settings *rs, const direct_settings *ds,
              lmc_sampler *smp, vec3 org, vec3 dir, const ray_diff *rd, render_counters *cnt) {
  direct__ctx c = {s, rs, smp, sampler_indep_rng(smp), cnt};
  rgb L = rgb_zero();
  const int seen = !ds->hide_emitters && direct__counts(rs, 1);

  /* The camera ray; on a miss, the infinite lights it sees. */
  surface_hit h;
  if (!render_trace(c.s, c.cnt, org, dir, 0.0, &h)) {
    for (int k = 0; seen && k < s->n_infinite; k++)
      L = rgb_add(L, light_le_infinite(&s->lights[s->infinite_lights[k]], dir));
    return L;
  }
  /* The camera hit reads its filtered textures over its footprint. */
  bsdf filtered;
  tex_footprint fp;
  if (rd && h.bsdf && bsdf_is_tex_filtered(h.bsdf) &&
      scene_tex_footprint(s, &h, org, rd->dx, rd->dy, &fp))
    h.bsdf = bsdf_with_footprint(h.bsdf, &fp, &filtered);
  vec3 wo = v3_neg(dir);

  /* An area light seen directly. */
  if (h.light >= 0 && seen) L = rgb_add(L, light_le_area(&s->lights[h.light], h.ng, wo));

  /* Direct light at the hit: paths of 2 segments, when counted and
   * allowed, and when shading and geometry agree on wo's side. */
  if ((rs->maxdepth >= 0 && rs->maxdepth < 2) || !direct__counts(rs, 2)) return L;
  vec3 wo_l = frame_to_local(&h.sh, wo);
  if (v3_dot(wo, h.ng) * wo_l.z <= 0.0) return L;
  L = rgb_add(L, direct__light_samples(&c, ds, &h, wo_l));
  return rgb_add(L, direct__bsdf_samples(&c, ds, &h, wo_l));
}
