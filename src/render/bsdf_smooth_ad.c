/*
 * bsdf_smooth_ad.c: the models without microfacets, as Mitsuba 0.6 defines
 * them. Conventions of bsdf.h: local frame, z-up, wo toward the viewer,
 * f without the cosine, weight = f |cos wi| / pdf, delta lobes only from
 * sampling (pdf = lobe probability).
 *
 * diffuse     f = R / pi; cosine-weighted sampling, pdf = cos(wi) / pi.
 *
 * phong       Mitsuba's energy-normalised modified Phong (Lafortune and
 *             Willems 1994):
 *               f = kd / pi + ks (n + 2) / (2 pi) cos^n(a),  cos(a) = wi . r,
 *             with r = (-wo.x, -wo.y, wo.z) the mirror direction (cos^n taken
 *             as 0 when cos(a) <= 0). The specular lobe is chosen with
 *             probability w = lum(mean ks) / (lum(mean ks) + lum(mean kd)),
 *             and sampled around r with density (n + 1) / (2 pi) cos^n(a)
 *             (cos(a) = u2^(1/(n+1)), azimuth 2 pi u1); directions below the
 *             surface are rejected, so the pdf, the mixture
 *               pdf = w (n + 1)/(2 pi) cos^n(a) + (1 - w) cos(wi) / pi,
 *             integrates to less than 1 over the upper hemisphere.
 *
 * conductor   delta reflection with weight specularReflectance F_cond(cos).
 *
 * dielectric  delta reflection (probability F) and refraction (1 - F),
 *             F = fresnel_dielectric(cos wo); weights specularReflectance,
 *             and specularTransmittance times (eta_o / eta_i)^2 in radiance
 *             mode (the 1/eta^2 radiance scaling) or 1 in importance mode.
 *             Total internal reflection: F = 1.
 *
 * plastic     Mitsuba's smooth plastic: a dielectric coating (eta) on a
 *             Lambertian base with reflectance kd. Specular: delta reflection
 *             with weight ks F_i. Diffuse, including the infinite series of
 *             internal reflections (F_dr: diffuse Fresnel reflectance seen
 *             from inside, at 1/eta):
 *               f = kd' (1 - F_i) (1 - F_o) / (pi eta^2),
 *               kd' = kd / (1 - F_dr)         (default, colour preserving),
 *               kd' = kd / (1 - kd F_dr)      (nonlinear = 1).
 *             F_i = F(cos wo), F_o = F(cos wi). The specular lobe is chosen
 *             with probability p = F_i w / (F_i w + (1 - F_i)(1 - w)), w the
 *             specular weight as for phong; pdf = (1 - p) cos(wi) / pi.
 *
 * This file is the dual-number form of bsdf_smooth.c (bsdf_ad.h): the same
 * models, branches (on values only) and formulas, so that with tangent
 * length 0 the values equal the plain ones (tests/test_bsdf_grad.c checks
 * 1e-12), and with tangent length n they carry their derivatives.
 * (The plain functions are kept as a separate copy for speed: running
 * them through these duals made pt 18-42% slower; see the README.)
 */
#include <math.h>
#include <stddef.h>

#include "render/bsdf_ad_internal.h"

/* ---- diffuse --------------------------------------------------------------- */

adrgb bsdf__diffuse_eval_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi,
                            transport_mode mode) {
  (void)mode;
  if (wo.z.v <= 0.0 || wi.z.v <= 0.0) return adrgb_zero(A);
  /* f = R / pi */
  return adrgb_scale_s(A, tex_eval_ad(A, &b->diffuse, tu, tv), 1.0 / M_PI);
}

ad bsdf__diffuse_pdf_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi) {
  (void)b, (void)tu, (void)tv;
  if (wo.z.v <= 0.0 || wi.z.v <= 0.0) return ad_const(A, 0.0);
  return ad_div_s(A, wi.z, M_PI);
}

