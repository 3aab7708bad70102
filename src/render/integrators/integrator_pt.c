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
 * The random numbers follow the fixed layout of integrator.h. The walk is
 * written once for this plain path and for path.c's differentiable one
 * (pt_generic.h).
 */
#define PT_MEDIA_CODE 0
#include "render/integrators/pt_plain.h"

rgb pt_li(const scene *s, const render_settings *rs, lmc_sampler *smp, vec3 org, vec3 dir,
          const ray_diff *rd, render_counters *cnt) {
  return pt__li(s, rs, smp, org, dir, rd, cnt);
}
