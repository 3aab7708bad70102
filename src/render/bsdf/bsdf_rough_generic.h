/*
 * bsdf_rough_generic.h: the microfacet models (roughconductor,
 * roughdielectric, roughplastic), written once in render/real.h's vocabulary and compiled
 * twice by bsdf_rough.c, in doubles and in duals. Not a header: no include
 * guard. The models are described in bsdf_rough.c's opening comment.
 *
 * The reverse density (pdf_rev, the density of sampling wo from wi, which
 * bidirectional MIS needs) is computed in the same pass by the plain
 * sampling functions only: the dual sample record has none.
 */

#undef BSDF_R_REV
#undef BSDF_R_SET_REV
#if R_DUAL
#define BSDF_R_REV(p) NULL
#define BSDF_R_SET_REV(out, rev) (void)(rev)
#else
#define BSDF_R_REV(p) (p)
#define BSDF_R_SET_REV(out, rev) ((out)->pdf_rev = (rev), (out)->has_pdf_rev = 1)
#endif

/* ---- roughconductor ------------------------------------------------------ */

/* f and pdf of one (wo, wi) pair in one pass: eval, pdf, sample and
 * next-event estimation all come here, so the three can never disagree, and
 * a caller that needs both shares the half vector, D and G1(wo) (the
 * visible-normal pdf uses the same G1). want_f = 0 skips f (Fresnel and
 * texture); OUT_pdf = NULL skips the pdf, OUT_pdf_rev = NULL the reverse
 * density. Each value is computed with the same operations, in the same
 * order, whatever the caller asks for. */
static RRGB R_FN(bsdf__rc_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                    int want_f, REAL *OUT_pdf, REAL *OUT_pdf_rev) {
  if (OUT_pdf) *OUT_pdf = R_C(0.0);
  if (OUT_pdf_rev) *OUT_pdf_rev = R_C(0.0);
  if (R_V(wo.z) <= 0.0 || R_V(wi.z) <= 0.0) return RRGB_ZERO();
  REAL alpha = R_C(b->alpha);
  REAL3 h = R3_NORMALIZE(R3_ADD(wo, wi));
  REAL d = R_FN(mf_D)(R_ARG b->dist, alpha, h);
  int need_f = want_f && R_V(d) != 0.0;
  /* G1(wo, h): shared by G and the visible-normal density; G1(wi, h) by G
   * and the reverse one. */
  REAL g1o = R_C(0.0), g1i = R_C(0.0);
  if (need_f || (OUT_pdf && b->sample_visible)) g1o = R_FN(mf_G1)(R_ARG b->dist, alpha, wo, h);
  if (need_f || (OUT_pdf_rev && b->sample_visible)) g1i = R_FN(mf_G1)(R_ARG b->dist, alpha, wi, h);

  /* pdf = p_m(h) / (4 wi.h); the reverse density p_m'(h) / (4 wo.h), the
   * normal drawn from wi's side. */
  if (OUT_pdf) {
    REAL wih = R3_DOT(wi, h);
    if (R_V(wih) > 0.0)
      *OUT_pdf = R_DIV(R_FN(mf_pdf_known)(R_ARG d, g1o, wo, h, b->sample_visible),
                       R_MUL_S(wih, 4.0));
  }
  if (OUT_pdf_rev) {
    REAL woh = R3_DOT(wo, h);
    if (R_V(woh) > 0.0)
      *OUT_pdf_rev = R_DIV(R_FN(mf_pdf_known)(R_ARG d, g1i, wi, h, b->sample_visible),
                           R_MUL_S(woh, 4.0));
  }

  /* f = F D G / (4 cos_o cos_i) ks, G = G1(wi, h) G1(wo, h). */
  if (!need_f) return RRGB_ZERO();
  REAL g = R_MUL(g1i, g1o);
  if (R_V(g) == 0.0) return RRGB_ZERO();
  RRGB fr = R_FN(fresnel_conductor)(R_ARG R3_DOT(wo, h), b->cond_eta, b->cond_k);
  RRGB ks = R_FN(tex_eval)(R_ARG &b->specular, tu, tv);
  REAL s = R_DIV(R_MUL(d, g), R_MUL(R_MUL_S(wo.z, 4.0), wi.z));
  return RRGB_SCALE(RRGB_MUL(fr, ks), s);
}

