/*
 * roughdielectric.c: rough glass (Mitsuba's roughdielectric; Walter et al. 2007), one BSDF model
 * (bsdf_model.h).
 * Parameters (Mitsuba's names and defaults): distribution, alpha, sampleVisible, intIOR, extIOR,
 *   specularReflectance, specularTransmittance.
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
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by model_twice.h, in doubles and in duals.
 */
#ifndef R_DUAL
#include <math.h>

#include "render/bsdf/bsdf_model_file.h"

#define MODEL_BODY "render/bsdf/models/roughdielectric.c"
#include "render/model_twice.h"

/* ---- The inverse of the sampler (values only; bsdf_invert) ----------------- */

static int bsdf__roughdielectric_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                                        int delta, const double r[4], double OUT_u[3],
                                        double *OUT_pmf) {
  (void)tu, (void)tv, (void)OUT_pmf;
  if (delta || wo.z == 0.0) return 0;
  /* The normal the sampler drew is the (generalised) half vector. */
  vec3 m;
  double e;
  int reflect;
  if (!bsdf__rd_half(b, wo, wi, &m, &e, &reflect)) return 0;
  double wom = v3_dot(wo, m);
  if (!(wom * wo.z > 0.0)) return 0;
  double fr = fresnel_dielectric(wom, b->eta, NULL);
  vec3 v = wo.z > 0.0 ? wo : v3_neg(wo);
  if (!mf_invert(b->dist, bsdf__rd_sample_alpha(b, wo.z), v, b->sample_visible, m, &OUT_u[1],
                 &OUT_u[2]))
    return 0;
  if (reflect ? !(fr > 0.0) : !(fr < 1.0)) return 0;
  OUT_u[0] = reflect ? warp_uniform_in(0.0, fr, r[1]) : warp_uniform_in(fr, 1.0, r[1]);
  return 1;
}

/* Mitsuba's default: bk7 inside, air outside. */
static void bsdf__roughdielectric_defaults(bsdf *b) { b->eta = 1.5046 / BSDF_AIR_IOR; }

static double bsdf__roughdielectric_roughness(const bsdf *b) { return b->alpha; }

static lmc_status bsdf__roughdielectric_read(bsdf *b, plugin_props *p) {
  lmc_status st = bsdf_read_eta(b, p, "bk7", "an index-matched interface, invisible");
  if (st == LMC_OK) st = bsdf_read_textures(b, p, BSDF_TEX_SPECULAR | BSDF_TEX_TRANSMITTANCE);
  if (st == LMC_OK) st = bsdf_read_microfacet(b, p);
  return st;
}

const bsdf_model bsdf_model_roughdielectric = {
    .name = "roughdielectric",
    .flags = BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_GLOSSY,
    .refracts = 1,
    .chain = 1,
    .defaults = bsdf__roughdielectric_defaults,
    .read = bsdf__roughdielectric_read,
    .roughness = bsdf__roughdielectric_roughness,
    BSDF_MODEL_OPS(roughdielectric),
    BSDF_MODEL_EVAL_PDF(roughdielectric),
};

#else /* the body, in render/real.h's vocabulary */

/* ---- roughdielectric ----------------------------------------------------- */

/* The roughness the sampler uses (Walter's widening without visible normals):
 * alpha (1.2 - 0.2 sqrt|cos_o|). */
static REAL R_FN(bsdf__rd_sample_alpha)(R_CTX const bsdf *b, REAL cos_o) {
  if (b->sample_visible) return R_C(b->alpha);
  REAL w = R_S_SUB(1.2, R_MUL_S(R_SQRT(R_FABS(cos_o)), 0.2));
  return R_MUL_S(w, b->alpha);
}

/* The half vector of (wo, wi) in the upper hemisphere and e (1 for
 * reflection); returns 0 when it is degenerate. */
static int R_FN(bsdf__rd_half)(R_CTX const bsdf *b, REAL3 wo, REAL3 wi, REAL3 *OUT_h, double *OUT_e,
                               int *OUT_reflect) {
  *OUT_reflect = R_V(wo.z) * R_V(wi.z) > 0.0;
  double e = *OUT_reflect ? 1.0 : (R_V(wo.z) > 0.0 ? b->eta : 1.0 / b->eta);
  *OUT_e = e;
  /* h = normalize(wo + e wi), flipped to the upper side. */
  REAL3 hh = R3_ADD(wo, R3_SCALE_S(wi, e));
  double x = R_V(hh.x), y = R_V(hh.y), z = R_V(hh.z);
  double l = sqrt(x * x + y * y + z * z);
  if (!(l > 0.0)) return 0;
  hh = R3_NORMALIZE(hh);
  if (R_V(hh.z) < 0.0) hh = R3_NEG(hh);
  if (R_V(hh.z) == 0.0) return 0;
  *OUT_h = hh;
  return 1;
}

