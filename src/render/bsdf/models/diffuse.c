/*
 * diffuse.c: Lambertian reflection (Mitsuba's diffuse), one BSDF model (bsdf_model.h).
 * Parameters (Mitsuba's names and defaults): reflectance (colour or texture, 0.5).
 *
 * f = R / pi; cosine-weighted sampling, pdf = cos(wi) / pi.
 *
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by model_twice.h, in doubles and in duals.
 */
#ifndef R_DUAL
#include <math.h>

#include "render/bsdf/bsdf_model_file.h"

#define MODEL_BODY "render/bsdf/models/diffuse.c"
#include "render/model_twice.h"

/* ---- The inverse of the sampler (values only; bsdf_invert) ----------------- */

static int bsdf__diffuse_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                                const double r[4], double OUT_u[3], double *OUT_pmf) {
  (void)b, (void)tu, (void)tv, (void)OUT_pmf;
  if (delta || !(wo.z > 0.0)) return 0;
  return bsdf__invert_cosine(wi, 0.0, 1.0, r, OUT_u);
}

static double bsdf__diffuse_roughness(const bsdf *b) {
  (void)b;
  return 1.0;
}

static lmc_status bsdf__diffuse_read(bsdf *b, plugin_props *p) {
  return props_texture(p, "reflectance", rgb_gray(0.5), &b->diffuse);
}

const bsdf_model bsdf_model_diffuse = {
    .name = "diffuse",
    .flags = BSDF_REFLECTION | BSDF_DIFFUSE_LOBE,
    .read = bsdf__diffuse_read,
    .roughness = bsdf__diffuse_roughness,
    BSDF_MODEL_OPS(diffuse),
};

#else /* the body, in render/real.h's vocabulary */

/* ---- diffuse --------------------------------------------------------------- */

static RRGB R_FN(bsdf__diffuse_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                     transport_mode mode) {
  (void)mode;
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return RRGB_ZERO();
  /* f = R / pi */
  return RRGB_SCALE_S(R_FN(tex_eval)(R_ARG &b->diffuse, tu, tv), 1.0 / M_PI);
}

static REAL R_FN(bsdf__diffuse_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  (void)b, (void)tu, (void)tv;
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return R_C(0.0);
  return R_DIV_S(wi.z, M_PI);
}

static int R_FN(bsdf__diffuse_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL u_lobe,
                                      REAL u1, REAL u2, transport_mode mode,
                                      R_FN(bsdf_sample) *out) {
  (void)u_lobe;
  if (R_V(wo.z) <= 0.0) return 0;
  REAL3 wi = R_FN(bsdf__cosine_hemisphere)(R_ARG u1, u2);
  if (R_V(wi.z) <= 0.0) return 0;
  return R_FN(bsdf__finish)(R_ARG out, wi, R_FN(bsdf__diffuse_eval)(R_ARG b, tu, tv, wo, wi, mode),
                            R_DIV_S(wi.z, M_PI), 1.0, BSDF_REFLECTION | BSDF_DIFFUSE_LOBE);
}

#endif
