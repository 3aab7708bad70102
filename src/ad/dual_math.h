/*
 * dual_math.h: elementary functions of dual numbers.
 *
 * Each function f(a) returns (f(v), f'(v) d_a) by the chain rule; binary
 * functions f(a, b) return (f, f_a d_a + f_b d_b). The comment above each
 * function gives its derivative rule. Where the mathematical derivative is
 * infinite (sqrt, cbrt at 0; asin, acos at +-1; log at 0) the tangent is
 * inf or NaN, as in plain arithmetic; the safe_ variants pick a finite
 * one-sided value instead. Functions that are piecewise (fabs, fmin, fmax,
 * clamp, floor) branch on the value and return the derivative of the piece
 * in use; at a kink they take the piece documented below.
 *
 * In a second-order arena each function also adds f''(v) g_a g_a^T (binary:
 * f_aa, f_ab, f_bb) to the Hessian; the second derivative is given next to
 * the code. Where it is infinite it is inf or NaN like the first.
 *
 * erfinv has no C library counterpart, so ad_erfinv_scalar implements it:
 * an initial guess (a series for small |y|, Winitzki's 2008 closed-form
 * approximation of erf's inverse elsewhere), then three Halley steps on
 * erf(x) - y (on (1 - y) - erfc(x) in the tails, where 1 - y is exact and
 * erfc keeps full relative precision). Halley's cubic convergence takes the
 * guess's ~2e-3 relative error to machine precision.
 */
#ifndef LMC_AD_DUAL_MATH_H
#define LMC_AD_DUAL_MATH_H

#include <math.h>

#include "ad/dual.h"

#define AD_PI 3.14159265358979323846
#define AD_2_SQRTPI 1.12837916709551257390 /* 2 / sqrt(pi) */
#define AD_SQRTPI_2 0.88622692545275801365 /* sqrt(pi) / 2 */

/* sqrt(a): d = d_a / (2 sqrt(a)) (inf at a = 0) */
static inline ad ad_sqrt(ad_arena *A, ad a) {
  double r = sqrt(a.v);
  return ad__op1(A, r, 0.5 / r, -0.25 / (r * r * r), a); /* f'' = -1 / (4 a^(3/2)) */
}

/* sqrt(max(a, 0)): d = d_a / (2 sqrt(a)) for a > 0, and 0 for a <= 0 (the
 * one-sided choice that keeps gradients finite at the edge of a domain). */
static inline ad ad_safe_sqrt(ad_arena *A, ad a) {
  double r = a.v > 0.0 ? sqrt(a.v) : 0.0;
  return ad__op1(A, r, r > 0.0 ? 0.5 / r : 0.0, r > 0.0 ? -0.25 / (r * r * r) : 0.0, a);
}

/* cbrt(a): d = d_a / (3 cbrt(a)^2) (inf at a = 0) */
static inline ad ad_cbrt(ad_arena *A, ad a) {
  double r = cbrt(a.v);
  return ad__op1(A, r, 1.0 / (3.0 * r * r), -2.0 / (9.0 * r * r * r * r * r), a); /* f'' = -2 / (9 a^(5/3)) */
}

/* exp(a): d = exp(a) d_a */
static inline ad ad_exp(ad_arena *A, ad a) {
  double r = exp(a.v);
  return ad__op1(A, r, r, r, a);
}

/* log(a): d = d_a / a */
static inline ad ad_log(ad_arena *A, ad a) {
  double i = 1.0 / a.v;
  return ad__op1(A, log(a.v), i, -i * i, a); /* f'' = -1 / a^2 */
}

/* log(1 + a): d = d_a / (1 + a) */
static inline ad ad_log1p(ad_arena *A, ad a) {
  double i = 1.0 / (1.0 + a.v);
  return ad__op1(A, log1p(a.v), i, -i * i, a); /* f'' = -1 / (1 + a)^2 */
}

/* exp(a) - 1: d = exp(a) d_a */
static inline ad ad_expm1(ad_arena *A, ad a) {
  double e = exp(a.v);
  return ad__op1(A, expm1(a.v), e, e, a);
}

/* a^p for a scalar exponent p: d = p a^(p-1) d_a (0 when p = 0). */
static inline ad ad_pow_s(ad_arena *A, ad a, double p) {
  double c = p == 0.0 ? 0.0 : p * pow(a.v, p - 1.0);
  double h = (p == 0.0 || p == 1.0 || !AD__H2(A)) ? 0.0 : p * (p - 1.0) * pow(a.v, p - 2.0);
  return ad__op1(A, pow(a.v, p), c, h, a); /* f'' = p (p - 1) a^(p-2) */
}

