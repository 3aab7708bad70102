/*
 * bsdf_generic.h: the BSDF front end written once in render/real.h's
 * vocabulary and compiled twice by bsdf.c: the Fresnel equations, the
 * sample record, what models in two files share (the cosine-weighted
 * hemisphere, the plastics' diffuse base), the twosided flip and the
 * dispatch on the model, in doubles (bsdf.h) and in duals (bsdf_ad.h). Not a
 * header: no include guard.
 * The formulas are in bsdf.c's opening comment.
 *
 * In duals the four entry points also keep the arena small: each marks it
 * on entry and, on exit, moves the duals it returns down to the mark
 * (bsdf__ad_keep in bsdf.c), so a call costs the arena only what it hands
 * back: 3 tangents for an eval, 1 for a pdf, 10 for a sample.
 */

/* ---- Fresnel --------------------------------------------------------------- */

REAL R_FN(fresnel_dielectric)(R_CTX REAL cos_i, double eta, REAL *OUT_cos_t) {
  REAL dummy;
  if (!OUT_cos_t) OUT_cos_t = &dummy;
  if (eta == 1.0) {
    *OUT_cos_t = R_NEG(cos_i);
    return R_C(0.0);
  }
  /* Swap the sides when the incident direction is inside. */
  double e = R_V(cos_i) > 0.0 ? eta : 1.0 / eta;
  REAL ci = R_FABS(cos_i);
  /* cos_t^2 = 1 - (1 - ci^2) / e^2 */
  REAL ct2 = R_S_SUB(1.0, R_DIV_S(R_S_SUB(1.0, R_SQR(ci)), e * e));
  if (R_V(ct2) <= 0.0) {
    *OUT_cos_t = R_C(0.0);
    return R_C(1.0);
  }
  REAL ct = R_SQRT(ct2);
  /* r_s = (ci - e ct) / (ci + e ct),  r_p = (e ci - ct) / (e ci + ct) */
  REAL ect = R_MUL_S(ct, e), eci = R_MUL_S(ci, e);
  REAL rs = R_DIV(R_SUB(ci, ect), R_ADD(ci, ect));
  REAL rp = R_DIV(R_SUB(eci, ct), R_ADD(eci, ct));
  *OUT_cos_t = R_V(cos_i) > 0.0 ? R_NEG(ct) : ct;
  /* F = (r_s^2 + r_p^2) / 2 */
  return R_MUL_S(R_ADD(R_SQR(rs), R_SQR(rp)), 0.5);
}

/* The exact conductor Fresnel reflectance of one channel (bsdf.c). */
static REAL R_FN(bsdf__fresnel_conductor1)(R_CTX REAL c, double eta, double k) {
  REAL c2 = R_SQR(c);
  REAL s2 = R_S_SUB(1.0, c2);
  /* t = eta^2 - k^2 - sin^2,  a^2 + b^2 = sqrt(t^2 + 4 eta^2 k^2) */
  REAL t = R_S_SUB(eta * eta - k * k, s2);
  REAL a2pb2 = R_SQRT(R_ADD_S(R_SQR(t), 4.0 * eta * eta * k * k));
  /* a = sqrt(max(0, (a^2 + b^2 + t) / 2)) */
  REAL a = R_SAFE_SQRT(R_MUL_S(R_ADD(a2pb2, t), 0.5));
  REAL t1 = R_ADD(a2pb2, c2);
  REAL t2 = R_MUL(R_MUL_S(a, 2.0), c);
  if (!(R_V(t1) + R_V(t2) > 0.0)) return R_C(1.0);
  /* R_s = (t1 - t2) / (t1 + t2) */
  REAL rs = R_DIV(R_SUB(t1, t2), R_ADD(t1, t2));
  /* R_p = R_s (t3 - t4) / (t3 + t4),  t3 = (a^2 + b^2) cos^2 + sin^4,  t4 = t2 sin^2 */
  REAL t3 = R_ADD(R_MUL(a2pb2, c2), R_SQR(s2));
  REAL t4 = R_MUL(t2, s2);
  REAL rp = R_V(t3) + R_V(t4) > 0.0 ? R_DIV(R_MUL(rs, R_SUB(t3, t4)), R_ADD(t3, t4)) : rs;
  return R_MUL_S(R_ADD(rs, rp), 0.5);
}

