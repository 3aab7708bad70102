/*
 * integrator.h: the unbiased reference integrators and the render driver.
 *
 * Path length is counted in segments, as Mitsuba's maxDepth: a path seen
 * directly (camera -> emitter) has length 1, direct lighting length 2.
 *
 * Primary sample layout of pt_li (stream LMC_STREAM_CAMERA; the caller has
 * already taken PT_DIMS_CAMERA numbers for the film position): per bounce,
 * PT_DIMS_PER_BOUNCE numbers in this order, always consumed whether used or
 * not, so a coordinate keeps its meaning when the path changes:
 *   0      light choice for next-event estimation
 *   1, 2   point on the light
 *   3      BSDF lobe choice
 *   4, 5   BSDF direction
 *   6      Russian roulette
 */
#ifndef LMC_RENDER_INTEGRATOR_H
#define LMC_RENDER_INTEGRATOR_H

#include <math.h>

#include "render/film.h"
#include "render/options.h"
#include "render/sampler.h"
#include "render/scene.h"
#include "render/settings.h"

#define PT_DIMS_CAMERA 2
#define PT_DIMS_PER_BOUNCE 7
#define PT_DIMS_MEDIA 2

/* A record of the rays an integrator traced (benchmarks only). */
typedef struct ray_record {
  float org[3], dir[3];
  float tmin, tmax; /* tmax < 0: a shadow ray to tmax = -tmax; INFINITY: closest hit */
} ray_record;

typedef struct ray_log {
  ray_record *rays;
  int64_t n, cap; /* recording stops silently when n reaches cap */
} ray_log;

/* Counters a thread keeps while it renders. */
typedef struct render_counters {
  int64_t rays;        /* closest-hit and shadow rays traced */
  int64_t samples;     /* camera samples (pixel samples) taken */
  int64_t nan_samples; /* non-finite estimates dropped */
  ray_log *log;        /* NULL, or where to record the rays (benchmarks) */
} render_counters;

/* Appends a ray to cnt->log when there is one. */
static inline void ray_log_add(render_counters *cnt, vec3 o, vec3 d, double tmin, double tmax,
                               int shadow) {
  ray_log *l = cnt->log;
  if (!l || l->n >= l->cap) return;
  ray_record *r = &l->rays[l->n++];
  r->org[0] = (float)o.x, r->org[1] = (float)o.y, r->org[2] = (float)o.z;
  r->dir[0] = (float)d.x, r->dir[1] = (float)d.y, r->dir[2] = (float)d.z;
  r->tmin = (float)tmin;
  r->tmax = shadow ? -(float)tmax : (float)tmax;
}

/* The closest hit along (org, dir) from tmin, counted (and logged). */
static inline int render_trace(const scene *s, render_counters *cnt, vec3 org, vec3 dir,
                               double tmin, surface_hit *OUT_h) {
  cnt->rays++;
  ray_log_add(cnt, org, dir, tmin, INFINITY, 0);
  return scene_intersect(s, org, dir, tmin, INFINITY, OUT_h);
}

/* Whether the shadow ray from p along wi to the light point lp, dist away
 * (INFINITY: a direction, nothing beyond the scene), is blocked; counted
 * (and logged). */
static inline int render_blocked(const scene *s, render_counters *cnt, vec3 p, vec3 wi, vec3 lp,
                                 double dist) {
  cnt->rays++;
  if (cnt->log) {
    double e = scene_ray_eps(s, p);
    double tmax = isinf(dist) ? INFINITY : dist - scene_ray_eps(s, lp);
    ray_log_add(cnt, p, wi, e, tmax, 1);
  }
  return isinf(dist) ? scene_occluded_ray(s, p, wi) : scene_occluded_segment(s, p, lp);
}

/* 1 when a render of s with rs goes through the scene's participating
 * media: it has some, and rs.no_media (the MCMC driver's, for integrators
 * and settings that do not render them) is unset. */
static inline int render_media_on(const scene *s, const render_settings *rs) {
  return s->n_media > 0 && !rs->no_media;
}

/* 1 when the integrator `name` of this library renders participating
 * media (pt, bdpt); the others render a scene's media as empty space,
 * after render_media_note's warning. */
