/*
 * path_internal.h: what path.c (the unidirectional estimator) and
 * path_bdpt.c (one bidirectional strategy) share. Not API: only these two
 * files include it.
 *
 * Both estimators run on the same machinery (path.h: "locate, then
 * re-evaluate"): an evaluation context that draws numbers from the sampler
 * and records them (pass 1) or replays them with tangent slots (pass 2);
 * closest hits and shadow rays traced with Embree and recorded (pass 1) or
 * read back (pass 2); the vertex re-evaluated on its recorded triangle in
 * duals; the camera ray; the emitters' sampling and density routines of
 * light.c in duals; and the two-pass driver path__run. Each exists once,
 * here or in path.c, and serves both estimators.
 *
 * Internal names carry the `path__` prefix (libuv's convention).
 */
#ifndef LMC_RENDER_PATH_INTERNAL_H
#define LMC_RENDER_PATH_INTERNAL_H

#include "ad/dual.h"
#include "ad/dual_math.h"
#include "ad/dual_vec3.h"
#include "render/bsdf/bsdf_ad.h"
#include "render/integrators/path.h"
#include "render/lights/light_ad.h"

/* A surface vertex re-evaluated in duals on its recorded triangle. */
typedef struct path__hit {
  int mesh;
  int64_t prim;
  adv3 p;
  vec3 ng;
  ad_frame sh;
  ad tu, tv;
  const bsdf *bsdf;
  int light;
} path__hit;

/* A vertex of a bidirectional subpath in duals: bdpt_vertex of
 * integrator.h with dual positions, directions, throughput and densities
 * (the geometric normal n is constant on its triangle). */
typedef struct path__bdv {
  bdpt_vertex_type type;
  int delta;       /* left through a delta lobe */
  int light;       /* as bdpt_vertex.light */
  unsigned lobe;   /* PATH_LOBE_* of the lobe sampled here (0: none) */
  adrgb beta;
  ad pdf_fwd, pdf_rev;
  adv3 p;
  vec3 n;
  adv3 dir;        /* vertices at infinity: the direction the light travels */
  adv3 wo;         /* SURFACE: towards the previous vertex of its subpath */
  path__hit hit;   /* SURFACE */
  ad jac;          /* the direction it scattered into was absolute: pdf J (integrator.h,
                      bdpt_param); else 1 */
} path__bdv;

#define PATH__MAX_HITS 1024
#define PATH__MAX_VIS 1024
#define PATH__ARENA_DUALS 16384 /* duals of length AD_CAPACITY one bounce may hold */
#define PATH__KEEP 48           /* duals carried from one bounce to the next */
#define PATH__ARENA2_DUALS 4096 /* duals of a second-order arena at first (it keeps every dual
                                   of an evaluation: ~1500 at length 5); grown when short */
#define PATH__ARENA2_MAX_BYTES ((size_t)256 << 20) /* ... up to this size (then gradient only) */

struct path_scratch {
  double *arena_buf; /* owned */
  size_t arena_cap;
  /* Second-order pass (PATH_WANT_HESS), allocated on first use and grown
   * with the tangent length and the path's operations: its arena (with the
   * tape) and the dense Hessian of the sweep. */
  double *arena2_buf; /* owned */
  size_t arena2_cap;
  size_t arena2_duals; /* the most duals it was sized for (where the next evaluation starts) */
  double *hfull;       /* owned: AD_H_CAPACITY^2 */
  ad_arena A;
  /* The record of pass 1. */
  int n_draw;
  double du[PATH_MAX_DRAWS];
  signed char dstream[PATH_MAX_DRAWS];
  int dpos[PATH_MAX_DRAWS];
  int dvar[PATH_MAX_DRAWS]; /* tangent slot, or -1 */
  int n_hit;
  int hit_mesh[PATH__MAX_HITS];
  int64_t hit_prim[PATH__MAX_HITS];
  int n_vis;
  unsigned char vis[PATH__MAX_VIS];
  /* Output and temporaries. */
  path_coord coords[PATH_MAX_DRAWS];
  double hlum[AD_H_CAPACITY * (AD_H_CAPACITY + 1) / 2]; /* path_eval.hlum */
  double keep_tmp[PATH__KEEP * AD_CAPACITY];
  /* The dual subpaths of path_eval_bdpt. */
  path__bdv bd_cam[BDPT_MAX_VERTICES], bd_light[BDPT_MAX_VERTICES];
};

