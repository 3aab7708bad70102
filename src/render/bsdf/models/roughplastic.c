/*
 * roughplastic.c: rough plastic (Mitsuba's roughplastic), one BSDF model (bsdf_model.h).
 * Parameters (Mitsuba's names and defaults): distribution, alpha, sampleVisible, intIOR, extIOR,
 *   diffuseReflectance, specularReflectance, nonlinear.
 *
 * roughplastic (one-sided; Mitsuba 0.6's roughplastic.cpp). A rough
 * dielectric coating (eta, Beckmann or GGX alpha) over a Lambertian base kd,
 * the sum of a specular and a diffuse lobe, with h = normalize(wo + wi):
 *   f_s = ks F(wo.h) D(h) G(wo, wi, h) / (4 cos_o cos_i),
 *   f_d = kd' T(cos_o) T(cos_i) / (pi eta^2),
 *   kd' = kd / (1 - F_dr)  or, nonlinear,  kd / (1 - kd F_dr).
 * T(c) is the rough transmittance: the energy that light arriving at cosine
 * c from outside carries through the rough interface, the hemispherical
 * integral of roughdielectric's refraction lobe (importance transport);
 * F_dr = 1 - int_0^1 2 c T_int(c) dc is the interface's diffuse reflectance
 * seen from inside (T_int: the same at 1 / eta). As alpha -> 0, T -> 1 - F
 * and F_dr -> plastic's F_dr: smooth plastic's diffuse term. Mitsuba 0.6
 * reads T and F_dr from tables it ships (data/microfacet/beckmann.dat and
 * ggx.dat, tricubic in cos^(1/4), alpha^(1/4), eta^(1/4)); here they are
 * computed when the model
 * is prepared (bsdf_prepare) for its own (dist, alpha, eta): T at 65 nodes
 * uniform in cos^(1/4) (where the boundary layer of width ~alpha near
 * grazing is resolved), by a product Gauss-Legendre rule over the visible
 * normals of each direction, interpolated by a C1 cubic; F_dr by
 * Gauss-Legendre in the cosine. Against Mitsuba's GGX table the nodes agree
 * to 1e-4 (8e-4 at alpha = 1); against its Beckmann table to 0.6%, the
 * difference of our exact Smith G1 and Mitsuba's rational approximation.
 * Sampling (Mitsuba's rule): the specular lobe with probability
 *   p_s = (1 - T_o) w / ((1 - T_o) w + T_o (1 - w)),  T_o = T(cos_o),
 * w the specular sampling weight (as for plastic), drawing a normal as the
 * rough conductor does and reflecting wo about it; else cosine-weighted.
 *   pdf = p_s p_m(h) / (4 wi.h) + (1 - p_s) cos_i / pi.
 * f is symmetric in (wo, wi): the model is reciprocal (its pdf is not).
 *
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by model_twice.h, in doubles and in duals.
 */
#ifndef R_DUAL
#include <math.h>

#include "render/bsdf/bsdf_model_file.h"

#define MODEL_BODY "render/bsdf/models/roughplastic.c"
#include "render/model_twice.h"

/* ---- The inverse of the sampler (values only; bsdf_invert) ----------------- */

static int bsdf__roughplastic_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                                     int delta, const double r[4], double OUT_u[3],
                                     double *OUT_pmf) {
  (void)OUT_pmf;
  if (delta || !(wo.z > 0.0) || !(wi.z > 0.0)) return 0;
  double w = bsdf__specular_weight(&b->specular, &b->diffuse);
  double ps = bsdf__rp_prob_specular(w, bsdf__rtrans_eval(bsdf__rtrans_get(b), wo.z));
  double pdf;
  bsdf__rp_eval_pdf(b, tu, tv, wo, wi, 0, &pdf, NULL);
  int glossy;
  if (!bsdf__invert_mixture(wi, ps, pdf, r, OUT_u, &glossy)) return 0;
  if (!glossy) return 1;
  vec3 m = v3_normalize(v3_add(wo, wi));
  return v3_dot(wo, m) > 0.0 &&
         mf_invert(b->dist, b->alpha, wo, b->sample_visible, m, &OUT_u[1], &OUT_u[2]);
}

