/*
 * roughconductor.c: a rough metal (Mitsuba's roughconductor; Walter et al. 2007), one BSDF model
 * (bsdf_model.h).
 * Parameters (Mitsuba's names and defaults): distribution (beckmann), alpha (0.1), sampleVisible,
 *   material (Cu), eta, k, extEta, specularReflectance.
 *
 * roughconductor (one-sided). With h = normalize(wo + wi):
 *   f = F_cond(wo . h) D(h) G(wo, wi, h) / (4 cos_o cos_i) * specularReflectance.
 * Sampling draws a normal m (visible normals of wo, or D(m) cos(theta_m))
 * and reflects wo about it; the density of wi is
 *   pdf = p_m(h) / (4 |wi . h|).
 *
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by model_twice.h, in doubles and in duals.
 */
#ifndef R_DUAL
#include <math.h>

#include "render/bsdf/bsdf_model_file.h"

#define MODEL_BODY "render/bsdf/models/roughconductor.c"
#include "render/model_twice.h"

/* ---- The inverse of the sampler (values only; bsdf_invert) ----------------- */

static int bsdf__roughconductor_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                                       int delta, const double r[4], double OUT_u[3],
                                       double *OUT_pmf) {
  (void)tu, (void)tv, (void)OUT_pmf;
  if (delta || !(wo.z > 0.0) || !(wi.z > 0.0)) return 0;
  vec3 m = v3_normalize(v3_add(wo, wi));
  OUT_u[0] = r[1];
  return mf_invert(b->dist, b->alpha, wo, b->sample_visible, m, &OUT_u[1], &OUT_u[2]);
}

static double bsdf__roughconductor_roughness(const bsdf *b) { return b->alpha; }

static lmc_status bsdf__roughconductor_read(bsdf *b, plugin_props *p) {
  lmc_status st = bsdf_read_conductor(b, p);
  if (st == LMC_OK) st = bsdf_read_textures(b, p, BSDF_TEX_SPECULAR);
  if (st == LMC_OK) st = bsdf_read_microfacet(b, p);
  return st;
}

const bsdf_model bsdf_model_roughconductor = {
    .name = "roughconductor",
    .flags = BSDF_REFLECTION | BSDF_GLOSSY,
    .chain = 1,
    .read = bsdf__roughconductor_read,
    .roughness = bsdf__roughconductor_roughness,
    BSDF_MODEL_OPS(roughconductor),
    BSDF_MODEL_EVAL_PDF(roughconductor),
};

#else /* the body, in render/real.h's vocabulary */

/* ---- roughconductor ------------------------------------------------------ */

/* f and pdf of one (wo, wi) pair in one pass: eval, pdf, sample and
 * next-event estimation all come here, so the three can never disagree, and
 * a caller that needs both shares the half vector, D and G1(wo) (the
 * visible-normal pdf uses the same G1). want_f = 0 skips f (Fresnel and
 * texture); OUT_pdf = NULL skips the pdf, OUT_pdf_rev = NULL the reverse
 * density. Each value is computed with the same operations, in the same
 * order, whatever the caller asks for. */
static RRGB R_FN(bsdf__rc_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                    int want_f, REAL *OUT_pdf, REAL *OUT_pdf_rev) {
  if (OUT_pdf) *OUT_pdf = R_C(0.0);
  if (OUT_pdf_rev) *OUT_pdf_rev = R_C(0.0);
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return RRGB_ZERO();
  REAL alpha = R_C(b->alpha);
  REAL3 h = R3_NORMALIZE(R3_ADD(wo, wi));
  REAL d = R_FN(mf_D)(R_ARG b->dist, alpha, h);
  int need_f = want_f && R_V(d) != 0.0;
  /* G1(wo, h): shared by G and the visible-normal density; G1(wi, h) by G
   * and the reverse one. */
  REAL g1o = R_C(0.0), g1i = R_C(0.0);
  if (need_f || (OUT_pdf && b->sample_visible)) g1o = R_FN(mf_G1)(R_ARG b->dist, alpha, wo, h);
  if (need_f || (OUT_pdf_rev && b->sample_visible)) g1i = R_FN(mf_G1)(R_ARG b->dist, alpha, wi, h);

  /* pdf = p_m(h) / (4 wi.h); the reverse density p_m'(h) / (4 wo.h), the
   * normal drawn from wi's side. */
  if (OUT_pdf) {
    REAL wih = R3_DOT(wi, h);
    if (R_V(wih) > 0.0)
      *OUT_pdf =
          R_DIV(R_FN(mf_pdf_known)(R_ARG d, g1o, wo, h, b->sample_visible), R_MUL_S(wih, 4.0));
  }
  if (OUT_pdf_rev) {
    REAL woh = R3_DOT(wo, h);
    if (R_V(woh) > 0.0)
      *OUT_pdf_rev =
          R_DIV(R_FN(mf_pdf_known)(R_ARG d, g1i, wi, h, b->sample_visible), R_MUL_S(woh, 4.0));
  }

  /* f = F D G / (4 cos_o cos_i) ks, G = G1(wi, h) G1(wo, h). */
  if (!need_f) return RRGB_ZERO();
  REAL g = R_MUL(g1i, g1o);
  if (R_V(g) == 0.0) return RRGB_ZERO();
  RRGB fr = R_FN(fresnel_conductor)(R_ARG R3_DOT(wo, h), b->cond_eta, b->cond_k);
  RRGB ks = R_FN(tex_eval)(R_ARG &b->specular, tu, tv);
  REAL s = R_DIV(R_MUL(d, g), R_MUL(R_MUL_S(wo.z, 4.0), wi.z));
  return RRGB_SCALE(RRGB_MUL(fr, ks), s);
}

static RRGB R_FN(bsdf__roughconductor_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                            REAL3 wi, transport_mode mode) {
  (void)mode;
  return R_FN(bsdf__rc_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, NULL, NULL);
}

static REAL R_FN(bsdf__roughconductor_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                           REAL3 wi) {
  REAL pdf;
  R_FN(bsdf__rc_eval_pdf)(R_ARG b, tu, tv, wo, wi, 0, &pdf, NULL);
  return pdf;
}

static RRGB R_FN(bsdf__roughconductor_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                                REAL3 wi, transport_mode mode, REAL *OUT_pdf) {
  (void)mode;
  return R_FN(bsdf__rc_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, OUT_pdf, NULL);
}

static int R_FN(bsdf__roughconductor_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                             REAL u_lobe, REAL u1, REAL u2, transport_mode mode,
                                             R_FN(bsdf_sample) *out) {
  (void)u_lobe, (void)mode;
  if (R_V(wo.z) <= 0.0) return 0;
  REAL3 m = R_FN(mf_sample)(R_ARG b->dist, R_C(b->alpha), wo, b->sample_visible, u1, u2);
  REAL wom = R3_DOT(wo, m);
  if (R_V(wom) <= 0.0) return 0;
  REAL3 wi = R3_NORMALIZE(R3_REFLECT(wo, m));
  if (R_V(wi.z) <= 0.0) return 0;
  REAL pdf, pdf_rev = R_C(0.0);
  RRGB f = R_FN(bsdf__rc_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, &pdf, BSDF_R_REV(&pdf_rev));
  int ok = R_FN(bsdf__finish)(R_ARG out, wi, f, pdf, 1.0, BSDF_REFLECTION | BSDF_GLOSSY);
  BSDF_R_SET_REV(out, pdf_rev);
  return ok;
}

#endif
