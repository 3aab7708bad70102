/*
 * media_trace.c: shadow rays through participating media (integrator.h's
 * render_transmittance): the transmittance of each medium the segment
 * crosses between the index-matched boundaries on its way; the free
 * flight of pt's and bdpt's walks across them (render_fly); and which
 * integrators render media.
 */
#include "render/integrators/integrator.h"

#include <string.h>

int render_integrator_media(const char *name) {
  return strcmp(name, "pt") == 0 || strcmp(name, "bdpt") == 0;
}

int render_media_note(const scene *s, const char *name, int renders) {
  if (s->n_media == 0 || renders) return 0;
  const medium *m = &s->media[0];
  lmc_warn(m->file, m->line,
           "integrator %s does not render participating media yet (with these settings): "
           "the scene's %d medi%s ignored (light crosses %s unattenuated); pt, bdpt, pssmlt and "
           "mmlt (without --technique-jump and --path-mutations), and lmc on the pt states "
           "(--states pt) render them",
           name, s->n_media, s->n_media == 1 ? "um is" : "a are", s->n_media == 1 ? "it" : "them");
  return 1;
}

int render_transmittance(const scene *s, render_counters *cnt, vec3 p, vec3 wi, vec3 lp,
                         double dist, int med, rgb *OUT_T) {
  rgb T = rgb_gray(1.0);
  const medium *m = scene_medium(s, med);
  if (!s->accel_media) {
    /* No boundary without a BSDF: one medium all the way. */
    if (render_blocked(s, cnt, p, wi, lp, dist)) return 0;
    *OUT_T = m ? medium_transmittance(m, dist) : T;
    return 1;
  }
  vec3 o = p;
  double tmin = scene_ray_eps(s, p);
  for (int n = 0; n <= RENDER_MAX_CROSSINGS; n++) {
    double rest = isinf(dist) ? INFINITY : v3_len(v3_sub(lp, o));
    double tmax = isinf(dist) ? INFINITY : rest - scene_ray_eps(s, lp);
    surface_hit h;
    cnt->rays++;
    ray_log_add(cnt, o, wi, tmin, tmax, 1);
    if (!(tmax > tmin) || !scene_intersect_media(s, o, wi, tmin, tmax, &h)) {
      *OUT_T = m ? rgb_mul(T, medium_transmittance(m, rest)) : T;
      return 1;
    }
    if (h.bsdf) return 0;
    if (m) T = rgb_mul(T, medium_transmittance(m, h.t));
    m = scene_medium(s, med = scene_medium_after(s, &h, med, wi));
    o = h.p;
    tmin = scene_ray_eps(s, h.p);
  }
  return 0;
}

int render_medium_at(const scene *s, int mesh_index, vec3 p, vec3 n, vec3 dir) {
  if (mesh_index >= 0) {
    const mesh *m = &s->meshes[mesh_index];
    if (m->interior || m->exterior) return v3_dot(dir, n) > 0.0 ? m->exterior : m->interior;
  }
  int med = scene_locate_medium(s, p, mesh_index);
  return med >= 0 ? med : s->ambient_medium;
}

int render_fly(const scene *s, render_counters *cnt, vec3 org, vec3 dir, double tmin, int *med,
               double u_ch, double u_t, surface_hit *h, vec3 *OUT_mp, rgb *OUT_T, double *OUT_pdf,
               rgb *OUT_w) {
  medium_track k;
  medium_track_begin(u_ch, u_t, &k);
  int found = 0;
  const medium *m = NULL;
  for (int n = 0;; n++) {
    if (n > RENDER_MAX_CROSSINGS) return -1;
    int hit = render_trace_media(s, cnt, org, dir, tmin, h);
    m = scene_medium(s, *med);
    double t;
    if (m && medium_track_piece(m, hit ? h->t : INFINITY, &k, &t)) {
      *OUT_mp = v3_fma(org, dir, t);
      found = 2;
      break;
    }
    m = NULL;
    if (!hit) break;
    if (h->bsdf) {
      found = 1;
      break;
    }
    *med = scene_medium_after(s, h, *med, dir);
    org = h->p;
    tmin = scene_ray_eps(s, h->p);
  }
  *OUT_T = k.T;
  *OUT_pdf = medium_track_pdf(m, found == 2, k.T);
  if (!(*OUT_pdf > 0.0)) return -1;
  *OUT_w = rgb_scale(found == 2 ? rgb_mul(k.T, m->sigma_s) : k.T, 1.0 / *OUT_pdf);
  return found;
}
