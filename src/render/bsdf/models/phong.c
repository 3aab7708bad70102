/*
 * phong.c: Mitsuba's energy-normalised modified Phong, one BSDF model (bsdf_model.h).
 * Parameters (Mitsuba's names and defaults): exponent (30), diffuseReflectance (0.5),
 *   specularReflectance (0.2).
 *
 * Mitsuba's energy-normalised modified Phong (Lafortune and
 * Willems 1994):
 *   f = kd / pi + ks (n + 2) / (2 pi) cos^n(a),  cos(a) = wi . r,
 * with r = (-wo.x, -wo.y, wo.z) the mirror direction (cos^n taken
 * as 0 when cos(a) <= 0). The specular lobe is chosen with
 * probability w = lum(mean ks) / (lum(mean ks) + lum(mean kd)),
 * and sampled around r with density (n + 1) / (2 pi) cos^n(a)
 * (cos(a) = u2^(1/(n+1)), azimuth 2 pi u1); directions below the
 * surface are rejected, so the pdf, the mixture
 *   pdf = w (n + 1)/(2 pi) cos^n(a) + (1 - w) cos(wi) / pi,
 * integrates to less than 1 over the upper hemisphere.
 *
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by model_twice.h, in doubles and in duals.
 */
#ifndef R_DUAL
#include <math.h>

#include "render/bsdf/bsdf_model_file.h"

#define MODEL_BODY "render/bsdf/models/phong.c"
#include "render/model_twice.h"

/* ---- The inverse of the sampler (values only; bsdf_invert) ----------------- */

static int bsdf__phong_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                              const double r[4], double OUT_u[3], double *OUT_pmf) {
  (void)OUT_pmf;
  if (delta || !(wo.z > 0.0) || !(wi.z > 0.0)) return 0;
  double pdf, w = bsdf__specular_weight(&b->specular, &b->diffuse);
  bsdf__ph_eval_pdf(b, tu, tv, wo, wi, 0, &pdf);
  int glossy;
  if (!bsdf__invert_mixture(wi, w, pdf, r, OUT_u, &glossy)) return 0;
  if (!glossy) return 1;
  /* The lobe's cos(a) = u2^(1/(n+1)) and azimuth 2 pi u1 about the mirror direction. */
  frame fr = frame_from_z(bsdf__mirror(wo));
  vec3 l = frame_to_local(&fr, wi);
  if (!(l.z > 0.0)) return 0;
  OUT_u[1] = warp_turn(atan2(l.y, l.x));
  OUT_u[2] = fmin(pow(fmin(l.z, 1.0), b->exponent + 1.0), nextafter(1.0, 0.0));
  return 1;
}

static void bsdf__phong_defaults(bsdf *b) { b->specular = tex_constant(rgb_gray(0.2)); }

/* A diffuse part makes it rough; a pure lobe of exponent n is as wide as a
 * Beckmann lobe of alpha = sqrt(2 / (n + 2)) (Walter et al. 2007). */
static double bsdf__phong_roughness(const bsdf *b) {
  if (rgb_luminance(tex_mean(&b->diffuse)) > 0.0) return 1.0;
  return sqrt(2.0 / (b->exponent + 2.0));
}

static lmc_status bsdf__phong_read(bsdf *b, plugin_props *p) {
  lmc_status st = props_float(p, "exponent", b->exponent, &b->exponent, NULL);
  if (st != LMC_OK) return st;
  return bsdf_read_textures(b, p, BSDF_TEX_DIFFUSE | BSDF_TEX_SPECULAR);
}

const bsdf_model bsdf_model_phong = {
    .name = "phong",
    .flags = BSDF_REFLECTION | BSDF_DIFFUSE_LOBE | BSDF_GLOSSY,
    .chain = 1,
    .defaults = bsdf__phong_defaults,
    .read = bsdf__phong_read,
    .roughness = bsdf__phong_roughness,
    BSDF_MODEL_OPS(phong),
    BSDF_MODEL_EVAL_PDF(phong),
};

#else /* the body, in render/real.h's vocabulary */

/* ---- phong ----------------------------------------------------------------- */

