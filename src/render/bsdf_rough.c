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
 * and pdf call too, so the three can never disagree.
 */
#include <math.h>
#include <stddef.h>

#include "render/bsdf_internal.h"
#include "render/microfacet.h"

/* ---- roughconductor ------------------------------------------------------ */

/* f and pdf of one (wo, wi) pair in one pass: eval, pdf, sample and
 * next-event estimation all come here, so the three can never disagree, and
 * a caller that needs both shares the half vector, D and G1(wo) (the
 * visible-normal pdf uses the same G1). want_f = 0 skips f (Fresnel and
 * texture); OUT_pdf = NULL skips the pdf. Each value is computed with the
 * same operations, in the same order, whatever the caller asks for. */
static rgb bsdf__rc_eval_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int want_f,
                             double *OUT_pdf, double *OUT_pdf_rev) {
  if (OUT_pdf) *OUT_pdf = 0.0;
  if (OUT_pdf_rev) *OUT_pdf_rev = 0.0;
  if (wo.z <= 0.0 || wi.z <= 0.0) return rgb_zero();
  vec3 h = v3_normalize(v3_add(wo, wi));
  double d = mf_D(b->dist, b->alpha, h);
  int need_f = want_f && d != 0.0;
  /* G1(wo, h): shared by G and the visible-normal density; G1(wi, h) by G
   * and the reverse one. */
  double g1o = 0.0, g1i = 0.0;
  if (need_f || (OUT_pdf && b->sample_visible)) g1o = mf_G1(b->dist, b->alpha, wo, h);
  if (need_f || (OUT_pdf_rev && b->sample_visible)) g1i = mf_G1(b->dist, b->alpha, wi, h);

  /* pdf = p_m(h) / (4 wi.h); the reverse density p_m'(h) / (4 wo.h), the
   * normal drawn from wi's side. */
  if (OUT_pdf) {
    double wih = v3_dot(wi, h);
    if (wih > 0.0) *OUT_pdf = mf_pdf_known(d, g1o, wo, h, b->sample_visible) / (4.0 * wih);
  }
  if (OUT_pdf_rev) {
    double woh = v3_dot(wo, h);
    if (woh > 0.0) *OUT_pdf_rev = mf_pdf_known(d, g1i, wi, h, b->sample_visible) / (4.0 * woh);
  }

  /* f = F D G / (4 cos_o cos_i) ks, G = G1(wi, h) G1(wo, h). */
  if (!need_f) return rgb_zero();
  double g = g1i * g1o;
  if (g == 0.0) return rgb_zero();
  rgb fr = fresnel_conductor(v3_dot(wo, h), b->cond_eta, b->cond_k);
  rgb ks = tex_eval(&b->specular, tu, tv);
  return rgb_scale(rgb_mul(fr, ks), d * g / (4.0 * wo.z * wi.z));
}

rgb bsdf__roughconductor_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                              transport_mode mode) {
  (void)mode;
  return bsdf__rc_eval_pdf(b, tu, tv, wo, wi, 1, NULL, NULL);
}

double bsdf__roughconductor_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi) {
  double pdf;
  bsdf__rc_eval_pdf(b, tu, tv, wo, wi, 0, &pdf, NULL);
  return pdf;
}

rgb bsdf__roughconductor_eval_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                                  transport_mode mode, double *OUT_pdf) {
  (void)mode;
  return bsdf__rc_eval_pdf(b, tu, tv, wo, wi, 1, OUT_pdf, NULL);
}

int bsdf__roughconductor_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe,
                                double u1, double u2, transport_mode mode, bsdf_sample *out) {
  (void)u_lobe, (void)mode;
  if (wo.z <= 0.0) return 0;
  vec3 m = mf_sample(b->dist, b->alpha, wo, b->sample_visible, u1, u2);
  double wom = v3_dot(wo, m);
  if (wom <= 0.0) return 0;
  vec3 wi = v3_normalize(v3_reflect(wo, m));
  if (wi.z <= 0.0) return 0;
  double pdf, pdf_rev;
  rgb f = bsdf__rc_eval_pdf(b, tu, tv, wo, wi, 1, &pdf, &pdf_rev);
  int ok = bsdf__finish(out, wi, f, pdf, 1.0, BSDF_REFLECTION | BSDF_GLOSSY);
  out->pdf_rev = pdf_rev;
  out->has_pdf_rev = 1;
  return ok;
}