RRGB R_FN(bsdf__roughconductor_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                     transport_mode mode) {
  (void)mode;
  return R_FN(bsdf__rc_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, NULL, NULL);
}

REAL R_FN(bsdf__roughconductor_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  REAL pdf;
  R_FN(bsdf__rc_eval_pdf)(R_ARG b, tu, tv, wo, wi, 0, &pdf, NULL);
  return pdf;
}

RRGB R_FN(bsdf__roughconductor_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                         REAL3 wi, transport_mode mode, REAL *OUT_pdf) {
  (void)mode;
  return R_FN(bsdf__rc_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, OUT_pdf, NULL);
}

int R_FN(bsdf__roughconductor_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                      REAL u_lobe, REAL u1, REAL u2, transport_mode mode,
                                      R_FN(bsdf_sample) *out) {
  (void)u_lobe, (void)mode;
  if (R_V(wo.z) <= 0.0) return 0;
  REAL3 m = R_FN(mf_sample)(R_ARG b->dist, R_C(b->alpha), wo, b->sample_visible, u1, u2);
  REAL wom = R3_DOT(wo, m);
  if (R_V(wom) <= 0.0) return 0;
  REAL3 wi = R3_NORMALIZE(R3_REFLECT(wo, m));
  if (R_V(wi.z) <= 0.0) return 0;
  REAL pdf, pdf_rev = R_C(0.0);
  RRGB f = R_FN(bsdf__rc_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, &pdf, BSDF_R_REV(&pdf_rev));
  int ok = R_FN(bsdf__finish)(R_ARG out, wi, f, pdf, 1.0, BSDF_REFLECTION | BSDF_GLOSSY);
  BSDF_R_SET_REV(out, pdf_rev);
  return ok;
}

/* ---- roughdielectric ----------------------------------------------------- */

/* The roughness the sampler uses (Walter's widening without visible normals):
 * alpha (1.2 - 0.2 sqrt|cos_o|). */
static REAL R_FN(bsdf__rd_sample_alpha)(R_CTX const bsdf *b, REAL cos_o) {
  if (b->sample_visible) return R_C(b->alpha);
  REAL w = R_S_SUB(1.2, R_MUL_S(R_SQRT(R_FABS(cos_o)), 0.2));
  return R_MUL_S(w, b->alpha);
}

/* The half vector of (wo, wi) in the upper hemisphere and e (1 for
 * reflection); returns 0 when it is degenerate. */
static int R_FN(bsdf__rd_half)(R_CTX const bsdf *b, REAL3 wo, REAL3 wi, REAL3 *OUT_h,
                               double *OUT_e, int *OUT_reflect) {
  *OUT_reflect = R_V(wo.z) * R_V(wi.z) > 0.0;
  double e = *OUT_reflect ? 1.0 : (R_V(wo.z) > 0.0 ? b->eta : 1.0 / b->eta);
  *OUT_e = e;
  /* h = normalize(wo + e wi), flipped to the upper side. */
  REAL3 hh = R3_ADD(wo, R3_SCALE_S(wi, e));
  double x = R_V(hh.x), y = R_V(hh.y), z = R_V(hh.z);
  double l = sqrt(x * x + y * y + z * z);
  if (!(l > 0.0)) return 0;
  hh = R3_NORMALIZE(hh);
  if (R_V(hh.z) < 0.0) hh = R3_NEG(hh);
  if (R_V(hh.z) == 0.0) return 0;
  *OUT_h = hh;
  return 1;
}

/* f and pdf of one (wo, wi) pair in one pass, as bsdf__rc_eval_pdf: the
 * half vector, wo.h, wi.h and F are shared, and with visible-normal
 * sampling (same roughness for sampling and evaluation) D(h) and G1(wo, h)
 * too, and G1(wi, h) with the reverse density: G1(v, h) with v = +-wo is
 * G1(wo, h) exactly, as G1 only sees the product (v.h) v.z and v.z^2. */