int render_integrator_media(const char *name);
/* Warns (naming the first medium's file and line) when s has media and
 * `renders` is 0 (the integrator `name` does not render them, with its
 * settings); 1 when it warned. */
int render_media_note(const scene *s, const char *name, int renders);

/* The medium (1-based; 0: none) a ray from p along dir starts in: on a
 * mesh that bounds media (mesh_index >= 0, n its normal at p) by the side
 * dir leaves on; elsewhere the medium around p (scene_locate_medium), the
 * scene's ambient medium when no boundary encloses p (media_trace.c). */
int render_medium_at(const scene *s, int mesh_index, vec3 p, vec3 n, vec3 dir);

/* How many index-matched boundaries between media a ray may cross before
 * the integrators that render media give it up (as absorbed). */
#define RENDER_MAX_CROSSINGS 1000

/* The closest surface or boundary between media along (org, dir) from
 * tmin (scene_intersect_media), counted (and logged). */
static inline int render_trace_media(const scene *s, render_counters *cnt, vec3 org, vec3 dir,
                                     double tmin, surface_hit *OUT_h) {
  cnt->rays++;
  ray_log_add(cnt, org, dir, tmin, INFINITY, 0);
  return scene_intersect_media(s, org, dir, tmin, INFINITY, OUT_h);
}

/* The free flight from org along dir (unit) from the medium *med (medium.h's
 * track from the numbers u_ch, u_t), across the index-matched boundaries
 * on the way (*med follows them): to the first surface with a BSDF (1, in
 * *h), a scattering point (2, at *OUT_mp, in *med), or out of the scene
 * (0); the track's transmittance in *OUT_T, the flight's density in
 * *OUT_pdf and its weight (T, times sigma_s at a scattering point, over
 * the density) in *OUT_w. -1: lost (RENDER_MAX_CROSSINGS boundaries, or a
 * density of 0). The walks of pt and bdpt through media (media_trace.c). */
int render_fly(const scene *s, render_counters *cnt, vec3 org, vec3 dir, double tmin, int *med,
               double u_ch, double u_t, surface_hit *h, vec3 *OUT_mp, rgb *OUT_T, double *OUT_pdf,
               rgb *OUT_w);

/* The shadow ray of render_blocked through media: 1 when no surface
 * blocks it, with the transmittance along it in *OUT_T, starting in the
 * medium med (1-based, 0: none) and crossing the index-matched boundaries
 * between media on its way (media_trace.c); 0 when blocked (or after
 * RENDER_MAX_CROSSINGS boundaries). */
int render_transmittance(const scene *s, render_counters *cnt, vec3 p, vec3 wi, vec3 lp,
                         double dist, int med, rgb *OUT_T);

/* A camera ray's differentials: the directions of the rays through the film
 * points one (scaled) step along x and along y, from the same origin. */
typedef struct ray_diff {
  vec3 dx, dy;
} ray_diff;

/* Radiance along the camera ray (org, dir): path tracing with next-event
 * estimation and multiple importance sampling (power heuristic). With ray
 * differentials rd (NULL: none), the first hit's filtered textures read
 * over its footprint (scene_tex_footprint), as Mitsuba's path tracer. */
rgb pt_li(const scene *s, const render_settings *rs, lmc_sampler *smp, vec3 org, vec3 dir,
          const ray_diff *rd, render_counters *cnt);
/* The same through the scene's participating media (Mitsuba's volpath):
 * the camera ray starts in the camera's medium; each segment's free
 * flight (medium.h's track across the index-matched boundaries it
 * crosses) ends at a surface or at a scattering point, where next-event
 * estimation (with the transmittance to the light) and the phase
 * function's sample are joined by MIS as at a surface. With media the
 * layout takes two numbers more per bounce, first: the flight's channel
 * and distance (PT_DIMS_MEDIA). */
rgb pt_li_media(const scene *s, const render_settings *rs, lmc_sampler *smp, vec3 org, vec3 dir,
                const ray_diff *rd, render_counters *cnt);

/* ---- Direct illumination (integrator_direct.c) ---------------------------
 *
 * Mitsuba's `direct`: the emitters the camera sees and the light reaching
 * the first hit straight from an emitter (paths of 1 and 2 segments, pt
 * --maxdepth 2 in expectation), by emitter_samples light samples and
 * bsdf_samples BSDF samples per pixel sample joined by MIS (the power
 * heuristic over the counts). */
