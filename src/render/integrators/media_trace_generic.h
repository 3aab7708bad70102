/*
 * media_trace_generic.h: the free flight and the shadow ray through
 * participating media, written once for the plain walks (media_trace.c:
 * render_fly, render_transmittance) and the differentiable path (path.c:
 * path__fly, path__transmit) in render/real.h's vocabulary. A ray crosses
 * the index-matched boundaries between media (hits without a BSDF) one
 * piece at a time: the track of medium.h runs over the pieces (the flight)
 * or each piece's transmittance multiplies in (the shadow ray), and the
 * medium changes at each boundary by the side the ray leaves it on
 * (scene_medium_across). Not a header: no include guard; each of the two
 * files includes it once, after real.h.
 *
 * The includer defines:
 *   MT_FLY, MT_TRANSMIT  the two functions' names;
 *   MT_CTX, MT_SC         its context parameter (named as the hooks use
 *                         it) and the scene from it; MT_ARENA the
 *                         statement that names the arena A (or nothing);
 *   MT_HIT                its hit type (fields p, mesh, ng, bsdf);
 *   MT_TRACE_FLY(org, dir, tmin, h)   the flight's closest surface or
 *                         boundary (scene_intersect_media), counted; 0 on
 *                         a miss;
 *   MT_SEGMENT(org, dir, tmin, tmax)  what the shadow ray notes before
 *                         each piece (the plain side counts and logs the
 *                         ray, the dual side its topology), and
 *                         MT_TRACE_SEG(org, dir, tmin, tmax, h) its trace;
 *   MT_LEN(org, h)        the length of the piece from org to h (Embree's
 *                         t, or the distance between the dual points);
 *   MT_DIST(a, b)         |b - a|; MT_FULL(p, lp, dist) the shadow ray's
 *                         whole length when no boundary is in the scene
 *                         (dist: INFINITY towards a light at infinity);
 *   MT_BLOCKED(p, wi, lp, dist)  the plain shadow ray, 1 when blocked;
 *   MT_TOPO(x)            the dual path's topology (nothing when plain).
 */

/* The free flight from org along dir (unit) in medium *med (medium.h's
 * track from u_ch, u_t) across the boundaries on the way (*med follows
 * them): 1 at the first surface with a BSDF (in *h), 2 at a scattering
 * point (*OUT_mp, in *med), 0 out of the scene; the track's transmittance
 * into *OUT_T and its density into *OUT_pdf (either may be NULL), the
 * flight's weight (T, times sigma_s at a scattering point, over the
 * density) into *OUT_w. -1: lost (RENDER_MAX_CROSSINGS boundaries, or a
 * density of 0). */
static int MT_FLY(MT_CTX, REAL3 org, REAL3 dir, double tmin, int *med, REAL u_ch, REAL u_t,
                  MT_HIT *h, REAL3 *OUT_mp, RRGB *OUT_T, REAL *OUT_pdf, RRGB *OUT_w) {
  MT_ARENA
  const scene *s = MT_SC;
  R_FN(medium_track) k;
  R_FN(medium_track_begin)(R_ARG u_ch, u_t, &k);
  MT_TOPO(k.c);
  int found = 0;
  const medium *m = NULL;
  for (int n = 0;; n++) {
    if (n > RENDER_MAX_CROSSINGS) return -1;
    int hit = MT_TRACE_FLY(org, dir, tmin, h);
    m = scene_medium(s, *med);
    REAL t;
    if (m && R_FN(medium_track_piece)(R_ARG m, hit ? MT_LEN(org, h) : R_C(INFINITY), &k, &t)) {
      *OUT_mp = R3_FMA(org, dir, t);
      found = 2;
      break;
    }
    m = NULL;
    if (!hit) break;
    if (h->bsdf) {
      found = 1;
      break;
    }
    *med = scene_medium_across(s, h->mesh, h->ng, *med, R3_V(dir));
    org = h->p;
    tmin = scene_ray_eps(s, R3_V(h->p));
  }
  REAL pdf = R_FN(medium_track_pdf)(R_ARG m, found == 2, k.T);
  if (OUT_T) *OUT_T = k.T;
  if (OUT_pdf) *OUT_pdf = pdf;
  if (!(R_V(pdf) > 0.0)) return -1;
  RRGB w = found == 2 ? RRGB_MUL(k.T, RRGB_CONST(m->sigma_s)) : k.T;
  *OUT_w = RRGB_SCALE(w, R_INV(pdf));
  return found;
}

/* The shadow ray from p along wi to the light point lp (dist away;
 * INFINITY: along wi forever, towards a light at infinity), starting in
 * medium med: 1 with the transmittance of every medium it crosses in
 * *OUT_T when no surface blocks it, else 0 (also after
 * RENDER_MAX_CROSSINGS boundaries). */
static int MT_TRANSMIT(MT_CTX, REAL3 p, REAL3 wi, REAL3 lp, double dist, int med, RRGB *OUT_T) {
  MT_ARENA
  const scene *s = MT_SC;
  int infinite = isinf(dist);
  RRGB T = RRGB_CONST(rgb_gray(1.0));
  const medium *m = scene_medium(s, med);
  if (!s->accel_media) {
    /* No boundary without a BSDF: one medium all the way. */
    if (MT_BLOCKED(p, wi, lp, dist)) return 0;
    *OUT_T = m ? R_FN(medium_transmittance)(R_ARG m, MT_FULL(p, lp, dist)) : T;
    return 1;
  }
  REAL3 o = p;
  double tmin = scene_ray_eps(s, R3_V(p));
  for (int n = 0; n <= RENDER_MAX_CROSSINGS; n++) {
    REAL rest = infinite ? R_C(INFINITY) : MT_DIST(o, lp);
    double tmax = infinite ? INFINITY : R_V(rest) - scene_ray_eps(s, R3_V(lp));
    MT_HIT h;
    MT_SEGMENT(o, wi, tmin, tmax);
    if (!(tmax > tmin) || !MT_TRACE_SEG(o, wi, tmin, tmax, &h)) {
      *OUT_T = m ? RRGB_MUL(T, R_FN(medium_transmittance)(R_ARG m, rest)) : T;
      return 1;
    }
    if (h.bsdf) return 0;
    if (m) T = RRGB_MUL(T, R_FN(medium_transmittance)(R_ARG m, MT_LEN(o, &h)));
    m = scene_medium(s, med = scene_medium_across(s, h.mesh, h.ng, med, R3_V(wi)));
    o = h.p;
    tmin = scene_ray_eps(s, R3_V(h.p));
  }
  return 0;
}
