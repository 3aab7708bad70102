/*
 * bsdf_ad_internal.h: the dual forms of bsdf_internal.h's functions (not
 * API), from the same sources (bsdf_generic.h, compiled twice by bsdf.c;
 * the models' own bodies are static in their files, models/): with tangent
 * length 0 their values are the plain ones to rounding
 * (tests/test_bsdf_grad.c checks them).
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

/* Dual of bsdf__mirror. */
static inline adv3 bsdf__mirror_ad(ad_arena *A, adv3 w) {
  return adv3_make(ad_neg(A, w.x), ad_neg(A, w.y), w.z);
}

#endif