/* ---- roughdielectric ----------------------------------------------------- */

/* The roughness the sampler uses (Walter's widening without visible normals). */
static double bsdf__rd_sample_alpha(const bsdf *b, double cos_o) {
  if (b->sample_visible) return b->alpha;
  return b->alpha * (1.2 - 0.2 * sqrt(fabs(cos_o)));
}

/* The half vector of (wo, wi) in the upper hemisphere and e (1 for
 * reflection); returns 0 when it is degenerate. */
static int bsdf__rd_half(const bsdf *b, vec3 wo, vec3 wi, vec3 *h, double *e, int *reflect) {
  *reflect = wo.z * wi.z > 0.0;
  *e = *reflect ? 1.0 : (wo.z > 0.0 ? b->eta : 1.0 / b->eta);
  vec3 hh = v3_add(wo, v3_scale(wi, *e));
  double l = v3_len(hh);
  if (!(l > 0.0)) return 0;
  hh = v3_scale(hh, 1.0 / l);
  if (hh.z < 0.0) hh = v3_neg(hh);
  if (hh.z == 0.0) return 0;
  *h = hh;
  return 1;
}

/* f and pdf of one (wo, wi) pair in one pass, as bsdf__rc_eval_pdf: the
 * half vector, wo.h, wi.h and F are shared, and with visible-normal
 * sampling (same roughness for sampling and evaluation) D(h) and G1(wo, h)
 * too, and G1(wi, h) with the reverse density: G1(v, h) with v = +-wo is
 * G1(wo, h) exactly, as G1 only sees the product (v.h) v.z and v.z^2. */
static rgb bsdf__rd_eval_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int want_f,
                             transport_mode mode, double *OUT_pdf, double *OUT_pdf_rev) {
  if (OUT_pdf) *OUT_pdf = 0.0;
  if (OUT_pdf_rev) *OUT_pdf_rev = 0.0;
  if (wo.z == 0.0 || wi.z == 0.0) return rgb_zero();
  vec3 h;
  double e;
  int reflect;
  if (!bsdf__rd_half(b, wo, wi, &h, &e, &reflect)) return rgb_zero();
  double woh = v3_dot(wo, h), wih = v3_dot(wi, h);
  double fr = fresnel_dielectric(woh, b->eta, NULL);
  int vis_pdf = b->sample_visible && (OUT_pdf || OUT_pdf_rev);
  double d = 0.0;
  if (want_f || vis_pdf) d = mf_D(b->dist, b->alpha, h);
  int need_f = want_f && d != 0.0;
  /* G1(wo, h) serves G and the visible-normal density, G1(wi, h) G and the
   * reverse one. */
  double g1o = 0.0, g1i = 0.0;
  if (need_f || (OUT_pdf && b->sample_visible)) g1o = mf_G1(b->dist, b->alpha, wo, h);
  if (need_f || (OUT_pdf_rev && b->sample_visible)) g1i = mf_G1(b->dist, b->alpha, wi, h);

  /* The density. A valid configuration has wo and wi on the sides of h
   * their z says; the normal was drawn from the side of wo. */
  if (OUT_pdf && !(woh * wo.z <= 0.0 || wih * wi.z <= 0.0)) {
    vec3 v = wo.z > 0.0 ? wo : v3_neg(wo);
    double pm = b->sample_visible
                    ? mf_pdf_known(d, g1o, v, h, 1)
                    : mf_pdf(b->dist, bsdf__rd_sample_alpha(b, wo.z), v, h, 0);
    if (pm != 0.0) {
      if (reflect) {
        *OUT_pdf = fr * pm / (4.0 * fabs(wih));
      } else {
        double den = woh + e * wih;
        if (den != 0.0) *OUT_pdf = (1.0 - fr) * pm * e * e * fabs(wih) / (den * den);
      }
    }
  }

  /* The reverse density (wi sampled at wo's place), as pdf(wi, wo) defines
   * it: the same h, the roles of wo.h and wi.h swapped, e replaced by 1 / e
   * (so the refraction Jacobian becomes |wo.h| / (wo.h + e wi.h)^2), the
   * normal drawn from wi's side; F is that of the same h. */
  if (OUT_pdf_rev && !(woh * wo.z <= 0.0 || wih * wi.z <= 0.0)) {
    vec3 v = wi.z > 0.0 ? wi : v3_neg(wi);
    double pm = b->sample_visible ? mf_pdf_known(d, g1i, v, h, 1)
                                  : mf_pdf(b->dist, bsdf__rd_sample_alpha(b, wi.z), v, h, 0);
    double fr_rev = fresnel_dielectric(wih, b->eta, NULL);
    if (pm != 0.0) {
      if (reflect) {
        *OUT_pdf_rev = fr_rev * pm / (4.0 * fabs(woh));
      } else {
        double den = woh + e * wih;
        if (den != 0.0) *OUT_pdf_rev = (1.0 - fr_rev) * pm * fabs(woh) / (den * den);
      }
    }
  }

  /* The value. */
  if (!need_f) return rgb_zero();
  double g = g1i * g1o;
  if (g == 0.0) return rgb_zero();
  if (reflect) {
    rgb ks = tex_eval(&b->specular, tu, tv);
    return rgb_scale(ks, fr * d * g / (4.0 * fabs(wo.z) * fabs(wi.z)));
  }
  /* Refraction: (1 - F) D G e^2 |wo.h wi.h| / (|cos_o cos_i| (wo.h + e wi.h)^2). */
  double den = woh + e * wih;
  if (den == 0.0) return rgb_zero();
  double v = (1.0 - fr) * d * g * e * e * fabs(woh * wih) / (fabs(wo.z * wi.z) * den * den);
  if (mode == TRANSPORT_RADIANCE) v /= e * e;
  return rgb_scale(tex_eval(&b->transmittance, tu, tv), v);
}

