/*
 * mut_lenssub.h: Veach's lens subpath mutation (Veach 1997, section
 * 11.4.4) on pathspace.h's states: the path's lens subpath is replaced by
 * a fresh one through a raster point drawn uniformly over the film, so
 * that chains cover the image evenly.
 *
 * The lens subpath of x is x_0 .. x_m, m the first vertex from the camera
 * that is D (connectible, a surface scattering through a smooth lobe, and
 * not G: ps_glossy): the form E (S|G)* D. The mutation applies when
 * x_{m+1} is connectible too (a D or G surface or the emitter end; not
 * x_m = x_k). The new subpath y_0 .. y_m' is a camera walk: the pinhole's
 * ray through a uniform raster point, then at each surface a direction:
 * at a G surface its BSDF's sample, and the walk goes on; elsewhere a lobe
 * sampled from its BSDF: through a delta lobe the walk goes on, through a
 * smooth one it stops there (that vertex is y_m'; the sampled direction
 * is not used), so m' may differ from m and the
 * path's length changes by m' - m, within the path space's lengths (a
 * walk longer than that, or one that leaves the scene, makes no
 * proposal). y_m' joins x_{m+1}; the rest of x is kept.
 *
 * Transition density. The walk's, in the path measure of y_1 .. y_m':
 *   T(x -> y) = pdf_cam(y_1) prod_{i=2..m'} pdf_cam(y_i) P_smooth(y_m'),
 * pdf_cam the camera-side densities of pathspace.h (through a delta lobe
 * its probability times the reduced Jacobian; after a G vertex its BSDF's
 * sampling density), P_smooth(v) the probability that v's BSDF samples a
 * smooth lobe from the direction the walk arrived along (1 for a BSDF
 * without delta lobes). It depends on y's
 * lens subpath alone, so the ratio is
 *   f(y) T(y -> x) / (f(x) T(x -> y)), T(y -> x) the same product over x's.
 */
#ifndef LMC_PATH_MUT_LENSSUB_H
#define LMC_PATH_MUT_LENSSUB_H

#include "lmc/path/pathspace.h"
#include "render/rng.h"

/* The mutation: the path space and a test hook. */
typedef struct mut_lenssub {
  const ps_context *ctx;   /* borrowed */
  double test_smooth_power; /* tests only: P_smooth raised to this wrong power in T (1) */
} mut_lenssub;

void mut_lenssub_init(mut_lenssub *ml, const ps_context *ctx);

/* x's lens subpath end m, or 0 when the mutation does not apply. */
int mut_lenssub_m(const ps_context *ctx, const ps_path *x);

/* The density of p's lens subpath as the mutation samples it (T above,
 * from p's caches), 0 when it does not apply to p. */
double mut_lenssub_density(const mut_lenssub *ml, const ps_path *p);

/* The probability that surface vertex v's BSDF samples a smooth lobe from
 * the unit direction wo (towards the vertex before it). */
double mut_lenssub_smooth_prob(const bdpt_vertex *v, vec3 wo);

/* Proposes y from x (the mutation must apply to x), with f(y) T(y -> x) /
 * (f(x) T(x -> y)) in *OUT_ratio. Returns 0 when there is no proposal.
 * rays (may be NULL) adds the rays traced. */
int mut_lenssub_propose(const mut_lenssub *ml, rng *r, const ps_path *x, ps_path *OUT_y,
                        double *OUT_ratio, int64_t *rays);

#endif