static RRGB R_FN(bsdf__rd_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                    int want_f, transport_mode mode, REAL *OUT_pdf,
                                    REAL *OUT_pdf_rev) {
  if (OUT_pdf) *OUT_pdf = R_C(0.0);
  if (OUT_pdf_rev) *OUT_pdf_rev = R_C(0.0);
  if (R_V(wo.z) == 0.0 || R_V(wi.z) == 0.0) return RRGB_ZERO();
  REAL3 h;
  double e;
  int reflect;
  if (!R_FN(bsdf__rd_half)(R_ARG b, wo, wi, &h, &e, &reflect)) return RRGB_ZERO();
  REAL alpha = R_C(b->alpha);
  REAL woh = R3_DOT(wo, h), wih = R3_DOT(wi, h);
  REAL fr = R_FN(fresnel_dielectric)(R_ARG woh, b->eta, NULL);
  int vis_pdf = b->sample_visible && (OUT_pdf || OUT_pdf_rev);
  REAL d = R_C(0.0);
  if (want_f || vis_pdf) d = R_FN(mf_D)(R_ARG b->dist, alpha, h);
  int need_f = want_f && R_V(d) != 0.0;
  /* G1(wo, h) serves G and the visible-normal density, G1(wi, h) G and the
   * reverse one. */
  REAL g1o = R_C(0.0), g1i = R_C(0.0);
  if (need_f || (OUT_pdf && b->sample_visible)) g1o = R_FN(mf_G1)(R_ARG b->dist, alpha, wo, h);
  if (need_f || (OUT_pdf_rev && b->sample_visible)) g1i = R_FN(mf_G1)(R_ARG b->dist, alpha, wi, h);
  /* A valid configuration has wo and wi on the sides of h their z says; the
   * normal was drawn from the side of wo. */
  int valid = !(R_V(woh) * R_V(wo.z) <= 0.0 || R_V(wih) * R_V(wi.z) <= 0.0);

  /* reflection  F p_m(h) / (4 |wi.h|),
   * refraction  (1 - F) p_m(h) e^2 |wi.h| / (wo.h + e wi.h)^2. */
  if (OUT_pdf && valid) {
    REAL3 v = R_V(wo.z) > 0.0 ? wo : R3_NEG(wo);
    REAL pm = b->sample_visible
                  ? R_FN(mf_pdf_known)(R_ARG d, g1o, v, h, 1)
                  : R_FN(mf_pdf)(R_ARG b->dist, R_FN(bsdf__rd_sample_alpha)(R_ARG b, wo.z), v, h, 0);
    if (R_V(pm) != 0.0) {
      if (reflect) {
        *OUT_pdf = R_DIV(R_MUL(fr, pm), R_MUL_S(R_FABS(wih), 4.0));
      } else {
        REAL den = R_ADD(woh, R_MUL_S(wih, e));
        if (R_V(den) != 0.0) {
          REAL num = R_MUL(R_MUL_S(R_MUL_S(R_MUL(R_S_SUB(1.0, fr), pm), e), e), R_FABS(wih));
          *OUT_pdf = R_DIV(num, R_SQR(den));
        }
      }
    }
  }

  /* The reverse density (wi sampled at wo's place), as pdf(wi, wo) defines
   * it: the same h, the roles of wo.h and wi.h swapped, e replaced by 1 / e
   * (so the refraction Jacobian becomes |wo.h| / (wo.h + e wi.h)^2), the
   * normal drawn from wi's side; F is that of the same h. */
  if (OUT_pdf_rev && valid) {
    REAL3 v = R_V(wi.z) > 0.0 ? wi : R3_NEG(wi);
    REAL pm = b->sample_visible
                  ? R_FN(mf_pdf_known)(R_ARG d, g1i, v, h, 1)
                  : R_FN(mf_pdf)(R_ARG b->dist, R_FN(bsdf__rd_sample_alpha)(R_ARG b, wi.z), v, h, 0);
    REAL fr_rev = R_FN(fresnel_dielectric)(R_ARG wih, b->eta, NULL);
    if (R_V(pm) != 0.0) {
      if (reflect) {
        *OUT_pdf_rev = R_DIV(R_MUL(fr_rev, pm), R_MUL_S(R_FABS(woh), 4.0));
      } else {
        REAL den = R_ADD(woh, R_MUL_S(wih, e));
        if (R_V(den) != 0.0)
          *OUT_pdf_rev = R_DIV(R_MUL(R_MUL(R_S_SUB(1.0, fr_rev), pm), R_FABS(woh)), R_SQR(den));
      }
    }
  }

  /* The value. */
  if (!need_f) return RRGB_ZERO();
  REAL g = R_MUL(g1i, g1o);
  if (R_V(g) == 0.0) return RRGB_ZERO();
  if (reflect) {
    /* f_r = ks F D G / (4 |cos_o| |cos_i|) */
    RRGB ks = R_FN(tex_eval)(R_ARG &b->specular, tu, tv);
    REAL den = R_MUL(R_MUL_S(R_FABS(wo.z), 4.0), R_FABS(wi.z));
    return RRGB_SCALE(ks, R_DIV(R_MUL(R_MUL(fr, d), g), den));
  }
  /* Refraction: (1 - F) D G e^2 |wo.h wi.h| / (|cos_o cos_i| (wo.h + e wi.h)^2). */
  REAL den = R_ADD(woh, R_MUL_S(wih, e));
  if (R_V(den) == 0.0) return RRGB_ZERO();
  REAL num = R_MUL(R_MUL_S(R_MUL_S(R_MUL(R_MUL(R_S_SUB(1.0, fr), d), g), e), e),
                   R_FABS(R_MUL(woh, wih)));
  REAL v = R_DIV(num, R_MUL(R_MUL(R_FABS(R_MUL(wo.z, wi.z)), den), den));
  /* Radiance is compressed by 1/e^2 when crossing into the denser side. */
  if (mode == TRANSPORT_RADIANCE) v = R_DIV_S(v, e * e);
  return RRGB_SCALE(R_FN(tex_eval)(R_ARG &b->transmittance, tu, tv), v);
}

