/*
 * bsdf_internal.h: what the BSDF files share (not API). bsdf.c dispatches
 * on the model and holds Fresnel, the IOR tables and the defaults;
 * bsdf_smooth.c has diffuse, phong, the smooth conductor, the smooth and
 * thin dielectrics, plastic, roughdiffuse (Oren-Nayar) and ward;
 * bsdf_rough.c the microfacet models (roughplastic and its rough
 * transmittance table among them). Each
 * compiles its *_generic.h body twice: in doubles (declared here) and in
 * duals (bsdf_ad_internal.h).
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
 * (bsdf_rough.c; bsdf.h's bsdf_rtrans says what it holds). */
void bsdf__rtrans_fill(bsdf_rtrans *rt, mf_dist dist, double alpha, double eta);
/* The rough transmittance table of roughplastic b: its own when its key
 * matches b's parameters, else one computed into a per-thread cache. */
const bsdf_rtrans *bsdf__rtrans_get(const bsdf *b);

/* The models: eval, pdf and sample with the signatures of bsdf.h; the
 * models whose eval and pdf share work also have eval_pdf (bsdf_eval_pdf).
 * Their dual forms are in bsdf_ad_internal.h; both come from one source
 * (bsdf_smooth_generic.h, bsdf_rough_generic.h). */
#define BSDF__MODEL(NAME)                                                                        \
  rgb bsdf__##NAME##_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,               \
                          transport_mode mode);                                                 \
  double bsdf__##NAME##_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi);            \
  int bsdf__##NAME##_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe,       \
                            double u1, double u2, transport_mode mode, bsdf_sample *out);
#define BSDF__MODEL_EVAL_PDF(NAME)                                                               \
  rgb bsdf__##NAME##_eval_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,           \
                              transport_mode mode, double *OUT_pdf);

BSDF__MODEL(diffuse)
BSDF__MODEL(phong)
BSDF__MODEL(conductor)
BSDF__MODEL(roughconductor)
BSDF__MODEL(dielectric)
BSDF__MODEL(roughdielectric)
BSDF__MODEL(plastic)
BSDF__MODEL(roughdiffuse)
BSDF__MODEL(ward)
BSDF__MODEL(roughplastic)
BSDF__MODEL(thindielectric)
BSDF__MODEL_EVAL_PDF(phong)
BSDF__MODEL_EVAL_PDF(roughconductor)
BSDF__MODEL_EVAL_PDF(roughdielectric)
BSDF__MODEL_EVAL_PDF(roughplastic)

/* The models' inverses of their samplers (bsdf_invert's contract, per
 * model, wo and wi already flipped by twosided): *OUT_pmf gets the
 * probability of the delta lobe found (delta only). */
#define BSDF__MODEL_INVERT(NAME)                                                                 \
  int bsdf__##NAME##_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,  \
                            const double r[4], double OUT_u[3], double *OUT_pmf);
BSDF__MODEL_INVERT(diffuse)
BSDF__MODEL_INVERT(phong)
BSDF__MODEL_INVERT(conductor)
BSDF__MODEL_INVERT(roughconductor)
BSDF__MODEL_INVERT(dielectric)
BSDF__MODEL_INVERT(roughdielectric)
BSDF__MODEL_INVERT(plastic)
BSDF__MODEL_INVERT(roughdiffuse)
BSDF__MODEL_INVERT(ward)
BSDF__MODEL_INVERT(roughplastic)
BSDF__MODEL_INVERT(thindielectric)

#undef BSDF__MODEL
#undef BSDF__MODEL_EVAL_PDF
#undef BSDF__MODEL_INVERT

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

/* The models by type, for the dispatchers (bsdf_generic.h): each
 * BSDF__CASE(TYPE, name) stands for one model. */
#define BSDF__CASES                                                                              \
  BSDF__CASE(BSDF_DIFFUSE, diffuse)                                                              \
  BSDF__CASE(BSDF_PHONG, phong)                                                                  \
  BSDF__CASE(BSDF_CONDUCTOR, conductor)                                                          \
  BSDF__CASE(BSDF_ROUGHCONDUCTOR, roughconductor)                                                \
  BSDF__CASE(BSDF_DIELECTRIC, dielectric)                                                        \
  BSDF__CASE(BSDF_ROUGHDIELECTRIC, roughdielectric)                                              \
  BSDF__CASE(BSDF_PLASTIC, plastic)                                                              \
  BSDF__CASE(BSDF_ROUGHDIFFUSE, roughdiffuse)                                                    \
  BSDF__CASE(BSDF_WARD, ward)                                                                    \
  BSDF__CASE(BSDF_ROUGHPLASTIC, roughplastic)                                                    \
  BSDF__CASE(BSDF_THINDIELECTRIC, thindielectric)

#endif