typedef struct path__ctx {
  const scene *sc;
  const render_settings *rs;
  path_scratch *ps;
  ad_arena *A;
  int replay;       /* 0: trace and record; 1: read the record */
  lmc_sampler *smp; /* pass 1 only */
  int stream;
  int spos[LMC_STREAM_COUNT];
  int k_draw, k_hit, k_vis; /* replay cursors */
  int n_var;                /* tangent slots handed out (pass 1) */
  int lost;                 /* a record overflowed: no gradient */
  int64_t rays;
  uint64_t topo; /* hash of the discrete choices (path_eval.topology) */
  unsigned flags;
  int length;
  const void *arg; /* the estimator's parameters (path_eval_bdpt: the strategy) */
  int media;       /* the unidirectional estimator walks through the scene's media */
  double jac;      /* the estimator's Jacobian factor in the value (1: none; path_eval.jac) */
} path__ctx;

/* A dual with the given value and the tangent coef * d_a (the chain rule
 * for a scalar map whose value comes from plain code). */
static inline ad path__chain(ad_arena *A, double value, double coef, ad a) {
  ad r = ad_mul_s(A, a, coef);
  r.v = value;
  return r;
}

static inline vec3 path__val(adv3 a) { return v3(a.x.v, a.y.v, a.z.v); }

static inline adv3 path__cv(const ad_arena *A, vec3 a) { return adv3_const(A, a.x, a.y, a.z); }

/* m v for the upper 3x3 of a row-major matrix (xform_vector's order). */
static inline adv3 path__mat_vec(ad_arena *A, const double (*m)[4], adv3 v) {
  adv3 r;
  r.x = ad_add(A, ad_lincomb(A, m[0][0], v.x, m[0][1], v.y), ad_mul_s(A, v.z, m[0][2]));
  r.y = ad_add(A, ad_lincomb(A, m[1][0], v.x, m[1][1], v.y), ad_mul_s(A, v.z, m[1][2]));
  r.z = ad_add(A, ad_lincomb(A, m[2][0], v.x, m[2][1], v.y), ad_mul_s(A, v.z, m[2][2]));
  return r;
}

/* b0 p0 + b1 p1 + b2 p2 in scene_intersect's order. */
static inline adv3 path__bary(ad_arena *A, vec3 p0, vec3 p1, vec3 p2, ad b0, ad b1, ad b2) {
  adv3 r;
  r.x = ad_add(A, ad_add(A, ad_mul_s(A, b0, p0.x), ad_mul_s(A, b1, p1.x)), ad_mul_s(A, b2, p2.x));
  r.y = ad_add(A, ad_add(A, ad_mul_s(A, b0, p0.y), ad_mul_s(A, b1, p1.y)), ad_mul_s(A, b2, p2.y));
  r.z = ad_add(A, ad_add(A, ad_mul_s(A, b0, p0.z), ad_mul_s(A, b1, p1.z)), ad_mul_s(A, b2, p2.z));
  return r;
}

/* a x e for a constant e: x = a_y e_z - a_z e_y (two-term combinations). */
static inline adv3 path__cross_c(ad_arena *A, adv3 a, vec3 e) {
  adv3 r;
  r.x = ad_lincomb(A, e.z, a.y, -e.y, a.z);
  r.y = ad_lincomb(A, e.x, a.z, -e.z, a.x);
  r.z = ad_lincomb(A, e.y, a.x, -e.x, a.y);
  return r;
}

/* e . a for a constant e, summed in v3_dot's order. */
static inline ad path__dot_c(ad_arena *A, vec3 e, adv3 a) {
  return ad_add(A, ad_lincomb(A, e.x, a.x, e.y, a.y), ad_mul_s(A, a.z, e.z));
}

