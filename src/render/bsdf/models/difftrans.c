/*
 * difftrans.c: an ideal diffuse transmitter (Mitsuba 0.6's difftrans: thin
 * paper, leaves, a lamp shade), one BSDF model (bsdf_model.h).
 * Parameters (Mitsuba's names and defaults): transmittance (colour or
 *   texture, 0.5).
 *
 * Light that arrives on one side leaves the other side with the cosine
 * distribution; nothing is reflected. With T the transmittance:
 *   f = T / pi   when wo and wi lie on opposite sides (wo.z wi.z < 0),
 *   f = 0        otherwise.
 * Both sides behave alike. Sampling: a cosine-weighted direction on the
 * side away from wo, pdf = |cos wi| / pi; f is symmetric and bends
 * nothing, so radiance and importance agree.
 *
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by model_twice.h, in doubles and in duals.
 */
#ifndef R_DUAL
#include <math.h>

#include "render/bsdf/bsdf_model_file.h"

#define MODEL_BODY "render/bsdf/models/difftrans.c"
#include "render/model_twice.h"

/* ---- The inverse of the sampler (values only; bsdf_invert) ----------------- */

static int bsdf__difftrans_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                                  const double r[4], double OUT_u[3], double *OUT_pmf) {
  (void)b, (void)tu, (void)tv, (void)OUT_pmf;
  if (delta || !(wo.z * wi.z < 0.0)) return 0;
  /* The sampler's cosine-weighted direction before it was turned away from wo. */
  return bsdf__invert_cosine(v3(wi.x, wi.y, fabs(wi.z)), 0.0, 1.0, r, OUT_u);
}

static double bsdf__difftrans_roughness(const bsdf *b) {
  (void)b;
  return 1.0;
}

static lmc_status bsdf__difftrans_read(bsdf *b, plugin_props *p) {
  return props_texture(p, "transmittance", rgb_gray(0.5), &b->transmittance);
}

static void bsdf__difftrans_defaults(bsdf *b) { b->transmittance = tex_constant(rgb_gray(0.5)); }

const bsdf_model bsdf_model_difftrans = {
    .name = "difftrans",
    .flags = BSDF_TRANSMISSION | BSDF_DIFFUSE_LOBE,
    .defaults = bsdf__difftrans_defaults,
    .read = bsdf__difftrans_read,
    .roughness = bsdf__difftrans_roughness,
    BSDF_MODEL_OPS(difftrans),
};

#else /* the body, in render/real.h's vocabulary */

static RRGB R_FN(bsdf__difftrans_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                       transport_mode mode) {
  (void)mode;
  if (!(R_V(wo.z) * R_V(wi.z) < 0.0)) return RRGB_ZERO();
  /* f = T / pi */
  return RRGB_SCALE_S(R_FN(tex_eval)(R_ARG & b->transmittance, tu, tv), 1.0 / M_PI);
}

static REAL R_FN(bsdf__difftrans_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  (void)b, (void)tu, (void)tv;
  if (!(R_V(wo.z) * R_V(wi.z) < 0.0)) return R_C(0.0);
  /* |cos wi| / pi */
  return R_DIV_S(R_FABS(wi.z), M_PI);
}

static int R_FN(bsdf__difftrans_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                        REAL u_lobe, REAL u1, REAL u2, transport_mode mode,
                                        R_FN(bsdf_sample) * out) {
  (void)u_lobe;
  if (R_V(wo.z) == 0.0) return 0;
  REAL3 wi = R_FN(bsdf__cosine_hemisphere)(R_ARG u1, u2);
  if (!(R_V(wi.z) > 0.0)) return 0;
  /* Away from wo's side. */
  if (R_V(wo.z) > 0.0) wi.z = R_NEG(wi.z);
  return R_FN(bsdf__finish)(
      R_ARG out, wi, R_FN(bsdf__difftrans_eval)(R_ARG b, tu, tv, wo, wi, mode),
      R_DIV_S(R_FABS(wi.z), M_PI), 1.0, BSDF_TRANSMISSION | BSDF_DIFFUSE_LOBE);
}

#endif
