/*
 * bsdf_ad.h: the BSDFs, textures and Fresnel terms in dual arithmetic, for
 * the differentiable path sampler (render/integrators/path.h).
 *
 * Every function here is the same formula as its plain counterpart in
 * bsdf.h / texture.h / microfacet.h, written once over dual numbers
 * (src/ad): with an arena of tangent length 0 it computes the plain value,
 * with tangent length n it also carries the derivatives with respect to the
 * n primary sample coordinates the inputs depend on. Branches (lobe choice,
 * total internal reflection, which side of the surface) look at values
 * only, so the derivative is that of the branch taken: the path sampler
 * holds that choice fixed, and MCMC acceptance handles the discontinuity.
 *
 * Conventions are those of bsdf.h (local shading frame, z-up, unit
 * directions pointing away from the surface, f without the cosine, a
 * sample's weight is f |cos wi| / pdf, delta lobes only from sampling).
 */
#ifndef LMC_RENDER_BSDF_AD_H
#define LMC_RENDER_BSDF_AD_H

#include "ad/dual.h"
#include "ad/dual_math.h"
#include "ad/dual_vec3.h"
#include "render/rgb_ad.h"
#include "render/bsdf/bsdf.h"
#include "render/bsdf/texture.h"

/* A BSDF sample in duals (see bsdf_sample in bsdf.h). */
typedef struct bsdf_sample_ad {
  adv3 wi;      /* sampled direction, local frame */
  adrgb f;      /* BSDF value (delta convention of bsdf.h) */
  ad pdf;       /* solid-angle density (lobe probability for delta lobes) */
  adrgb weight; /* f |cos wi| / pdf */
  double eta;   /* relative IOR crossed (1 for reflection) */
  int flags;    /* the lobe sampled (BSDF_REFLECTION/TRANSMISSION | DIFFUSE/GLOSSY/DELTA) */
} bsdf_sample_ad;

/* Texture value at (u, v), bilinear for bitmaps (differentiable in u, v). */
adrgb tex_eval_ad(ad_arena *A, const texture *t, ad u, ad v);
/* tex_lum_gradient (texture.h) in duals. */
void tex_lum_gradient_ad(ad_arena *A, const texture *t, ad u, ad v, ad *OUT_du, ad *OUT_dv);

/* bsdf_eval, bsdf_pdf, bsdf_eval_pdf and bsdf_sample_f of bsdf.h in duals,
 * from the same source (bsdf_generic.h). (The sampler is bsdf_sample_f_ad,
 * after bsdf_sample_f: C cannot have a function named like the typedef
 * bsdf_sample_ad.) eval, pdf and sample rewind the arena to where they
 * found it, keeping only the duals they return. */
adrgb bsdf_eval_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi,
                   transport_mode mode);
ad bsdf_pdf_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi);
adrgb bsdf_eval_pdf_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi,
                       transport_mode mode, ad *OUT_pdf);
/* bsdf_shading_frame (bsdf.h) in duals. */
ad_frame bsdf_shading_frame_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, vec3 dpdu, vec3 dpdv, adv3 n,
                            vec3 ng);
/* Fresnel reflectance of a dielectric and of a conductor (bsdf.h) in duals. */
ad fresnel_dielectric_ad(ad_arena *A, ad cos_i, double eta, ad *OUT_cos_t);
adrgb fresnel_conductor_ad(ad_arena *A, ad cos_i, rgb eta, rgb k);
int bsdf_sample_f_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, ad u_lobe, ad u1, ad u2,
                     transport_mode mode, bsdf_sample_ad *OUT_sample);

#endif