static inline adrgb path__rgb_fma(ad_arena *A, adrgb acc, adrgb a, adrgb b) {
  return (adrgb){ad_fma(A, a.r, b.r, acc.r), ad_fma(A, a.g, b.g, acc.g), ad_fma(A, a.b, b.b, acc.b)};
}

static inline adrgb path__rgb_scale_c(ad_arena *A, rgb c, ad s) {
  return (adrgb){ad_mul_s(A, s, c.r), ad_mul_s(A, s, c.g), ad_mul_s(A, s, c.b)};
}

static inline int path__rgb_black(adrgb c) { return c.r.v == 0.0 && c.g.v == 0.0 && c.b.v == 0.0; }

/* The power heuristic of integrator.h (mis_power) on duals. */
static inline ad path__mis(ad_arena *A, ad a, ad b) {
  if (!(a.v > 0.0)) return ad_const(A, 0.0);
  if (!isfinite(a.v)) return ad_const(A, 1.0);
  ad a2 = ad_sqr(A, a), b2 = ad_sqr(A, b);
  ad r = ad_div(A, a2, ad_add(A, a2, b2));
  r.v = a2.v / (a2.v + b2.v);
  return r;
}



/* A light sample from a receiver, in duals (light_ad.h). */
typedef light_li_sample_ad path__li;

/* ---- Shared routines (path.c) -------------------------------------------- */

/* Mixes a discrete choice into the topology hash. */
void path__topo(path__ctx *c, int64_t x);
/* Switches the stream numbers are drawn from. */
void path__use_stream(path__ctx *c, int stream);
/* The next number of the current stream; `diff` asks for a tangent slot. */
ad path__draw(path__ctx *c, int diff);
/* Carries the duals *v[0..n-1] over a rewind of the arena to `mark`
 * (their tangents are copied out and remade at the bottom); n <= PATH__KEEP,
 * otherwise nothing is rewound. */
void path__keep(path__ctx *c, size_t mark, ad *const *v, int n);
/* The surface point of triangle prim of mesh mi hit by the dual ray. */
void path__hit_eval(path__ctx *c, int mi, int64_t prim, adv3 org, adv3 dir, path__hit *h);
/* Closest hit along the dual ray (traced or replayed); 0 on a miss. */
int path__intersect(path__ctx *c, adv3 org, adv3 dir, double tmin, path__hit *h);
/* Shadow ray from p towards lp (or along wi when infinite): 1 when blocked. */
int path__blocked(path__ctx *c, vec3 p, vec3 wi, vec3 lp, int infinite);
/* The camera ray through the film position (u0, u1): raster position and
 * the pinhole ray (camera.c's formulas) in duals. */
void path__camera_ray(path__ctx *c, ad u0, ad u1, ad *OUT_rx, ad *OUT_ry, adv3 *OUT_org,
                      adv3 *OUT_dir);

/* Emitters in duals (light_ad.h, path_lights.c): the density of direct
 * sampling, direct sampling with its choices noted in the topology, and
 * that noting for a light sample's triangle (tri) and pixel (cell). */
ad path__pdf_li(path__ctx *c, const light *l, adv3 ref, adv3 w, adv3 p, vec3 n);
int path__sample_li(path__ctx *c, const light *l, adv3 ref, ad u1, ad u2, path__li *out);
void path__light_topo(path__ctx *c, int64_t tri, const int64_t cell[2]);
unsigned path__emit_flag(const light *l);
unsigned path__lobe_flag(int bsdf_flags);

/* An estimator: the contribution, and the raster position it goes to. */
typedef void (*path__estimator)(path__ctx *c, adrgb *OUT_L, ad *OUT_rx, ad *OUT_ry);

/* Runs est in pass 1 and, with want_grad, pass 2; fills ev. `arg` is
 * handed to the estimator as c->arg. */
void path__run(const scene *sc, const render_settings *rs, lmc_sampler *smp, int want_grad,
               path_scratch *ps, path_eval *ev, int64_t *rays, path__estimator est,
               const void *arg);

#endif