/* Mitsuba's default: polypropylene over air. */
static void bsdf__roughplastic_defaults(bsdf *b) { b->eta = 1.49 / BSDF_AIR_IOR; }

/* By its coating alone, as roughconductor: a narrow glossy lobe over the
 * diffuse base keeps relative parametrization. */
static double bsdf__roughplastic_roughness(const bsdf *b) { return b->alpha; }

static void bsdf__roughplastic_prepare(bsdf *b) {
  bsdf_rtrans *rt = &b->rtrans;
  if (rt->ready && rt->dist == b->dist && rt->alpha == b->alpha && rt->eta == b->eta) return;
  bsdf__rtrans_fill(rt, b->dist, b->alpha, b->eta);
}

static lmc_status bsdf__roughplastic_read(bsdf *b, plugin_props *p) {
  lmc_status st =
      bsdf_read_eta(b, p, "polypropylene", "no specular coating, only the diffuse base");
  if (st == LMC_OK) st = bsdf_read_textures(b, p, BSDF_TEX_DIFFUSE | BSDF_TEX_SPECULAR);
  if (st == LMC_OK) st = props_bool(p, "nonlinear", b->nonlinear, &b->nonlinear);
  if (st == LMC_OK) st = bsdf_read_microfacet(b, p);
  if (st != LMC_OK) return st;
  /* Mitsuba 0.6 tabulates the rough transmittance for alpha in [0, 4] and
   * rejects the scene beyond; it is computed here for any alpha. */
  if (b->alpha > 4.0)
    props_warn(p, NULL,
               "roughplastic alpha %g is above 4, where Mitsuba 0.6 refuses it; accepted here",
               b->alpha);
  return LMC_OK;
}

const bsdf_model bsdf_model_roughplastic = {
    .name = "roughplastic",
    .flags = BSDF_REFLECTION | BSDF_DIFFUSE_LOBE | BSDF_GLOSSY,
    .defaults = bsdf__roughplastic_defaults,
    .read = bsdf__roughplastic_read,
    .prepare = bsdf__roughplastic_prepare,
    .roughness = bsdf__roughplastic_roughness,
    BSDF_MODEL_OPS(roughplastic),
    BSDF_MODEL_EVAL_PDF(roughplastic),
};

#else /* the body, in render/real.h's vocabulary */

/* ---- roughplastic -------------------------------------------------------- */

/* T(c) from the table of bsdf_rtrans: a cubic Hermite spline in
 * s = c^(1/4), on whose uniform grid the nodes lie, with Catmull-Rom
 * tangents (one-sided differences at the ends, as Mitsuba's
 * evalCubicInterp1D), clamped to [0, 1]. It is C1 in s, so the derivative
 * in c that duals carry is continuous for c > 0. */
static REAL R_FN(bsdf__rtrans_eval)(R_CTX const bsdf_rtrans *rt, REAL c) {
  const int last = BSDF_RTRANS_NODES - 1;
  const double *y = rt->t_ext;
  double cv = R_V(c);
  if (!(cv > 0.0)) return R_C(y[0]);
  if (cv >= 1.0) return R_C(y[last]);
  REAL s = R_SQRT(R_SQRT(c));
  int i = (int)(R_V(s) * last);
  if (i > last - 1) i = last - 1;
  double p0 = y[i], p1 = y[i + 1];
  double m0 = i > 0 ? 0.5 * (y[i + 1] - y[i - 1]) : y[1] - y[0];
  double m1 = i + 1 < last ? 0.5 * (y[i + 2] - y[i]) : y[last] - y[last - 1];
  /* p(t) = p0 + t (m0 + t (k2 + t k3)), t = s (N - 1) - i */
  double k2 = 3.0 * (p1 - p0) - 2.0 * m0 - m1, k3 = 2.0 * (p0 - p1) + m0 + m1;
  REAL t = R_SUB_S(R_MUL_S(s, (double)last), (double)i);
  REAL p = R_ADD_S(R_MUL(t, R_ADD_S(R_MUL(t, R_ADD_S(R_MUL_S(t, k3), k2)), m0)), p0);
  if (R_V(p) < 0.0) return R_C(0.0);
  if (R_V(p) > 1.0) return R_C(1.0);
  return p;
}