RRGB R_FN(bsdf__roughdielectric_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                      transport_mode mode) {
  return R_FN(bsdf__rd_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, mode, NULL, NULL);
}

REAL R_FN(bsdf__roughdielectric_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  REAL pdf;
  R_FN(bsdf__rd_eval_pdf)(R_ARG b, tu, tv, wo, wi, 0, TRANSPORT_RADIANCE, &pdf, NULL);
  return pdf;
}

RRGB R_FN(bsdf__roughdielectric_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                          REAL3 wi, transport_mode mode, REAL *OUT_pdf) {
  return R_FN(bsdf__rd_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, mode, OUT_pdf, NULL);
}

int R_FN(bsdf__roughdielectric_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
                                       REAL u_lobe, REAL u1, REAL u2, transport_mode mode,
                                       R_FN(bsdf_sample) *out) {
  if (R_V(wo.z) == 0.0) return 0;
  /* Draw a normal from the side of wo. */
  REAL3 v = R_V(wo.z) > 0.0 ? wo : R3_NEG(wo);
  REAL3 m = R_FN(mf_sample)(R_ARG b->dist, R_FN(bsdf__rd_sample_alpha)(R_ARG b, wo.z), v,
                            b->sample_visible, u1, u2);
  REAL wom = R3_DOT(wo, m);
  if (R_V(wom) * R_V(wo.z) <= 0.0) return 0;
  REAL cos_t;
  REAL fr = R_FN(fresnel_dielectric)(R_ARG wom, b->eta, &cos_t);
  REAL3 wi;
  int flags;
  double eta_out;
  if (R_V(u_lobe) < R_V(fr)) {
    /* Reflection about m. */
    wi = R3_NORMALIZE(R3_REFLECT(wo, m));
    if (R_V(wi.z) * R_V(wo.z) <= 0.0) return 0;
    flags = BSDF_REFLECTION | BSDF_GLOSSY;
    eta_out = 1.0;
  } else {
    /* Refraction through m: wi = m (wo.m s + cos_t) - wo s, s = eta_o / eta_i. */
    if (R_V(cos_t) == 0.0) return 0;
    double s = R_V(wom) > 0.0 ? 1.0 / b->eta : b->eta;
    REAL k = R_ADD(R_MUL_S(wom, s), cos_t);
    wi = R3_NORMALIZE(R3_SUB(R3_SCALE(m, k), R3_SCALE_S(wo, s)));
    if (R_V(wi.z) * R_V(wo.z) >= 0.0) return 0;
    flags = BSDF_TRANSMISSION | BSDF_GLOSSY;
    eta_out = R_V(cos_t) < 0.0 ? b->eta : 1.0 / b->eta;
  }
  REAL pdf, pdf_rev = R_C(0.0);
  RRGB f = R_FN(bsdf__rd_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, mode, &pdf, BSDF_R_REV(&pdf_rev));
  int ok = R_FN(bsdf__finish)(R_ARG out, wi, f, pdf, eta_out, flags);
  BSDF_R_SET_REV(out, pdf_rev);
  return ok;
}

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

