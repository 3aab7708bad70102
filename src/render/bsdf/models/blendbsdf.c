/*
 * blendbsdf.c: a linear blend of two BSDFs (Mitsuba 0.6's blendbsdf: worn
 * paint over metal, a glaze over a diffuse base), one BSDF model
 * (bsdf_model.h).
 * Parameters (Mitsuba's names and defaults): weight (a number or texture in
 *   [0, 1], 0.5: how much of the second BSDF), two nested BSDFs.
 *
 * With w the weight (the mean of its three channels, clamped to [0, 1], as
 * Mitsuba takes it) and f0, f1 the nested BSDFs (each with its own
 * twosided flip and mask):
 *   f = (1 - w) f0 + w f1.
 * Sampling picks the second BSDF with probability w (u_lobe rescaled into
 * the chosen one) and samples it. A delta lobe keeps its direction and
 * weight, its f and probability scaled by the choice's (1 - w or w); a
 * non-delta direction gets the blend's f and the mixture density
 *   pdf = (1 - w) pdf0 + w pdf1
 * of the two samplers, so the sample's weight is f |cos| / pdf of the
 * whole blend. The inverse picks the nested BSDF by its share of the
 * density (or of the delta lobe's probability) at wi and inverts it.
 * The blend's lobes are the union of its BSDFs'; it is never "rough" for
 * bsdf_is_rough (its directions keep the relative parametrization), never
 * a glossy chain vertex or an interface for the manifold walks. Its shading
 * frame is the surface's, turned to follow dpdu when a nested BSDF is
 * anisotropic; a nested bumpmap's displacement is not applied.
 * The weight lives in the `diffuse` texture slot.
 *
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by model_twice.h, in doubles and in duals.
 */
#ifndef R_DUAL
#include <math.h>

#include "render/bsdf/bsdf_model_file.h"

#define MODEL_BODY "render/bsdf/models/blendbsdf.c"
#include "render/model_twice.h"

/* ---- The inverse of the sampler (values only; bsdf_invert) ----------------- */

static int bsdf__blendbsdf_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                                  const double r[4], double OUT_u[3], double *OUT_pmf) {
  double w1 = bsdf__blendbsdf_weight(b, tu, tv), wk[2] = {1.0 - w1, w1};
  /* Each nested BSDF's share of what gives wi: its choice's probability
   * times its density at wi, or, for a delta lobe, times the probability
   * of the lobe its inverse finds (its sampler's pdf from those numbers). */
  double share[2] = {0.0, 0.0}, u[3];
  for (int k = 0; k < 2; k++) {
    const bsdf *in = b->nested_bsdf[k];
    if (!(wk[k] > 0.0) || !bsdf_invert(in, tu, tv, wo, wi, delta, r, u)) continue;
    if (!delta) {
      share[k] = wk[k] * bsdf_pdf(in, tu, tv, wo, wi);
      continue;
    }
    bsdf_sample s;
    if (bsdf_sample_f(in, tu, tv, wo, u[0], u[1], u[2], TRANSPORT_RADIANCE, &s))
      share[k] = wk[k] * s.pdf;
  }
  double total = share[0] + share[1];
  if (!(total > 0.0)) return 0;
  double t = r[0] * total;
  int k = t < share[0] && share[0] > 0.0 ? 0 : 1;
  if (!(share[k] > 0.0)) k = 1 - k;
  double lo = k == 0 ? 0.0 : share[0];
  double rr[4] = {fmin((t - lo) / share[k], nextafter(1.0, 0.0)), r[1], r[2], r[3]};
  if (!(rr[0] >= 0.0)) rr[0] = 0.0;
  if (!bsdf_invert(b->nested_bsdf[k], tu, tv, wo, wi, delta, rr, u)) return 0;
  /* u_lobe into the chosen BSDF's interval of the blend's u_lobe. */
  OUT_u[0] = k == 0 ? fmin(u[0] * wk[0], nextafter(wk[0], 0.0))
                    : fmin(wk[0] + u[0] * wk[1], nextafter(1.0, 0.0));
  OUT_u[1] = u[1];
  OUT_u[2] = u[2];
  *OUT_pmf = share[k];
  return 1;
}

static int bsdf__blendbsdf_lobes(const bsdf *b) {
  return bsdf_flags(b->nested_bsdf[0]) | bsdf_flags(b->nested_bsdf[1]);
}

static int bsdf__blendbsdf_anisotropic(const bsdf *b) {
  return bsdf_is_anisotropic(b->nested_bsdf[0]) || bsdf_is_anisotropic(b->nested_bsdf[1]);
}

static void bsdf__blendbsdf_defaults(bsdf *b) { b->diffuse = tex_constant(rgb_gray(0.5)); }

static lmc_status bsdf__blendbsdf_read(bsdf *b, plugin_props *p) {
  lmc_status st = props_texture(p, "weight", rgb_gray(0.5), &b->diffuse);
  if (st != LMC_OK) return st;
  int n;
  if ((st = props_bsdfs(p, 2, b->nested, &n)) != LMC_OK) return st;
  if (n != 2) return props_fail(p, NULL, "a blendbsdf needs two nested BSDFs (it has %d)", n);
  return LMC_OK;
}