typedef struct direct_settings {
  int emitter_samples; /* --emitter-samples: light samples (Mitsuba's emitterSamples) */
  int bsdf_samples;    /* --bsdf-samples: BSDF samples (bsdfSamples); not both 0 */
  int hide_emitters;   /* --hide-emitters on: emitters seen by the camera are black */
} direct_settings;

/* Its flags (defaults 1, 1, off); the values travel in render_settings.params. */
extern const lmc_opt_table direct_options;
/* Its numbers for the Sobol sampler: the film pair, then (choice, pair) per sample. */
extern const sampler_layout sampler_layout_direct;

/* direct's settings from rs (lmc_opt_read of direct_options); LMC_EINVAL
 * on a bad value or when both counts are 0. */
lmc_status direct_read_settings(const render_settings *rs, direct_settings *OUT,
                                lmc_error *err);

/* Radiance along the camera ray (org, dir) by direct illumination; the
 * camera hit's filtered textures read over rd's footprint (NULL: none). */
rgb direct_li(const scene *s, const render_settings *rs, const direct_settings *ds,
              lmc_sampler *smp, vec3 org, vec3 dir, const ray_diff *rd, render_counters *cnt);

/* One BDPT sample for the camera ray through raster point (rx, ry): the
 * camera-side estimate is returned; light-tracing (t = 1) contributions are
 * splatted into `splat` (scaled later by the film's splat_scale). */
rgb bdpt_li(const scene *s, const render_settings *rs, lmc_sampler *smp, double rx, double ry,
            film *splat, render_counters *cnt);

typedef struct render_stats {
  double seconds;
  int64_t passes;      /* complete passes (samples per pixel) */
  int64_t samples;     /* all camera samples */
  int64_t rays;
  int64_t nan_samples;
  int interrupted;     /* stopped by a signal */
  int timed_out;       /* stopped by the time limit */
  double mcmc_b_boot, mcmc_b_boot_se; /* MCMC: b (sum over families) from the bootstrap alone, its SE */
  int64_t mcmc_boot_paths;            /* MCMC: bootstrap paths drawn (over all families) */
  double mcmc_b, mcmc_b_se;           /* MCMC: b the image uses (refined with large steps), its SE */
  int64_t rank_rays, rank_samples;    /* this process's own share (over MPI ranks, render/dist.h;
                                         the counts above are every rank's, on rank 0) */
} render_stats;

/* Renders with pt, bdpt or direct according to rs->integrator into `out` (created
 * here). Stops at rs->spp passes, at rs->time_limit, or when
 * render_request_stop() is called (e.g. from a signal handler); the film
 * then holds a correctly normalised image of all samples taken. */
lmc_status render_run(const scene *s, const render_settings *rs, film *out, render_stats *st,
                      lmc_error *err);

/* Asks a running render to stop (async-signal-safe). */
void render_request_stop(int signal_number);
/* The signal that asked to stop, or 0. */
int render_stop_signal(void);
/* Clears a previous stop request. */
void render_reset_stop(void);

/* Progress bar on stderr (only when stderr is a terminal and not quiet). */
typedef struct progress {
  int enabled;
  double start, last_print;
  char label[32];
  char phase[24];   /* "" or the render's phase (MCMC: direct light, bootstrap, chains) */
  double rate;      /* > 0: shown with rate_unit after the ETA */
  char rate_unit[24];
  int open;         /* a line is on the terminal, not yet ended */
} progress;
void progress_init(progress *p, const char *label, int quiet);
/* fraction in [0, 1]; prints at most a few times a second. */
void progress_update(progress *p, double fraction);
/* Names the phase and prints the line at once with fraction. */
void progress_phase(progress *p, const char *phase, double fraction);
/* progress_update with a rate (e.g. mutations per second) on the line. */
void progress_update_rate(progress *p, double fraction, double rate, const char *unit);
void progress_finish(progress *p);
/* Ends the line where it stands (an error or an interruption), once. */
void progress_end(progress *p);