RRGB R_FN(fresnel_conductor)(R_CTX REAL cos_i, rgb eta, rgb k) {
  REAL c = R_FABS(cos_i);
  if (R_V(c) > 1.0 || isnan(R_V(c))) c = R_C(1.0);
  return RRGB_MAKE(R_FN(bsdf__fresnel_conductor1)(R_ARG c, eta.r, k.r),
                   R_FN(bsdf__fresnel_conductor1)(R_ARG c, eta.g, k.g),
                   R_FN(bsdf__fresnel_conductor1)(R_ARG c, eta.b, k.b));
}

/* ---- The sample record ------------------------------------------------------ */

int R_FN(bsdf__finish)(R_CTX R_FN(bsdf_sample) *out, REAL3 wi, RRGB f, REAL pdf, double eta,
                       int flags) {
  out->wi = wi;
  out->f = f;
  out->pdf = pdf;
  out->eta = eta;
  out->flags = flags;
  out->weight = RRGB_ZERO();
  if (!(R_V(pdf) > 0.0) || !isfinite(R_V(pdf)) || !isfinite(R_V(wi.x)) || !isfinite(R_V(wi.y)) ||
      !isfinite(R_V(wi.z)))
    return 0;
  /* weight = f (|cos wi| / pdf) */
  RRGB w = RRGB_SCALE(f, R_DIV(R_FABS(wi.z), pdf));
#if R_DUAL
  rgb wv = adrgb_value(w);
#else
  rgb wv = w;
#endif
  if (!rgb_isfinite(wv) || rgb_is_black(wv)) return 0;
  out->weight = w;
  return 1;
}

/* ---- Mask ------------------------------------------------------------------- */

/* The mask's opacity at (tu, tv) into *OUT_alpha and the probability of
 * choosing the wrapped model's lobes, P = luminance(opacity). */
static REAL R_FN(bsdf__mask_prob)(R_CTX const bsdf *b, REAL tu, REAL tv, RRGB *OUT_alpha) {
  *OUT_alpha = R_FN(tex_eval)(R_ARG &b->opacity, tu, tv);
  return RRGB_LUMINANCE(*OUT_alpha);
}

/* The pass-through lobe: wi = -wo with probability 1 - P, weight
 * (1 - opacity) / (1 - P), f = (1 - opacity) / |cos wi| by the delta
 * convention; no change of index (eta 1), the same from either side. */
static int R_FN(bsdf__mask_pass)(R_CTX REAL3 wo, RRGB alpha, REAL prob,
                                 R_FN(bsdf_sample) *out) {
  REAL3 wi = R3_NEG(wo);
  if (R_V(wi.z) == 0.0) return 0;
  RRGB t = RRGB_MAKE(R_S_SUB(1.0, alpha.r), R_S_SUB(1.0, alpha.g), R_S_SUB(1.0, alpha.b));
  REAL pdf = R_S_SUB(1.0, prob);
  RRGB f = RRGB_SCALE(t, R_DIV(R_C(1.0), R_FABS(wi.z)));
  int ok = R_FN(bsdf__finish)(R_ARG out, wi, f, pdf, 1.0, BSDF_TRANSMISSION | BSDF_DELTA);
#if !R_DUAL
  out->has_pdf_rev = 1;
  out->pdf_rev = pdf;
#endif
  return ok;
}

/* ---- Shading frame ------------------------------------------------------------ */

/* The frame with normal n whose first axis is d made orthogonal to n
 * (frame.h's frame_from_zx), the frame of n alone when that is degenerate. */