/* f and pdf of one (wo, wi) pair in one pass, as bsdf__rc_eval_pdf: the
 * half vector, wo.h, wi.h and F are shared, and with visible-normal
 * sampling (same roughness for sampling and evaluation) D(h) and G1(wo, h)
 * too, and G1(wi, h) with the reverse density: G1(v, h) with v = +-wo is
 * G1(wo, h) exactly, as G1 only sees the product (v.h) v.z and v.z^2. */
static RRGB R_FN(bsdf__rd_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                    int want_f, transport_mode mode, REAL *OUT_pdf,
                                    REAL *OUT_pdf_rev) {
  if (OUT_pdf) *OUT_pdf = R_C(0.0);
  if (OUT_pdf_rev) *OUT_pdf_rev = R_C(0.0);
  if (R_V(wo.z) == 0.0 || R_V(wi.z) == 0.0) return RRGB_ZERO();
  REAL3 h;
  double e;
  int reflect;
  if (!R_FN(bsdf__rd_half)(R_ARG b, wo, wi, &h, &e, &reflect)) return RRGB_ZERO();
  REAL alpha = R_C(b->alpha);
  REAL woh = R3_DOT(wo, h), wih = R3_DOT(wi, h);
  REAL fr = R_FN(fresnel_dielectric)(R_ARG woh, b->eta, NULL);
  int vis_pdf = b->sample_visible && (OUT_pdf || OUT_pdf_rev);
  REAL d = R_C(0.0);
  if (want_f || vis_pdf) d = R_FN(mf_D)(R_ARG b->dist, alpha, h);
  int need_f = want_f && R_V(d) != 0.0;
  /* G1(wo, h) serves G and the visible-normal density, G1(wi, h) G and the
   * reverse one. */
  REAL g1o = R_C(0.0), g1i = R_C(0.0);
  if (need_f || (OUT_pdf && b->sample_visible)) g1o = R_FN(mf_G1)(R_ARG b->dist, alpha, wo, h);
  if (need_f || (OUT_pdf_rev && b->sample_visible)) g1i = R_FN(mf_G1)(R_ARG b->dist, alpha, wi, h);
  /* A valid configuration has wo and wi on the sides of h their z says; the
   * normal was drawn from the side of wo. */
  int valid = !(R_V(woh) * R_V(wo.z) <= 0.0 || R_V(wih) * R_V(wi.z) <= 0.0);

  /* reflection  F p_m(h) / (4 |wi.h|),
   * refraction  (1 - F) p_m(h) e^2 |wi.h| / (wo.h + e wi.h)^2. */
  if (OUT_pdf && valid) {
    REAL3 v = R_V(wo.z) > 0.0 ? wo : R3_NEG(wo);
    REAL pm = b->sample_visible ? R_FN(mf_pdf_known)(R_ARG d, g1o, v, h, 1)
                                : R_FN(mf_pdf)(R_ARG b->dist,
                                               R_FN(bsdf__rd_sample_alpha)(R_ARG b, wo.z), v, h, 0);
    if (R_V(pm) != 0.0) {
      if (reflect) {
        *OUT_pdf = R_DIV(R_MUL(fr, pm), R_MUL_S(R_FABS(wih), 4.0));
      } else {
        REAL den = R_ADD(woh, R_MUL_S(wih, e));
        if (R_V(den) != 0.0) {
          REAL num = R_MUL(R_MUL_S(R_MUL_S(R_MUL(R_S_SUB(1.0, fr), pm), e), e), R_FABS(wih));
          *OUT_pdf = R_DIV(num, R_SQR(den));
        }
      }
    }
  }

  /* The reverse density (wi sampled at wo's place), as pdf(wi, wo) defines
   * it: the same h, the roles of wo.h and wi.h swapped, e replaced by 1 / e
   * (so the refraction Jacobian becomes |wo.h| / (wo.h + e wi.h)^2), the
   * normal drawn from wi's side; F is that of the same h. */
  if (OUT_pdf_rev && valid) {
    REAL3 v = R_V(wi.z) > 0.0 ? wi : R3_NEG(wi);
    REAL pm = b->sample_visible ? R_FN(mf_pdf_known)(R_ARG d, g1i, v, h, 1)
                                : R_FN(mf_pdf)(R_ARG b->dist,
                                               R_FN(bsdf__rd_sample_alpha)(R_ARG b, wi.z), v, h, 0);
    REAL fr_rev = R_FN(fresnel_dielectric)(R_ARG wih, b->eta, NULL);
    if (R_V(pm) != 0.0) {
      if (reflect) {
        *OUT_pdf_rev = R_DIV(R_MUL(fr_rev, pm), R_MUL_S(R_FABS(woh), 4.0));
      } else {
        REAL den = R_ADD(woh, R_MUL_S(wih, e));
        if (R_V(den) != 0.0)
          *OUT_pdf_rev = R_DIV(R_MUL(R_MUL(R_S_SUB(1.0, fr_rev), pm), R_FABS(woh)), R_SQR(den));
      }
    }
  }

  /* The value. */
  if (!need_f) return RRGB_ZERO();
  REAL g = R_MUL(g1i, g1o);
  if (R_V(g) == 0.0) return RRGB_ZERO();
  if (reflect) {
    /* f_r = ks F D G / (4 |cos_o| |cos_i|) */
    RRGB ks = R_FN(tex_eval)(R_ARG &b->specular, tu, tv);
    REAL den = R_MUL(R_MUL_S(R_FABS(wo.z), 4.0), R_FABS(wi.z));
    return RRGB_SCALE(ks, R_DIV(R_MUL(R_MUL(fr, d), g), den));
  }
  /* Refraction: (1 - F) D G e^2 |wo.h wi.h| / (|cos_o cos_i| (wo.h + e wi.h)^2). */
  REAL den = R_ADD(woh, R_MUL_S(wih, e));
  if (R_V(den) == 0.0) return RRGB_ZERO();
  REAL num =
      R_MUL(R_MUL_S(R_MUL_S(R_MUL(R_MUL(R_S_SUB(1.0, fr), d), g), e), e), R_FABS(R_MUL(woh, wih)));
  REAL v = R_DIV(num, R_MUL(R_MUL(R_FABS(R_MUL(wo.z, wi.z)), den), den));
  /* Radiance is compressed by 1/e^2 when crossing into the denser side. */
  if (mode == TRANSPORT_RADIANCE) v = R_DIV_S(v, e * e);
  return RRGB_SCALE(R_FN(tex_eval)(R_ARG &b->transmittance, tu, tv), v);
}

