/*
 * bsdf_smooth_generic.h: the models without microfacets (diffuse, phong,
 * the smooth conductor and dielectric, thindielectric, plastic,
 * roughdiffuse, ward), written once in render/real.h's vocabulary and
 * compiled twice by bsdf_smooth.c, in doubles and in duals. Not a header:
 * no include guard. The models are
 * described in bsdf_smooth.c's opening comment.
 */

/* (-w.x, -w.y, w.z): the mirror direction about the shading normal. */
static REAL3 R_FN(bsdf__mirror)(R_CTX REAL3 w) { return R3_MAKE(R_NEG(w.x), R_NEG(w.y), w.z); }

/* ---- diffuse --------------------------------------------------------------- */

RRGB R_FN(bsdf__diffuse_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                              transport_mode mode) {
  (void)mode;
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return RRGB_ZERO();
  /* f = R / pi */
  return RRGB_SCALE_S(R_FN(tex_eval)(R_ARG &b->diffuse, tu, tv), 1.0 / M_PI);
}

REAL R_FN(bsdf__diffuse_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  (void)b, (void)tu, (void)tv;
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return R_C(0.0);
  return R_DIV_S(wi.z, M_PI);
}

int R_FN(bsdf__diffuse_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL u_lobe,
                               REAL u1, REAL u2, transport_mode mode, R_FN(bsdf_sample) *out) {
  (void)u_lobe;
  if (R_V(wo.z) <= 0.0) return 0;
  REAL3 wi = R_FN(bsdf__cosine_hemisphere)(R_ARG u1, u2);
  if (R_V(wi.z) <= 0.0) return 0;
  return R_FN(bsdf__finish)(R_ARG out, wi, R_FN(bsdf__diffuse_eval)(R_ARG b, tu, tv, wo, wi, mode),
                            R_DIV_S(wi.z, M_PI), 1.0, BSDF_REFLECTION | BSDF_DIFFUSE_LOBE);
}

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
    *OUT_pdf = R_V(ca) > 0.0 ? R_ADD(R_MUL_S(R_MUL_S(can, (n + 1.0) / (2.0 * M_PI)), w), diff)
                             : diff;
  }
  if (!want_f) return RRGB_ZERO();
  /* f = kd / pi + ks (n + 2) / (2 pi) cos^n(a) */
  RRGB f = RRGB_SCALE_S(R_FN(tex_eval)(R_ARG &b->diffuse, tu, tv), 1.0 / M_PI);
  if (R_V(ca) > 0.0)
    f = RRGB_ADD(f, RRGB_SCALE(R_FN(tex_eval)(R_ARG &b->specular, tu, tv),
                               R_MUL_S(can, (n + 2.0) / (2.0 * M_PI))));
  return f;
}

RRGB R_FN(bsdf__phong_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                            transport_mode mode) {
  (void)mode;
  return R_FN(bsdf__ph_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, NULL);
}

REAL R_FN(bsdf__phong_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  REAL pdf;
  R_FN(bsdf__ph_eval_pdf)(R_ARG b, tu, tv, wo, wi, 0, &pdf);
  return pdf;
}

RRGB R_FN(bsdf__phong_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                transport_mode mode, REAL *OUT_pdf) {
  (void)mode;
  return R_FN(bsdf__ph_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, OUT_pdf);
}

int R_FN(bsdf__phong_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL u_lobe,
                             REAL u1, REAL u2, transport_mode mode, R_FN(bsdf_sample) *out) {
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

/* ---- conductor (smooth) ------------------------------------------------- */

RRGB R_FN(bsdf__conductor_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                transport_mode mode) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi, (void)mode;
  return RRGB_ZERO();
}

REAL R_FN(bsdf__conductor_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi;
  return R_C(0.0);
}