int bsdf__diffuse_sample_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, ad u_lobe, ad u1,
                            ad u2, transport_mode mode, bsdf_sample_ad *OUT_sample) {
  (void)u_lobe;
  if (wo.z.v <= 0.0) return 0;
  adv3 wi = bsdf__ad_cosine_hemisphere(A, u1, u2);
  if (wi.z.v <= 0.0) return 0;
  return bsdf__finish_ad(A, OUT_sample, wi, bsdf__diffuse_eval_ad(A, b, tu, tv, wo, wi, mode),
                         ad_div_s(A, wi.z, M_PI), 1.0, BSDF_REFLECTION | BSDF_DIFFUSE_LOBE);
}

/* ---- phong ----------------------------------------------------------------- */

adrgb bsdf__phong_eval_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi,
                          transport_mode mode) {
  (void)mode;
  if (wo.z.v <= 0.0 || wi.z.v <= 0.0) return adrgb_zero(A);
  adrgb f = adrgb_scale_s(A, tex_eval_ad(A, &b->diffuse, tu, tv), 1.0 / M_PI);
  /* cos(a) = wi . r with r the mirror of wo about the normal. */
  ad ca = adv3_dot(A, wi, bsdf__ad_mirror(A, wo));
  if (ca.v > 0.0) {
    /* f += ks (n + 2) / (2 pi) cos^n(a) */
    double n = b->exponent;
    ad s = ad_mul_s(A, ad_pow_s(A, ca, n), (n + 2.0) / (2.0 * M_PI));
    f = adrgb_add(A, f, adrgb_scale(A, tex_eval_ad(A, &b->specular, tu, tv), s));
  }
  return f;
}

ad bsdf__phong_pdf_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi) {
  (void)tu, (void)tv;
  if (wo.z.v <= 0.0 || wi.z.v <= 0.0) return ad_const(A, 0.0);
  double w = bsdf__specular_weight(&b->specular, &b->diffuse);
  ad ca = adv3_dot(A, wi, bsdf__ad_mirror(A, wo));
  double n = b->exponent;
  /* pdf = w (n + 1)/(2 pi) cos^n(a) + (1 - w) cos(wi) / pi */
  ad diff = ad_div_s(A, ad_mul_s(A, wi.z, 1.0 - w), M_PI);
  if (!(ca.v > 0.0)) return diff;
  ad spec = ad_mul_s(A, ad_pow_s(A, ca, n), (n + 1.0) / (2.0 * M_PI));
  return ad_add(A, ad_mul_s(A, spec, w), diff);
}

int bsdf__phong_sample_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, ad u_lobe, ad u1,
                          ad u2, transport_mode mode, bsdf_sample_ad *OUT_sample) {
  if (wo.z.v <= 0.0) return 0;
  double w = bsdf__specular_weight(&b->specular, &b->diffuse);
  adv3 wi;
  int flags;
  if (u_lobe.v < w) {
    /* Specular lobe: cos(a) = u2^(1/(n+1)) around the mirror direction,
     * azimuth 2 pi u1, in the frame of the mirror direction. */
    double n = b->exponent;
    ad ca = ad_pow_s(A, u2, 1.0 / (n + 1.0));
    ad sa = ad_safe_sqrt(A, ad_s_sub(A, 1.0, ad_sqr(A, ca)));
    ad phi = ad_mul_s(A, u1, 2.0 * M_PI);
    ad_frame fr = adv3_frame_from_z(A, bsdf__ad_mirror(A, wo));
    adv3 local = adv3_make(ad_mul(A, sa, ad_cos(A, phi)), ad_mul(A, sa, ad_sin(A, phi)), ca);
    wi = adv3_normalize(A, adv3_to_world(A, &fr, local));
    flags = BSDF_REFLECTION | BSDF_GLOSSY;
  } else {
    wi = bsdf__ad_cosine_hemisphere(A, u1, u2);
    flags = BSDF_REFLECTION | BSDF_DIFFUSE_LOBE;
  }
  if (wi.z.v <= 0.0) return 0;
  return bsdf__finish_ad(A, OUT_sample, wi, bsdf__phong_eval_ad(A, b, tu, tv, wo, wi, mode),
                         bsdf__phong_pdf_ad(A, b, tu, tv, wo, wi), 1.0, flags);
}

