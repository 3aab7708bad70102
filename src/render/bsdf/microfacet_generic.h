/*
 * microfacet_generic.h: the Beckmann and GGX distributions, written once in
 * render/real.h's vocabulary and compiled twice by microfacet.c: in doubles
 * (mf_D, ... of microfacet.h) and in duals (mf_D_ad, ... of
 * microfacet_ad.h). Not a header: no include guard; see microfacet.h for
 * the papers and conventions and microfacet.c for the value-only helpers
 * (mf_erfinv, mf__beckmann_slope_x) used here.
 */

/* tan^2(theta) of a direction (|v.z| used); +inf at grazing. */
static REAL R_FN(mf__tan2)(R_CTX REAL3 v) {
  REAL c2 = R_SQR(v.z);
  if (!(R_V(c2) > 0.0)) return R_C(INFINITY);
  REAL s2 = R_S_SUB(1.0, c2);
  if (R_V(s2) < 0.0) s2 = R_C(0.0);
  return R_DIV(s2, c2);
}

REAL R_FN(mf_D)(R_CTX mf_dist dist, REAL alpha, REAL3 m) {
  if (R_V(m.z) <= 0.0) return R_C(0.0);
  REAL a2 = R_SQR(alpha), c2 = R_SQR(m.z);
  if (dist == MF_BECKMANN) {
    /* D = exp(-tan^2 / alpha^2) / (pi alpha^2 cos^4) */
    REAL t2 = R_FN(mf__tan2)(R_ARG m);
    REAL den = R_MUL(R_MUL(R_MUL_S(a2, M_PI), c2), c2);
    REAL d = R_DIV(R_EXP(R_NEG(R_DIV(t2, a2))), den);
    return isfinite(R_V(d)) ? d : R_C(0.0);
  }
  /* GGX: D = alpha^2 / (pi ((alpha^2 - 1) cos^2 + 1)^2) */
  REAL k = R_ADD_S(R_MUL(R_SUB_S(a2, 1.0), c2), 1.0);
  return R_DIV(a2, R_MUL(R_MUL_S(k, M_PI), k));
}

REAL R_FN(mf_lambda)(R_CTX mf_dist dist, REAL alpha, REAL3 v) {
  REAL t2 = R_FN(mf__tan2)(R_ARG v);
  if (R_V(t2) == 0.0) return R_C(0.0);
  if (!isfinite(R_V(t2))) return R_C(INFINITY);
  if (dist == MF_BECKMANN) {
    /* a = 1 / (alpha tan); Lambda = (erf(a) - 1)/2 + exp(-a^2) / (2 a sqrt(pi)) */
    REAL a = R_INV(R_MUL(alpha, R_SQRT(t2)));
    if (R_V(a) > 26.0) return R_C(0.0); /* both terms below double precision */
    REAL e2 = R_DIV(R_MUL_S(R_EXP(R_NEG(R_SQR(a))), MF_INV_SQRT_PI), a);
    return R_MUL_S(R_SUB(e2, R_ERFC(a)), 0.5);
  }
  /* GGX: Lambda = (-1 + sqrt(1 + alpha^2 tan^2)) / 2 */
  REAL r = R_SQRT(R_ADD_S(R_MUL(R_SQR(alpha), t2), 1.0));
  return R_MUL_S(R_SUB_S(r, 1.0), 0.5);
}

REAL R_FN(mf_G1)(R_CTX mf_dist dist, REAL alpha, REAL3 v, REAL3 m) {
  if (R_V(R3_DOT(v, m)) * R_V(v.z) <= 0.0) return R_C(0.0);
  REAL l = R_FN(mf_lambda)(R_ARG dist, alpha, v);
  /* G1 = 1 / (1 + Lambda) */
  return isfinite(R_V(l)) ? R_S_DIV(1.0, R_ADD_S(l, 1.0)) : R_C(0.0);
}

REAL R_FN(mf_G)(R_CTX mf_dist dist, REAL alpha, REAL3 wi, REAL3 wo, REAL3 m) {
  return R_MUL(R_FN(mf_G1)(R_ARG dist, alpha, wi, m), R_FN(mf_G1)(R_ARG dist, alpha, wo, m));
}

/* erfinv(x): mf_erfinv's value; in duals with ad_erfinv's tangent. */
static REAL R_FN(mf__erfinv)(R_CTX REAL x) {
#if R_DUAL
  return ad_with_value(A, ad_erfinv(A, x), mf_erfinv(x.v));
#else
  return mf_erfinv(x);
#endif
}