const bsdf_model bsdf_model_blendbsdf = {
    .name = "blendbsdf",
    .flags = BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_DIFFUSE_LOBE | BSDF_GLOSSY | BSDF_DELTA,
    .defaults = bsdf__blendbsdf_defaults,
    .read = bsdf__blendbsdf_read,
    .anisotropic = bsdf__blendbsdf_anisotropic,
    .lobes = bsdf__blendbsdf_lobes,
    BSDF_MODEL_OPS(blendbsdf),
    BSDF_MODEL_EVAL_PDF(blendbsdf),
};

#else /* the body, in render/real.h's vocabulary */

/* w: the mean of the weight's channels, clamped to [0, 1]. */
static REAL R_FN(bsdf__blendbsdf_weight)(R_CTX const bsdf *b, REAL tu, REAL tv) {
  RRGB c = R_FN(tex_eval)(R_ARG &b->diffuse, tu, tv);
  REAL w = R_MUL_S(R_ADD(R_ADD(c.r, c.g), c.b), 1.0 / 3.0);
  if (!(R_V(w) > 0.0)) return R_C(0.0);
  if (R_V(w) >= 1.0) return R_C(1.0);
  return w;
}

/* (1 - w) a + w b */
static RRGB R_FN(bsdf__blendbsdf_mix)(R_CTX REAL w, RRGB a, RRGB b) {
  return RRGB_ADD(RRGB_SCALE(a, R_S_SUB(1.0, w)), RRGB_SCALE(b, w));
}

static RRGB R_FN(bsdf__blendbsdf_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                       transport_mode mode) {
  REAL w = R_FN(bsdf__blendbsdf_weight)(R_ARG b, tu, tv);
  RRGB f0 = R_FN(bsdf_eval)(R_ARG b->nested_bsdf[0], tu, tv, wo, wi, mode);
  RRGB f1 = R_FN(bsdf_eval)(R_ARG b->nested_bsdf[1], tu, tv, wo, wi, mode);
  return R_FN(bsdf__blendbsdf_mix)(R_ARG w, f0, f1);
}

static REAL R_FN(bsdf__blendbsdf_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  REAL w = R_FN(bsdf__blendbsdf_weight)(R_ARG b, tu, tv);
  REAL p0 = R_FN(bsdf_pdf)(R_ARG b->nested_bsdf[0], tu, tv, wo, wi);
  REAL p1 = R_FN(bsdf_pdf)(R_ARG b->nested_bsdf[1], tu, tv, wo, wi);
  /* (1 - w) p0 + w p1 */
  return R_ADD(R_MUL(p0, R_S_SUB(1.0, w)), R_MUL(p1, w));
}

static RRGB R_FN(bsdf__blendbsdf_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                           REAL3 wi, transport_mode mode, REAL *OUT_pdf) {
  REAL w = R_FN(bsdf__blendbsdf_weight)(R_ARG b, tu, tv), p0, p1;
  RRGB f0 = R_FN(bsdf_eval_pdf)(R_ARG b->nested_bsdf[0], tu, tv, wo, wi, mode, &p0);
  RRGB f1 = R_FN(bsdf_eval_pdf)(R_ARG b->nested_bsdf[1], tu, tv, wo, wi, mode, &p1);
  *OUT_pdf = R_ADD(R_MUL(p0, R_S_SUB(1.0, w)), R_MUL(p1, w));
  return R_FN(bsdf__blendbsdf_mix)(R_ARG w, f0, f1);
}

static int R_FN(bsdf__blendbsdf_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                        REAL u_lobe, REAL u1, REAL u2, transport_mode mode,
                                        R_FN(bsdf_sample) *out) {
  REAL w = R_FN(bsdf__blendbsdf_weight)(R_ARG b, tu, tv);
  /* The second BSDF with probability w; u_lobe rescaled into the choice. */
  int k = !(R_V(u_lobe) < 1.0 - R_V(w));
  REAL wk = k ? w : R_S_SUB(1.0, w);
  REAL u = k ? R_DIV(R_SUB(u_lobe, R_S_SUB(1.0, w)), w) : R_DIV(u_lobe, wk);
  if (!R_FN(bsdf_sample_f)(R_ARG b->nested_bsdf[k], tu, tv, wo, u, u1, u2, mode, out)) return 0;
  if (out->flags & BSDF_DELTA) {
    /* The lobe's f and probability times the choice's; the weight stays. */
    out->f = RRGB_SCALE(out->f, wk);
    out->pdf = R_MUL(out->pdf, wk);
#if !R_DUAL
    if (out->has_pdf_rev) out->pdf_rev *= wk;
#endif
    return 1;
  }
  /* A direction of a non-delta lobe: the whole blend's f and density. */
  REAL pdf;
  RRGB f = R_FN(bsdf__blendbsdf_eval_pdf)(R_ARG b, tu, tv, wo, out->wi, mode, &pdf);
  int flags = out->flags;
  double eta = out->eta;
#if !R_DUAL
  out->has_pdf_rev = 0;
#endif
  return R_FN(bsdf__finish)(R_ARG out, out->wi, f, pdf, eta, flags);
}

#endif