/* ---- conductor (smooth) ------------------------------------------------- */

adrgb bsdf__conductor_eval_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi,
                              transport_mode mode) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi, (void)mode;
  return adrgb_zero(A);
}

ad bsdf__conductor_pdf_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi;
  return ad_const(A, 0.0);
}

int bsdf__conductor_sample_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, ad u_lobe, ad u1,
                              ad u2, transport_mode mode, bsdf_sample_ad *OUT_sample) {
  (void)u_lobe, (void)u1, (void)u2, (void)mode;
  if (wo.z.v <= 0.0) return 0;
  adv3 wi = bsdf__ad_mirror(A, wo);
  /* weight = ks F_cond(cos wo); delta convention: pdf 1, f = weight / cos wi. */
  adrgb weight = adrgb_mul(A, tex_eval_ad(A, &b->specular, tu, tv),
                           fresnel_conductor_ad(A, wo.z, b->cond_eta, b->cond_k));
  return bsdf__finish_ad(A, OUT_sample, wi, adrgb_scale(A, weight, ad_s_div(A, 1.0, wi.z)),
                         ad_const(A, 1.0), 1.0, BSDF_REFLECTION | BSDF_DELTA);
}

/* ---- dielectric (smooth) ------------------------------------------------ */

adrgb bsdf__dielectric_eval_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi,
                               transport_mode mode) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi, (void)mode;
  return adrgb_zero(A);
}

ad bsdf__dielectric_pdf_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi;
  return ad_const(A, 0.0);
}

int bsdf__dielectric_sample_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, ad u_lobe,
                               ad u1, ad u2, transport_mode mode, bsdf_sample_ad *OUT_sample) {
  (void)u1, (void)u2;
  if (wo.z.v == 0.0) return 0;
  ad cos_t;
  ad fr = fresnel_dielectric_ad(A, wo.z, b->eta, &cos_t);
  if (u_lobe.v < fr.v) {
    /* Reflection, chosen with probability F: weight = specularReflectance,
     * f = ks F / |cos wi|. */
    adv3 wi = bsdf__ad_mirror(A, wo);
    adrgb weight = tex_eval_ad(A, &b->specular, tu, tv);
    return bsdf__finish_ad(A, OUT_sample, wi,
                           adrgb_scale(A, weight, ad_div(A, fr, ad_fabs(A, wi.z))), fr, 1.0,
                           BSDF_REFLECTION | BSDF_DELTA);
  }
  /* Refraction, probability 1 - F. s = eta_o / eta_i of the two sides:
   * wi = (-s wo.x, -s wo.y, cos_t). */
  if (cos_t.v == 0.0) return 0;
  double s = wo.z.v > 0.0 ? 1.0 / b->eta : b->eta;
  adv3 wi = adv3_make(ad_mul_s(A, wo.x, -s), ad_mul_s(A, wo.y, -s), cos_t);
  double scale = mode == TRANSPORT_RADIANCE ? s * s : 1.0;
  adrgb weight = adrgb_scale_s(A, tex_eval_ad(A, &b->transmittance, tu, tv), scale);
  ad pdf = ad_s_sub(A, 1.0, fr);
  return bsdf__finish_ad(A, OUT_sample, wi, adrgb_scale(A, weight, ad_div(A, pdf, ad_fabs(A, cos_t))),
                         pdf, cos_t.v < 0.0 ? b->eta : 1.0 / b->eta,
                         BSDF_TRANSMISSION | BSDF_DELTA);
}

/* ---- plastic -------------------------------------------------------------- */

/* Probability of choosing the specular coating given F_i:
 * p = F_i w / (F_i w + (1 - F_i)(1 - w)). */