/* Slopes of the alpha = 1 Beckmann visible-slope distribution seen at
 * incidence (cos_t, sin_t), phi = 0 (microfacet.c): x by the safeguarded
 * Newton inversion of mf__beckmann_slope_x, y = erfinv(2 u2 - 1).
 *
 * The x-slope's derivative. x solves C(x; c, s) = u1 C(a; c, s) with
 *   C(x) = [c erfc(-x) + s exp(-x^2)/sqrt(pi)] / 2,  a = c / s.
 * By the implicit function theorem
 *   dx = (d[u1 C(a)] - C_c dc - C_s ds) / C_x,
 *   C_c = erfc(-x)/2,  C_s = exp(-x^2)/(2 sqrt(pi)),
 *   C_x = (c - x s) exp(-x^2)/sqrt(pi)  (the slope density, > 0 for x < a),
 * with d[u1 C(a)] carried by dual arithmetic through C(a) (its a-derivative
 * vanishes at a = c / s, so no special care is needed). */
static void R_FN(mf__beckmann_visible_slopes)(R_CTX REAL cos_t, REAL sin_t, REAL u1, REAL u2,
                                               REAL *OUT_x, REAL *OUT_y) {
  *OUT_y = R_FN(mf__erfinv)(R_ARG R_SUB_S(R_MUL_S(u2, 2.0), 1.0));
  if (R_V(sin_t) < 1e-9) {
    *OUT_x = R_FN(mf__erfinv)(R_ARG R_SUB_S(R_MUL_S(u1, 2.0), 1.0));
    return;
  }
  double x = mf__beckmann_slope_x(R_V(cos_t), R_V(sin_t), R_V(u1));
#if R_DUAL
  /* The right-hand side u1 C(a) with a = cos_t / sin_t, in duals. */
  ad a = ad_div(A, cos_t, sin_t);
  ad e = ad_mul_s(A, ad_exp(A, ad_neg(A, ad_sqr(A, a))), MF_INV_SQRT_PI);
  ad c_hi = ad_mul_s(A, ad_add(A, ad_mul(A, cos_t, ad_erfc(A, ad_neg(A, a))), ad_mul(A, sin_t, e)),
                     0.5);
  ad target = ad_mul(A, u1, c_hi);
  /* dx = (d target - C_c d cos_t - C_s d sin_t) / C_x */
  double ex = exp(-x * x) * MF_INV_SQRT_PI;
  double c_c = 0.5 * erfc(-x), c_s = 0.5 * ex;
  double c_x = (cos_t.v - x * sin_t.v) * ex;
  ad rhs = ad_sub(A, target, ad_lincomb(A, c_c, cos_t, c_s, sin_t));
  ad dx = c_x > 0.0 ? ad_mul_s(A, rhs, 1.0 / c_x) : ad_const(A, 0.0);
  *OUT_x = ad_with_value(A, dx, x);
#else
  *OUT_x = x;
#endif
}

