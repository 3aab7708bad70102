/*
 * integrator_pt_media.c: the path tracer through participating media
 * (integrator.h's pt_li_media): integrator_pt.c's walk compiled with its
 * media blocks (pt_generic.h's PT_MEDIA_CODE).
 */
#define PT_MEDIA_CODE 1
#include "render/integrators/pt_plain.h"

rgb pt_li_media(const scene *s, const render_settings *rs, lmc_sampler *smp, vec3 org, vec3 dir,
                const ray_diff *rd, render_counters *cnt) {
  return pt__li(s, rs, smp, org, dir, rd, cnt);
}