static ad bsdf__plastic_prob_specular_ad(ad_arena *A, const bsdf *b, ad fi) {
  double w = bsdf__specular_weight(&b->specular, &b->diffuse);
  ad fiw = ad_mul_s(A, fi, w);
  ad den = ad_add(A, fiw, ad_mul_s(A, ad_s_sub(A, 1.0, fi), 1.0 - w));
  return den.v > 0.0 ? ad_div(A, fiw, den) : ad_const(A, 0.0);
}

adrgb bsdf__plastic_eval_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi,
                            transport_mode mode) {
  (void)mode;
  if (wo.z.v <= 0.0 || wi.z.v <= 0.0) return adrgb_zero(A);
  ad fi = fresnel_dielectric_ad(A, wo.z, b->eta, NULL);
  ad fo = fresnel_dielectric_ad(A, wi.z, b->eta, NULL);
  double fdr = bsdf__fresnel_diffuse_reflectance(1.0 / b->eta);
  adrgb kd = tex_eval_ad(A, &b->diffuse, tu, tv);
  /* kd' = kd / (1 - kd F_dr) (nonlinear; 0 where the denominator is 0, as
   * rgb_div) or kd / (1 - F_dr). */
  adrgb kdp;
  if (b->nonlinear) {
    ad *c[3] = {&kd.r, &kd.g, &kd.b};
    ad *o[3] = {&kdp.r, &kdp.g, &kdp.b};
    for (int i = 0; i < 3; i++) {
      ad den = ad_s_sub(A, 1.0, ad_mul_s(A, *c[i], fdr));
      *o[i] = den.v != 0.0 ? ad_div(A, *c[i], den) : ad_const(A, 0.0);
    }
  } else {
    kdp = adrgb_scale_s(A, kd, 1.0 / (1.0 - fdr));
  }
  /* f = kd' (1 - F_i)(1 - F_o) / (pi eta^2) */
  ad s = ad_div_s(A, ad_mul(A, ad_s_sub(A, 1.0, fi), ad_s_sub(A, 1.0, fo)),
                  M_PI * b->eta * b->eta);
  return adrgb_scale(A, kdp, s);
}

ad bsdf__plastic_pdf_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi) {
  (void)tu, (void)tv;
  if (wo.z.v <= 0.0 || wi.z.v <= 0.0) return ad_const(A, 0.0);
  ad p = bsdf__plastic_prob_specular_ad(A, b, fresnel_dielectric_ad(A, wo.z, b->eta, NULL));
  /* (1 - p) cos(wi) / pi */
  return ad_div_s(A, ad_mul(A, ad_s_sub(A, 1.0, p), wi.z), M_PI);
}

int bsdf__plastic_sample_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, ad u_lobe, ad u1,
                            ad u2, transport_mode mode, bsdf_sample_ad *OUT_sample) {
  if (wo.z.v <= 0.0) return 0;
  ad fi = fresnel_dielectric_ad(A, wo.z, b->eta, NULL);
  ad p = bsdf__plastic_prob_specular_ad(A, b, fi);
  if (u_lobe.v < p.v) {
    /* Specular coating: f = ks F_i / cos, pdf = p (weight ks F_i / p). */
    adv3 wi = bsdf__ad_mirror(A, wo);
    adrgb ks = tex_eval_ad(A, &b->specular, tu, tv);
    return bsdf__finish_ad(A, OUT_sample, wi, adrgb_scale(A, ks, ad_div(A, fi, wi.z)), p, 1.0,
                           BSDF_REFLECTION | BSDF_DELTA);
  }
  adv3 wi = bsdf__ad_cosine_hemisphere(A, u1, u2);
  if (wi.z.v <= 0.0) return 0;
  ad pdf = ad_div_s(A, ad_mul(A, ad_s_sub(A, 1.0, p), wi.z), M_PI);
  return bsdf__finish_ad(A, OUT_sample, wi, bsdf__plastic_eval_ad(A, b, tu, tv, wo, wi, mode), pdf,
                         1.0, BSDF_REFLECTION | BSDF_DIFFUSE_LOBE);
}
