/*
 * pathspace.h: a state of path-space Metropolis light transport (Veach and
 * Guibas 1997; Veach 1997, chapter 11): one whole light path and what its
 * partial re-evaluation needs.
 *
 * Indexing. A path of length k (segments) is x_0 ... x_k: x_0 the pinhole,
 * x_1 ... x_{k-1} scattering surfaces, x_k a point on an emitter (an area
 * light, hit or sampled, or a point or spot light) or a direction at
 * infinity: the infinite lights together (constant, envmap, sunsky; an
 * escaped camera walk or an environment's light walk), or a directional
 * light's own direction (its light walk only: no walk hits it). Vertices
 * are bdpt's records (bdpt_vertex, integrator.h).
 *
 * Measure and contribution. f is the measurement contribution in the area
 * measure of every vertex, for the whole film (camera.h's We, normalised per
 * pixel: the film's splat of a path is f times the filter around (rx, ry)):
 *   f(x) = We(x_0 -> x_1) prod_{i<k} G(x_i, x_{i+1}) prod_{0<i<k} f_s(x_i) Le(x_k -> x_{k-1}),
 *   G(a, b) = |cos_a| |cos_b| / |a - b|^2 (geometric normals; 1 for a point
 *   light's cosine, the optical axis' cosine at the pinhole),
 *   f_s(x_i) = f(w_cam, w_light) |w_light . n_s| / |w_light . n_g|
 * in radiance mode (w_cam towards x_{i-1}, w_light towards x_{i+1}; Mitsuba's
 * side rule), the shading-normal form whose camera-side and light-side
 * walks both estimate it (integrator_bdpt.c). The chain's target is the
 * luminance of f. Densities are in the same area measure; the pinhole and
 * point lights are discrete positions (their density is the probability of
 * choosing them). An endpoint at infinity is measured in solid angle: its
 * edge's G is |cos| at x_{k-1} alone, its emission every infinite light's
 * radiance from that direction, its density from the camera side the
 * direction's, from the light side the direction's summed over the
 * infinite lights (bdpt's), and x_{k-1}'s from the light side the disk
 * density of the environment's rays (light_disk_point) times |cos|. A
 * directional light's endpoint is measured by its Dirac in direction,
 * reduced: its emission is the irradiance, its density from the light
 * side the light's selection probability, x_{k-1}'s the disk's times |cos|
 * (bdpt's), and from the camera side none.
 *
 * Degenerate vertices. A surface whose BSDF is all delta lobes (conductor,
 * dielectric, thindielectric; `delta` below) carries its lobe reduced by
 * the Dirac in solid angle: f_s uses the lobe's sampled value bs.f and the
 * density of the vertex sampled through it is the lobe's probability times
 * |cos| / d^2, so that f and every density carry the same Dirac, which
 * cancels in the acceptance ratio. The lobe is found by sampling
 * (ps_delta_lobe); its probability is the same in both directions for every
 * delta lobe lmc has (Fresnel at the same angle). The Dirac is the one in
 * the direction towards the light, as f's; a vertex sampled from the light
 * side through a refraction, whose walk's Dirac is in the direction towards
 * the camera, carries the change of measure between the two,
 * |dw_l / dw_c| = eta^2 |cos w_c| / |cos w_l| (1 for reflections and
 * thindielectric). A BSDF that mixes delta and smooth lobes (plastic's
 * coating, a mask's pass-through) gives each vertex on it one of the two:
 * the vertex's flag (bdpt_vertex.delta, set by the walk that scattered
 * there, cleared at a connection's ends) says which, and f and the
 * densities see that lobe alone (the path space is the union of both).
 *
 * What each vertex caches: its factor of f (We at x_0, f_s at surfaces, Le at
 * x_k), the geometry term of its edge to x_{i+1}, and its two densities:
 * pdf_cam, sampled from the camera side (by x_{i-1} reached from x_{i-2};
 * at x_0 the pinhole's 1), and pdf_light, sampled from the light side (by
 * x_{i+1} reached from x_{i+2}; at x_k the light choice times position
 * density; 0 at x_0, which no walk can hit). The path caches f, its
 * luminance and (rx, ry).
 */
#ifndef LMC_PATH_PATHSPACE_H
#define LMC_PATH_PATHSPACE_H

#include "render/integrators/integrator.h"

#define PS_MAX_VERTICES BDPT_MAX_VERTICES

typedef struct ps_vertex {
  bdpt_vertex v;    /* position, normal, hit and light index (bdpt's record) */
  int delta;        /* a surface whose BSDF is all delta lobes */
  int inf;          /* the endpoint of an infinite light: a direction (v.dir, the way the
                       light travels), not a point */
  rgb fac;          /* its factor of f: We (x_0), f_s (surfaces), Le (x_k) */
  double pdf_cam;   /* area density when sampled from the camera side */
  double pdf_light; /* area density when sampled from the light side */
  double g;         /* geometry term G(x_i, x_{i+1}); 0 at x_k */
} ps_vertex;

