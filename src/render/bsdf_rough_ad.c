/*
 * bsdf_rough_ad.c: the microfacet models of Walter, Marschner, Li and Torrance
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
 * Sample weights are computed as f |cos_i| / pdf from the same eval and pdf
 * functions, so the three can never disagree.
 *
 * This file is the dual-number form of bsdf_rough.c (bsdf_ad.h): the same
 * models, branches (on values only) and formulas, so that with tangent
 * length 0 the values equal the plain ones (tests/test_bsdf_grad.c checks
 * 1e-12), and with tangent length n they carry their derivatives.
 * (The plain functions are kept as a separate copy for speed: running
 * them through these duals made pt 18-42% slower; see the README.)
 */
#include <math.h>
#include <stddef.h>

#include "render/bsdf_ad_internal.h"
#include "render/microfacet_ad.h"

/* ---- roughconductor ------------------------------------------------------ */

adrgb bsdf__roughconductor_eval_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi,
                                   transport_mode mode) {
  (void)mode;
  if (wo.z.v <= 0.0 || wi.z.v <= 0.0) return adrgb_zero(A);
  ad alpha = ad_const(A, b->alpha);
  adv3 h = adv3_normalize(A, adv3_add(A, wo, wi));
  ad d = mf_D_ad(A, b->dist, alpha, h);
  if (d.v == 0.0) return adrgb_zero(A);
  ad g = mf_G_ad(A, b->dist, alpha, wi, wo, h);
  if (g.v == 0.0) return adrgb_zero(A);
  adrgb fr = fresnel_conductor_ad(A, adv3_dot(A, wo, h), b->cond_eta, b->cond_k);
  adrgb ks = tex_eval_ad(A, &b->specular, tu, tv);
  /* f = F ks D G / (4 cos_o cos_i) */
  ad s = ad_div(A, ad_mul(A, d, g), ad_mul(A, ad_mul_s(A, wo.z, 4.0), wi.z));
  return adrgb_scale(A, adrgb_mul(A, fr, ks), s);
}

ad bsdf__roughconductor_pdf_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi) {
  (void)tu, (void)tv;
  if (wo.z.v <= 0.0 || wi.z.v <= 0.0) return ad_const(A, 0.0);
  adv3 h = adv3_normalize(A, adv3_add(A, wo, wi));
  ad wih = adv3_dot(A, wi, h);
  if (wih.v <= 0.0) return ad_const(A, 0.0);
  /* pdf = p_m(h) / (4 wi.h) */
  ad pm = mf_pdf_ad(A, b->dist, ad_const(A, b->alpha), wo, h, b->sample_visible);
  return ad_div(A, pm, ad_mul_s(A, wih, 4.0));
}

int bsdf__roughconductor_sample_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, ad u_lobe,
                                   ad u1, ad u2, transport_mode mode, bsdf_sample_ad *OUT_sample) {
  (void)u_lobe;
  if (wo.z.v <= 0.0) return 0;
  adv3 m = mf_sample_ad(A, b->dist, ad_const(A, b->alpha), wo, b->sample_visible, u1, u2);
  ad wom = adv3_dot(A, wo, m);
  if (wom.v <= 0.0) return 0;
  adv3 wi = adv3_normalize(A, adv3_reflect(A, wo, m));
  if (wi.z.v <= 0.0) return 0;
  return bsdf__finish_ad(A, OUT_sample, wi,
                         bsdf__roughconductor_eval_ad(A, b, tu, tv, wo, wi, mode),
                         bsdf__roughconductor_pdf_ad(A, b, tu, tv, wo, wi), 1.0,
                         BSDF_REFLECTION | BSDF_GLOSSY);
}

/* ---- roughdielectric ----------------------------------------------------- */

/* The roughness the sampler uses (Walter's widening without visible normals):
 * alpha (1.2 - 0.2 sqrt|cos_o|). */
