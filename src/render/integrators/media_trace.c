/*
 * media_trace.c: shadow rays through participating media (integrator.h's
 * render_transmittance): the transmittance of each medium the segment
 * crosses between the index-matched boundaries on its way; the free
 * flight of pt's and bdpt's walks across them (render_fly), both the plain
 * forms of media_trace_generic.h (path.c has their dual forms); the medium
 * a light's paths start in; and which integrators render media.
 */
#include "render/integrators/integrator.h"

#include <math.h>
#include <string.h>

/* The flight and the shadow ray, written once with path.c's dual forms. */
#define R_DUAL 0
#include "render/real.h"
#define MT_FLY media__fly
#define MT_TRANSMIT media__transmit
#define MT_CTX const scene *mt_sc, render_counters *cnt
#define MT_SC mt_sc
#define MT_ARENA
#define MT_HIT surface_hit
#define MT_TRACE_FLY(org, dir, tmin, h) render_trace_media(mt_sc, cnt, (org), (dir), (tmin), (h))
#define MT_SEGMENT(org, dir, tmin, tmax) \
  (cnt->rays++, ray_log_add(cnt, (org), (dir), (tmin), (tmax), 1))
#define MT_TRACE_SEG(org, dir, tmin, tmax, h) \
  scene_intersect_media(mt_sc, (org), (dir), (tmin), (tmax), (h))
#define MT_LEN(org, h) ((h)->t)
#define MT_DIST(a, b) v3_len(v3_sub((b), (a)))
#define MT_FULL(p, lp, dist) (dist)
#define MT_BLOCKED(p, wi, lp, dist) render_blocked(mt_sc, cnt, (p), (wi), (lp), (dist))
#define MT_TOPO(x) ((void)0)
#include "render/integrators/media_trace_generic.h"

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

int render_medium_at(const scene *s, int mesh_index, vec3 p, vec3 n, vec3 dir) {
  if (mesh_index >= 0) {
    const mesh *m = &s->meshes[mesh_index];
    if (m->interior || m->exterior) return v3_dot(dir, n) > 0.0 ? m->exterior : m->interior;
  }
  int med = scene_locate_medium(s, p, mesh_index);
  return med >= 0 ? med : s->ambient_medium;
}

int render_transmittance(const scene *s, render_counters *cnt, vec3 p, vec3 wi, vec3 lp,
                         double dist, int med, rgb *OUT_T) {
  return media__transmit(s, cnt, p, wi, lp, dist, med, OUT_T);
}

int render_fly(const scene *s, render_counters *cnt, vec3 org, vec3 dir, double tmin, int *med,
               double u_ch, double u_t, surface_hit *h, vec3 *OUT_mp, rgb *OUT_T, double *OUT_pdf,
               rgb *OUT_w) {
  return media__fly(s, cnt, org, dir, tmin, med, u_ch, u_t, h, OUT_mp, OUT_T, OUT_pdf, OUT_w);
}