REAL3 R_FN(mf_sample)(R_CTX mf_dist dist, REAL alpha, REAL3 v, int visible, REAL u1, REAL u2) {
  if (!visible) {
    /* Sample D(m) cos(theta_m): tan^2(theta_m) by inversion of its CDF,
     * Beckmann: 1 - exp(-tan^2 / alpha^2); GGX: tan^2 / (alpha^2 + tan^2). */
    REAL a2 = R_SQR(alpha);
    REAL t2 = dist == MF_BECKMANN ? R_MUL(R_NEG(a2), R_LOG1P(R_NEG(u1)))
                                  : R_DIV(R_MUL(a2, u1), R_S_SUB(1.0, u1));
    REAL cos_m = R_INV(R_SQRT(R_ADD_S(t2, 1.0)));
    REAL sin_m = R_SAFE_SQRT(R_S_SUB(1.0, R_SQR(cos_m)));
    REAL phi = R_MUL_S(u2, 2.0 * M_PI);
    return R3_MAKE(R_MUL(sin_m, R_COS(phi)), R_MUL(sin_m, R_SIN(phi)), cos_m);
  }
  /* Stretch v to the alpha = 1 configuration. */
  REAL3 vh = R3_NORMALIZE(R3_MAKE(R_MUL(alpha, v.x), R_MUL(alpha, v.y), v.z));
  if (dist == MF_GGX) {
    /* Heitz 2018: the visible normals of the alpha = 1 GGX (a hemisphere)
     * project to a disk; sample the disk with its lower half squeezed by
     * s = (1 + vh.z)/2, lift to the hemisphere, unstretch. */
    REAL lensq = R_ADD(R_SQR(vh.x), R_SQR(vh.y));
    REAL3 t1;
    if (R_V(lensq) > 0.0) {
      REAL il = R_INV(R_SQRT(lensq));
      t1 = R3_MAKE(R_MUL(R_NEG(vh.y), il), R_MUL(vh.x, il), R_C(0.0));
    } else {
      t1 = R3_CONST(1.0, 0.0, 0.0);
    }
    REAL3 t2 = R3_CROSS(vh, t1);
    REAL r = R_SQRT(u1), phi = R_MUL_S(u2, 2.0 * M_PI);
    REAL p1 = R_MUL(r, R_COS(phi)), p2 = R_MUL(r, R_SIN(phi));
    REAL s = R_MUL_S(R_ADD_S(vh.z, 1.0), 0.5);
    /* p2 = (1 - s) sqrt(max(0, 1 - p1^2)) + s p2 */
    REAL p1sq = R_SQR(p1);
    p2 = R_ADD(R_MUL(R_S_SUB(1.0, s), R_SAFE_SQRT(R_S_SUB(1.0, p1sq))), R_MUL(s, p2));
    /* nh = t1 p1 + t2 p2 + vh sqrt(max(0, 1 - p1^2 - p2^2)) */
    REAL lift = R_SAFE_SQRT(R_SUB(R_S_SUB(1.0, p1sq), R_SQR(p2)));
    REAL3 nh = R3_ADD(R3_ADD(R3_SCALE(t1, p1), R3_SCALE(t2, p2)), R3_SCALE(vh, lift));
    REAL nz = R_V(nh.z) < 1e-12 || isnan(R_V(nh.z)) ? R_C(1e-12) : nh.z;
    return R3_NORMALIZE(R3_MAKE(R_MUL(alpha, nh.x), R_MUL(alpha, nh.y), nz));
  }
  /* Beckmann (Heitz and d'Eon 2014): slopes in the standard configuration,
   * rotated to the azimuth of vh, scaled by alpha. */
  REAL cos_t = vh.z;
  REAL sin_t = R_SAFE_SQRT(R_S_SUB(1.0, R_SQR(cos_t)));
  REAL sx, sy;
  R_FN(mf__beckmann_visible_slopes)(R_ARG cos_t, sin_t, u1, u2, &sx, &sy);
  REAL cos_p = R_C(1.0), sin_p = R_C(0.0);
  if (R_V(sin_t) > 0.0) {
    REAL l = R_SQRT(R_ADD(R_SQR(vh.x), R_SQR(vh.y)));
    if (R_V(l) > 0.0) {
      cos_p = R_DIV(vh.x, l);
      sin_p = R_DIV(vh.y, l);
    }
  }
  REAL rx = R_SUB(R_MUL(cos_p, sx), R_MUL(sin_p, sy));
  REAL ry = R_ADD(R_MUL(sin_p, sx), R_MUL(cos_p, sy));
  rx = R_MUL(rx, alpha);
  ry = R_MUL(ry, alpha);
  return R3_NORMALIZE(R3_MAKE(R_NEG(rx), R_NEG(ry), R_C(1.0)));
}

REAL R_FN(mf_pdf_known)(R_CTX REAL d, REAL g1, REAL3 v, REAL3 m, int visible) {
  if (!visible) return R_MUL(d, R_V(m.z) > 0.0 ? m.z : R_C(0.0));
  if (R_V(v.z) <= 0.0) return R_C(0.0);
  /* D_v(m) = G1(v, m) max(0, v.m) D(m) / v.z */
  REAL vm = R3_DOT(v, m);
  if (R_V(vm) <= 0.0) return R_C(0.0);
  return R_DIV(R_MUL(R_MUL(g1, vm), d), v.z);
}

REAL R_FN(mf_pdf)(R_CTX mf_dist dist, REAL alpha, REAL3 v, REAL3 m, int visible) {
  if (!visible) return R_FN(mf_pdf_known)(R_ARG R_FN(mf_D)(R_ARG dist, alpha, m), R_C(0.0), v, m, 0);
  if (R_V(v.z) <= 0.0 || R_V(R3_DOT(v, m)) <= 0.0) return R_C(0.0);
  return R_FN(mf_pdf_known)(R_ARG R_FN(mf_D)(R_ARG dist, alpha, m),
                            R_FN(mf_G1)(R_ARG dist, alpha, v, m), v, m, 1);
}
