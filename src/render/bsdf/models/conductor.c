/*
 * conductor.c: a smooth metal (Mitsuba's conductor), one BSDF model (bsdf_model.h).
 * Parameters (Mitsuba's names and defaults): material (Cu), eta, k, extEta (1),
 *   specularReflectance (1).
 *
 * delta reflection with weight specularReflectance F_cond(cos).
 *
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by model_twice.h, in doubles and in duals.
 */
#ifndef R_DUAL
#include <math.h>

#include "render/bsdf/bsdf_model_file.h"

#define MODEL_BODY "render/bsdf/models/conductor.c"
#include "render/model_twice.h"

/* ---- The inverse of the sampler (values only; bsdf_invert) ----------------- */

static int bsdf__conductor_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                                  const double r[4], double OUT_u[3], double *OUT_pmf) {
  (void)b, (void)tu, (void)tv;
  if (!delta || !(wo.z > 0.0) || !bsdf__same_dir(wi, bsdf__mirror(wo))) return 0;
  return bsdf__invert_delta(0.0, 1.0, r, OUT_u, OUT_pmf);
}

static lmc_status bsdf__conductor_read(bsdf *b, plugin_props *p) {
  lmc_status st = bsdf_read_conductor(b, p);
  if (st != LMC_OK) return st;
  return bsdf_read_textures(b, p, BSDF_TEX_SPECULAR);
}

const bsdf_model bsdf_model_conductor = {
    .name = "conductor",
    .flags = BSDF_REFLECTION | BSDF_DELTA,
    .read = bsdf__conductor_read,
    BSDF_MODEL_OPS(conductor),
};

#else /* the body, in render/real.h's vocabulary */

/* ---- conductor (smooth) ------------------------------------------------- */

static RRGB R_FN(bsdf__conductor_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                       transport_mode mode) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi, (void)mode;
  return RRGB_ZERO();
}

static REAL R_FN(bsdf__conductor_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi;
  return R_C(0.0);
}

static int R_FN(bsdf__conductor_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                        REAL u_lobe, REAL u1, REAL u2, transport_mode mode,
                                        R_FN(bsdf_sample) *out) {
  (void)u_lobe, (void)u1, (void)u2, (void)mode;
  if (R_V(wo.z) <= 0.0) return 0;
  REAL3 wi = R_FN(bsdf__mirror)(R_ARG wo);
  /* weight = ks F_cond(cos wo); delta convention: pdf 1, f = weight / cos wi. */
  RRGB weight = RRGB_MUL(R_FN(tex_eval)(R_ARG &b->specular, tu, tv),
                         R_FN(fresnel_conductor)(R_ARG wo.z, b->cond_eta, b->cond_k));
  return R_FN(bsdf__finish)(R_ARG out, wi, RRGB_SCALE(weight, R_S_DIV(1.0, wi.z)), R_C(1.0), 1.0,
                            BSDF_REFLECTION | BSDF_DELTA);
}

#endif