/* a^b for a dual exponent: d = b a^(b-1) d_a + a^b log(a) d_b.
 * The d_b term is defined for a > 0 only; it is taken as 0 for a <= 0 (where
 * a^b is 0 or only defined at integer b). */
static inline ad ad_pow(ad_arena *A, ad a, ad b) {
  double r = pow(a.v, b.v);
  double ca = b.v == 0.0 ? 0.0 : b.v * pow(a.v, b.v - 1.0);
  double cb = a.v > 0.0 ? r * log(a.v) : 0.0;
  ad o = ad__lin2(A, r, ca, a, cb, b);
  if (AD__H2(A)) {
    /* f_aa = b (b - 1) a^(b-2), f_ab = a^(b-1) (1 + b log a), f_bb = a^b log(a)^2 */
    double la = a.v > 0.0 ? log(a.v) : 0.0;
    double haa = (b.v == 0.0 || b.v == 1.0) ? 0.0 : b.v * (b.v - 1.0) * pow(a.v, b.v - 2.0);
    ad__h_sq(A, o, haa, a);
    if (a.v > 0.0) {
      ad__h_sym(A, o, pow(a.v, b.v - 1.0) * (1.0 + b.v * la), a, b);
      ad__h_sq(A, o, r * la * la, b);
    }
  }
  return o;
}

/* s^a for a scalar base s > 0: d = s^a log(s) d_a */
static inline ad ad_s_pow(ad_arena *A, double s, ad a) {
  double r = pow(s, a.v);
  double ls = s > 0.0 ? log(s) : 0.0;
  return ad__op1(A, r, r * ls, r * ls * ls, a); /* f'' = s^a log(s)^2 */
}

/* sin(a): d = cos(a) d_a */
static inline ad ad_sin(ad_arena *A, ad a) {
  double s = sin(a.v);
  return ad__op1(A, s, cos(a.v), -s, a); /* f'' = -sin(a) */
}

/* cos(a): d = -sin(a) d_a */
static inline ad ad_cos(ad_arena *A, ad a) {
  double c = cos(a.v);
  return ad__op1(A, c, -sin(a.v), -c, a); /* f'' = -cos(a) */
}

/* tan(a): d = (1 + tan(a)^2) d_a */
static inline ad ad_tan(ad_arena *A, ad a) {
  double r = tan(a.v);
  return ad__op1(A, r, 1.0 + r * r, 2.0 * r * (1.0 + r * r), a); /* f'' = 2 tan (1 + tan^2) */
}

/* asin(a): d = d_a / sqrt(1 - a^2) (inf at |a| = 1) */
static inline ad ad_asin(ad_arena *A, ad a) {
  double w = 1.0 / ((1.0 - a.v) * (1.0 + a.v)), c = sqrt(w);
  return ad__op1(A, asin(a.v), c, a.v * w * c, a); /* f'' = a / (1 - a^2)^(3/2) */
}

/* acos(a): d = -d_a / sqrt(1 - a^2) (inf at |a| = 1) */
static inline ad ad_acos(ad_arena *A, ad a) {
  double w = 1.0 / ((1.0 - a.v) * (1.0 + a.v)), c = sqrt(w);
  return ad__op1(A, acos(a.v), -c, -a.v * w * c, a); /* f'' = -a / (1 - a^2)^(3/2) */
}

/* atan(a): d = d_a / (1 + a^2) */
static inline ad ad_atan(ad_arena *A, ad a) {
  double c = 1.0 / (1.0 + a.v * a.v);
  return ad__op1(A, atan(a.v), c, -2.0 * a.v * c * c, a); /* f'' = -2 a / (1 + a^2)^2 */
}

/* atan2(y, x): d = (x d_y - y d_x) / (x^2 + y^2) (NaN at the origin) */
static inline ad ad_atan2(ad_arena *A, ad y, ad x) {
  double inv_r2 = 1.0 / (x.v * x.v + y.v * y.v);
  ad r = ad__lin2(A, atan2(y.v, x.v), x.v * inv_r2, y, -y.v * inv_r2, x);
  if (AD__H2(A)) {
    /* f_yy = -2 x y / r^4, f_xx = 2 x y / r^4, f_xy = (y^2 - x^2) / r^4 */
    double i4 = inv_r2 * inv_r2;
    ad__h_sq(A, r, -2.0 * x.v * y.v * i4, y);
    ad__h_sq(A, r, 2.0 * x.v * y.v * i4, x);
    ad__h_sym(A, r, (y.v * y.v - x.v * x.v) * i4, y, x);
  }
  return r;
}

/* |a|: d = sign(a) d_a, with 0 at a = 0 */
static inline ad ad_fabs(ad_arena *A, ad a) {
  double s = a.v > 0.0 ? 1.0 : (a.v < 0.0 ? -1.0 : 0.0);
  return ad__lin1(A, fabs(a.v), s, a);
}