int R_FN(bsdf__conductor_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL u_lobe,
                                 REAL u1, REAL u2, transport_mode mode, R_FN(bsdf_sample) *out) {
  (void)u_lobe, (void)u1, (void)u2, (void)mode;
  if (R_V(wo.z) <= 0.0) return 0;
  REAL3 wi = R_FN(bsdf__mirror)(R_ARG wo);
  /* weight = ks F_cond(cos wo); delta convention: pdf 1, f = weight / cos wi. */
  RRGB weight = RRGB_MUL(R_FN(tex_eval)(R_ARG &b->specular, tu, tv),
                         R_FN(fresnel_conductor)(R_ARG wo.z, b->cond_eta, b->cond_k));
  return R_FN(bsdf__finish)(R_ARG out, wi, RRGB_SCALE(weight, R_S_DIV(1.0, wi.z)), R_C(1.0), 1.0,
                            BSDF_REFLECTION | BSDF_DELTA);
}

/* ---- dielectric (smooth) ------------------------------------------------ */

RRGB R_FN(bsdf__dielectric_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                 transport_mode mode) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi, (void)mode;
  return RRGB_ZERO();
}

REAL R_FN(bsdf__dielectric_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi;
  return R_C(0.0);
}

int R_FN(bsdf__dielectric_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL u_lobe,
                                  REAL u1, REAL u2, transport_mode mode, R_FN(bsdf_sample) *out) {
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

RRGB R_FN(bsdf__thindielectric_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                     transport_mode mode) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi, (void)mode;
  return RRGB_ZERO();
}

REAL R_FN(bsdf__thindielectric_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  (void)b, (void)tu, (void)tv, (void)wo, (void)wi;
  return R_C(0.0);
}

