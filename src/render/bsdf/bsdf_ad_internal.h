/*
 * bsdf_ad_internal.h: the dual forms of bsdf_internal.h's functions (not
 * API), from the same sources (bsdf_generic.h, bsdf_smooth_generic.h,
 * bsdf_rough_generic.h, compiled twice by bsdf.c, bsdf_smooth.c and
 * bsdf_rough.c): with tangent length 0 their values are the plain ones to
 * rounding (tests/test_bsdf_grad.c checks them).
 */
#ifndef LMC_RENDER_BSDF_AD_INTERNAL_H
#define LMC_RENDER_BSDF_AD_INTERNAL_H

#include "render/bsdf/bsdf_ad.h"
#include "render/bsdf/bsdf_internal.h"

/* Dual of bsdf__finish: fills *out (weight = f |cos wi| / pdf) and returns
 * 0 when the weight is black, not finite or pdf <= 0. */
int bsdf__finish_ad(ad_arena *A, bsdf_sample_ad *out, adv3 wi, adrgb f, ad pdf, double eta,
                    int flags);
/* Dual of bsdf__cosine_hemisphere: the same concentric map with its
 * derivatives. */
adv3 bsdf__cosine_hemisphere_ad(ad_arena *A, ad u1, ad u2);
/* Dual of bsdf__plastic_kd. */
adrgb bsdf__plastic_kd_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, double fdr);

#define BSDF__AD_MODEL(NAME)                                                                    \
  adrgb bsdf__##NAME##_eval_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi,     \
                               transport_mode mode);                                            \
  ad bsdf__##NAME##_pdf_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi);         \
  int bsdf__##NAME##_sample_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, ad u_lobe,    \
                               ad u1, ad u2, transport_mode mode, bsdf_sample_ad *out);
#define BSDF__AD_MODEL_EVAL_PDF(NAME)                                                           \
  adrgb bsdf__##NAME##_eval_pdf_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi, \
                                   transport_mode mode, ad *OUT_pdf);

BSDF__AD_MODEL(diffuse)
BSDF__AD_MODEL(phong)
BSDF__AD_MODEL(conductor)
BSDF__AD_MODEL(roughconductor)
BSDF__AD_MODEL(dielectric)
BSDF__AD_MODEL(roughdielectric)
BSDF__AD_MODEL(plastic)
BSDF__AD_MODEL(roughdiffuse)
BSDF__AD_MODEL(ward)
BSDF__AD_MODEL(roughplastic)
BSDF__AD_MODEL(thindielectric)
BSDF__AD_MODEL_EVAL_PDF(phong)
BSDF__AD_MODEL_EVAL_PDF(roughconductor)
BSDF__AD_MODEL_EVAL_PDF(roughdielectric)
BSDF__AD_MODEL_EVAL_PDF(roughplastic)

#undef BSDF__AD_MODEL
#undef BSDF__AD_MODEL_EVAL_PDF

#endif
