/*
 * bsdf_internal.h: what the BSDF files share (not API). bsdf.c calls the
 * models through their records (bsdf_model.h) and holds Fresnel, the IOR
 * tables and the common defaults; each model is one file of models/, its
 * body compiled twice (render/model_twice.h); bsdf_rtrans.c has
 * roughplastic's rough transmittance table. The helpers below are in
 * doubles; their dual forms are in bsdf_ad_internal.h.
 *
 * Every model gets its arguments already in the orientation it expects
 * (bsdf.c applies the twosided flip), and the conventions of bsdf.h.
 */
#ifndef LMC_RENDER_BSDF_INTERNAL_H
#define LMC_RENDER_BSDF_INTERNAL_H

#include "render/bsdf/bsdf.h"
#include "render/warp.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Mitsuba's IOR of air (its "air"), the default outside. */
#define BSDF_AIR_IOR 1.000277

/* (-w.x, -w.y, w.z): the mirror direction about the shading normal. */
static inline vec3 bsdf__mirror(vec3 w) { return v3(-w.x, -w.y, w.z); }

/* Fills *out with wi, f, pdf, eta, flags and weight = f |cos wi| / pdf;
 * returns 0 (absorbed) when the weight is black, not finite or pdf <= 0. */
int bsdf__finish(bsdf_sample *out, vec3 wi, rgb f, double pdf, double eta, int flags);
/* Diffuse Fresnel reflectance: the cosine-weighted hemispherical average
 * of fresnel_dielectric at relative IOR eta (numerical, cached per thread). */
double bsdf__fresnel_diffuse_reflectance(double eta);
/* Mitsuba's specular sampling weight: lum(mean spec) / (lum(mean spec) + lum(mean diff)). */
double bsdf__specular_weight(const texture *spec, const texture *diff);
/* Cosine-weighted hemisphere sample (bsdf_generic.h; dual form in
 * bsdf_ad_internal.h). */
vec3 bsdf__cosine_hemisphere(double u1, double u2);
/* The plastics' diffuse reflectance with its internal reflections, kd' =
 * kd / (1 - F_dr) or, nonlinear, kd / (1 - kd F_dr) (bsdf_generic.h; dual
 * form in bsdf_ad_internal.h). fdr: the interface's diffuse reflectance
 * seen from inside. */
rgb bsdf__plastic_kd(const bsdf *b, double tu, double tv, double fdr);
/* Fills *rt with the rough transmittance of (dist, alpha, eta)
 * (bsdf_rtrans.c; bsdf.h's bsdf_rtrans says what it holds). */
void bsdf__rtrans_fill(bsdf_rtrans *rt, mf_dist dist, double alpha, double eta);
/* The rough transmittance table of roughplastic b: its own when its key
 * matches b's parameters, else one computed into a per-thread cache. */
const bsdf_rtrans *bsdf__rtrans_get(const bsdf *b);

/* Helpers of the inverses (bsdf_generic.h; a lobe's u_lobe in its interval
 * [lo, hi) is warp_uniform_in). The numbers of a cosine-weighted direction wi (wi.z > 0): u_lobe from
 * r[1] in [lo, hi), (u1, u2) by the concentric map's inverse. */
int bsdf__invert_cosine(vec3 wi, double lo, double hi, const double r[4], double OUT_u[3]);
/* A glossy lobe chosen with probability w (u_lobe in [0, w)) mixed with a
 * cosine-weighted one ([w, 1)), whose mixture density at wi is pdf: picks
 * the diffuse lobe with its share (1 - w) cos(wi) / (pi pdf) by r[0], else
 * *OUT_glossy = 1 and u_lobe in [0, w) for the caller to fill (u1, u2). */
int bsdf__invert_mixture(vec3 wi, double w, double pdf, const double r[4], double OUT_u[3],
                         int *OUT_glossy);
/* 1 when unit directions agree to rounding (a delta lobe's wi). */
int bsdf__same_dir(vec3 a, vec3 b);
/* A delta lobe chosen for u_lobe in [lo, hi) (*OUT_pmf = hi - lo); the
 * direction numbers are r's. */
int bsdf__invert_delta(double lo, double hi, const double r[4], double OUT_u[3],
                       double *OUT_pmf);

#endif