RRGB R_FN(bsdf__roughplastic_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                   transport_mode mode) {
  (void)mode;
  return R_FN(bsdf__rp_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, NULL, NULL);
}

REAL R_FN(bsdf__roughplastic_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
  REAL pdf;
  R_FN(bsdf__rp_eval_pdf)(R_ARG b, tu, tv, wo, wi, 0, &pdf, NULL);
  return pdf;
}

RRGB R_FN(bsdf__roughplastic_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                                       transport_mode mode, REAL *OUT_pdf) {
  (void)mode;
  return R_FN(bsdf__rp_eval_pdf)(R_ARG b, tu, tv, wo, wi, 1, OUT_pdf, NULL);
}

int R_FN(bsdf__roughplastic_sample)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo,
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

/* ---- The inverses of the samplers (values only; bsdf_invert) ---------------- */

#if !R_DUAL
int bsdf__roughconductor_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                                const double r[4], double OUT_u[3], double *OUT_pmf) {
  (void)tu, (void)tv, (void)OUT_pmf;
  if (delta || !(wo.z > 0.0) || !(wi.z > 0.0)) return 0;
  vec3 m = v3_normalize(v3_add(wo, wi));
  OUT_u[0] = r[1];
  return mf_invert(b->dist, b->alpha, wo, b->sample_visible, m, &OUT_u[1], &OUT_u[2]);
}

int bsdf__roughdielectric_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                                 const double r[4], double OUT_u[3], double *OUT_pmf) {
  (void)tu, (void)tv, (void)OUT_pmf;
  if (delta || wo.z == 0.0) return 0;
  /* The normal the sampler drew is the (generalised) half vector. */
  vec3 m;
  double e;
  int reflect;
  if (!bsdf__rd_half(b, wo, wi, &m, &e, &reflect)) return 0;
  double wom = v3_dot(wo, m);
  if (!(wom * wo.z > 0.0)) return 0;
  double fr = fresnel_dielectric(wom, b->eta, NULL);
  vec3 v = wo.z > 0.0 ? wo : v3_neg(wo);
  if (!mf_invert(b->dist, bsdf__rd_sample_alpha(b, wo.z), v, b->sample_visible, m, &OUT_u[1],
                 &OUT_u[2]))
    return 0;
  if (reflect ? !(fr > 0.0) : !(fr < 1.0)) return 0;
  OUT_u[0] = reflect ? warp_uniform_in(0.0, fr, r[1]) : warp_uniform_in(fr, 1.0, r[1]);
  return 1;
}

int bsdf__roughplastic_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                              const double r[4], double OUT_u[3], double *OUT_pmf) {
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
#endif
