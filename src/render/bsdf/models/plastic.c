/*
 * plastic.c: smooth plastic (Mitsuba's plastic), one BSDF model (bsdf_model.h).
 * Parameters (Mitsuba's names and defaults): intIOR (polypropylene), extIOR (air),
 *   diffuseReflectance, specularReflectance, nonlinear.
 *
 * Mitsuba's smooth plastic: a dielectric coating (eta) on a
 * Lambertian base with reflectance kd. Specular: delta reflection
 * with weight ks F_i. Diffuse, including the infinite series of
 * internal reflections (F_dr: diffuse Fresnel reflectance seen
 * from inside, at 1/eta):
 *   f = kd' (1 - F_i) (1 - F_o) / (pi eta^2),
 *   kd' = kd / (1 - F_dr)         (default, colour preserving),
 *   kd' = kd / (1 - kd F_dr)      (nonlinear = 1).
 * F_i = F(cos wo), F_o = F(cos wi). The specular lobe is chosen
 * with probability p = F_i w / (F_i w + (1 - F_i)(1 - w)), w the
 * specular weight as for phong; pdf = (1 - p) cos(wi) / pi.
 *
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by model_twice.h, in doubles and in duals.
 */
#ifndef R_DUAL
#include <math.h>

#include "render/bsdf/bsdf_model_file.h"

#define MODEL_BODY "render/bsdf/models/plastic.c"
#include "render/model_twice.h"

/* ---- The inverse of the sampler (values only; bsdf_invert) ----------------- */

static int bsdf__plastic_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                                const double r[4], double OUT_u[3], double *OUT_pmf) {
  (void)tu, (void)tv;
  if (!(wo.z > 0.0)) return 0;
  double p = bsdf__plastic_prob_specular(b, fresnel_dielectric(wo.z, b->eta, NULL));
  if (delta)
    return bsdf__same_dir(wi, bsdf__mirror(wo)) && bsdf__invert_delta(0.0, p, r, OUT_u, OUT_pmf);
  return p < 1.0 && bsdf__invert_cosine(wi, p, 1.0, r, OUT_u);
}

/* Mitsuba's default: polypropylene over air. */
static void bsdf__plastic_defaults(bsdf *b) { b->eta = 1.49 / BSDF_AIR_IOR; }

static lmc_status bsdf__plastic_read(bsdf *b, plugin_props *p) {
  lmc_status st =
      bsdf_read_eta(b, p, "polypropylene", "no specular coating, only the diffuse base");
  if (st == LMC_OK) st = bsdf_read_textures(b, p, BSDF_TEX_DIFFUSE | BSDF_TEX_SPECULAR);
  if (st == LMC_OK) st = props_bool(p, "nonlinear", b->nonlinear, &b->nonlinear);
  return st;
}

const bsdf_model bsdf_model_plastic = {
    .name = "plastic",
    .flags = BSDF_REFLECTION | BSDF_DIFFUSE_LOBE | BSDF_DELTA,
    .defaults = bsdf__plastic_defaults,
    .read = bsdf__plastic_read,
    BSDF_MODEL_OPS(plastic),
};

#else /* the body, in render/real.h's vocabulary */

/* ---- plastic -------------------------------------------------------------- */

/* Probability of choosing the specular coating given F_i:
 * p = F_i w / (F_i w + (1 - F_i)(1 - w)). */
static REAL R_FN(bsdf__plastic_prob_specular)(R_CTX const bsdf *b, REAL fi) {
  double w = bsdf__specular_weight(&b->specular, &b->diffuse);
  REAL fiw = R_MUL_S(fi, w);
  REAL den = R_ADD(fiw, R_MUL_S(R_S_SUB(1.0, fi), 1.0 - w));
  return R_V(den) > 0.0 ? R_DIV(fiw, den) : R_C(0.0);
}

static RRGB R_FN(bsdf__plastic_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                     transport_mode mode) {
  (void)mode;
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return RRGB_ZERO();
  REAL fi = R_FN(fresnel_dielectric)(R_ARG wo.z, b->eta, NULL);
  REAL fo = R_FN(fresnel_dielectric)(R_ARG wi.z, b->eta, NULL);
  double fdr = bsdf__fresnel_diffuse_reflectance(1.0 / b->eta);
  RRGB kdp = R_FN(bsdf__plastic_kd)(R_ARG b, tu, tv, fdr);
  /* f = kd' (1 - F_i)(1 - F_o) / (pi eta^2) */
  REAL s = R_DIV_S(R_MUL(R_S_SUB(1.0, fi), R_S_SUB(1.0, fo)), M_PI * b->eta * b->eta);
  return RRGB_SCALE(kdp, s);
}

static REAL R_FN(bsdf__plastic_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  (void)tu, (void)tv;
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return R_C(0.0);
  REAL p = R_FN(bsdf__plastic_prob_specular)(R_ARG b,
                                             R_FN(fresnel_dielectric)(R_ARG wo.z, b->eta, NULL));
  /* (1 - p) cos(wi) / pi */
  return R_DIV_S(R_MUL(R_S_SUB(1.0, p), wi.z), M_PI);
}

static int R_FN(bsdf__plastic_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL u_lobe,
                                      REAL u1, REAL u2, transport_mode mode,
                                      R_FN(bsdf_sample) *out) {
  if (R_V(wo.z) <= 0.0) return 0;
  REAL fi = R_FN(fresnel_dielectric)(R_ARG wo.z, b->eta, NULL);
  REAL p = R_FN(bsdf__plastic_prob_specular)(R_ARG b, fi);
  if (R_V(u_lobe) < R_V(p)) {
    /* Specular coating: f = ks F_i / cos, pdf = p (weight ks F_i / p). */
    REAL3 wi = R_FN(bsdf__mirror)(R_ARG wo);
    RRGB ks = R_FN(tex_eval)(R_ARG &b->specular, tu, tv);
    return R_FN(bsdf__finish)(R_ARG out, wi, RRGB_SCALE(ks, R_DIV(fi, wi.z)), p, 1.0,
                              BSDF_REFLECTION | BSDF_DELTA);
  }
  REAL3 wi = R_FN(bsdf__cosine_hemisphere)(R_ARG u1, u2);
  if (R_V(wi.z) <= 0.0) return 0;
  REAL pdf = R_DIV_S(R_MUL(R_S_SUB(1.0, p), wi.z), M_PI);
  return R_FN(bsdf__finish)(R_ARG out, wi, R_FN(bsdf__plastic_eval)(R_ARG b, tu, tv, wo, wi, mode),
                            pdf, 1.0, BSDF_REFLECTION | BSDF_DIFFUSE_LOBE);
}

#endif
