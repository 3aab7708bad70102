/*
 * path.h: the differentiable path sampler, u -> path -> f(u) and its exact
 * gradient in primary sample space (the target of Langevin Monte Carlo,
 * Luan et al. 2020, "Langevin Monte Carlo Rendering with Gradient-based
 * Adaptation").
 *
 * "Locate, then re-evaluate". One function per estimator computes a path's
 * contribution from the numbers it draws, written once in dual arithmetic
 * (src/ad). Pass 1 runs it with tangent length 0: rays are traced with
 * Embree on the values, and the topology is recorded (the numbers drawn,
 * the triangle each ray hit or a miss, the result of each shadow ray).
 * f alone is pass 1. For the gradient, pass 2 replays the same function
 * with tangent length n = the number of differentiated coordinates, taking
 * hits and visibility from the record instead of casting rays: each vertex
 * is the ray-triangle intersection (Moller-Trumbore, mesh_intersect_triangle)
 * with the recorded triangle in duals, so it slides with u; shading normals
 * and texture coordinates are interpolated in duals; BSDF values, pdfs and
 * samples come from bsdf_ad.h; emitters, geometry terms and power-heuristic
 * MIS weights are duals too. Branches look at values only, and values do
 * not depend on the tangent length, so pass 2 takes exactly the branches of
 * pass 1 and f is the same number in both. Discontinuities (another
 * triangle, another lobe, an occluder, Russian roulette) are not
 * differentiated; MCMC acceptance takes care of them.
 *
 * The layout of u. The j-th number drawn from stream k is coordinate
 * stream_offset(k) + j of the state (src/lmc/kernels/target.h); path_eval reports,
 * for every number drawn, its stream and position. path_eval_pt follows
 * pt_li exactly (integrator.h), all from LMC_STREAM_CAMERA:
 *   0, 1      film position: rx = u0 * width, ry = u1 * height (raster
 *             space, uniform over the whole film: the pixel is not fixed;
 *             with render.c's box filter this is the same density pt gives
 *             every pixel, which is what an MCMC target needs);
 *   2 + 7 b + 0   next-event light choice       (discrete: derivative 0)
 *   2 + 7 b + 1,2 point on the light             (differentiated)
 *   2 + 7 b + 3   BSDF lobe choice               (discrete: derivative 0)
 *   2 + 7 b + 4,5 BSDF direction                 (differentiated)
 *   2 + 7 b + 6   Russian roulette               (discrete: derivative 0)
 * for bounces b = 0, 1, ... (PT_DIMS_CAMERA, PT_DIMS_PER_BOUNCE). Only the
 * continuous coordinates get a tangent slot, which keeps n small
 * (2 + 4 per bounce); the discrete ones are reported with derivative 0.
 *
 * path_eval_bdpt evaluates one bidirectional strategy (s, t) with the
 * BDPT layout of integrator.h (camera, light and connect streams; see its
 * declaration below).
 *
 * Conventions: those of integrator.h (path length in segments, mindepth,
 * maxdepth, rrdepth; Russian roulette as pt_li) and bsdf.h.
 *
 * Memory: a path_scratch per thread holds the arena and the record; no
 * allocation happens per path. The scene is borrowed and read-only.
 */
#ifndef LMC_RENDER_PATH_H
#define LMC_RENDER_PATH_H

#include "render/error.h"
#include "render/integrators/integrator.h"
#include "render/sampler.h"
#include "render/scene.h"
#include "render/settings.h"

/* Most numbers one path may draw (beyond that the gradient is dropped). */
#define PATH_MAX_DRAWS 2048

/* Flags of path_eval.flags: which lobes and emitters the contributing
 * parts of the path used (for tests and statistics). */
enum {
  PATH_LOBE_DIFFUSE = 1 << 0,
  PATH_LOBE_GLOSSY = 1 << 1,
  PATH_LOBE_DELTA = 1 << 2,
  PATH_LOBE_TRANSMISSION = 1 << 3,
  PATH_EMIT_AREA = 1 << 4,
  PATH_EMIT_INFINITE = 1 << 5, /* constant or envmap */
  PATH_EMIT_DELTA = 1 << 6,    /* point, spot, directional */
  PATH_EMIT_ENVMAP = 1 << 7
};

/* One number the path drew and what it does to the result. */
typedef struct path_coord {
  int stream;       /* LMC_STREAM_* */
  int pos;          /* position within its stream: coordinate = offset(stream) + pos */
  double u;         /* its value */
  int diff;         /* 1 when it got a tangent slot (continuous use) */
  int var;          /* that slot, in [0, n_diff) (-1: none); indexes path_eval.hlum */
  double dlum;      /* d luminance / du */
  rgb drgb;         /* d value / du */
  double drx, dry;  /* d raster position / du */
} path_coord;

/* What one evaluation gives. */
typedef struct path_eval {
  rgb value;        /* the path's contribution (MIS-weighted) */
  double lum;       /* rgb_luminance(value): the MCMC target */
  double rx, ry;    /* raster position of the contribution */
  int grad_ok;      /* gradient present and valid: asked for, lum > 0, no overflow */
  int n_coords;     /* numbers drawn */
  const path_coord *coords; /* borrowed from the scratch; valid until its next use */
  unsigned flags;   /* PATH_* of the vertices and emitters used */
  int length;       /* segments of the longest contributing path (0: none) */
  int n_diff;       /* tangent length of pass 2 */
  int hess_ok;      /* hlum present: asked for (PATH_WANT_HESS), grad_ok, n_diff <= AD_H_CAPACITY */
  const double *hlum; /* d^2 luminance / du_i du_j over the tangent slots i <= j, the upper
                         triangle row by row ((i, j) at i n - i (i - 1) / 2 + j - i,
                         n = n_diff); borrowed like coords */
  double jac;       /* path_eval_bdpt_abs: the Jacobian of the absolute directions that
                       value includes (value / jac is path_eval_bdpt's); 1 otherwise */
  uint64_t topology; /* hash of the discrete choices: triangles hit, shadow rays,
                        lights, light triangles, envmap pixels, lobes, roulette.
                        Equal hashes: the same branch of f (up to rare side-rule flips) */
} path_eval;

