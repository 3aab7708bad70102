/*
 * dielectric.c: smooth glass (Mitsuba's dielectric), one BSDF model (bsdf_model.h).
 * Parameters (Mitsuba's names and defaults): intIOR (bk7), extIOR (air), specularReflectance,
 *   specularTransmittance.
 *
 * delta reflection (probability F) and refraction (1 - F),
 * F = fresnel_dielectric(cos wo); weights specularReflectance,
 * and specularTransmittance times (eta_o / eta_i)^2 in radiance
 * mode (the 1/eta^2 radiance scaling) or 1 in importance mode.
 * Total internal reflection: F = 1.
 *
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by model_twice.h, in doubles and in duals.
 */
#ifndef R_DUAL
#include <math.h>

#include "render/bsdf/bsdf_model_file.h"

#define MODEL_BODY "render/bsdf/models/dielectric.c"
#include "render/model_twice.h"

/* ---- The inverse of the sampler (values only; bsdf_invert) ----------------- */

static int bsdf__dielectric_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                                   const double r[4], double OUT_u[3], double *OUT_pmf) {
  (void)tu, (void)tv;
  if (!delta || wo.z == 0.0) return 0;
  double cos_t, fr = fresnel_dielectric(wo.z, b->eta, &cos_t);
  if (wo.z * wi.z > 0.0) {
    if (!bsdf__same_dir(wi, bsdf__mirror(wo))) return 0;
    return bsdf__invert_delta(0.0, fr, r, OUT_u, OUT_pmf);
  }
  double s = wo.z > 0.0 ? 1.0 / b->eta : b->eta;
  if (cos_t == 0.0 || !bsdf__same_dir(wi, v3(-s * wo.x, -s * wo.y, cos_t))) return 0;
  return bsdf__invert_delta(fr, 1.0, r, OUT_u, OUT_pmf);
}

/* Mitsuba's default: bk7 inside, air outside. */
static void bsdf__dielectric_defaults(bsdf *b) { b->eta = 1.5046 / BSDF_AIR_IOR; }

static lmc_status bsdf__dielectric_read(bsdf *b, plugin_props *p) {
  lmc_status st = bsdf_read_eta(b, p, "bk7", "an index-matched interface, invisible");
  if (st != LMC_OK) return st;
  return bsdf_read_textures(b, p, BSDF_TEX_SPECULAR | BSDF_TEX_TRANSMITTANCE);
}

const bsdf_model bsdf_model_dielectric = {
    .name = "dielectric",
    .flags = BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_DELTA,
    .refracts = 1,
    .defaults = bsdf__dielectric_defaults,
    .read = bsdf__dielectric_read,
    BSDF_MODEL_OPS(dielectric),
};

#else /* the body, in render/real.h's vocabulary */

/* ---- dielectric (smooth) ------------------------------------------------ */

static RRGB R_FN(bsdf__dielectric_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                        transport_mode mode) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi, (void)mode;
  return RRGB_ZERO();
}

static REAL R_FN(bsdf__dielectric_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi;
  return R_C(0.0);
}

static int R_FN(bsdf__dielectric_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                         REAL u_lobe, REAL u1, REAL u2, transport_mode mode,
                                         R_FN(bsdf_sample) *out) {
  (void)u1, (void)u2;
  if (R_V(wo.z) == 0.0) return 0;
  REAL cos_t;
  REAL fr = R_FN(fresnel_dielectric)(R_ARG wo.z, b->eta, &cos_t);
  if (R_V(u_lobe) < R_V(fr)) {
    /* Reflection, chosen with probability F: weight = specularReflectance,
     * f = ks F / |cos wi|. */
    REAL3 wi = R_FN(bsdf__mirror)(R_ARG wo);
    RRGB weight = R_FN(tex_eval)(R_ARG &b->specular, tu, tv);
    return R_FN(bsdf__finish)(R_ARG out, wi, RRGB_SCALE(weight, R_DIV(fr, R_FABS(wi.z))), fr, 1.0,
                              BSDF_REFLECTION | BSDF_DELTA);
  }
  /* Refraction, probability 1 - F. s = eta_o / eta_i of the two sides:
   * wi = (-s wo.x, -s wo.y, cos_t). */
  if (R_V(cos_t) == 0.0) return 0;
  double s = R_V(wo.z) > 0.0 ? 1.0 / b->eta : b->eta;
  REAL3 wi = R3_MAKE(R_MUL_S(wo.x, -s), R_MUL_S(wo.y, -s), cos_t);
  double scale = mode == TRANSPORT_RADIANCE ? s * s : 1.0;
  RRGB weight = RRGB_SCALE_S(R_FN(tex_eval)(R_ARG &b->transmittance, tu, tv), scale);
  REAL pdf = R_S_SUB(1.0, fr);
  return R_FN(bsdf__finish)(R_ARG out, wi, RRGB_SCALE(weight, R_DIV(pdf, R_FABS(cos_t))), pdf,
                            R_V(cos_t) < 0.0 ? b->eta : 1.0 / b->eta,
                            BSDF_TRANSMISSION | BSDF_DELTA);
}

#endif