typedef struct ps_path {
  int k;                        /* length in segments: vertices x_0 .. x_k */
  ps_vertex x[PS_MAX_VERTICES]; /* the vertices, camera first */
  rgb f;                        /* measurement contribution (area measure) */
  double lum;                   /* luminance of f: the target */
  double rx, ry;                /* raster point where x_1 is seen */
  int64_t rays;                 /* rays traced to make it (mut_bidir_generate, _finish) */
} ps_path;

/* What every evaluation reads. */
typedef struct ps_context {
  const scene *sc;      /* borrowed */
  render_settings rs;   /* the render's settings, Russian roulette off (walks) */
  int kmin, kmax;       /* lengths of the path space (segments) */
  int can_hit_emitter;  /* the scene has area lights: a camera walk may end on one */
  double glossy_rough;  /* G vertices: roughness at most this (0.1; 0: none; ps_glossy) */
} ps_context;

/* Fills ctx for scene sc and the render's depths: kmin = max(1, mindepth),
 * kmax = maxdepth (capped at PS_MAX_VERTICES - 1); glossy_rough 0.1. */
void ps_context_init(ps_context *ctx, const scene *sc, const render_settings *rs);

/* Whether surface vertex v is glossy (G), the class of material that the
 * moves retrace by sampling its BSDF rather than join through: a rough
 * conductor or dielectric, phong or ward without diffuse part, whose
 * roughness is at most ctx->glossy_rough (bsdf_is_rough). A property of
 * the material at the hit alone. */
int ps_glossy_vertex(const ps_context *ctx, const bdpt_vertex *v);
/* Whether vertex i of p is G: an inner surface vertex that is not delta
 * and ps_glossy_vertex. */
int ps_glossy(const ps_context *ctx, const ps_path *p, int i);

/* Recomputes the caches of vertices lo .. hi (clipped to 0 .. k) from the
 * geometry: factor, geometry term, both densities. */
void ps_update(const ps_context *ctx, ps_path *p, int lo, int hi);
/* f, its luminance and (rx, ry) from the cached factors and geometry terms. */
void ps_total(ps_path *p);
/* ps_update of every vertex, then ps_total: f from scratch. */
void ps_eval(const ps_context *ctx, ps_path *p);

/* The path cam[0 .. t-1] joined with lp[s-1 .. 0] (bdpt's strategy (s, t):
 * s = 0, cam[t-1] on an emitter; t = 1, the pinhole joined to lp[s-1]),
 * evaluated (ps_eval; f may be 0). Returns 0 when the path is not one of
 * this space's (a length beyond PS_MAX_VERTICES, a vertex out of place). */
int ps_from_bdpt(const ps_context *ctx, const bdpt_vertex *cam, int t, const bdpt_vertex *lp,
                 int s, ps_path *OUT_p);

/* Whether a vertex record may stand in a path: a finite light endpoint,
 * the pinhole or a surface (as its position in the path requires). */
int ps_vertex_fits(const ps_context *ctx, const bdpt_vertex *v, int index, int k);
/* A surface vertex's delta lobe that maps wo to wi (unit, world): its
 * reduced value (bs.f) and probability; *OUT_trans is 1 for a
 * transmission; *OUT_eta (may be NULL) the relative index eta_wi / eta_wo
 * it crosses (1 for a reflection). Returns 0 when no lobe does. */
int ps_delta_lobe(const bdpt_vertex *v, vec3 wo, vec3 wi, transport_mode mode, rgb *OUT_f,
                  double *OUT_prob, int *OUT_trans, double *OUT_eta);

/* Whether the edge from vertex a to a + 1 of p is blocked (a shadow ray:
 * towards the direction when a + 1 is at infinity). */
int ps_edge_blocked(const ps_context *ctx, const ps_path *p, int a);

/* Unit direction from vertex a to vertex b of p (against the light's
 * travel when b is a direction at infinity). */
vec3 ps_dir(const ps_path *p, int a, int b);

/* The densities of vertex i from the geometry (what ps_update caches). */
double ps_density_cam(const ps_context *ctx, const ps_path *p, int i);
double ps_density_light(const ps_context *ctx, const ps_path *p, int i);

/* The densities of vertex `to` sampled through a forced lobe, as the
 * perturbations sample (mut_perturb.h): |cos| / d^2 of a solid-angle
 * density of one at vertex a (1 when b is a direction at infinity)
 * (ps_area_jacobian); and the reduced measure's density of `to` reached
 * through the delta lobe of vertex s from `from` without the lobe's
 * probability (light_side: with the refraction's change of measure above)
 * (ps_forced_density; 0 when no delta lobe of s joins the two). */
double ps_area_jacobian(const ps_context *ctx, const ps_path *p, int a, int b);
double ps_forced_density(const ps_context *ctx, const ps_path *p, int s, int from, int to,
                         int light_side);

/* Whether vertex i can end a connecting edge: the pinhole, a light
 * endpoint, or a surface with a smooth lobe. */
int ps_connectible(const ps_path *p, int i);
/* 1 when vertex i is the pinhole or a point or spot light (no walk hits it). */
int ps_unhittable(const ps_context *ctx, const ps_path *p, int i);

#endif