static RFRAME R_FN(bsdf__frame_zx)(R_CTX REAL3 n, REAL3 d) {
  REAL3 s = R3_SUB(d, R3_SCALE(n, R3_DOT(n, d)));
  if (!(v3_len2(R3_V(s)) > 1e-24)) return R3_FRAME_FROM_Z(n);
  RFRAME f;
  f.n = n;
  f.s = R3_NORMALIZE(s);
  f.t = R3_CROSS(n, f.s);
  return f;
}

RFRAME R_FN(bsdf_shading_frame)(R_CTX const bsdf *b, REAL tu, REAL tv, vec3 dpdu, vec3 dpdv,
                                REAL3 n, vec3 ng) {
  REAL3 pu = R3_CONST(dpdu.x, dpdu.y, dpdu.z);
  if (!b->bumped) return bsdf_is_anisotropic(b) ? R_FN(bsdf__frame_zx)(R_ARG n, pu)
                                                : R3_FRAME_FROM_Z(n);
  REAL du, dv;
  R_FN(tex_lum_gradient)(R_ARG &b->bump, tu, tv, &du, &dv);
  /* dpdu' = dpdu + n (du - n.dpdu), dpdv' = dpdv + n (dv - n.dpdv) */
  REAL3 a = R3_ADD(pu, R3_SCALE(n, R_SUB(du, R3_DOT_C(dpdu, n))));
  REAL3 c = R3_ADD(R3_CONST(dpdv.x, dpdv.y, dpdv.z), R3_SCALE(n, R_SUB(dv, R3_DOT_C(dpdv, n))));
  REAL3 m = R3_CROSS(a, c);
  double len2 = v3_len2(R3_V(m));
  if (!(len2 > 0.0) || !isfinite(len2)) return R3_FRAME_FROM_Z(n);
  m = R3_NORMALIZE(m);
  if (v3_dot(R3_V(m), ng) < 0.0) m = R3_NEG(m);
  /* Its first axis along dpdu', as Mitsuba's. */
  return R_FN(bsdf__frame_zx)(R_ARG m, a);
}

/* ---- Cosine-weighted hemisphere --------------------------------------------- */

/* Cosine-weighted hemisphere (the diffuse lobes of bsdf_smooth.c and
 * bsdf_rough.c): warp_square_to_cosine_hemisphere (warp.c); in duals the
 * same concentric map (Shirley and Chiu 1997) with its derivatives. */
REAL3 R_FN(bsdf__cosine_hemisphere)(R_CTX REAL u1, REAL u2) {
#if R_DUAL
  /* (a, b) in [-1, 1]^2 to the disk. */
  ad a = ad_sub_s(A, ad_mul_s(A, u1, 2.0), 1.0);
  ad b = ad_sub_s(A, ad_mul_s(A, u2, 2.0), 1.0);
  if (a.v == 0.0 && b.v == 0.0) return adv3_const(A, 0.0, 0.0, 1.0);
  ad r, phi;
  if (fabs(a.v) > fabs(b.v)) {
    /* r = a, phi = pi/4 (b / a) */
    r = a;
    phi = ad_mul_s(A, ad_div(A, b, a), M_PI / 4.0);
  } else {
    /* r = b, phi = pi/2 - pi/4 (a / b) */
    r = b;
    phi = ad_s_sub(A, M_PI / 2.0, ad_mul_s(A, ad_div(A, a, b), M_PI / 4.0));
  }
  ad x = ad_mul(A, r, ad_cos(A, phi));
  ad y = ad_mul(A, r, ad_sin(A, phi));
  /* Lift to the hemisphere: z = sqrt(max(0, 1 - x^2 - y^2)). */
  ad z = ad_safe_sqrt(A, ad_sub(A, ad_s_sub(A, 1.0, ad_sqr(A, x)), ad_sqr(A, y)));
  return adv3_make(x, y, z);
#else
  return warp_square_to_cosine_hemisphere(u1, u2);
#endif
}

