/*
 * bsdf_rough.c: the microfacet models of Walter, Marschner, Li and Torrance
 * 2007, "Microfacet Models for Refraction through Rough Surfaces", with the
 * distributions of microfacet.h, as Mitsuba 0.6's roughconductor and
 * roughdielectric define them.
 *
 * roughconductor (one-sided). With h = normalize(wo + wi):
 *   f = F_cond(wo . h) D(h) G(wo, wi, h) / (4 cos_o cos_i) * specularReflectance.
 * Sampling draws a normal m (visible normals of wo, or D(m) cos(theta_m))
 * and reflects wo about it; the density of wi is
 *   pdf = p_m(h) / (4 |wi . h|).
 *
 * roughdielectric (both sides; wo.z < 0 means wo is inside, where the IOR
 * is eta = intIOR / extIOR). Let e = eta_i / eta_o be the IOR of wi's side
 * over the IOR of wo's side (e = eta when wo is outside, 1/eta inside).
 *   reflection (cos_o cos_i > 0):  h = normalize(wo + wi),
 *     f_r = F D G / (4 |cos_o| |cos_i|) * specularReflectance;
 *   refraction (cos_o cos_i < 0):  h = normalize(wo + e wi) (the generalised
 *     half vector), flipped to the upper hemisphere,
 *     f_t = (1 - F) D G e^2 |wo.h| |wi.h| / (|cos_o| |cos_i| (wo.h + e wi.h)^2)
 *           * specularTransmittance,
 *     times 1/e^2 in radiance mode (radiance is compressed when it enters a
 *     denser medium), so that f_imp(wo, wi) = f_rad(wi, wo).
 * F = fresnel_dielectric(wo . h, eta). Sampling: a normal m is drawn as for
 * the conductor (from the side of wo, i.e. with wo mirrored to the upper
 * hemisphere), reflection is chosen with probability F(wo . m), refraction
 * otherwise. Densities of wi:
 *   reflection  F p_m(h) / (4 |wi.h|),
 *   refraction  (1 - F) p_m(h) e^2 |wi.h| / (wo.h + e wi.h)^2.
 * Without visible-normal sampling, Mitsuba samples a slightly wider
 * distribution, alpha (1.2 - 0.2 sqrt(|cos_o|)) (Walter et al.'s trick to
 * lower the weights at grazing angles); the pdf uses the same alpha.
 *
 * Sample weights are computed as f |cos_i| / pdf from the one function
 * that evaluates both (bsdf__rc_eval_pdf, bsdf__rd_eval_pdf), which eval
 * and pdf call too, so the three can never disagree. The models are
 * written once (bsdf_rough_generic.h) and compiled here twice, in doubles
 * and in duals (render/real.h).
 */
#include <math.h>
#include <stddef.h>

#include "render/bsdf/bsdf_ad_internal.h"
#include "render/bsdf/bsdf_internal.h"
#include "render/bsdf/microfacet.h"
#include "render/bsdf/microfacet_ad.h"

/* The models in doubles (bsdf_internal.h), then in duals
 * (bsdf_ad_internal.h), from one source. */
#define R_DUAL 0
#include "render/real.h"
#include "render/bsdf/bsdf_rough_generic.h"
#undef R_DUAL
#define R_DUAL 1
#include "render/real.h"
#include "render/bsdf/bsdf_rough_generic.h"