/* min(a, b): the smaller argument, derivative included; a on ties; like
 * fmin, a NaN argument loses to a number. Allocates nothing. */
static inline ad ad_fmin(const ad_arena *A, ad a, ad b) {
  (void)A;
  if (isnan(a.v)) return b;
  return b.v < a.v ? b : a;
}

/* max(a, b): the larger argument; a on ties; NaN loses. */
static inline ad ad_fmax(const ad_arena *A, ad a, ad b) {
  (void)A;
  if (isnan(a.v)) return b;
  return b.v > a.v ? b : a;
}

/* clamp(a, lo, hi): a inside [lo, hi] (derivative d_a, also on the bounds),
 * the constant bound outside (derivative 0). */
static inline ad ad_clamp(const ad_arena *A, ad a, double lo, double hi) {
  if (a.v < lo) return ad_const(A, lo);
  if (a.v > hi) return ad_const(A, hi);
  return a;
}

/* floor(a): piecewise constant, d = 0 */
static inline ad ad_floor(const ad_arena *A, ad a) { return ad_const(A, floor(a.v)); }

/* erf(a): d = 2/sqrt(pi) exp(-a^2) d_a */
static inline ad ad_erf(ad_arena *A, ad a) {
  double c = AD_2_SQRTPI * exp(-a.v * a.v);
  return ad__op1(A, erf(a.v), c, -2.0 * a.v * c, a); /* f'' = -2 a f' */
}

/* erfc(a) = 1 - erf(a), without the cancellation for large a:
 * d = -2/sqrt(pi) exp(-a^2) d_a */
static inline ad ad_erfc(ad_arena *A, ad a) {
  double c = -AD_2_SQRTPI * exp(-a.v * a.v);
  return ad__op1(A, erfc(a.v), c, -2.0 * a.v * c, a); /* f'' = -2 a f' */
}

/* Inverse error function of a double: erf(x) = y for y in [-1, 1]
 * (+-inf at +-1, NaN outside). Accurate to a few ulp. */
static inline double ad_erfinv_scalar(double y) {
  if (!(y >= -1.0 && y <= 1.0)) return NAN;
  if (y == 0.0) return y; /* keeps the sign of zero */
  if (y == 1.0) return INFINITY;
  if (y == -1.0) return -INFINITY;
  double ay = fabs(y);
  double q = 1.0 - ay; /* exact for ay >= 0.5 (Sterbenz) */
  double x;

  /* Initial guess. For small y, the series erfinv(y) = c y (1 + pi/12 y^2 +
   * O(y^4)) with c = sqrt(pi)/2; elsewhere Winitzki's approximation
   *   x^2 = sqrt(t^2 - L/a) - t,  t = 2/(pi a) + L/2,  L = log(1 - y^2),
   * a = 0.147 (relative error below 2e-3 on (0, 1)). */
  if (ay <= 0.1) {
    x = AD_SQRTPI_2 * ay * (1.0 + (AD_PI / 12.0) * ay * ay);
  } else {
    const double wa = 0.147;
    double L = log(q * (1.0 + ay));
    double t = 2.0 / (AD_PI * wa) + 0.5 * L;
    x = sqrt(sqrt(t * t - L / wa) - t);
  }

  /* Halley's method on g(x) = erf(x) - y, with g' = 2/sqrt(pi) exp(-x^2) and
   * g'' = -2 x g':  x <- x - u / (1 + x u),  u = g / g'.
   * In the tail g = (1 - y) - erfc(x) avoids the cancellation in erf - y. */
  for (int it = 0; it < 3; it++) {
    double g = ay > 0.5 ? q - erfc(x) : erf(x) - ay;
    double u = g / (AD_2_SQRTPI * exp(-x * x));
    x -= u / (1.0 + x * u);
  }
  return y < 0.0 ? -x : x;
}

/* erfinv(a): d = sqrt(pi)/2 exp(erfinv(a)^2) d_a */
static inline ad ad_erfinv(ad_arena *A, ad a) {
  double x = ad_erfinv_scalar(a.v);
  double c = AD_SQRTPI_2 * exp(x * x);
  return ad__op1(A, x, c, 2.0 * x * c * c, a); /* f'' = 2 x f'^2 */
}

/* A dual with value v and the tangent (and Hessian) of t: t - t.v + v, which
 * shares t's block and allocates nothing; the value is exactly v when t.v is
 * finite. For a value computed by iteration whose derivatives come from the
 * implicit function theorem. */
static inline ad ad_with_value(const ad_arena *A, ad t, double v) {
  if (!isfinite(t.v)) return (ad){v, t.d};
  return ad_add_s(A, ad_sub_s(A, t, t.v), v);
}

#endif