rgb bsdf__roughdielectric_eval(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                               transport_mode mode) {
  return bsdf__rd_eval_pdf(b, tu, tv, wo, wi, 1, mode, NULL, NULL);
}

double bsdf__roughdielectric_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi) {
  double pdf;
  bsdf__rd_eval_pdf(b, tu, tv, wo, wi, 0, TRANSPORT_RADIANCE, &pdf, NULL);
  return pdf;
}

rgb bsdf__roughdielectric_eval_pdf(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                                   transport_mode mode, double *OUT_pdf) {
  return bsdf__rd_eval_pdf(b, tu, tv, wo, wi, 1, mode, OUT_pdf, NULL);
}

int bsdf__roughdielectric_sample(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe,
                                 double u1, double u2, transport_mode mode, bsdf_sample *out) {
  if (wo.z == 0.0) return 0;
  /* Draw a normal from the side of wo. */
  vec3 v = wo.z > 0.0 ? wo : v3_neg(wo);
  vec3 m = mf_sample(b->dist, bsdf__rd_sample_alpha(b, wo.z), v, b->sample_visible, u1, u2);
  double wom = v3_dot(wo, m);
  if (wom * wo.z <= 0.0) return 0;
  double cos_t;
  double fr = fresnel_dielectric(wom, b->eta, &cos_t);
  vec3 wi;
  int flags;
  double eta_out;
  if (u_lobe < fr) {
    /* Reflection about m. */
    wi = v3_normalize(v3_reflect(wo, m));
    if (wi.z * wo.z <= 0.0) return 0;
    flags = BSDF_REFLECTION | BSDF_GLOSSY;
    eta_out = 1.0;
  } else {
    /* Refraction through m: wi = m (wo.m s + cos_t) - wo s, s = eta_o / eta_i. */
    if (cos_t == 0.0) return 0;
    double s = wom > 0.0 ? 1.0 / b->eta : b->eta;
    wi = v3_normalize(v3_sub(v3_scale(m, wom * s + cos_t), v3_scale(wo, s)));
    if (wi.z * wo.z >= 0.0) return 0;
    flags = BSDF_TRANSMISSION | BSDF_GLOSSY;
    eta_out = cos_t < 0.0 ? b->eta : 1.0 / b->eta;
  }
  double pdf, pdf_rev;
  rgb f = bsdf__rd_eval_pdf(b, tu, tv, wo, wi, 1, mode, &pdf, &pdf_rev);
  int ok = bsdf__finish(out, wi, f, pdf, eta_out, flags);
  out->pdf_rev = pdf_rev;
  out->has_pdf_rev = 1;
  return ok;
}