static ad bsdf__rd_sample_alpha_ad(ad_arena *A, const bsdf *b, ad cos_o) {
  if (b->sample_visible) return ad_const(A, b->alpha);
  ad w = ad_s_sub(A, 1.2, ad_mul_s(A, ad_sqrt(A, ad_fabs(A, cos_o)), 0.2));
  return ad_mul_s(A, w, b->alpha);
}

/* The half vector of (wo, wi) in the upper hemisphere and e (1 for
 * reflection); returns 0 when it is degenerate. */
static int bsdf__rd_half_ad(ad_arena *A, const bsdf *b, adv3 wo, adv3 wi, adv3 *OUT_h,
                            double *OUT_e, int *OUT_reflect) {
  *OUT_reflect = wo.z.v * wi.z.v > 0.0;
  double e = *OUT_reflect ? 1.0 : (wo.z.v > 0.0 ? b->eta : 1.0 / b->eta);
  *OUT_e = e;
  /* h = normalize(wo + e wi), flipped to the upper side. */
  adv3 hh = adv3_make(ad_add(A, wo.x, ad_mul_s(A, wi.x, e)), ad_add(A, wo.y, ad_mul_s(A, wi.y, e)),
                      ad_add(A, wo.z, ad_mul_s(A, wi.z, e)));
  double l = sqrt(hh.x.v * hh.x.v + hh.y.v * hh.y.v + hh.z.v * hh.z.v);
  if (!(l > 0.0)) return 0;
  hh = adv3_normalize(A, hh);
  if (hh.z.v < 0.0) hh = adv3_neg(A, hh);
  if (hh.z.v == 0.0) return 0;
  *OUT_h = hh;
  return 1;
}

adrgb bsdf__roughdielectric_eval_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi,
                                    transport_mode mode) {
  if (wo.z.v == 0.0 || wi.z.v == 0.0) return adrgb_zero(A);
  adv3 h;
  double e;
  int reflect;
  if (!bsdf__rd_half_ad(A, b, wo, wi, &h, &e, &reflect)) return adrgb_zero(A);
  ad alpha = ad_const(A, b->alpha);
  ad d = mf_D_ad(A, b->dist, alpha, h);
  if (d.v == 0.0) return adrgb_zero(A);
  ad g = mf_G_ad(A, b->dist, alpha, wi, wo, h);
  if (g.v == 0.0) return adrgb_zero(A);
  ad woh = adv3_dot(A, wo, h), wih = adv3_dot(A, wi, h);
  ad fr = fresnel_dielectric_ad(A, woh, b->eta, NULL);
  ad dg = ad_mul(A, d, g);
  if (reflect) {
    /* f_r = ks F D G / (4 |cos_o| |cos_i|) */
    adrgb ks = tex_eval_ad(A, &b->specular, tu, tv);
    ad den = ad_mul(A, ad_mul_s(A, ad_fabs(A, wo.z), 4.0), ad_fabs(A, wi.z));
    return adrgb_scale(A, ks, ad_div(A, ad_mul(A, fr, dg), den));
  }
  /* Refraction: (1 - F) D G e^2 |wo.h wi.h| / (|cos_o cos_i| (wo.h + e wi.h)^2). */
  ad den = ad_add(A, woh, ad_mul_s(A, wih, e));
  if (den.v == 0.0) return adrgb_zero(A);
  ad num = ad_mul(A, ad_mul_s(A, ad_mul(A, ad_s_sub(A, 1.0, fr), dg), e * e),
                  ad_fabs(A, ad_mul(A, woh, wih)));
  ad v = ad_div(A, num, ad_mul(A, ad_fabs(A, ad_mul(A, wo.z, wi.z)), ad_sqr(A, den)));
  /* Radiance is compressed by 1/e^2 when crossing into the denser side. */
  if (mode == TRANSPORT_RADIANCE) v = ad_div_s(A, v, e * e);
  return adrgb_scale(A, tex_eval_ad(A, &b->transmittance, tu, tv), v);
}