static RRGB R_FN(bsdf__roughdielectric_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                             REAL3 wi, transport_mode mode) {
  return R_FN(bsdf__rd_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, mode, NULL, NULL);
}

static REAL R_FN(bsdf__roughdielectric_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                            REAL3 wi) {
  REAL pdf;
  R_FN(bsdf__rd_eval_pdf)(R_ARG b, tu, tv, wo, wi, 0, TRANSPORT_RADIANCE, &pdf, NULL);
  return pdf;
}

static RRGB R_FN(bsdf__roughdielectric_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                                 REAL3 wi, transport_mode mode, REAL *OUT_pdf) {
  return R_FN(bsdf__rd_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, mode, OUT_pdf, NULL);
}

static int R_FN(bsdf__roughdielectric_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                              REAL u_lobe, REAL u1, REAL u2, transport_mode mode,
                                              R_FN(bsdf_sample) *out) {
  if (R_V(wo.z) == 0.0) return 0;
  /* Draw a normal from the side of wo. */
  REAL3 v = R_V(wo.z) > 0.0 ? wo : R3_NEG(wo);
  REAL3 m = R_FN(mf_sample)(R_ARG b->dist, R_FN(bsdf__rd_sample_alpha)(R_ARG b, wo.z), v,
                            b->sample_visible, u1, u2);
  REAL wom = R3_DOT(wo, m);
  if (R_V(wom) * R_V(wo.z) <= 0.0) return 0;
  REAL cos_t;
  REAL fr = R_FN(fresnel_dielectric)(R_ARG wom, b->eta, &cos_t);
  REAL3 wi;
  int flags;
  double eta_out;
  if (R_V(u_lobe) < R_V(fr)) {
    /* Reflection about m. */
    wi = R3_NORMALIZE(R3_REFLECT(wo, m));
    if (R_V(wi.z) * R_V(wo.z) <= 0.0) return 0;
    flags = BSDF_REFLECTION | BSDF_GLOSSY;
    eta_out = 1.0;
  } else {
    /* Refraction through m: wi = m (wo.m s + cos_t) - wo s, s = eta_o / eta_i. */
    if (R_V(cos_t) == 0.0) return 0;
    double s = R_V(wom) > 0.0 ? 1.0 / b->eta : b->eta;
    REAL k = R_ADD(R_MUL_S(wom, s), cos_t);
    wi = R3_NORMALIZE(R3_SUB(R3_SCALE(m, k), R3_SCALE_S(wo, s)));
    if (R_V(wi.z) * R_V(wo.z) >= 0.0) return 0;
    flags = BSDF_TRANSMISSION | BSDF_GLOSSY;
    eta_out = R_V(cos_t) < 0.0 ? b->eta : 1.0 / b->eta;
  }
  REAL pdf, pdf_rev = R_C(0.0);
  RRGB f = R_FN(bsdf__rd_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, mode, &pdf, BSDF_R_REV(&pdf_rev));
  int ok = R_FN(bsdf__finish)(R_ARG out, wi, f, pdf, eta_out, flags);
  BSDF_R_SET_REV(out, pdf_rev);
  return ok;
}

#endif