/* The power heuristic (beta = 2) for two strategies with densities a and b. */
static inline double mis_power(double a, double b) {
  if (!(a > 0.0)) return 0.0;
  if (!isfinite(a)) return 1.0;
  double a2 = a * a, b2 = b * b;
  return a2 / (a2 + b2);
}


/* ---- Bidirectional path tracing (integrator_bdpt.c) ----------------------
 *
 * BDPT (Veach and Guibas 1995; Veach 1997, ch. 10) joins a camera subpath
 * of t vertices and a light subpath of s vertices in every way (s, t) and
 * weights each strategy with the power heuristic. A full path has s + t - 1
 * segments and is counted only when that length lies in [mindepth,
 * maxdepth] (Mitsuba's convention, as pt_li). Strategy (s=1, t=1), a light
 * endpoint joined straight to the pinhole, is not used (as pbrt): lights
 * seen directly come from s = 0, point lights are never seen directly.
 *
 * Primary sample layout of bdpt_li, per stream (numbers are always taken,
 * used or not, so that each keeps its meaning when the path changes):
 *   LMC_STREAM_CAMERA   2 for the film position (taken by the caller), then
 *                       BDPT_DIMS_PER_VERTEX per camera-subpath surface vertex:
 *                       0 BSDF lobe, 1-2 BSDF direction, 3 Russian roulette.
 *   LMC_STREAM_LIGHT    BDPT_DIMS_LIGHT_START for the emitter: 0 light choice,
 *                       1-2 position, 3-4 direction (light_sample_le); then
 *                       BDPT_DIMS_PER_VERTEX per light-subpath surface vertex
 *                       (same order as the camera's).
 *   LMC_STREAM_CONNECT  BDPT_DIMS_CONNECT per camera vertex t = 2, 3, ...:
 *                       0 light choice, 1-2 point on the light (the s = 1
 *                       strategy, next-event estimation, for that t).
 */
#define BDPT_MAX_VERTICES 64 /* per subpath; with maxdepth < 0 paths are capped at 63 segments */
#define BDPT_DIMS_PER_VERTEX 4
#define BDPT_DIMS_LIGHT_START 5
#define BDPT_DIMS_CONNECT 3
#define BDPT_DIMS_MEDIA 2 /* through media: each vertex's free flight, before its own */

typedef enum bdpt_vertex_type {
  BDPT_VERTEX_CAMERA = 0, /* the pinhole */
  BDPT_VERTEX_LIGHT,      /* a light endpoint (also an escaped camera ray: light = -1) */
  BDPT_VERTEX_SURFACE,    /* a scattering vertex (possibly on an area light) */
  BDPT_VERTEX_MEDIUM      /* a scattering point in a medium (bdpt through media) */
} bdpt_vertex_type;

/* One subpath vertex. Densities are per unit area at the vertex, except
 * for vertices at infinity (infinite and directional light endpoints),
 * whose densities are per unit solid angle (as pbrt's). */
typedef struct bdpt_vertex {
  bdpt_vertex_type type;
  int delta;       /* the subpath left this vertex through a delta BSDF lobe */
  int light;       /* LIGHT: light index (-1: all infinite lights); SURFACE: area light of the mesh or -1 */
  rgb beta;        /* subpath throughput up to this vertex (divided by its sampling densities) */
  double pdf_fwd;  /* density of this vertex when its own subpath samples it */
  double pdf_rev;  /* density when sampled from the other end (0 until known) */
  vec3 p;          /* position (a far point for vertices at infinity) */
  vec3 n;          /* geometric normal (surfaces, area lights); zero otherwise */
  vec3 dir;        /* vertices at infinity: the direction the light travels */
  vec3 wo;         /* SURFACE: unit direction towards the previous vertex of its subpath */
  surface_hit hit; /* SURFACE: the shading point */
  /* The direction this vertex scattered into (bdpt_param below): */
  int rough;       /* 1 when its BSDF is rough (bsdf_is_rough): the direction has an
                      absolute parametrization */
  double sph[2];   /* rough: the direction's spherical coordinates (bdpt_sphere_dir) */
  double jac;      /* rough: d(direction numbers) / d(spherical coordinates) = pdf J,
                      pdf the BSDF's solid-angle density of the direction and J the
                      sphere map's; 1 otherwise */
  /* Through media (bdpt_li on a scene with media; else 0 and unset): */
  int med;         /* the medium (1-based; 0: none) a MEDIUM vertex lies in, or the one a
                      SURFACE vertex was reached through, the camera's, a light's */
  rgb tseg;        /* the transmittance of the segment from the previous vertex of its
                      subpath (pdf_fwd holds that segment's free-flight density) */
  const phase_fn *ph; /* MEDIUM: its medium's phase function */
  int media;       /* CAMERA: 1 when its subpath (and the light subpath joined to it) was
                      walked through the scene's media; bdpt_connect then joins through them */
} bdpt_vertex;