ad bsdf__roughdielectric_pdf_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi) {
  (void)tu, (void)tv;
  if (wo.z.v == 0.0 || wi.z.v == 0.0) return ad_const(A, 0.0);
  adv3 h;
  double e;
  int reflect;
  if (!bsdf__rd_half_ad(A, b, wo, wi, &h, &e, &reflect)) return ad_const(A, 0.0);
  ad woh = adv3_dot(A, wo, h), wih = adv3_dot(A, wi, h);
  /* A valid configuration has wo and wi on the sides of h their z says. */
  if (woh.v * wo.z.v <= 0.0 || wih.v * wi.z.v <= 0.0) return ad_const(A, 0.0);
  adv3 v = wo.z.v > 0.0 ? wo : adv3_neg(A, wo);
  ad pm = mf_pdf_ad(A, b->dist, bsdf__rd_sample_alpha_ad(A, b, wo.z), v, h, b->sample_visible);
  if (pm.v == 0.0) return ad_const(A, 0.0);
  ad fr = fresnel_dielectric_ad(A, woh, b->eta, NULL);
  /* reflection  F p_m / (4 |wi.h|) */
  if (reflect) return ad_div(A, ad_mul(A, fr, pm), ad_mul_s(A, ad_fabs(A, wih), 4.0));
  /* refraction  (1 - F) p_m e^2 |wi.h| / (wo.h + e wi.h)^2 */
  ad den = ad_add(A, woh, ad_mul_s(A, wih, e));
  if (den.v == 0.0) return ad_const(A, 0.0);
  ad num = ad_mul(A, ad_mul_s(A, ad_mul(A, ad_s_sub(A, 1.0, fr), pm), e * e), ad_fabs(A, wih));
  return ad_div(A, num, ad_sqr(A, den));
}

int bsdf__roughdielectric_sample_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, ad u_lobe,
                                    ad u1, ad u2, transport_mode mode,
                                    bsdf_sample_ad *OUT_sample) {
  if (wo.z.v == 0.0) return 0;
  /* Draw a normal from the side of wo. */
  adv3 v = wo.z.v > 0.0 ? wo : adv3_neg(A, wo);
  adv3 m = mf_sample_ad(A, b->dist, bsdf__rd_sample_alpha_ad(A, b, wo.z), v, b->sample_visible,
                        u1, u2);
  ad wom = adv3_dot(A, wo, m);
  if (wom.v * wo.z.v <= 0.0) return 0;
  ad cos_t;
  ad fr = fresnel_dielectric_ad(A, wom, b->eta, &cos_t);
  adv3 wi;
  int flags;
  double eta_out;
  if (u_lobe.v < fr.v) {
    /* Reflection about m. */
    wi = adv3_normalize(A, adv3_reflect(A, wo, m));
    if (wi.z.v * wo.z.v <= 0.0) return 0;
    flags = BSDF_REFLECTION | BSDF_GLOSSY;
    eta_out = 1.0;
  } else {
    /* Refraction through m: wi = m (wo.m s + cos_t) - wo s, s = eta_o / eta_i. */
    if (cos_t.v == 0.0) return 0;
    double s = wom.v > 0.0 ? 1.0 / b->eta : b->eta;
    ad k = ad_add(A, ad_mul_s(A, wom, s), cos_t);
    adv3 raw = adv3_make(ad_sub(A, ad_mul(A, m.x, k), ad_mul_s(A, wo.x, s)),
                         ad_sub(A, ad_mul(A, m.y, k), ad_mul_s(A, wo.y, s)),
                         ad_sub(A, ad_mul(A, m.z, k), ad_mul_s(A, wo.z, s)));
    wi = adv3_normalize(A, raw);
    if (wi.z.v * wo.z.v >= 0.0) return 0;
    flags = BSDF_TRANSMISSION | BSDF_GLOSSY;
    eta_out = cos_t.v < 0.0 ? b->eta : 1.0 / b->eta;
  }
  return bsdf__finish_ad(A, OUT_sample, wi,
                         bsdf__roughdielectric_eval_ad(A, b, tu, tv, wo, wi, mode),
                         bsdf__roughdielectric_pdf_ad(A, b, tu, tv, wo, wi), eta_out, flags);
}