/* Probability of choosing the specular lobe at wo, Mitsuba's rule with
 * T_o = T(cos wo) and the specular weight w (bsdf__specular_weight):
 *   p = (1 - T_o) w / ((1 - T_o) w + T_o (1 - w)). */
static REAL R_FN(bsdf__rp_prob_specular)(R_CTX double w, REAL t_o) {
  REAL s = R_MUL_S(R_S_SUB(1.0, t_o), w);
  REAL den = R_ADD(s, R_MUL_S(t_o, 1.0 - w));
  return R_V(den) > 0.0 ? R_DIV(s, den) : R_C(0.0);
}

/* f and pdf of one (wo, wi) pair in one pass, as bsdf__rc_eval_pdf: the
 * half vector, D, G1 and the two transmittances are shared. */
static RRGB R_FN(bsdf__rp_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                    int want_f, REAL *OUT_pdf, REAL *OUT_pdf_rev) {
  if (OUT_pdf) *OUT_pdf = R_C(0.0);
  if (OUT_pdf_rev) *OUT_pdf_rev = R_C(0.0);
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return RRGB_ZERO();
  const bsdf_rtrans *rt = bsdf__rtrans_get(b);
  REAL alpha = R_C(b->alpha);
  REAL3 h = R3_NORMALIZE(R3_ADD(wo, wi));
  REAL d = R_FN(mf_D)(R_ARG b->dist, alpha, h);
  int need_spec = want_f && R_V(d) != 0.0;
  REAL g1o = R_C(0.0), g1i = R_C(0.0);
  if (need_spec || (OUT_pdf && b->sample_visible)) g1o = R_FN(mf_G1)(R_ARG b->dist, alpha, wo, h);
  if (need_spec || (OUT_pdf_rev && b->sample_visible))
    g1i = R_FN(mf_G1)(R_ARG b->dist, alpha, wi, h);
  /* The transmittances into the coating at wo and at wi. */
  REAL t_o = R_FN(bsdf__rtrans_eval)(R_ARG rt, wo.z);
  REAL t_i = R_FN(bsdf__rtrans_eval)(R_ARG rt, wi.z);

  /* pdf = p_s p_m(h) / (4 wi.h) + (1 - p_s) cos(wi) / pi, p_s at wo; the
   * reverse density with the roles of wo and wi swapped. */
  if (OUT_pdf || OUT_pdf_rev) {
    double w = bsdf__specular_weight(&b->specular, &b->diffuse);
    if (OUT_pdf) {
      REAL ps = R_FN(bsdf__rp_prob_specular)(R_ARG w, t_o);
      REAL wih = R3_DOT(wi, h);
      REAL spec = R_C(0.0);
      if (R_V(wih) > 0.0)
        spec = R_DIV(R_FN(mf_pdf_known)(R_ARG d, g1o, wo, h, b->sample_visible), R_MUL_S(wih, 4.0));
      *OUT_pdf = R_ADD(R_MUL(ps, spec), R_DIV_S(R_MUL(R_S_SUB(1.0, ps), wi.z), M_PI));
    }
    if (OUT_pdf_rev) {
      REAL ps = R_FN(bsdf__rp_prob_specular)(R_ARG w, t_i);
      REAL woh = R3_DOT(wo, h);
      REAL spec = R_C(0.0);
      if (R_V(woh) > 0.0)
        spec = R_DIV(R_FN(mf_pdf_known)(R_ARG d, g1i, wi, h, b->sample_visible), R_MUL_S(woh, 4.0));
      *OUT_pdf_rev = R_ADD(R_MUL(ps, spec), R_DIV_S(R_MUL(R_S_SUB(1.0, ps), wo.z), M_PI));
    }
  }
  if (!want_f) return RRGB_ZERO();

  /* Diffuse: f_d = kd' T_o T_i / (pi eta^2), kd' with the rough F_dr seen
   * from inside. */
  RRGB kdp = R_FN(bsdf__plastic_kd)(R_ARG b, tu, tv, rt->fdr_int);
  RRGB f = RRGB_SCALE(kdp, R_DIV_S(R_MUL(t_o, t_i), M_PI * b->eta * b->eta));
  /* Specular: f_s = ks F(wo.h) D G / (4 cos_o cos_i), G = G1(wo, h) G1(wi, h). */
  if (need_spec) {
    REAL g = R_MUL(g1i, g1o);
    if (R_V(g) != 0.0) {
      REAL fr = R_FN(fresnel_dielectric)(R_ARG R3_DOT(wo, h), b->eta, NULL);
      REAL s = R_DIV(R_MUL(R_MUL(fr, d), g), R_MUL(R_MUL_S(wo.z, 4.0), wi.z));
      f = RRGB_ADD(f, RRGB_SCALE(R_FN(tex_eval)(R_ARG &b->specular, tu, tv), s));
    }
  }
  return f;
}