typedef struct path_scratch path_scratch;

/* want_grad of the evaluators: 0 value only, PATH_WANT_GRAD the gradient
 * (path_coord's derivatives), PATH_WANT_HESS also the Hessian of the
 * luminance (path_eval.hlum, a second-order pass: its cost grows as n_diff^2
 * per operation, see bench_grad). */
enum { PATH_WANT_GRAD = 1, PATH_WANT_HESS = 2 };

/* A per-thread scratch (arena and record). */
lmc_status path_scratch_create(path_scratch **OUT_scratch, lmc_error *err);
/* Accepts NULL. */
void path_scratch_destroy(path_scratch *ps);

/* Unidirectional path with next-event estimation, as pt_li (integrator.h)
 * for the same numbers: draws 2 + 7 per bounce numbers from the current
 * LMC_STREAM_CAMERA stream of smp (the caller selects it). With want_grad,
 * also fills the derivatives of path_coord. `rays` (may be NULL) is
 * incremented by the rays traced. Returns LMC_OK. */
lmc_status path_eval_pt(const scene *sc, const render_settings *rs, lmc_sampler *smp,
                        int want_grad, path_scratch *ps, path_eval *OUT_eval, int64_t *rays);

/* One strategy (s, t) of bidirectional path tracing, as bdpt_connect
 * (integrator.h) for the same numbers, with its power-heuristic MIS weight
 * over all strategies (bdpt_mis_weight), in duals: the camera subpath of t
 * vertices and the light subpath of s vertices are traced (path_bdpt.c)
 * and joined. The BDPT layout of integrator.h:
 *   LMC_STREAM_CAMERA   t >= 2: 2 film numbers (rx = u0 W, ry = u1 H), then
 *                       BDPT_DIMS_PER_VERTEX per camera-subpath surface
 *                       vertex: lobe (discrete), direction (2), roulette
 *                       (discrete); nothing for t = 1.
 *   LMC_STREAM_LIGHT    s >= 2: BDPT_DIMS_LIGHT_START (light choice, discrete;
 *                       position (2); direction (2)), then
 *                       BDPT_DIMS_PER_VERTEX per light-subpath surface vertex;
 *                       nothing for s <= 1.
 *   LMC_STREAM_CONNECT  s = 1: positions 3 (t - 2) .. 3 (t - 2) + 2, the
 *                       light choice (discrete) and the point on the light of
 *                       camera vertex t (the 3 (t - 2) before are drawn and
 *                       unused, so each t keeps bdpt_li's coordinates).
 * s = 0 is a camera subpath ending on an emitter (area light, or escaped to
 * the infinite lights); t = 1 is light tracing: value and gradient are
 * those of the film splat at (rx, ry), which depend on u (path_coord.drx,
 * dry). The (s, t) BDPT does not use ((1, 1); lengths s + t - 1 outside
 * [mindepth, maxdepth]; t > maxdepth + 1) give 0 and draw nothing. With
 * want_grad the derivatives of path_coord are filled as path_eval_pt's.
 * Returns LMC_OK. */
lmc_status path_eval_bdpt(const scene *sc, const render_settings *rs, lmc_sampler *smp, int s,
                          int t, int want_grad, path_scratch *ps, path_eval *OUT_eval,
                          int64_t *rays);

/* The same strategy with absolute directions (integrator.h, bdpt_param) at
 * every scattering vertex of its two subpaths whose BSDF is rougher than
 * rough_min: bdpt_camera_subpath_p and bdpt_light_subpath_p with
 * abs_until t - 1 and s - 1, as mcmc.c's bdpt states read a state of label
 * (s, t). value (and its gradient) is in the absolute numbers' measure:
 * the contribution times the product of those vertices' pdf J, which
 * OUT_eval->jac reports. rough_min >= 1: path_eval_bdpt. */
lmc_status path_eval_bdpt_abs(const scene *sc, const render_settings *rs, lmc_sampler *smp, int s,
                              int t, double rough_min, int want_grad, path_scratch *ps,
                              path_eval *OUT_eval, int64_t *rays);

/* ---- A sampler over stored vectors, for replaying and perturbing paths ---
 * Each stream is a growable array; reading past its end draws a fresh
 * uniform number from `r` and appends it (so one object records a path
 * from random numbers and then replays it, e.g. with a coordinate moved
 * by h for finite differences). */
typedef struct path_vec_sampler {
  lmc_sampler base;
  double *u[LMC_STREAM_COUNT];
  int n[LMC_STREAM_COUNT], cap[LMC_STREAM_COUNT];
  int pos[LMC_STREAM_COUNT];
  int stream;
  rng r;
} path_vec_sampler;

lmc_status path_vec_sampler_init(path_vec_sampler *s, uint64_t seed, lmc_error *err);
void path_vec_sampler_free(path_vec_sampler *s);
/* Forgets the stored numbers (keeps the buffers), next numbers are fresh. */
void path_vec_sampler_clear(path_vec_sampler *s);
/* Rewinds every stream to position 0 and selects LMC_STREAM_CAMERA. */
void path_vec_sampler_rewind(path_vec_sampler *s);

#endif