/* ---- The plastics' diffuse base ------------------------------------------------ */

/* kd', the base with its internal reflections under a coating whose
 * diffuse reflectance from inside is fdr (bsdf_internal.h). */
RRGB R_FN(bsdf__plastic_kd)(R_CTX const bsdf *b, REAL tu, REAL tv, double fdr) {
  RRGB kd = R_FN(tex_eval)(R_ARG &b->diffuse, tu, tv);
  /* kd' = kd / (1 - kd F_dr) (nonlinear; 0 where the denominator is 0, as
   * rgb_div) or kd / (1 - F_dr). */
  RRGB kdp;
  if (b->nonlinear) {
    REAL *c[3] = {&kd.r, &kd.g, &kd.b};
    REAL *o[3] = {&kdp.r, &kdp.g, &kdp.b};
    for (int i = 0; i < 3; i++) {
      REAL den = R_S_SUB(1.0, R_MUL_S(*c[i], fdr));
      *o[i] = R_V(den) != 0.0 ? R_DIV(*c[i], den) : R_C(0.0);
    }
  } else {
    kdp = RRGB_SCALE_S(kd, 1.0 / (1.0 - fdr));
  }
  return kdp;
}

/* ---- Dispatch --------------------------------------------------------------- */

/* 1 when the model is reflection-only and the twosided flip applies to wo. */
static int R_FN(bsdf__flip)(const bsdf *b, REAL3 wo) {
  return b->twosided && R_V(wo.z) < 0.0 && !(bsdf__lobes(b) & BSDF_TRANSMISSION);
}

/* The twosided flip of a (wo, wi) pair: both mirrored to the upper side. */
static void R_FN(bsdf__flip_pair)(R_CTX const bsdf *b, REAL3 *wo, REAL3 *wi) {
  if (!R_FN(bsdf__flip)(b, *wo)) return;
  wo->z = R_NEG(wo->z);
  wi->z = R_NEG(wi->z);
}

RRGB R_FN(bsdf_eval)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                     transport_mode mode) {
#if R_DUAL
  size_t mark = ad_arena_mark(A);
#endif
  R_FN(bsdf__flip_pair)(R_ARG b, &wo, &wi);
  RRGB f = b->model->R_FN(eval)(R_ARG b, tu, tv, wo, wi, mode);
  if (b->masked) f = RRGB_MUL(f, R_FN(tex_eval)(R_ARG &b->opacity, tu, tv));
#if R_DUAL
  ad *keep[3] = {&f.r, &f.g, &f.b};
  bsdf__ad_keep(A, mark, keep, 3);
#endif
  return f;
}

REAL R_FN(bsdf_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi) {
#if R_DUAL
  size_t mark = ad_arena_mark(A);
#endif
  R_FN(bsdf__flip_pair)(R_ARG b, &wo, &wi);
  REAL p = b->model->R_FN(pdf)(R_ARG b, tu, tv, wo, wi);
  if (b->masked) {
    RRGB alpha;
    p = R_MUL(p, R_FN(bsdf__mask_prob)(R_ARG b, tu, tv, &alpha));
  }
#if R_DUAL
  ad *keep[1] = {&p};
  bsdf__ad_keep(A, mark, keep, 1);
#endif
  return p;
}

