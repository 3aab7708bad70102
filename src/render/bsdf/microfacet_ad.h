/*
 * microfacet_ad.h: the microfacet distributions of microfacet.h (Beckmann
 * and GGX: D, Smith Lambda / G1 / G, sampling of all or of the visible
 * normals, and the sampling density) in dual arithmetic, for the rough
 * models (models/rough*.c).
 *
 * The same source as the plain functions (microfacet_generic.h, compiled
 * twice by microfacet.c; see microfacet.h for the papers: Walter et al.
 * 2007, Heitz and d'Eon 2014, Heitz 2018), so with tangent length 0 the
 * values are the plain ones to rounding. The
 * roughness alpha is a dual because the rough dielectric widens it with
 * cos(wo) when it does not sample visible normals. Sampling the visible
 * Beckmann slopes inverts a CDF by Newton iteration; the iteration runs on
 * values and the slope's tangent comes from the implicit function theorem
 * (see microfacet_generic.h), which is the exact derivative of the converged
 * solution.
 */
#ifndef LMC_RENDER_MICROFACET_AD_H
#define LMC_RENDER_MICROFACET_AD_H

#include "render/bsdf/bsdf_ad.h"
#include "render/bsdf/microfacet.h"

/* D(m), the dual mf_D. */
ad mf_D_ad(ad_arena *A, mf_dist dist, ad alpha, adv3 m);
/* Smith Lambda(v), the dual mf_lambda (+inf at grazing, as a constant). */
ad mf_lambda_ad(ad_arena *A, mf_dist dist, ad alpha, adv3 v);
/* Smith G1(v, m), the dual mf_G1. */
ad mf_G1_ad(ad_arena *A, mf_dist dist, ad alpha, adv3 v, adv3 m);
/* G(wi, wo, m) = G1(wi, m) G1(wo, m). */
ad mf_G_ad(ad_arena *A, mf_dist dist, ad alpha, adv3 wi, adv3 wo, adv3 m);
/* A microfacet normal from (u1, u2), the dual mf_sample. */
adv3 mf_sample_ad(ad_arena *A, mf_dist dist, ad alpha, adv3 v, int visible, ad u1, ad u2);
/* Density of mf_sample_ad producing m, the dual mf_pdf. */
ad mf_pdf_ad(ad_arena *A, mf_dist dist, ad alpha, adv3 v, adv3 m, int visible);
/* That density from D(m) = d and G1(v, m) = g1 already known, the dual
 * mf_pdf_known. */
ad mf_pdf_known_ad(ad_arena *A, ad d, ad g1, adv3 v, adv3 m, int visible);

#endif
