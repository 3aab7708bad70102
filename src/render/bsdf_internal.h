/*
 * bsdf_internal.h: what the BSDF files share (not API). bsdf.c dispatches
 * on the model and holds Fresnel, the IOR tables and the defaults;
 * bsdf_smooth.c has diffuse, phong, the smooth conductor, the smooth
 * dielectric and plastic; bsdf_rough.c the microfacet models.
 *
 * Every model gets its arguments already in the orientation it expects
 * (bsdf.c applies the twosided flip), and the conventions of bsdf.h.
 */
#ifndef LMC_RENDER_BSDF_INTERNAL_H
#define LMC_RENDER_BSDF_INTERNAL_H

#include "render/bsdf.h"

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

/* The models: eval, pdf and sample with the signatures of bsdf.h; the
 * models whose eval and pdf share work also have eval_pdf (bsdf_eval_pdf). */
rgb bsdf__diffuse_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode);
double bsdf__diffuse_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi);
int bsdf__diffuse_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe, double u1, double u2,
                     transport_mode mode, bsdf_sample *out);

rgb bsdf__phong_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode);
double bsdf__phong_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi);
rgb bsdf__phong_eval_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                         transport_mode mode, double *OUT_pdf);
int bsdf__phong_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe, double u1, double u2,
                     transport_mode mode, bsdf_sample *out);

rgb bsdf__conductor_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode);
double bsdf__conductor_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi);
int bsdf__conductor_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe, double u1, double u2,
                     transport_mode mode, bsdf_sample *out);

rgb bsdf__roughconductor_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode);
double bsdf__roughconductor_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi);
rgb bsdf__roughconductor_eval_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                         transport_mode mode, double *OUT_pdf);
int bsdf__roughconductor_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe, double u1, double u2,
                     transport_mode mode, bsdf_sample *out);

rgb bsdf__dielectric_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode);
double bsdf__dielectric_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi);
int bsdf__dielectric_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe, double u1, double u2,
                     transport_mode mode, bsdf_sample *out);

rgb bsdf__roughdielectric_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode);
double bsdf__roughdielectric_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi);
rgb bsdf__roughdielectric_eval_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                         transport_mode mode, double *OUT_pdf);
int bsdf__roughdielectric_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe, double u1, double u2,
                     transport_mode mode, bsdf_sample *out);

rgb bsdf__plastic_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode);
double bsdf__plastic_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi);
int bsdf__plastic_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe, double u1, double u2,
                     transport_mode mode, bsdf_sample *out);

#endif