/* f and pdf of one (wo, wi) pair in one pass (eval, pdf and sample all
 * come here), sharing cos^n(a), the costly pow. want_f = 0 skips f;
 * OUT_pdf = NULL skips the pdf. */
static RRGB R_FN(bsdf__ph_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                    int want_f, REAL *OUT_pdf) {
  if (OUT_pdf) *OUT_pdf = R_C(0.0);
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return RRGB_ZERO();
  /* cos(a) = wi . r with r the mirror of wo about the normal. */
  REAL ca = R3_DOT(wi, R_FN(bsdf__mirror)(R_ARG wo));
  double n = b->exponent;
  REAL can = R_V(ca) > 0.0 ? R_POW_S(ca, n) : R_C(0.0);
  if (OUT_pdf) {
    /* pdf = w (n + 1)/(2 pi) cos^n(a) + (1 - w) cos(wi) / pi */
    double w = bsdf__specular_weight(&b->specular, &b->diffuse);
    REAL diff = R_DIV_S(R_MUL_S(wi.z, 1.0 - w), M_PI);
    *OUT_pdf =
        R_V(ca) > 0.0 ? R_ADD(R_MUL_S(R_MUL_S(can, (n + 1.0) / (2.0 * M_PI)), w), diff) : diff;
  }
  if (!want_f) return RRGB_ZERO();
  /* f = kd / pi + ks (n + 2) / (2 pi) cos^n(a) */
  RRGB f = RRGB_SCALE_S(R_FN(tex_eval)(R_ARG &b->diffuse, tu, tv), 1.0 / M_PI);
  if (R_V(ca) > 0.0)
    f = RRGB_ADD(f, RRGB_SCALE(R_FN(tex_eval)(R_ARG &b->specular, tu, tv),
                               R_MUL_S(can, (n + 2.0) / (2.0 * M_PI))));
  return f;
}

static RRGB R_FN(bsdf__phong_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                   transport_mode mode) {
  (void)mode;
  return R_FN(bsdf__ph_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, NULL);
}

static REAL R_FN(bsdf__phong_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  REAL pdf;
  R_FN(bsdf__ph_eval_pdf)(R_ARG b, tu, tv, wo, wi, 0, &pdf);
  return pdf;
}

static RRGB R_FN(bsdf__phong_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                       transport_mode mode, REAL *OUT_pdf) {
  (void)mode;
  return R_FN(bsdf__ph_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, OUT_pdf);
}

static int R_FN(bsdf__phong_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL u_lobe,
                                    REAL u1, REAL u2, transport_mode mode,
                                    R_FN(bsdf_sample) *out) {
  (void)mode;
  if (R_V(wo.z) <= 0.0) return 0;
  double w = bsdf__specular_weight(&b->specular, &b->diffuse);
  REAL3 wi;
  int flags;
  if (R_V(u_lobe) < w) {
    /* Specular lobe: cos(a) = u2^(1/(n+1)) around the mirror direction,
     * azimuth 2 pi u1, in the frame of the mirror direction. */
    double n = b->exponent;
    REAL ca = R_POW_S(u2, 1.0 / (n + 1.0));
    REAL sa = R_SAFE_SQRT(R_S_SUB(1.0, R_SQR(ca)));
    REAL phi = R_MUL_S(u1, 2.0 * M_PI);
    RFRAME fr = R3_FRAME_FROM_Z(R_FN(bsdf__mirror)(R_ARG wo));
    REAL3 local = R3_MAKE(R_MUL(sa, R_COS(phi)), R_MUL(sa, R_SIN(phi)), ca);
    wi = R3_NORMALIZE(R3_TO_WORLD(&fr, local));
    flags = BSDF_REFLECTION | BSDF_GLOSSY;
  } else {
    wi = R_FN(bsdf__cosine_hemisphere)(R_ARG u1, u2);
    flags = BSDF_REFLECTION | BSDF_DIFFUSE_LOBE;
  }
  if (R_V(wi.z) <= 0.0) return 0;
  REAL pdf;
  RRGB f = R_FN(bsdf__ph_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, &pdf);
  return R_FN(bsdf__finish)(R_ARG out, wi, f, pdf, 1.0, flags);
}

#endif
