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

#include "render/film.h"
#include "render/sampler.h"
#include "render/scene.h"
#include "render/settings.h"

#define PT_DIMS_CAMERA 2
#define PT_DIMS_PER_BOUNCE 7

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

/* Radiance along the camera ray (org, dir): path tracing with next-event
 * estimation and multiple importance sampling (power heuristic). */
rgb pt_li(const scene *s, const render_settings *rs, lmc_sampler *smp, vec3 org, vec3 dir,
          render_counters *cnt);

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
} render_stats;

/* Renders with pt or bdpt according to rs->integrator into `out` (created
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
} progress;
void progress_init(progress *p, const char *label, int quiet);
/* fraction in [0, 1]; prints at most a few times a second. */
void progress_update(progress *p, double fraction);
void progress_finish(progress *p);

/* The power heuristic (beta = 2) for two strategies with densities a and b. */
static inline double mis_power(double a, double b) {
  if (!(a > 0.0)) return 0.0;
  if (!isfinite(a)) return 1.0;
  double a2 = a * a, b2 = b * b;
  return a2 / (a2 + b2);
}

#endif
