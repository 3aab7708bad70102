/*
 * integrator_pt.c: unidirectional path tracing with next-event estimation
 * and multiple importance sampling (Veach and Guibas 1995, power
 * heuristic), for area and infinite lights alike; delta lights and delta
 * BSDF lobes bypass MIS. Russian roulette from rrdepth on, with survival
 * probability min(0.95, max(beta)), keeps the estimator unbiased.
 *
 * Shading normals: a direction is only used when it lies on the same side
 * of the geometric and the shading surface (Mitsuba's rule), so shading
 * normals cannot leak light through a surface.
 *
 * The random numbers follow the fixed layout of integrator.h.
 */
#include "render/integrators/integrator.h"

static int pt__counts(const render_settings *rs, int length) {
  return rs->mindepth <= 0 || length >= rs->mindepth;
}

/* The next number of smp, r = sampler_indep_rng(smp): drawn inline for the
 * independent sampler (the same number, without the indirect call). */
static inline double pt__next(lmc_sampler *smp, rng *r) {
  return r ? rng_uniform(r) : sampler_next(smp);
}

rgb pt_li(const scene *s, const render_settings *rs, lmc_sampler *smp, vec3 org, vec3 dir,
          render_counters *cnt) {
  rng *r = sampler_indep_rng(smp);
  rgb L = rgb_zero(), beta = rgb_gray(1.0);
  int prev_delta = 1;      /* the previous vertex was the camera or a delta lobe */
  double prev_pdf = 0.0;   /* solid-angle density of the previous BSDF sample */
  vec3 prev_p = org;
  double tmin = 0.0;
  double eta_scale = 1.0;

  for (int depth = 1;; depth++) {
    /* Find the next vertex; on a miss, add the infinite lights. */
    surface_hit h;
    cnt->rays++;
    ray_log_add(cnt, org, dir, tmin, INFINITY, 0);
    if (!scene_intersect(s, org, dir, tmin, INFINITY, &h)) {
      if (!pt__counts(rs, depth)) break;
      for (int k = 0; k < s->n_infinite; k++) {
        int li = s->infinite_lights[k];
        const light *l = &s->lights[li];
        double pdf_li; /* light_pdf_li of dir, for the MIS weight */
        rgb le = light_le_pdf_infinite(l, s, dir, &pdf_li);
        if (rgb_is_black(le)) continue;
        double w = 1.0;
        if (!prev_delta) {
          double pdf_l = scene_light_pmf(s, li) * pdf_li;
          w = mis_power(prev_pdf, pdf_l);
        }
        L = rgb_fma(L, beta, rgb_scale(le, w));
      }
      break;
    }
    vec3 wo = v3_neg(dir);

    /* Emission of an area light that the path hit. */
    if (h.light >= 0 && pt__counts(rs, depth)) {
      const light *l = &s->lights[h.light];
      rgb le = light_le_area(l, h.ng, wo);
      if (!rgb_is_black(le)) {
        double w = 1.0;
        if (!prev_delta) {
          double pdf_l = scene_light_pmf(s, h.light) * light_pdf_li(l, s, prev_p, dir, h.p, h.ng);
          w = mis_power(prev_pdf, pdf_l);
        }
        L = rgb_fma(L, beta, rgb_scale(le, w));
      }
    }

    /* Take this bounce's numbers (fixed layout), then stop if too long. */
    double u_light = pt__next(smp, r), ul1 = pt__next(smp, r), ul2 = pt__next(smp, r);
    double u_lobe = pt__next(smp, r), ub1 = pt__next(smp, r), ub2 = pt__next(smp, r);
    double u_rr = pt__next(smp, r);
    if (rs->maxdepth >= 0 && depth >= rs->maxdepth) break;

    const bsdf *b = h.bsdf;
    vec3 wo_l = frame_to_local(&h.sh, wo);
    if (v3_dot(wo, h.ng) * wo_l.z <= 0.0) break; /* shading and geometry disagree */

    /* Next-event estimation: sample a light, weight by MIS. */
    if (!bsdf_is_delta(b) && s->n_lights > 0 && pt__counts(rs, depth + 1)) {
      double pmf, u_rem;
      int li = scene_sample_light(s, u_light, &pmf, &u_rem);
      light_li_sample ls;
      if (li >= 0 && pmf > 0.0 && light_sample_li(&s->lights[li], s, h.p, ul1, ul2, &ls) &&
          ls.pdf > 0.0 && !rgb_is_black(ls.li)) {
        vec3 wi_l = frame_to_local(&h.sh, ls.wi);
        if (v3_dot(ls.wi, h.ng) * wi_l.z > 0.0) {
          double pdf_b; /* the BSDF's density of wi, for the MIS weight */
          rgb f = bsdf_eval_pdf(b, h.tu, h.tv, wo_l, wi_l, TRANSPORT_RADIANCE, &pdf_b);
          if (!rgb_is_black(f)) {
            cnt->rays++;
            if (cnt->log) {
              double e = scene_ray_eps(s, h.p);
              double tmax = isinf(ls.dist) ? INFINITY : ls.dist - scene_ray_eps(s, ls.p);
              ray_log_add(cnt, h.p, ls.wi, e, tmax, 1);
            }
            int blocked = isinf(ls.dist) ? scene_occluded_ray(s, h.p, ls.wi)
                                         : scene_occluded_segment(s, h.p, ls.p);
            if (!blocked) {
              double pdf_l = pmf * ls.pdf;
              double w = ls.delta ? 1.0 : mis_power(pdf_l, pdf_b);
              rgb c = rgb_scale(rgb_mul(f, ls.li), fabs(wi_l.z) * w / pdf_l);
              L = rgb_fma(L, beta, c);
            }
          }
        }
      }
    }

    /* Sample the BSDF for the next direction. */
    bsdf_sample bs;
    if (!bsdf_sample_f(b, h.tu, h.tv, wo_l, u_lobe, ub1, ub2, TRANSPORT_RADIANCE, &bs)) break;
    vec3 wi = frame_to_world(&h.sh, bs.wi);
    if (v3_dot(wi, h.ng) * bs.wi.z <= 0.0) break;
    beta = rgb_mul(beta, bs.weight);
    if (rgb_is_black(beta)) break;
    prev_delta = (bs.flags & BSDF_DELTA) != 0;
    prev_pdf = bs.pdf;
    prev_p = h.p;
    if (bs.flags & BSDF_TRANSMISSION) eta_scale *= bs.eta * bs.eta;

    /* Russian roulette on the throughput (without the radiance scaling of
     * refraction, which would otherwise end paths inside glass). */
    if (depth >= rs->rrdepth) {
      double q = fmin(0.95, rgb_max(beta) * eta_scale);
      if (!(u_rr < q)) break;
      beta = rgb_scale(beta, 1.0 / q);
    }
    org = h.p;
    dir = wi;
    tmin = scene_ray_eps(s, h.p);
  }
  return L;
}