static RRGB R_FN(bsdf__roughplastic_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                          transport_mode mode) {
  (void)mode;
  return R_FN(bsdf__rp_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, NULL, NULL);
}

static REAL R_FN(bsdf__roughplastic_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                         REAL3 wi) {
  REAL pdf;
  R_FN(bsdf__rp_eval_pdf)(R_ARG b, tu, tv, wo, wi, 0, &pdf, NULL);
  return pdf;
}

static RRGB R_FN(bsdf__roughplastic_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                              REAL3 wi, transport_mode mode, REAL *OUT_pdf) {
  (void)mode;
  return R_FN(bsdf__rp_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, OUT_pdf, NULL);
}

static int R_FN(bsdf__roughplastic_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                           REAL u_lobe, REAL u1, REAL u2, transport_mode mode,
                                           R_FN(bsdf_sample) *out) {
  (void)mode;
  if (R_V(wo.z) <= 0.0) return 0;
  const bsdf_rtrans *rt = bsdf__rtrans_get(b);
  double w = bsdf__specular_weight(&b->specular, &b->diffuse);
  REAL ps = R_FN(bsdf__rp_prob_specular)(R_ARG w, R_FN(bsdf__rtrans_eval)(R_ARG rt, wo.z));
  REAL3 wi;
  int flags;
  if (R_V(u_lobe) < R_V(ps)) {
    /* The coating: reflect wo about a sampled normal. */
    REAL3 m = R_FN(mf_sample)(R_ARG b->dist, R_C(b->alpha), wo, b->sample_visible, u1, u2);
    if (R_V(R3_DOT(wo, m)) <= 0.0) return 0;
    wi = R3_NORMALIZE(R3_REFLECT(wo, m));
    flags = BSDF_REFLECTION | BSDF_GLOSSY;
  } else {
    /* The base: cosine-weighted. */
    wi = R_FN(bsdf__cosine_hemisphere)(R_ARG u1, u2);
    flags = BSDF_REFLECTION | BSDF_DIFFUSE_LOBE;
  }
  if (R_V(wi.z) <= 0.0) return 0;
  /* The mixture density and f of the pair (Mitsuba's sample does the same). */
  REAL pdf, pdf_rev = R_C(0.0);
  RRGB f = R_FN(bsdf__rp_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, &pdf, BSDF_R_REV(&pdf_rev));
  int ok = R_FN(bsdf__finish)(R_ARG out, wi, f, pdf, 1.0, flags);
  BSDF_R_SET_REV(out, pdf_rev);
  return ok;
}

#endif
