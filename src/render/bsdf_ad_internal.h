/*
 * bsdf_ad_internal.h: what the dual BSDF files share (not API).
 * bsdf_ad.c dispatches on the model, applies the twosided flip, keeps the
 * arena small and holds the dual Fresnel terms; bsdf_smooth_ad.c has
 * diffuse, phong, the smooth conductor, the smooth dielectric and plastic;
 * bsdf_rough_ad.c the microfacet models (with microfacet_ad.c).
 *
 * Each model is the dual form of the function with the same name in
 * bsdf_internal.h: same branches (on values), same formulas, same order of
 * operations where that is cheap, so that with tangent length 0 the value
 * is the plain one to rounding (tests/test_bsdf_grad.c checks 1e-12).
 */
#ifndef LMC_RENDER_BSDF_AD_INTERNAL_H
#define LMC_RENDER_BSDF_AD_INTERNAL_H

#include "render/bsdf_ad.h"
#include "render/bsdf_internal.h"

/* ---- Small dual helpers -------------------------------------------------- */

static inline adrgb adrgb_zero(const ad_arena *A) {
  return (adrgb){ad_const(A, 0.0), ad_const(A, 0.0), ad_const(A, 0.0)};
}
static inline adrgb adrgb_scale_s(ad_arena *A, adrgb a, double s) {
  return (adrgb){ad_mul_s(A, a.r, s), ad_mul_s(A, a.g, s), ad_mul_s(A, a.b, s)};
}
/* (-w.x, -w.y, w.z): the mirror direction about the shading normal. */
static inline adv3 bsdf__ad_mirror(ad_arena *A, adv3 w) {
  return adv3_make(ad_neg(A, w.x), ad_neg(A, w.y), w.z);
}

/* Dual of bsdf__finish: fills *out (weight = f |cos wi| / pdf) and returns
 * 0 when the weight is black, not finite or pdf <= 0. */
int bsdf__finish_ad(ad_arena *A, bsdf_sample_ad *out, adv3 wi, adrgb f, ad pdf, double eta,
                    int flags);
/* Dual fresnel_dielectric; OUT_cos_t may be NULL. */
ad fresnel_dielectric_ad(ad_arena *A, ad cos_i, double eta, ad *OUT_cos_t);
/* Dual fresnel_conductor. */
adrgb fresnel_conductor_ad(ad_arena *A, ad cos_i, rgb eta, rgb k);
/* Cosine-weighted hemisphere (Malley, through the concentric disk), the
 * dual warp_square_to_cosine_hemisphere. */
adv3 bsdf__ad_cosine_hemisphere(ad_arena *A, ad u1, ad u2);

/* ---- The models (arguments as in bsdf_internal.h) ------------------------ */

#define BSDF__AD_MODEL(NAME)                                                                    \
  adrgb bsdf__##NAME##_eval_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi,     \
                               transport_mode mode);                                            \
  ad bsdf__##NAME##_pdf_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi);         \
  int bsdf__##NAME##_sample_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, ad u_lobe,    \
                               ad u1, ad u2, transport_mode mode, bsdf_sample_ad *OUT_sample);

BSDF__AD_MODEL(diffuse)
BSDF__AD_MODEL(phong)
BSDF__AD_MODEL(conductor)
BSDF__AD_MODEL(roughconductor)
BSDF__AD_MODEL(dielectric)
BSDF__AD_MODEL(roughdielectric)
BSDF__AD_MODEL(plastic)

#undef BSDF__AD_MODEL

#endif