int R_FN(bsdf__thindielectric_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
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

/* ---- plastic -------------------------------------------------------------- */

/* Probability of choosing the specular coating given F_i:
 * p = F_i w / (F_i w + (1 - F_i)(1 - w)). */
static REAL R_FN(bsdf__plastic_prob_specular)(R_CTX const bsdf *b, REAL fi) {
  double w = bsdf__specular_weight(&b->specular, &b->diffuse);
  REAL fiw = R_MUL_S(fi, w);
  REAL den = R_ADD(fiw, R_MUL_S(R_S_SUB(1.0, fi), 1.0 - w));
  return R_V(den) > 0.0 ? R_DIV(fiw, den) : R_C(0.0);
}

RRGB R_FN(bsdf__plastic_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
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

REAL R_FN(bsdf__plastic_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  (void)tu, (void)tv;
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return R_C(0.0);
  REAL p = R_FN(bsdf__plastic_prob_specular)(
      R_ARG b, R_FN(fresnel_dielectric)(R_ARG wo.z, b->eta, NULL));
  /* (1 - p) cos(wi) / pi */
  return R_DIV_S(R_MUL(R_S_SUB(1.0, p), wi.z), M_PI);
}

int R_FN(bsdf__plastic_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL u_lobe,
                               REAL u1, REAL u2, transport_mode mode, R_FN(bsdf_sample) *out) {
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

/* ---- roughdiffuse (Oren-Nayar) ---------------------------------------------- */

/* sin(theta) = sqrt(x^2 + y^2): at the normal its dual has tangent 0 (the
 * one-sided choice of ad_safe_sqrt), never an infinite one. */
static REAL R_FN(bsdf__sin_theta)(R_CTX REAL3 w) {
  return R_SAFE_SQRT(R_ADD(R_SQR(w.x), R_SQR(w.y)));
}

RRGB R_FN(bsdf__roughdiffuse_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                   transport_mode mode) {
  (void)mode;
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return RRGB_ZERO();
  RRGB rho = R_FN(tex_eval)(R_ARG &b->diffuse, tu, tv);
  /* Oren and Nayar's sigma from Mitsuba's RMS slope: sigma = alpha / sqrt(2). */
  double sigma = b->alpha / sqrt(2.0), s2 = sigma * sigma;
  /* wa: the direction farther from the normal (Oren-Nayar's angle alpha),
   * wb: the nearer one (beta). p = sin(a) sin(b) cos(phi_a - phi_b). */
  int wo_near = R_V(wo.z) > R_V(wi.z);
  REAL3 wa = wo_near ? wi : wo, wb = wo_near ? wo : wi;
  REAL p = R_ADD(R_MUL(wa.x, wb.x), R_MUL(wa.y, wb.y));
  REAL cb = wb.z;

  if (b->fast_approx) {
    /* f = rho / pi (A + B max(0, cos dphi) sin(alpha) tan(beta)), where
     * cos(dphi) sin(alpha) tan(beta) = p / cos(beta). */
    double ka = 1.0 - 0.5 * s2 / (s2 + 0.33), kb = 0.45 * s2 / (s2 + 0.09);
    REAL s = R_V(p) > 0.0 ? R_ADD_S(R_MUL_S(R_DIV(p, cb), kb), ka) : R_C(ka);
    return RRGB_SCALE(rho, R_MUL_S(s, 1.0 / M_PI));
  }

  /* The full model: the angles, and the products with cos(dphi) written so
   * that no factor divides by sin(beta), which vanishes at the normal. */
  REAL sa = R_FN(bsdf__sin_theta)(R_ARG wa), sb = R_FN(bsdf__sin_theta)(R_ARG wb), ca = wa.z;
  REAL alpha = R_ATAN2(sa, ca), beta = R_ATAN2(sb, cb);
  /* ps = p / sin(alpha) = sin(beta) cos(dphi) (0 when both are at the normal) */
  REAL ps = R_V(sa) > 1e-12 ? R_DIV(p, sa) : R_C(0.0);
  /* q = beta / sin(beta), 1 + beta^2 / 6 near the normal; then
   * cos(dphi) beta^2 = ps beta q. */
  REAL q = R_V(beta) > 1e-4 ? R_DIV(beta, sb) : R_ADD_S(R_MUL_S(R_SQR(beta), 1.0 / 6.0), 1.0);
  REAL psbq = R_MUL(R_MUL(ps, beta), q);
  double tmp = s2 / (s2 + 0.09);
  double c1 = 1.0 - 0.5 * s2 / (s2 + 0.33), c4 = 0.17 * s2 / (s2 + 0.13);
  /* cos(dphi) C2 tan(beta), C2 = 0.45 tmp sin(alpha) (cos dphi > 0) or
   * 0.45 tmp (sin(alpha) - (2 beta / pi)^3):
   *   = 0.45 tmp (p - [cos dphi <= 0] (2 beta / pi)^3 ps) / cos(beta). */
  REAL t2 = p;
  if (!(R_V(p) > 0.0)) {
    REAL g = R_MUL_S(beta, 2.0 / M_PI);
    t2 = R_SUB(t2, R_MUL(R_MUL(R_SQR(g), g), ps));
  }
  t2 = R_MUL_S(R_DIV(t2, cb), 0.45 * tmp);
  /* (1 - |cos dphi|) C3 tan((alpha + beta) / 2), C3 = 0.125 tmp (4 alpha beta / pi^2)^2:
   *   = 0.125 tmp (4 alpha / pi^2)^2 (beta^2 - |ps| beta q) tan((alpha + beta) / 2),
   * tan((alpha + beta) / 2) = (sin a + sin b) / (cos a + cos b). */
  REAL tan_half = R_DIV(R_ADD(sa, sb), R_ADD(ca, cb));
  REAL k3 = R_MUL_S(R_SQR(R_MUL_S(alpha, 4.0 / (M_PI * M_PI))), 0.125 * tmp);
  REAL t3 = R_MUL(R_MUL(k3, R_SUB(R_SQR(beta), R_MUL(R_MUL(R_FABS(ps), beta), q))), tan_half);
  /* Single scattering C1 + t2 + t3; the interreflection term
   * C4 (1 - cos(dphi) (2 beta / pi)^2) = C4 (1 - (4 / pi^2) ps beta q). */
  REAL single = R_ADD(R_ADD_S(t2, c1), t3);
  REAL dbl = R_MUL_S(R_S_SUB(1.0, R_MUL_S(psbq, 4.0 / (M_PI * M_PI))), c4);
  /* f = (rho single + rho^2 dbl) / pi */
  RRGB f = RRGB_ADD(RRGB_SCALE(rho, single), RRGB_SCALE(RRGB_MUL(rho, rho), dbl));
  return RRGB_SCALE_S(f, 1.0 / M_PI);
}

REAL R_FN(bsdf__roughdiffuse_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  return R_FN(bsdf__diffuse_pdf)(R_ARG b, tu, tv, wo, wi);
}

int R_FN(bsdf__roughdiffuse_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL u_lobe,
                                    REAL u1, REAL u2, transport_mode mode,
                                    R_FN(bsdf_sample) *out) {
  (void)u_lobe;
  if (R_V(wo.z) <= 0.0) return 0;
  REAL3 wi = R_FN(bsdf__cosine_hemisphere)(R_ARG u1, u2);
  if (R_V(wi.z) <= 0.0) return 0;
  return R_FN(bsdf__finish)(R_ARG out, wi,
                            R_FN(bsdf__roughdiffuse_eval)(R_ARG b, tu, tv, wo, wi, mode),
                            R_DIV_S(wi.z, M_PI), 1.0, BSDF_REFLECTION | BSDF_GLOSSY);
}

/* ---- ward ------------------------------------------------------------------ */

/* f and pdf of one (wo, wi) pair in one pass (eval, pdf and sample all come
 * here). want_f = 0 skips f; OUT_pdf = NULL skips the pdf. */
static RRGB R_FN(bsdf__ward_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                      int want_f, REAL *OUT_pdf) {
  if (OUT_pdf) *OUT_pdf = R_C(0.0);
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return RRGB_ZERO();
  double au = b->alpha_u, av = b->alpha_v;
  /* h = wo + wi, not normalised; the exponent
   * e = -((h.x / au)^2 + (h.y / av)^2) / h.z^2 does not depend on its length. */
  REAL3 h = R3_ADD(wo, wi);
  REAL hz2 = R_SQR(h.z);
  REAL e = R_NEG(R_DIV(R_ADD(R_SQR(R_DIV_S(h.x, au)), R_SQR(R_DIV_S(h.y, av))), hz2));
  REAL ex = R_EXP(e);
  REAL hh = R3_LEN2(h);
  if (OUT_pdf) {
    /* Specular density of wi (Walter 2005), with hn = h / |h|:
     *   exp(e) / (4 pi au av (hn . wo) hn.z^3) = exp(e) (h.h)^2 / (4 pi au av (h . wo) h.z^3);
     * mixed with the cosine density: w spec + (1 - w) cos(wi) / pi. */
    double w = bsdf__specular_weight(&b->specular, &b->diffuse);
    REAL spec = R_DIV(R_MUL(ex, R_SQR(hh)),
                      R_MUL_S(R_MUL(R3_DOT(h, wo), R_MUL(hz2, h.z)), 4.0 * M_PI * au * av));
    *OUT_pdf = R_ADD(R_MUL_S(spec, w), R_DIV_S(R_MUL_S(wi.z, 1.0 - w), M_PI));
  }
  if (!want_f) return RRGB_ZERO();
  /* The lobe's normalisation c, by variant:
   *   ward       1 / (4 pi au av sqrt(cos_o cos_i))
   *   ward-duer  1 / (4 pi au av cos_o cos_i)
   *   balanced   (h . h) / (pi au av h.z^4)
   * f = kd / pi + ks c exp(e), the specular part dropped where c exp(e) <= 1e-10 (as Mitsuba). */
  REAL c;
  switch (b->variant) {
  case WARD_ORIGINAL:
    c = R_S_DIV(1.0, R_MUL_S(R_SQRT(R_MUL(wo.z, wi.z)), 4.0 * M_PI * au * av));
    break;
  case WARD_DUER:
    c = R_S_DIV(1.0, R_MUL_S(R_MUL(wo.z, wi.z), 4.0 * M_PI * au * av));
    break;
  default:
    c = R_DIV(hh, R_MUL_S(R_SQR(hz2), M_PI * au * av));
    break;
  }
  REAL spec = R_MUL(c, ex);
  RRGB f = RRGB_SCALE_S(R_FN(tex_eval)(R_ARG &b->diffuse, tu, tv), 1.0 / M_PI);
  if (R_V(spec) > 1e-10)
    f = RRGB_ADD(f, RRGB_SCALE(R_FN(tex_eval)(R_ARG &b->specular, tu, tv), spec));
  return f;
}

RRGB R_FN(bsdf__ward_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                           transport_mode mode) {
  (void)mode;
  return R_FN(bsdf__ward_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, NULL);
}

REAL R_FN(bsdf__ward_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  REAL pdf;
  R_FN(bsdf__ward_eval_pdf)(R_ARG b, tu, tv, wo, wi, 0, &pdf);
  return pdf;
}

int R_FN(bsdf__ward_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL u_lobe, REAL u1,
                            REAL u2, transport_mode mode, R_FN(bsdf_sample) *out) {
  (void)mode;
  if (R_V(wo.z) <= 0.0) return 0;
  double w = bsdf__specular_weight(&b->specular, &b->diffuse);
  REAL3 wi;
  int flags;
  if (R_V(u_lobe) < w) {
    /* Specular lobe (Walter 2005): the half vector's azimuth phi has
     * tan(phi) = (av / au) tan(2 pi u2) in the quadrant of 2 pi u2, i.e.
     * (cos phi, sin phi) ~ (au cos 2 pi u2, av sin 2 pi u2), and
     *   tan^2(theta_h) = -log(u1) / (cos^2 phi / au^2 + sin^2 phi / av^2),
     * so that hn ~ (r au cos 2 pi u2, r av sin 2 pi u2, 1), r = sqrt(-log u1).
     * Reflect wo about hn; directions below the surface are rejected. */
    if (!(R_V(u1) > 0.0)) return 0;
    double au = b->alpha_u, av = b->alpha_v;
    REAL t = R_MUL_S(u2, 2.0 * M_PI);
    REAL r = R_SAFE_SQRT(R_NEG(R_LOG(u1)));
    REAL3 hn = R3_NORMALIZE(R3_MAKE(R_MUL(r, R_MUL_S(R_COS(t), au)),
                                    R_MUL(r, R_MUL_S(R_SIN(t), av)), R_C(1.0)));
    /* wi = 2 (wo . hn) hn - wo */
    wi = R3_SUB(R3_SCALE(hn, R_MUL_S(R3_DOT(wo, hn), 2.0)), wo);
    flags = BSDF_REFLECTION | BSDF_GLOSSY;
  } else {
    wi = R_FN(bsdf__cosine_hemisphere)(R_ARG u1, u2);
    flags = BSDF_REFLECTION | BSDF_DIFFUSE_LOBE;
  }
  if (R_V(wi.z) <= 0.0) return 0;
  REAL pdf;
  RRGB f = R_FN(bsdf__ward_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, &pdf);
  return R_FN(bsdf__finish)(R_ARG out, wi, f, pdf, 1.0, flags);
}

/* ---- The inverses of the samplers (values only; bsdf_invert) ---------------- */

#if !R_DUAL
/* 1 when unit directions agree to rounding (a delta lobe's wi). */
static int bsdf__same_dir(vec3 a, vec3 b) { return v3_len2(v3_sub(a, b)) < 1e-10; }

/* A delta lobe chosen for u_lobe in [lo, hi); the direction numbers are r's. */
static int bsdf__invert_delta(double lo, double hi, const double r[4], double OUT_u[3],
                              double *OUT_pmf) {
  if (!(hi > lo)) return 0;
  OUT_u[0] = warp_uniform_in(lo, hi, r[1]);
  OUT_u[1] = r[2];
  OUT_u[2] = r[3];
  *OUT_pmf = hi - lo;
  return 1;
}

int bsdf__diffuse_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                         const double r[4], double OUT_u[3], double *OUT_pmf) {
  (void)b, (void)tu, (void)tv, (void)OUT_pmf;
  if (delta || !(wo.z > 0.0)) return 0;
  return bsdf__invert_cosine(wi, 0.0, 1.0, r, OUT_u);
}

int bsdf__roughdiffuse_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                              const double r[4], double OUT_u[3], double *OUT_pmf) {
  return bsdf__diffuse_invert(b, tu, tv, wo, wi, delta, r, OUT_u, OUT_pmf);
}

int bsdf__phong_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
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

int bsdf__conductor_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                           const double r[4], double OUT_u[3], double *OUT_pmf) {
  (void)b, (void)tu, (void)tv;
  if (!delta || !(wo.z > 0.0) || !bsdf__same_dir(wi, bsdf__mirror(wo))) return 0;
  return bsdf__invert_delta(0.0, 1.0, r, OUT_u, OUT_pmf);
}

