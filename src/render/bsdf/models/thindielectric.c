/*
 * thindielectric.c: a thin glass slab (Mitsuba's thindielectric), one BSDF model (bsdf_model.h).
 * Parameters (Mitsuba's names and defaults): intIOR (bk7), extIOR (air), specularReflectance,
 *   specularTransmittance.
 *
 * Mitsuba's thin slab of glass: both faces of a plate of
 *             relative IOR eta at one surface. With R = F(|cos wo|) at the
 *             outer face, the light reflected after any number of passes
 *             (R, T R T, T R^3 T, ...) sums to
 *               R' = R + (1 - R)^2 R / (1 - R^2),
 *             and the rest, 1 - R' = (1 - R) / (1 + R), leaves the far face
 *             parallel to where it came in: wi = -wo, no bending, no 1/eta^2
 *             scaling, sample eta 1. Delta reflection (probability R', weight
 *             specularReflectance) and delta transmission (probability
 *             1 - R', weight specularTransmittance); the same from both sides.
 *
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by model_twice.h, in doubles and in duals.
 */
#ifndef R_DUAL
#include <math.h>

#include "render/bsdf/bsdf_model_file.h"

#define MODEL_BODY "render/bsdf/models/thindielectric.c"
#include "render/model_twice.h"

/* ---- The inverse of the sampler (values only; bsdf_invert) ----------------- */

static int bsdf__thindielectric_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                                       int delta, const double r[4], double OUT_u[3],
                                       double *OUT_pmf) {
  (void)tu, (void)tv;
  if (!delta || wo.z == 0.0) return 0;
  double refl = bsdf__thin_reflectance(b, wo.z);
  if (wo.z * wi.z > 0.0)
    return bsdf__same_dir(wi, bsdf__mirror(wo)) && bsdf__invert_delta(0.0, refl, r, OUT_u, OUT_pmf);
  return bsdf__same_dir(wi, v3_neg(wo)) && bsdf__invert_delta(refl, 1.0, r, OUT_u, OUT_pmf);
}

/* Mitsuba's default: bk7 inside, air outside. */
static void bsdf__thindielectric_defaults(bsdf *b) { b->eta = 1.5046 / BSDF_AIR_IOR; }

static lmc_status bsdf__thindielectric_read(bsdf *b, plugin_props *p) {
  lmc_status st = bsdf_read_eta(b, p, "bk7", "a slab that reflects nothing, invisible");
  if (st != LMC_OK) return st;
  return bsdf_read_textures(b, p, BSDF_TEX_SPECULAR | BSDF_TEX_TRANSMITTANCE);
}

const bsdf_model bsdf_model_thindielectric = {
    .name = "thindielectric",
    .flags = BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_DELTA,
    .defaults = bsdf__thindielectric_defaults,
    .read = bsdf__thindielectric_read,
    BSDF_MODEL_OPS(thindielectric),
};

#else /* the body, in render/real.h's vocabulary */

/* ---- thindielectric ------------------------------------------------------ */

/* The slab's reflectance with its interreflections,
 *   R' = R + (1 - R)^2 R / (1 - R^2),  R = F(|cos wo|) from outside
 * (R' = 1 when R = 1). */
static REAL R_FN(bsdf__thin_reflectance)(R_CTX const bsdf *b, REAL cos_o) {
  REAL r = R_FN(fresnel_dielectric)(R_ARG R_FABS(cos_o), b->eta, NULL);
  if (!(R_V(r) < 1.0)) return r;
  REAL t = R_S_SUB(1.0, r);
  return R_ADD(r, R_DIV(R_MUL(R_SQR(t), r), R_S_SUB(1.0, R_SQR(r))));
}

static RRGB R_FN(bsdf__thindielectric_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                            REAL3 wi, transport_mode mode) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi, (void)mode;
  return RRGB_ZERO();
}

static REAL R_FN(bsdf__thindielectric_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                           REAL3 wi) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi;
  return R_C(0.0);
}

static int R_FN(bsdf__thindielectric_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                             REAL u_lobe, REAL u1, REAL u2, transport_mode mode,
                                             R_FN(bsdf_sample) *out) {
  (void)u1, (void)u2, (void)mode;
  if (R_V(wo.z) == 0.0) return 0;
  REAL r = R_FN(bsdf__thin_reflectance)(R_ARG b, wo.z);
  if (R_V(u_lobe) < R_V(r)) {
    /* Reflection, probability R': weight specularReflectance, f = ks R' / |cos wi|. */
    REAL3 wi = R_FN(bsdf__mirror)(R_ARG wo);
    RRGB ks = R_FN(tex_eval)(R_ARG &b->specular, tu, tv);
    return R_FN(bsdf__finish)(R_ARG out, wi, RRGB_SCALE(ks, R_DIV(r, R_FABS(wi.z))), r, 1.0,
                              BSDF_REFLECTION | BSDF_DELTA);
  }
  /* Transmission straight through, probability 1 - R': wi = -wo, weight
   * specularTransmittance in both modes (the ray leaves at the IOR it came
   * in with), eta 1. */
  REAL3 wi = R3_NEG(wo);
  RRGB kt = R_FN(tex_eval)(R_ARG &b->transmittance, tu, tv);
  REAL pdf = R_S_SUB(1.0, r);
  return R_FN(bsdf__finish)(R_ARG out, wi, RRGB_SCALE(kt, R_DIV(pdf, R_FABS(wi.z))), pdf, 1.0,
                            BSDF_TRANSMISSION | BSDF_DELTA);
}

#endif