/* How a subpath reads its direction numbers (the MCMC reparametrization,
 * mcmc.c's bdpt states). By default a surface vertex draws its direction
 * by BSDF sampling from (u1, u2), relative to its shading frame. At a
 * rough vertex (bsdf_is_rough) with index < abs_until, (u1, u2) are
 * instead the absolute spherical coordinates of the world direction
 * (bdpt_sphere_dir): the direction stays put when the vertex before it
 * moves, as in the LMC paper's implementation (after Li et al.'s H2MC),
 * where BSDF-relative numbers would swing it round with the shading
 * frame. The throughputs stay those of BSDF sampling (f cos / pdf) either
 * way, so values, Russian roulette and MIS weights are the same functions
 * of the path; the vertex's `jac` is the Jacobian between the two
 * parametrizations, by which a target in the absolute numbers differs. */
typedef struct bdpt_param {
  int abs_until;      /* vertices of index < abs_until read absolute directions when rough */
  double rough_min;   /* bsdf_is_rough's threshold */
} bdpt_param;

/* World direction of spherical coordinates (v1, v2) in [0,1)^2: azimuth
 * 2 pi v1, polar angle pi v2 from +z; *OUT_jac (may be NULL) gets the
 * solid angle per unit (v1, v2), J = 2 pi^2 sin(pi v2). */
vec3 bdpt_sphere_dir(double v1, double v2, double *OUT_jac);
/* Its inverse: the coordinates of a unit direction, and J. */
void bdpt_sphere_coords(vec3 w, double *OUT_v1, double *OUT_v2, double *OUT_jac);

/* Subpath lengths for render settings: at most max_camera camera vertices
 * and max_light light vertices (maxdepth + 1 and maxdepth, capped). */
void bdpt_subpath_limits(const render_settings *rs, int *OUT_max_camera, int *OUT_max_light);

/* The camera subpath through raster point (rx, ry) from the current stream
 * of smp (BDPT_DIMS_PER_VERTEX per surface vertex); path[0] is the camera.
 * Returns the number of vertices written (1 ... max_vertices). par (may
 * be NULL: BSDF sampling everywhere) is the parametrization. */
int bdpt_camera_subpath(const scene *sc, const render_settings *rs, lmc_sampler *smp, double rx,
                        double ry, int max_vertices, bdpt_vertex *OUT_path, render_counters *cnt);
int bdpt_camera_subpath_p(const scene *sc, const render_settings *rs, lmc_sampler *smp, double rx,
                          double ry, int max_vertices, const bdpt_param *par,
                          bdpt_vertex *OUT_path, render_counters *cnt);

/* Both subpaths of one bdpt_li sample, from smp's camera and light streams
 * (left on the connect stream), through the scene's media when `media` is
 * set (each vertex then two numbers more, first: its flight's; MEDIUM
 * vertices; every density with its free flight's). The vertex counts into
 * *OUT_nc and *OUT_nl. */
void bdpt_subpaths(const scene *sc, const render_settings *rs, lmc_sampler *smp, double rx,
                   double ry, int media, bdpt_vertex *OUT_cam, int *OUT_nc, bdpt_vertex *OUT_lp,
                   int *OUT_nl, render_counters *cnt);

/* The light subpath from the current stream of smp (BDPT_DIMS_LIGHT_START,
 * then BDPT_DIMS_PER_VERTEX per surface vertex); path[0] is the light.
 * Returns the number of vertices written (0 ... max_vertices). */