int bsdf__dielectric_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
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

int bsdf__thindielectric_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                                const double r[4], double OUT_u[3], double *OUT_pmf) {
  (void)tu, (void)tv;
  if (!delta || wo.z == 0.0) return 0;
  double refl = bsdf__thin_reflectance(b, wo.z);
  if (wo.z * wi.z > 0.0)
    return bsdf__same_dir(wi, bsdf__mirror(wo)) && bsdf__invert_delta(0.0, refl, r, OUT_u, OUT_pmf);
  return bsdf__same_dir(wi, v3_neg(wo)) && bsdf__invert_delta(refl, 1.0, r, OUT_u, OUT_pmf);
}

int bsdf__plastic_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                         const double r[4], double OUT_u[3], double *OUT_pmf) {
  (void)tu, (void)tv;
  if (!(wo.z > 0.0)) return 0;
  double p = bsdf__plastic_prob_specular(b, fresnel_dielectric(wo.z, b->eta, NULL));
  if (delta)
    return bsdf__same_dir(wi, bsdf__mirror(wo)) && bsdf__invert_delta(0.0, p, r, OUT_u, OUT_pmf);
  return p < 1.0 && bsdf__invert_cosine(wi, p, 1.0, r, OUT_u);
}

int bsdf__ward_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                      const double r[4], double OUT_u[3], double *OUT_pmf) {
  (void)OUT_pmf;
  if (delta || !(wo.z > 0.0) || !(wi.z > 0.0)) return 0;
  double pdf, w = bsdf__specular_weight(&b->specular, &b->diffuse);
  bsdf__ward_eval_pdf(b, tu, tv, wo, wi, 0, &pdf);
  int glossy;
  if (!bsdf__invert_mixture(wi, w, pdf, r, OUT_u, &glossy)) return 0;
  if (!glossy) return 1;
  /* The half vector h ~ (r au cos t, r av sin t, 1), r^2 = -log u1, t = 2 pi u2. */
  vec3 h = v3_add(wo, wi);
  if (!(h.z > 0.0)) return 0;
  double x = h.x / (h.z * b->alpha_u), y = h.y / (h.z * b->alpha_v);
  OUT_u[1] = fmin(exp(-(x * x + y * y)), nextafter(1.0, 0.0));
  OUT_u[2] = warp_turn(atan2(y, x));
  return OUT_u[1] > 0.0;
}
#endif