RRGB R_FN(bsdf_eval_pdf)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL3 wi,
                         transport_mode mode, REAL *OUT_pdf) {
  if (!b->model->R_FN(eval_pdf)) {
    /* Nothing to share: the two dispatchers (each applies the flip and
     * the mask itself). */
    *OUT_pdf = R_FN(bsdf_pdf)(R_ARG b, tu, tv, wo, wi);
    return R_FN(bsdf_eval)(R_ARG b, tu, tv, wo, wi, mode);
  }
  REAL3 fo = wo, fi = wi;
  R_FN(bsdf__flip_pair)(R_ARG b, &fo, &fi);
  RRGB f = b->model->R_FN(eval_pdf)(R_ARG b, tu, tv, fo, fi, mode, OUT_pdf);
  if (b->masked) {
    RRGB alpha;
    *OUT_pdf = R_MUL(*OUT_pdf, R_FN(bsdf__mask_prob)(R_ARG b, tu, tv, &alpha));
    f = RRGB_MUL(f, alpha);
  }
  return f;
}

int R_FN(bsdf_sample_f)(R_CTX const bsdf *b, REAL tu, REAL tv, REAL3 wo, REAL u_lobe, REAL u1,
                        REAL u2, transport_mode mode, R_FN(bsdf_sample) *out) {
#if R_DUAL
  size_t mark = ad_arena_mark(A);
#endif
#if R_DUAL
  out->wi = R3_CONST(0.0, 0.0, 0.0);
  out->f = RRGB_ZERO();
  out->pdf = R_C(0.0);
  out->weight = RRGB_ZERO();
  out->eta = 0.0;
  out->flags = 0;
#else
  memset(out, 0, sizeof *out);
#endif
  /* A mask passes with probability 1 - P, else its lobes take u_lobe
   * rescaled to [0, 1). */
  RRGB alpha = RRGB_ZERO();
  REAL prob = R_C(1.0);
  int ok = 0;
  if (b->masked) {
    prob = R_FN(bsdf__mask_prob)(R_ARG b, tu, tv, &alpha);
    if (!(R_V(u_lobe) < R_V(prob))) {
      ok = R_FN(bsdf__mask_pass)(R_ARG wo, alpha, prob, out);
      goto done;
    }
    u_lobe = R_DIV(u_lobe, prob);
  }
  int flip = R_FN(bsdf__flip)(b, wo);
  if (flip) wo.z = R_NEG(wo.z);
  ok = b->model->R_FN(sample)(R_ARG b, tu, tv, wo, u_lobe, u1, u2, mode, out);
  if (flip) out->wi.z = R_NEG(out->wi.z);
  if (b->masked && ok) {
    /* The wrapped lobe's f times the opacity, its density times P. */
    out->f = RRGB_MUL(out->f, alpha);
    out->pdf = R_MUL(out->pdf, prob);
    out->weight = RRGB_MUL(out->weight, RRGB_SCALE(alpha, R_DIV(R_C(1.0), prob)));
#if !R_DUAL
    if (out->has_pdf_rev) out->pdf_rev *= prob;
#endif
    ok = !RRGB_IS_BLACK(out->weight) && RRGB_IS_FINITE(out->weight);
  }
done:;
#if R_DUAL
  ad *keep[10] = {&out->wi.x, &out->wi.y, &out->wi.z, &out->f.r,      &out->f.g,
                  &out->f.b,  &out->pdf,  &out->weight.r, &out->weight.g, &out->weight.b};
  bsdf__ad_keep(A, mark, keep, 10);
#endif
  return ok;
}

/* ---- The inverse of bsdf_sample_f (values only) ------------------------------ */

#if !R_DUAL
int bsdf__same_dir(vec3 a, vec3 b) { return v3_len2(v3_sub(a, b)) < 1e-10; }

int bsdf__invert_delta(double lo, double hi, const double r[4], double OUT_u[3], double *OUT_pmf) {
  if (!(hi > lo)) return 0;
  OUT_u[0] = warp_uniform_in(lo, hi, r[1]);
  OUT_u[1] = r[2];
  OUT_u[2] = r[3];
  *OUT_pmf = hi - lo;
  return 1;
}

int bsdf__invert_cosine(vec3 wi, double lo, double hi, const double r[4], double OUT_u[3]) {
  if (!(wi.z > 0.0)) return 0;
  OUT_u[0] = warp_uniform_in(lo, hi, r[1]);
  warp_cosine_hemisphere_to_square(wi, &OUT_u[1], &OUT_u[2]);
  return 1;
}