int bdpt_light_subpath(const scene *sc, const render_settings *rs, lmc_sampler *smp,
                       int max_vertices, bdpt_vertex *OUT_path, render_counters *cnt);
int bdpt_light_subpath_p(const scene *sc, const render_settings *rs, lmc_sampler *smp,
                         int max_vertices, const bdpt_param *par, bdpt_vertex *OUT_path,
                         render_counters *cnt);

/* The inverses of the subpaths (inverse path sampling; Bitterli, Jakob,
 * Novak and Jarosz 2017): the numbers from which the walks above, with
 * the same settings and parametrization, make the first n vertices of
 * `path` again (to rounding). path is one subpath as the walks write it,
 * or a full path's vertices re-split at another strategy: surfaces with
 * their hit, wo (towards the previous vertex of this subpath) and delta
 * flag; the light endpoint with its light index (-1: the infinite lights,
 * one of which is then chosen in proportion to its share of the density),
 * p, n, dir and, on an area light, hit.prim (its triangle). Where the walk
 * has a choice (a lobe, a light, a number the vertices do not fix: the
 * last vertex's four, a delta lobe's direction, Russian roulette below
 * its survival probability), the number is drawn from g so that uniform
 * numbers, walked and inverted, are uniform again. Each returns 0 when the
 * walk cannot make those vertices.
 * bdpt_invert_camera_subpath (n >= 2): the raster point (*OUT_rx,
 * *OUT_ry; outside the film when the camera ray is, as the MCMC states'
 * film grown by the filter's radius allows) and BDPT_DIMS_PER_VERTEX
 * numbers per surface vertex 1 .. n - 1. */
int bdpt_invert_camera_subpath(const scene *sc, const render_settings *rs, const bdpt_param *par,
                               const bdpt_vertex *path, int n, rng *g, double *OUT_rx,
                               double *OUT_ry, double *OUT_u);
/* bdpt_invert_light_subpath (n >= 2): BDPT_DIMS_LIGHT_START numbers for the
 * emitter, then BDPT_DIMS_PER_VERTEX per surface vertex 1 .. n - 1. */
int bdpt_invert_light_subpath(const scene *sc, const render_settings *rs, const bdpt_param *par,
                              const bdpt_vertex *path, int n, rng *g, double *OUT_u);
/* bdpt_invert_connect: the s = 1 strategy's numbers (light choice, point)
 * with which camera vertex ref samples the light vertex y. */
int bdpt_invert_connect(const scene *sc, const bdpt_vertex *ref, const bdpt_vertex *y, rng *g,
                        double OUT_u[BDPT_DIMS_CONNECT]);
/* Its forward map: the light vertex record (type LIGHT, as the light walks
 * make their endpoint) that the s = 1 strategy samples from the point ref
 * with the connect numbers u. Returns 0 when none is sampled. */
int bdpt_connect_vertex(const scene *sc, vec3 ref, const double u[BDPT_DIMS_CONNECT],
                        bdpt_vertex *OUT_y);

/* The subpaths of strategy (s, t), s + t = k + 1, of the full path x_0 ..
 * x_k (camera first, vertex records as the walks or ps_path keep them):
 * cam[i] = x_i with wo towards x_{i-1}, lp[j] = x_{k-j} with wo towards
 * x_{k-j+1}, for the inverses above. Delta flags are the path's; an
 * area light the camera walk hit (a surface) becomes, as lp[0], the light
 * endpoint the light walks make (type LIGHT), which MIS weights expect. */
void bdpt_resplit(const scene *sc, const bdpt_vertex *x, int k, int s, int t,
                  bdpt_vertex *OUT_cam, bdpt_vertex *OUT_lp);

/* The power-heuristic MIS weights of every strategy t = 1 .. k + 1 (s =
 * k + 1 - t) of the full path x_0 .. x_k at once, into OUT_w[t] (0 where a
 * delta vertex at the joint makes the strategy impossible; length 1 has
 * (0, 2) alone, impossible at a delta light): the densities
 * of every vertex from both sides once (bdpt_path_pdfs), then the ratio
 * walk's sums for all t. The same numbers, to rounding, as bdpt_mis_weight
 * on each re-split. scratch: room for k + 2 vertices. */
void bdpt_mis_weights(const scene *sc, const bdpt_vertex *x, int k, bdpt_vertex *scratch,
                      double *OUT_w);