int bsdf__invert_mixture(vec3 wi, double w, double pdf, const double r[4], double OUT_u[3],
                         int *OUT_glossy) {
  *OUT_glossy = 0;
  if (!(pdf > 0.0) || !(wi.z > 0.0)) return 0;
  double diff = (1.0 - w) * wi.z / M_PI / pdf;
  if (r[0] < diff) return bsdf__invert_cosine(wi, w, 1.0, r, OUT_u);
  *OUT_glossy = 1;
  OUT_u[0] = warp_uniform_in(0.0, w, r[1]);
  return 1;
}

/* The model's own inverse (bsdf_invert without the mask). */
static int bsdf__invert_model(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                              const double r[4], double OUT_u[3], double *OUT_pmf) {
  if (bsdf__flip(b, wo)) {
    wo.z = -wo.z;
    wi.z = -wi.z;
  }
  *OUT_pmf = 1.0;
  return b->model->invert(b, tu, tv, wo, wi, delta, r, OUT_u, OUT_pmf);
}

/* bsdf_invert without the check that the sampler gives wi back. */
static int bsdf__invert_unchecked(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi,
                                  int delta, const double r[4], double OUT_u[3]) {
  if (!b->masked) return bsdf__invert_model(b, tu, tv, wo, wi, delta, r, OUT_u, &(double){0.0});
  /* A mask: the pass-through lobe makes wi = -wo (delta, probability
   * 1 - P); the wrapped lobes have u_lobe scaled into [0, P). */
  rgb alpha;
  double prob = bsdf__mask_prob(b, tu, tv, &alpha);
  double pass_w = delta && wo.z != 0.0 && v3_len2(v3_add(wo, wi)) < 1e-18 ? 1.0 - prob : 0.0;
  double u[3], pmf = 0.0;
  int ok = prob > 0.0 && bsdf__invert_model(b, tu, tv, wo, wi, delta, r, u, &pmf);
  double wrapped_w = ok ? (delta ? prob * pmf : 1.0) : 0.0;
  if (pass_w > 0.0) {
    /* Between the pass-through and a wrapped delta lobe that also gives
     * -wo, each with its probability; r[0] rescaled for the model's own
     * choice when the wrapped lobe wins. */
    double t = r[0] * (pass_w + wrapped_w);
    if (!(t < wrapped_w)) {
      OUT_u[0] = warp_uniform_in(prob, 1.0, r[1]);
      OUT_u[1] = r[2];
      OUT_u[2] = r[3];
      return 1;
    }
    double rr[4] = {fmin(t / wrapped_w, nextafter(1.0, 0.0)), r[1], r[2], r[3]};
    ok = bsdf__invert_model(b, tu, tv, wo, wi, delta, rr, u, &pmf);
  }
  if (!ok) return 0;
  OUT_u[0] = fmin(u[0] * prob, nextafter(prob, 0.0));
  OUT_u[1] = u[1];
  OUT_u[2] = u[2];
  return 1;
}

int bsdf_invert(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta,
                const double r[4], double OUT_u[3]) {
  if (!bsdf__invert_unchecked(b, tu, tv, wo, wi, delta, r, OUT_u)) return 0;
  /* Where a sampler clamps (Beckmann's slopes beyond 9, numbers at the
   * square's edge) the inverse of a direction deep in a tail is not
   * sampled back to it: refused, as the sampler never makes it. */
  bsdf_sample s;
  return bsdf_sample_f(b, tu, tv, wo, OUT_u[0], OUT_u[1], OUT_u[2], TRANSPORT_RADIANCE, &s) &&
         ((s.flags & BSDF_DELTA) != 0) == (delta != 0) && v3_len2(v3_sub(s.wi, wi)) < 1e-14;
}
#endif