/* A strategy t != skip (0: none skipped) with w[t] > 0 among t = 1 .. k +
 * 1, drawn with probability w[t] / sum (sum: the weights but skip's) from
 * the uniform u; the last one with weight where rounding leaves the draw
 * past them all; -1 when none has weight. */
int bdpt_draw_strategy(const double *w, int k, int skip, double sum, double u);

/* Evaluates the single strategy (s, t): the first t vertices of cam joined
 * with the first s of lp (for s = 1 the light is sampled afresh from
 * u_connect, which may be NULL otherwise). Returns the MIS-weighted
 * contribution (0 when the strategy cannot produce a path); for t = 1 it
 * is a film splat at (*OUT_rx, *OUT_ry). OUT_weight (may be NULL) gets the
 * MIS weight. This is what multiplexed MLT evaluates per state. */
rgb bdpt_connect(const scene *sc, const bdpt_vertex *cam, int t, const bdpt_vertex *lp, int s,
                 const double *u_connect, double *OUT_rx, double *OUT_ry, double *OUT_weight,
                 render_counters *cnt);

/* The power-heuristic MIS weight of strategy (s, t) for the full path made
 * of cam[0..t-1] and lp[0..s-1] (pbrt's ratio walk). `sampled` replaces
 * lp[0] when s = 1 (may be NULL). The densities of the four vertices
 * next to the connection are recomputed here; the arrays are not changed. */
double bdpt_mis_weight(const scene *sc, const bdpt_vertex *cam, int t, const bdpt_vertex *lp,
                       int s, const bdpt_vertex *sampled);

/* Recomputes pdf_fwd and pdf_rev of every vertex of the full path
 * cam[0..t-1] + lp[0..s-1] from its geometry (tests use it to check the
 * bookkeeping of the random walks and to re-split a path). */
void bdpt_path_pdfs(const scene *sc, bdpt_vertex *cam, int t, bdpt_vertex *lp, int s);

/* ---- BDPT's vertex densities and walk, for other samplers of whole paths
 * (path-space MLT, src/lmc/path/). Thin wrappers of the functions BDPT
 * itself uses (bdpt_generic.h): the same numbers, bit for bit. */

/* Density of `next` sampled at v reached from `prev` (pbrt's Vertex::Pdf):
 * the camera's direction density, or the BSDF's (zero for delta lobes),
 * converted to area at `next` (solid angle when `next` is at infinity);
 * light endpoints (type LIGHT) use the emission density. */
double bdpt_vertex_pdf(const scene *sc, const bdpt_vertex *v, const bdpt_vertex *prev,
                       const bdpt_vertex *next);
/* Density of `next` emitted from the light endpoint v (any vertex type
 * whose light index is set), per unit area at `next`. */
double bdpt_vertex_pdf_light(const scene *sc, const bdpt_vertex *v, const bdpt_vertex *next);
/* Density of choosing v as the light endpoint: the light's selection
 * probability times its position density (area lights), or alone (delta
 * positions); `next` is the vertex it connects to. */
double bdpt_vertex_pdf_light_origin(const scene *sc, const bdpt_vertex *v,
                                    const bdpt_vertex *next);
/* f(v.wo, wi) |wi . n_s| at a surface vertex with Mitsuba's side rule
 * (0 when a direction breaks it), with Veach's shading-normal correction
 * in importance mode. */
rgb bdpt_vertex_f_cos(const bdpt_vertex *v, vec3 wi, transport_mode mode);
/* Continues a subpath of n vertices whose last vertex scattered into the
 * unit direction dir (solid-angle density pdf_dir) from org: BDPT's walk
 * (four numbers per vertex from smp's current stream), until the path has
 * max_vertices vertices or the walk ends. Russian roulette applies from
 * rs->rrdepth segments on (pass a large rrdepth for none). The throughputs
 * start at one. Returns the new vertex count. */
int bdpt_continue_subpath(const scene *sc, const render_settings *rs, lmc_sampler *smp,
                          transport_mode mode, vec3 org, vec3 dir, double pdf_dir,
                          bdpt_vertex *path, int n, int max_vertices, render_counters *cnt);

#endif
