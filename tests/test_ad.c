/*
 * test_ad.c: forward-mode AD (src/ad) against finite differences.
 *
 * Every operation is evaluated at thousands of random points of its domain,
 * many of them close to its edges (log near 0+, asin near +-1, pow with tiny
 * bases, atan2 in all quadrants and next to its branch cut, refraction next
 * to the critical angle, frames next to the poles). Each partial derivative
 * of the dual result is compared with a 6th-order central difference
 *   f'(x) ~ (-f(x-3h) + 9 f(x-2h) - 45 f(x-h) + 45 f(x+h) - 9 f(x+2h)
 *            + f(x+3h)) / (60 h)
 * of the plain double formula.
 *
 * Choice of h. Each sample comes with a length L over which the function
 * changes smoothly (1 for exp or sin, |x| for log or pow, the distance to a
 * singularity or kink near an edge). The truncation error of the formula is
 * h^6 |f^(7)| / 140 ~ (h/L)^6 |f'| times a modest constant; the rounding
 * error is about 1.83 eps |f| / h. With h = 2^-7 L to 2^-8 L the truncation
 * is ~1e-13 relative and the rounding ~1e-12 (1e-8 at the worst edge
 * points: asin at 1 - 1e-12, where |f| / (h f') ~ 1e5 ... 1e6), both well
 * under the 1e-7 tolerance. (A 4th-order formula needed h ~ 2^-7 L for
 * pow(x, -3)-like curvature and h ~ 2^-9 L against rounding at the asin
 * edge: no single choice kept both under 1e-7 with margin.) h is rounded
 * down to a power of two and x to a multiple of h, so x +- k h are exact in
 * floating point and the steps are exactly h.
 *
 * Error measure: |d_ad - d_fd| <= 1e-7 |d_ad| + 16 eps |f| / h, where |f| is
 * the largest output magnitude: a relative error of 1e-7, except where the
 * derivative itself is below the rounding noise of the difference quotient
 * (cos at 0, a cross product component that does not depend on x_j). The
 * printed figure is the worst ratio of |d_ad - d_fd| to that tolerance.
 *
 * The same tables run a second time in a second-order arena: each Hessian
 * entry against central differences of the dual gradient
 * (check_hessian_at), and the arena's values and gradients bit for bit
 * those of a first-order one.
 */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "ad/dual.h"
#include "ad/dual_math.h"
#include "ad/dual_vec3.h"
#include "render/frame.h"

#define TOL 1e-7  /* first derivatives (see the header) */
#define TOL2 1e-7 /* second derivatives (see check_hessian_at) */
#define NPTS 4000 /* points per operation */
#define MAXDIM 8
#define MAXOUT 9

/* ---- A small fixed-seed generator (splitmix64). ---------------------------- */
typedef struct trng {
  uint64_t s;
} trng;

static double rnd(trng *r) {
  uint64_t z = (r->s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return (double)(z >> 11) * 0x1.0p-53;
}
static double uni(trng *r, double a, double b) { return a + (b - a) * rnd(r); }
static double logu(trng *r, double e0, double e1) { return pow(10.0, uni(r, e0, e1)); }
static double sgn(trng *r) { return rnd(r) < 0.5 ? -1.0 : 1.0; }

/* ---- The harness. ---------------------------------------------------------- */
typedef void (*plain_fn)(const double *x, double *out);
typedef void (*dual_fn)(ad_arena *A, const ad *x, ad *out);
/* Fills x[dim] and the smoothness lengths len[dim]; returns 0 to reject. */
typedef int (*sample_fn)(trng *r, double *x, double *len);

typedef struct tcase {
  const char *name;
  int dim, nout;
  plain_fn plain;
  dual_fn dual;
  sample_fn sample;
} tcase;

static double g_arena_buf[1 << 16];

/* The gradient of every output at x (first-order arena): g[k * MAXDIM + j]. */
static void dual_grad(const tcase *c, const double *x, double *vals, double *g) {
  ad_arena A;
  assert_int_equal(ad_arena_init(&A, g_arena_buf, sizeof g_arena_buf / sizeof(double), c->dim), 0);
  ad xv[MAXDIM], out[MAXOUT];
  for (int j = 0; j < c->dim; j++) xv[j] = ad_var(&A, x[j], j);
  c->dual(&A, xv, out);
  assert_true(ad_arena_ok(&A));
  for (int k = 0; k < c->nout; k++) {
    if (vals) vals[k] = out[k].v;
    for (int j = 0; j < c->dim; j++) g[k * MAXDIM + j] = ad_deriv(&A, out[k], j);
  }
}

/* The second-order check at one point x (steps h): a second-order arena
 * gives the same values and gradients as a first-order one, bit for bit,
 * and each Hessian entry d^2 out_k / dx_i dx_j matches the same 6th-order
 * central difference, taken of the first-order dual gradient d out_k / dx_i
 * along x_j (so every entry is checked twice, once from each side of the
 * diagonal). Tolerance: |H_ad - H_fd| <= TOL2 |H_ad| + 1e-9 Hmax_k +
 * 16 eps gmax / h, with gmax the largest gradient magnitude (the rounding
 * term, as |f| is for the gradient) and Hmax_k the largest second partial
 * of output k: an entry that vanishes by symmetry (atan2's f_xy on the
 * diagonal) still carries the difference formula's truncation error,
 * ~36 (h/L)^6 (1e-12 here) relative to the Hessian's scale, not to the
 * entry. The last term, twice the change of the difference quotient from
 * step 2h to h, is its own error estimate: the reference is the dual
 * gradient in double (the gradient check differences the plain formula in
 * long double where it must), and next to the critical angle of refraction
 * (cos_t^2 down to 1e-5) that gradient's rounding, magnified by the
 * cancellation in cos_t^2 and by 1 / h, reaches 2e-6 of the entry; it
 * changes with h where a wrong rule would not. Returns the entries
 * checked. */
static long check_hessian_at(const tcase *c, const double *x, const double *h, long *fails,
                             double *maxerr) {
  static double buf2[1 << 16];
  ad_arena A;
  assert_int_equal(ad_arena_init2(&A, buf2, sizeof buf2 / sizeof(double), c->dim), 0);
  ad xv[MAXDIM], out[MAXOUT];
  for (int j = 0; j < c->dim; j++) xv[j] = ad_var(&A, x[j], j);
  c->dual(&A, xv, out);
  assert_true(ad_arena_ok(&A));
  double v1[MAXOUT], g1[MAXOUT * MAXDIM];
  dual_grad(c, x, v1, g1);
  double gscale = 0.0;
  for (int k = 0; k < c->nout; k++) {
    if (memcmp(&out[k].v, &v1[k], sizeof(double)) != 0) (*fails)++;
    for (int i = 0; i < c->dim; i++) {
      /* The same number (a zero's sign aside: a second-order arena skips
       * the products of a coefficient with a tangent's zeros past its
       * width, dual.h). */
      double g2 = ad_deriv(&A, out[k], i);
      if (!(g2 == g1[k * MAXDIM + i])) {
        if (*fails < 20) print_error("%s: second-order arena changed d out%d / d x%d\n", c->name, k, i);
        (*fails)++;
      }
      gscale = fmax(gscale, fabs(g2));
    }
  }
  /* Each output's Hessian from the reverse sweep over the tape. */
  static double hk[MAXOUT][MAXDIM * MAXDIM];
  double hmax[MAXOUT] = {0.0};
  for (int k = 0; k < c->nout; k++) {
    assert_int_equal(ad_hessian(&A, out[k], hk[k]), 0);
    for (int i = 0; i < c->dim * c->dim; i++) hmax[k] = fmax(hmax[k], fabs(hk[k][i]));
  }
  long checked = 0;
  for (int j = 0; j < c->dim; j++) {
    /* gradients at x + m h, m = -6 .. 6 (the even m serve the step 2h) */
    double gk[13][MAXOUT * MAXDIM], xs[MAXDIM];
    memcpy(xs, x, sizeof xs);
    for (int m = -6; m <= 6; m++) {
      if (m == 0 || ((m > 3 || m < -3) && (m & 1))) continue;
      xs[j] = x[j] + m * h[j];
      dual_grad(c, xs, NULL, gk[m + 6]);
    }
    for (int k = 0; k < c->nout; k++)
      for (int i = 0; i < c->dim; i++) {
        int q = k * MAXDIM + i;
        double fd = (-gk[3][q] + 9.0 * gk[4][q] - 45.0 * gk[5][q] + 45.0 * gk[7][q] -
                     9.0 * gk[8][q] + gk[9][q]) /
                    (60.0 * h[j]);
        double fd2 = (-gk[0][q] + 9.0 * gk[2][q] - 45.0 * gk[4][q] + 45.0 * gk[8][q] -
                      9.0 * gk[10][q] + gk[12][q]) /
                     (120.0 * h[j]);
        double ha = hk[k][i * c->dim + j];
        double noise = 16.0 * DBL_EPSILON * gscale / h[j] + 1e-9 * hmax[k] + 2.0 * fabs(fd - fd2);
        double diff = fabs(ha - fd);
        if (!(diff <= TOL2 * fabs(ha) + noise)) {
          if (*fails < 20)
            print_error("%s: d2 out%d / d x%d d x%d at x = (%.17g, %.17g, %.17g ...): ad %.17g fd "
                        "%.17g (rel err %.3g)\n",
                        c->name, k, i, j, x[0], c->dim > 1 ? x[1] : 0.0, c->dim > 2 ? x[2] : 0.0, ha,
                        fd, diff / fabs(ha));
          (*fails)++;
        } else if (diff / (TOL2 * fabs(ha) + noise) > *maxerr) {
          *maxerr = diff / (TOL2 * fabs(ha) + noise);
        }
        checked++;
      }
  }
  return checked;
}

/* Checks one case at NPTS accepted points; returns the number of partials
 * checked and adds the failures to *fails. Order 1: each partial derivative
 * against central differences of the plain formula; order 2: each second
 * partial (check_hessian_at). */
static long check_case(const tcase *c, uint64_t seed, int order, long *fails, double *maxerr) {
  trng r = {seed};
  long checked = 0;
  int accepted = 0, tries = 0;
  *maxerr = 0.0;
  while (accepted < NPTS && tries < 100 * NPTS) {
    double x[MAXDIM], len[MAXDIM], h[MAXDIM];
    tries++;
    if (!c->sample(&r, x, len)) continue;
    /* Round h to a power of two and x to a multiple of h. */
    for (int j = 0; j < c->dim; j++) {
      h[j] = exp2(floor(log2(0x1.0p-7 * len[j]))); /* in (2^-8 L, 2^-7 L] */
      x[j] = nearbyint(x[j] / h[j]) * h[j];
    }
    double f0[MAXOUT];
    c->plain(x, f0);
    int finite = 1;
    for (int k = 0; k < c->nout; k++) finite &= isfinite(f0[k]);
    if (!finite) continue;
    accepted++;
    if (order == 2) {
      checked += check_hessian_at(c, x, h, fails, maxerr);
      continue;
    }

    /* Dual evaluation with one variable per input. */
    ad_arena A;
    assert_int_equal(ad_arena_init(&A, g_arena_buf, sizeof g_arena_buf / sizeof(double), c->dim), 0);
    ad xv[MAXDIM], out[MAXOUT];
    for (int j = 0; j < c->dim; j++) xv[j] = ad_var(&A, x[j], j);
    c->dual(&A, xv, out);
    assert_true(ad_arena_ok(&A));
    double fscale = 0.0;
    for (int k = 0; k < c->nout; k++) fscale = fmax(fscale, fabs(f0[k]));
    for (int k = 0; k < c->nout; k++) {
      if (!(fabs(out[k].v - f0[k]) <= 1e-12 * fmax(fscale, 1e-300))) {
        print_error("%s: value %d at point %d: dual %.17g plain %.17g\n", c->name, k, accepted,
                    out[k].v, f0[k]);
        (*fails)++;
      }
    }

    /* Each partial derivative against the central difference. */
    for (int j = 0; j < c->dim; j++) {
      double fm3[MAXOUT], fm2[MAXOUT], fm1[MAXOUT], fp1[MAXOUT], fp2[MAXOUT], fp3[MAXOUT];
      double xs[MAXDIM];
      double *fk[6] = {fm3, fm2, fm1, fp1, fp2, fp3};
      const double step[6] = {-3.0, -2.0, -1.0, 1.0, 2.0, 3.0};
      memcpy(xs, x, sizeof xs);
      for (int s = 0; s < 6; s++) {
        xs[j] = x[j] + step[s] * h[j];
        c->plain(xs, fk[s]);
      }
      for (int k = 0; k < c->nout; k++) {
        double fd = (-fm3[k] + 9.0 * fm2[k] - 45.0 * fm1[k] + 45.0 * fp1[k] - 9.0 * fp2[k] + fp3[k]) /
                    (60.0 * h[j]);
        double da = ad_deriv(&A, out[k], j);
        double noise = 16.0 * DBL_EPSILON * fscale / h[j];
        double diff = fabs(da - fd);
        if (!(diff <= TOL * fabs(da) + noise)) {
          if (*fails < 20)
            print_error("%s: d out%d / d x%d at x = (%.17g, %.17g, %.17g ...) len %.3g: ad %.17g fd "
                        "%.17g (rel err %.3g)\n",
                        c->name, k, j, x[0], c->dim > 1 ? x[1] : 0.0, c->dim > 2 ? x[2] : 0.0,
                        len[j], da, fd, diff / fabs(da));
          (*fails)++;
        } else if (diff / (TOL * fabs(da) + noise) > *maxerr) {
          *maxerr = diff / (TOL * fabs(da) + noise);
        }
        checked++;
      }
    }
  }
  assert_int_equal(accepted, NPTS);
  return checked;
}

static void run_cases_order(const tcase *cases, int count, uint64_t seed, int order) {
  long fails = 0, total = 0, expected = 0;
  for (int i = 0; i < count; i++) {
    double maxerr;
    long n = check_case(&cases[i], seed + (uint64_t)i * 7919u, order, &fails, &maxerr);
    printf("  %-14s %7ld %s, worst |ad - fd| / tolerance %.2e\n", cases[i].name, n,
           order == 2 ? "second partials" : "partials", maxerr);
    total += n;
    expected += (long)NPTS * cases[i].dim * cases[i].nout * (order == 2 ? cases[i].dim : 1);
  }
  assert_int_equal(fails, 0);
  assert_int_equal(total, expected);
}

/* The order a case-table test checks: 1, or 2 when run with the prestate
 * &k_order2 (the same tables, second partials). */
static int k_order2 = 2;
static int test_order(void **state) { return state && *state ? *(const int *)*state : 1; }

/* ---- Unary operations. -----------------------------------------------------
 * UNARY(name, plain expression of a, dual expression of a) */
#define UNARY(NAME, PE, DE)                                                     \
  static void p_##NAME(const double *x, double *o) {                            \
    double a = x[0];                                                            \
    o[0] = (PE);                                                                \
  }                                                                             \
  static void d_##NAME(ad_arena *A, const ad *x, ad *o) {                       \
    ad a = x[0];                                                                \
    (void)A;                                                                    \
    o[0] = (DE);                                                                \
  }

UNARY(neg, -a, ad_neg(A, a))
UNARY(sqr, a * a, ad_sqr(A, a))
UNARY(inv, 1.0 / a, ad_inv(A, a))
UNARY(add_s, a + 2.5, ad_add_s(A, a, 2.5))
UNARY(sub_s, a - 2.5, ad_sub_s(A, a, 2.5))
UNARY(s_sub, 1.0 - a, ad_s_sub(A, 1.0, a))
UNARY(mul_s, a * -3.7, ad_mul_s(A, a, -3.7))
UNARY(div_s, a / 0.37, ad_div_s(A, a, 0.37))
UNARY(s_div, 2.5 / a, ad_s_div(A, 2.5, a))
UNARY(sqrt, sqrt(a), ad_sqrt(A, a))
UNARY(safe_sqrt, sqrt(a), ad_safe_sqrt(A, a))
UNARY(cbrt, cbrt(a), ad_cbrt(A, a))
UNARY(exp, exp(a), ad_exp(A, a))
UNARY(log, log(a), ad_log(A, a))
UNARY(log1p, log1p(a), ad_log1p(A, a))
UNARY(expm1, expm1(a), ad_expm1(A, a))
UNARY(pow_2_5, pow(a, 2.5), ad_pow_s(A, a, 2.5))
UNARY(pow_m1_3, pow(a, -1.3), ad_pow_s(A, a, -1.3))
UNARY(pow_0_5, pow(a, 0.5), ad_pow_s(A, a, 0.5))
UNARY(pow_3, pow(a, 3.0), ad_pow_s(A, a, 3.0))
UNARY(s_pow, pow(0.3, a), ad_s_pow(A, 0.3, a))
UNARY(sin, sin(a), ad_sin(A, a))
UNARY(cos, cos(a), ad_cos(A, a))
UNARY(tan, tan(a), ad_tan(A, a))
UNARY(asin, asin(a), ad_asin(A, a))
UNARY(acos, acos(a), ad_acos(A, a))
UNARY(atan, atan(a), ad_atan(A, a))
UNARY(fabs, fabs(a), ad_fabs(A, a))
UNARY(clamp, fmin(fmax(a, -0.5), 0.75), ad_clamp(A, a, -0.5, 0.75))
UNARY(floor, floor(a), ad_floor(A, a))
UNARY(erf, erf(a), ad_erf(A, a))
UNARY(erfc, erfc(a), ad_erfc(A, a))
UNARY(erfinv, ad_erfinv_scalar(a), ad_erfinv(A, a))

/* Samplers: bulk points and points near the edges of each domain. */
static int s_wide(trng *r, double *x, double *len) {
  x[0] = uni(r, -100.0, 100.0);
  len[0] = fmax(1.0, fabs(x[0]));
  return 1;
}
static int s_unit_scale(trng *r, double *x, double *len) { /* functions varying on scale 1 */
  x[0] = rnd(r) < 0.3 ? sgn(r) * logu(r, -8.0, 0.0) : uni(r, -30.0, 30.0);
  len[0] = 1.0;
  return 1;
}
static int s_pos(trng *r, double *x, double *len) { /* (0, inf), relative scale, near 0+ */
  x[0] = logu(r, -12.0, 6.0);
  len[0] = x[0];
  return 1;
}
static int s_pos_far(trng *r, double *x, double *len) { /* log: down to 1e-100 */
  x[0] = logu(r, -100.0, 100.0);
  len[0] = x[0];
  return 1;
}
static int s_pos_small(trng *r, double *x, double *len) { /* pow: small bases */
  x[0] = logu(r, -10.0, 3.0);
  len[0] = x[0];
  return 1;
}
static int s_nonzero(trng *r, double *x, double *len) {
  x[0] = sgn(r) * logu(r, -10.0, 10.0);
  len[0] = fabs(x[0]);
  return 1;
}
static int s_log1p(trng *r, double *x, double *len) { /* (-1, inf), near -1+ */
  x[0] = rnd(r) < 0.5 ? -1.0 + logu(r, -12.0, 0.0) : uni(r, -1.0, 100.0);
  len[0] = 1.0 + x[0];
  return x[0] > -1.0;
}
static int s_trig(trng *r, double *x, double *len) { /* with points near 0 and k pi/2 */
  double u = rnd(r);
  if (u < 0.3) x[0] = uni(r, -100.0, 100.0);
  else x[0] = floor(uni(r, -8.0, 8.0)) * (AD_PI / 2.0) + sgn(r) * logu(r, -9.0, -1.0);
  len[0] = 1.0;
  return 1;
}
static int s_tan(trng *r, double *x, double *len) { /* near the poles pi/2 + k pi */
  double k = floor(uni(r, -5.0, 5.0));
  x[0] = rnd(r) < 0.5 ? uni(r, -1.5, 1.5) + k * AD_PI
                      : (AD_PI / 2.0 + k * AD_PI) + sgn(r) * logu(r, -7.0, -1.0);
  len[0] = fmin(1.0, fabs(cos(x[0])));
  return 1;
}
static int s_pm1(trng *r, double *x, double *len) { /* (-1, 1), near +-1 */
  x[0] = rnd(r) < 0.5 ? uni(r, -1.0, 1.0) : sgn(r) * (1.0 - logu(r, -12.0, -0.5));
  len[0] = fmin(1.0, 1.0 - fabs(x[0]));
  return fabs(x[0]) < 1.0;
}
static int s_atan(trng *r, double *x, double *len) {
  x[0] = sgn(r) * logu(r, -6.0, 8.0);
  len[0] = fmax(1.0, fabs(x[0]));
  return 1;
}
static int s_clamp(trng *r, double *x, double *len) {
  x[0] = uni(r, -2.0, 2.0);
  len[0] = fmin(fabs(x[0] + 0.5), fabs(x[0] - 0.75));
  return len[0] > 1e-6;
}
static int s_floor(trng *r, double *x, double *len) {
  x[0] = uni(r, -10.0, 10.0);
  len[0] = fabs(x[0] - nearbyint(x[0]));
  return len[0] > 1e-6;
}
static int s_erf(trng *r, double *x, double *len) {
  x[0] = uni(r, -6.0, 6.0);
  len[0] = 1.0;
  return 1;
}

#define CASE1(NAME, S) {#NAME, 1, 1, p_##NAME, d_##NAME, S}

static void test_unary(void **state) {
  const tcase cases[] = {
      CASE1(neg, s_wide),          CASE1(sqr, s_wide),         CASE1(inv, s_nonzero),
      CASE1(add_s, s_wide),        CASE1(sub_s, s_wide),       CASE1(s_sub, s_wide),
      CASE1(mul_s, s_wide),        CASE1(div_s, s_wide),       CASE1(s_div, s_nonzero),
      CASE1(sqrt, s_pos),          CASE1(safe_sqrt, s_pos),    CASE1(cbrt, s_nonzero),
      CASE1(exp, s_unit_scale),    CASE1(log, s_pos_far),      CASE1(log1p, s_log1p),
      CASE1(expm1, s_unit_scale),  CASE1(pow_2_5, s_pos_small), CASE1(pow_m1_3, s_pos_small),
      CASE1(pow_0_5, s_pos_small), CASE1(pow_3, s_pos_small),  CASE1(s_pow, s_unit_scale),
      CASE1(sin, s_trig),          CASE1(cos, s_trig),         CASE1(tan, s_tan),
      CASE1(asin, s_pm1),          CASE1(acos, s_pm1),         CASE1(atan, s_atan),
      CASE1(fabs, s_nonzero),      CASE1(clamp, s_clamp),      CASE1(floor, s_floor),
      CASE1(erf, s_erf),           CASE1(erfinv, s_pm1),
      CASE1(erfc, s_erf),
  };
  run_cases_order(cases, (int)(sizeof cases / sizeof cases[0]), 1001, test_order(state));
}

/* ---- Binary and ternary operations. ---------------------------------------- */
#define BINARY(NAME, PE, DE)                                                    \
  static void p_##NAME(const double *x, double *o) {                            \
    double a = x[0], b = x[1];                                                  \
    o[0] = (PE);                                                                \
  }                                                                             \
  static void d_##NAME(ad_arena *A, const ad *x, ad *o) {                       \
    ad a = x[0], b = x[1];                                                      \
    (void)A;                                                                    \
    o[0] = (DE);                                                                \
  }

BINARY(add, a + b, ad_add(A, a, b))
BINARY(sub, a - b, ad_sub(A, a, b))
BINARY(mul, a * b, ad_mul(A, a, b))
BINARY(div, a / b, ad_div(A, a, b))
BINARY(pow, pow(a, b), ad_pow(A, a, b))
BINARY(atan2, atan2(a, b), ad_atan2(A, a, b))
BINARY(fmin, fmin(a, b), ad_fmin(A, a, b))
BINARY(fmax, fmax(a, b), ad_fmax(A, a, b))
BINARY(lincomb, 1.5 * a - 0.25 * b, ad_lincomb(A, 1.5, a, -0.25, b))
BINARY(fma_s, a * b + 0.5, ad_fma_s(A, a, b, 0.5))

static void p_fma(const double *x, double *o) { o[0] = x[0] * x[1] + x[2]; }
static void d_fma(ad_arena *A, const ad *x, ad *o) { o[0] = ad_fma(A, x[0], x[1], x[2]); }

static int s_two(trng *r, double *x, double *len) {
  for (int j = 0; j < 2; j++) {
    x[j] = uni(r, -10.0, 10.0);
    len[j] = fmax(1.0, fabs(x[j]));
  }
  return 1;
}
static int s_three(trng *r, double *x, double *len) {
  for (int j = 0; j < 3; j++) {
    x[j] = uni(r, -10.0, 10.0);
    len[j] = fmax(1.0, fabs(x[j]));
  }
  return 1;
}
static int s_div(trng *r, double *x, double *len) {
  x[0] = uni(r, -10.0, 10.0);
  len[0] = fmax(1.0, fabs(x[0]));
  x[1] = sgn(r) * logu(r, -6.0, 4.0);
  len[1] = fabs(x[1]);
  return 1;
}
static int s_pow2(trng *r, double *x, double *len) { /* small bases, exponents of both signs */
  x[0] = logu(r, -8.0, 2.0);
  x[1] = uni(r, -3.0, 3.0);
  len[0] = x[0];
  len[1] = fmin(1.0, 1.0 / fabs(log(x[0])));
  return 1;
}
static int s_atan2(trng *r, double *x, double *len) { /* all quadrants, near axes and cut */
  double phi = rnd(r) < 0.6 ? uni(r, -AD_PI, AD_PI)
                            : floor(uni(r, -2.0, 2.0)) * (AD_PI / 2.0) + sgn(r) * logu(r, -6.0, -1.0);
  double rad = logu(r, -5.0, 5.0);
  x[0] = rad * sin(phi); /* y */
  x[1] = rad * cos(phi); /* x */
  len[0] = x[1] < 0.0 ? fmin(rad, fabs(x[0])) : rad; /* the branch cut is y = 0, x < 0 */
  len[1] = rad;
  return x[1] >= 0.0 || fabs(x[0]) > 1e-9 * rad;
}
static int s_minmax(trng *r, double *x, double *len) {
  s_two(r, x, len);
  double gap = fabs(x[0] - x[1]);
  len[0] = fmin(len[0], gap);
  len[1] = fmin(len[1], gap);
  return gap > 1e-6;
}

static void test_binary(void **state) {
  const tcase cases[] = {
      {"add", 2, 1, p_add, d_add, s_two},
      {"sub", 2, 1, p_sub, d_sub, s_two},
      {"mul", 2, 1, p_mul, d_mul, s_two},
      {"div", 2, 1, p_div, d_div, s_div},
      {"pow", 2, 1, p_pow, d_pow, s_pow2},
      {"atan2", 2, 1, p_atan2, d_atan2, s_atan2},
      {"fmin", 2, 1, p_fmin, d_fmin, s_minmax},
      {"fmax", 2, 1, p_fmax, d_fmax, s_minmax},
      {"lincomb", 2, 1, p_lincomb, d_lincomb, s_two},
      {"fma_s", 2, 1, p_fma_s, d_fma_s, s_two},
      {"fma", 3, 1, p_fma, d_fma, s_three},
  };
  run_cases_order(cases, (int)(sizeof cases / sizeof cases[0]), 2002, test_order(state));
}

/* ---- Vectors. ---------------------------------------------------------------- */
static vec3 pv(const double *x) { return v3(x[0], x[1], x[2]); }
static adv3 dv(const ad *x) { return adv3_make(x[0], x[1], x[2]); }
static void put3(double *o, vec3 v) {
  o[0] = v.x;
  o[1] = v.y;
  o[2] = v.z;
}
static void putd3(ad *o, adv3 v) {
  o[0] = v.x;
  o[1] = v.y;
  o[2] = v.z;
}

static void p_dot(const double *x, double *o) { o[0] = v3_dot(pv(x), pv(x + 3)); }
static void d_dot(ad_arena *A, const ad *x, ad *o) { o[0] = adv3_dot(A, dv(x), dv(x + 3)); }
static void p_cross(const double *x, double *o) { put3(o, v3_cross(pv(x), pv(x + 3))); }
static void d_cross(ad_arena *A, const ad *x, ad *o) { putd3(o, adv3_cross(A, dv(x), dv(x + 3))); }
static void p_len2(const double *x, double *o) { o[0] = v3_len2(pv(x)); }
static void d_len2(ad_arena *A, const ad *x, ad *o) { o[0] = adv3_len2(A, dv(x)); }
static void p_length(const double *x, double *o) { o[0] = v3_len(pv(x)); }
static void d_length(ad_arena *A, const ad *x, ad *o) { o[0] = adv3_length(A, dv(x)); }
static void p_normalize(const double *x, double *o) { put3(o, v3_normalize(pv(x))); }
static void d_normalize(ad_arena *A, const ad *x, ad *o) { putd3(o, adv3_normalize(A, dv(x))); }
static void p_reflect(const double *x, double *o) { put3(o, v3_reflect(pv(x), pv(x + 3))); }
static void d_reflect(ad_arena *A, const ad *x, ad *o) { putd3(o, adv3_reflect(A, dv(x), dv(x + 3))); }
static void p_addsub(const double *x, double *o) {
  put3(o, v3_sub(v3_add(pv(x), v3_scale(pv(x + 3), -0.5)), v3_neg(v3_scale(pv(x), 2.0))));
}
static void d_addsub(ad_arena *A, const ad *x, ad *o) {
  adv3 a = dv(x), b = dv(x + 3);
  putd3(o, adv3_sub(A, adv3_add(A, a, adv3_scale_s(A, b, -0.5)), adv3_neg(A, adv3_scale_s(A, a, 2.0))));
}
static void p_fma3(const double *x, double *o) { put3(o, v3_fma(pv(x), pv(x + 3), x[6] * x[6])); }
static void d_fma3(ad_arena *A, const ad *x, ad *o) {
  putd3(o, adv3_fma(A, dv(x), dv(x + 3), ad_sqr(A, x[6])));
}
static void p_scale(const double *x, double *o) { put3(o, v3_scale(pv(x), x[3])); }
static void d_scale(ad_arena *A, const ad *x, ad *o) { putd3(o, adv3_scale(A, dv(x), x[3])); }

/* Plain refraction with the same conventions as adv3_refract (written from
 * the textbook formula, independently of the dual code). It runs in long
 * double: next to the critical angle, cos_t = sqrt(1 - (1 - c^2)/e^2) loses
 * digits to cancellation, and the extra precision (x87: 11 bits) keeps the
 * finite-difference reference below 1e-8 relative noise down to
 * cos_t^2 = 1e-5 (see s_refract). */
static int plain_refract(vec3 wi, vec3 n, double eta, vec3 *wt) {
  long double cos_i = (long double)wi.x * n.x + (long double)wi.y * n.y + (long double)wi.z * n.z;
  long double e = eta, sn = 1.0L;
  if (cos_i < 0.0L) {
    e = 1.0L / e;
    cos_i = -cos_i;
    sn = -1.0L;
  }
  long double sin2_t = (1.0L - cos_i * cos_i) / (e * e);
  if (sin2_t >= 1.0L) return 0;
  long double cos_t = sqrtl(1.0L - sin2_t);
  long double k = sn * (cos_i / e - cos_t);
  *wt = v3((double)(-wi.x / e + k * n.x), (double)(-wi.y / e + k * n.y), (double)(-wi.z / e + k * n.z));
  return 1;
}
static double g_eta = 1.5;
static void p_refract(const double *x, double *o) {
  vec3 wt = v3(0.0, 0.0, 0.0);
  plain_refract(pv(x), pv(x + 3), g_eta, &wt);
  put3(o, wt);
}
static void d_refract(ad_arena *A, const ad *x, ad *o) {
  adv3 wt;
  int ok = adv3_refract(A, dv(x), dv(x + 3), g_eta, &wt);
  assert_true(ok);
  putd3(o, wt);
}

static void p_frame(const double *x, double *o) {
  frame f = frame_from_z(pv(x));
  put3(o, f.s);
  put3(o + 3, f.t);
  put3(o + 6, f.n);
}
static void d_frame(ad_arena *A, const ad *x, ad *o) {
  ad_frame f = adv3_frame_from_z(A, dv(x));
  putd3(o, f.s);
  putd3(o + 3, f.t);
  putd3(o + 6, f.n);
}

/* A world vector from local coordinates v in the frame of normalize(m). */
static void p_to_world(const double *x, double *o) {
  frame f = frame_from_z(v3_normalize(pv(x)));
  put3(o, frame_to_world(&f, pv(x + 3)));
}
static void d_to_world(ad_arena *A, const ad *x, ad *o) {
  ad_frame f = adv3_frame_from_z(A, adv3_normalize(A, dv(x)));
  putd3(o, adv3_to_world(A, &f, dv(x + 3)));
}

static vec3 rnd_dir(trng *r) {
  double z = uni(r, -1.0, 1.0), phi = uni(r, 0.0, 2.0 * AD_PI);
  double s = sqrt(fmax(0.0, 1.0 - z * z));
  return v3(s * cos(phi), s * sin(phi), z);
}
static int s_vec6(trng *r, double *x, double *len) {
  for (int j = 0; j < 6; j++) {
    x[j] = uni(r, -2.0, 2.0);
    len[j] = 1.0;
  }
  return 1;
}
static int s_vec7(trng *r, double *x, double *len) {
  s_vec6(r, x, len);
  x[6] = uni(r, -2.0, 2.0);
  len[6] = 1.0;
  return 1;
}
static int s_vec4(trng *r, double *x, double *len) { return s_vec6(r, x, len); }
static int s_vec3_scaled(trng *r, double *x, double *len) {
  vec3 d = v3_scale(rnd_dir(r), logu(r, -3.0, 3.0));
  put3(x, d);
  for (int j = 0; j < 3; j++) len[j] = v3_len(d);
  return 1;
}
static int s_reflect(trng *r, double *x, double *len) {
  put3(x, rnd_dir(r));
  put3(x + 3, rnd_dir(r));
  for (int j = 0; j < 6; j++) len[j] = 1.0;
  return 1;
}
/* Refraction: 30% of the points near the critical angle (from the dense
 * side, cos_t^2 = delta in [1e-5, 0.1], i.e. cos_t down to 0.003); the
 * smoothness length shrinks with cos_t^2 and with the distance to grazing
 * incidence (where the side switches). The relative noise of the
 * difference quotient there is ~eps' / (h cos_t) with h ~ 1e-3 cos_t^2 and
 * eps' the precision of the reference, hence plain_refract in long double;
 * in double the noise would pass 1e-7 already at cos_t^2 ~ 2e-4. */
static int s_refract(trng *r, double *x, double *len) {
  vec3 n = rnd_dir(r);
  frame f = frame_from_z(n);
  double eta_in = 1.0 / g_eta; /* e seen from the int side */
  double c;
  int inside = rnd(r) < 0.5;
  if (inside && rnd(r) < 0.6) {
    /* cos_t^2 = 1 - (1 - c^2) / e^2 = delta  =>  c^2 = 1 - e^2 (1 - delta) */
    double delta = logu(r, -5.0, -1.0);
    c = sqrt(1.0 - eta_in * eta_in * (1.0 - delta));
  } else {
    c = logu(r, -4.0, 0.0);
  }
  double phi = uni(r, 0.0, 2.0 * AD_PI), s = sqrt(fmax(0.0, 1.0 - c * c));
  vec3 wl = v3(s * cos(phi), s * sin(phi), inside ? -c : c);
  vec3 wi = frame_to_world(&f, wl);
  double e = inside ? eta_in : g_eta;
  double cos_t2 = 1.0 - (1.0 - c * c) / (e * e);
  if (!(cos_t2 > 0.0)) return 0;
  put3(x, wi);
  put3(x + 3, n);
  double l = fmin(1.0, fmin(0.2 * cos_t2, 0.2 * c));
  for (int j = 0; j < 6; j++) len[j] = l;
  return 1;
}
static int s_frame(trng *r, double *x, double *len) {
  vec3 n = rnd_dir(r);
  if (rnd(r) < 0.3) { /* near the poles and the equator */
    double z = rnd(r) < 0.5 ? sgn(r) * (1.0 - logu(r, -12.0, -1.0)) : sgn(r) * logu(r, -6.0, -1.0);
    double phi = uni(r, 0.0, 2.0 * AD_PI), s = sqrt(fmax(0.0, 1.0 - z * z));
    n = v3(s * cos(phi), s * sin(phi), z);
  }
  put3(x, n);
  for (int j = 0; j < 3; j++) len[j] = fmin(1.0, 0.2 * fabs(n.z));
  return n.z != 0.0;
}

/* m near the unit sphere (the frame's poles as in s_frame), v in a box. */
static int s_to_world(trng *r, double *x, double *len) {
  if (!s_frame(r, x, len)) return 0;
  for (int j = 3; j < 6; j++) {
    x[j] = uni(r, -2.0, 2.0);
    len[j] = 1.0;
  }
  return 1;
}

static void test_vec3(void **state) {
  const tcase cases[] = {
      {"dot", 6, 1, p_dot, d_dot, s_vec6},
      {"cross", 6, 3, p_cross, d_cross, s_vec6},
      {"add_sub_neg", 6, 3, p_addsub, d_addsub, s_vec6},
      {"vec_fma", 7, 3, p_fma3, d_fma3, s_vec7},
      {"vec_scale", 4, 3, p_scale, d_scale, s_vec4},
      {"len2", 3, 1, p_len2, d_len2, s_vec3_scaled},
      {"length", 3, 1, p_length, d_length, s_vec3_scaled},
      {"normalize", 3, 3, p_normalize, d_normalize, s_vec3_scaled},
      {"reflect", 6, 3, p_reflect, d_reflect, s_reflect},
      {"frame_from_z", 3, 9, p_frame, d_frame, s_frame},
      {"to_world", 6, 3, p_to_world, d_to_world, s_to_world},
  };
  run_cases_order(cases, (int)(sizeof cases / sizeof cases[0]), 3003, test_order(state));
}

static void test_refract(void **state) {
  const tcase c = {"refract", 6, 3, p_refract, d_refract, s_refract};
  const double etas[] = {1.5, 1.33, 2.4, 0.8};
  for (int i = 0; i < 4; i++) {
    g_eta = etas[i];
    printf(" eta %.2f\n", g_eta);
    run_cases_order(&c, 1, 4004 + (uint64_t)i, test_order(state));
  }
}

/* Total internal reflection is reported exactly where the plain formula
 * reports it. */
static void test_refract_tir(void **state) {
  (void)state;
  trng r = {77};
  static double buf[64];
  ad_arena A;
  assert_int_equal(ad_arena_init(&A, buf, 64, 0), 0);
  int tir = 0, agree = 0, total = 20000;
  for (int i = 0; i < total; i++) {
    vec3 wi = rnd_dir(&r), n = rnd_dir(&r), wt = v3(0, 0, 0);
    double eta = uni(&r, 1.05, 2.5);
    ad_arena_reset(&A);
    adv3 dwt;
    int ok_p = plain_refract(wi, n, eta, &wt);
    int ok_d = adv3_refract(&A, adv3_const(&A, wi.x, wi.y, wi.z), adv3_const(&A, n.x, n.y, n.z), eta, &dwt);
    tir += !ok_p;
    agree += ok_p == ok_d;
  }
  assert_int_equal(agree, total);
  assert_true(tir > 1000); /* a good share of samples is in TIR */
}

/* ---- A composite with five independent variables. ---------------------------
 * A GGX-like microfacet evaluation driven by u in [0,1)^5: wi from (u0, u1),
 * the shading normal tilted by (u2, u3), roughness from u4; the result uses
 * normalize, frame_from_z, to_local, dot, sqrt, sin, cos, div, pow, atan2,
 * erf. Smoothness length 1e-3 in u (the sharpest feature, the GGX peak at
 * alpha = 0.1, is ~1e-2 wide in u). */
static double g_comp_cos; /* min of the two local cosines at the last p_comp */
static void p_comp(const double *u, double *o) {
  double phi = 2.0 * AD_PI * u[0], ct = sqrt(1.0 - u[1]), st = sqrt(u[1]);
  vec3 wi = v3(st * cos(phi), st * sin(phi), ct);
  vec3 n = v3_normalize(v3(u[2] - 0.5, u[3] - 0.5, 1.0));
  frame f = frame_from_z(n);
  vec3 wo = v3_normalize(v3(0.3, -0.2, 1.0));
  vec3 wil = frame_to_local(&f, wi), wol = frame_to_local(&f, wo);
  vec3 h = v3_normalize(v3_add(wil, wol));
  double alpha = 0.1 + 0.5 * u[4], a2 = alpha * alpha;
  double t = h.z * h.z * (a2 - 1.0) + 1.0;
  double D = a2 / (AD_PI * t * t);
  double F = 0.04 + 0.96 * pow(1.0 - v3_dot(wol, h), 5.0);
  o[0] = D * F / (4.0 * wil.z * wol.z);
  o[1] = atan2(wil.z, wol.z) + erf(alpha);
  g_comp_cos = fmin(wil.z, wol.z);
}
static void d_comp(ad_arena *A, const ad *u, ad *o) {
  ad phi = ad_mul_s(A, u[0], 2.0 * AD_PI);
  ad ct = ad_sqrt(A, ad_s_sub(A, 1.0, u[1])), st = ad_sqrt(A, u[1]);
  adv3 wi = adv3_make(ad_mul(A, st, ad_cos(A, phi)), ad_mul(A, st, ad_sin(A, phi)), ct);
  adv3 n = adv3_normalize(A, adv3_make(ad_sub_s(A, u[2], 0.5), ad_sub_s(A, u[3], 0.5), ad_const(A, 1.0)));
  ad_frame f = adv3_frame_from_z(A, n);
  vec3 wo0 = v3_normalize(v3(0.3, -0.2, 1.0));
  adv3 wo = adv3_const(A, wo0.x, wo0.y, wo0.z);
  adv3 wil = adv3_to_local(A, &f, wi), wol = adv3_to_local(A, &f, wo);
  adv3 h = adv3_normalize(A, adv3_add(A, wil, wol));
  ad alpha = ad_add_s(A, ad_mul_s(A, u[4], 0.5), 0.1), a2 = ad_sqr(A, alpha);
  ad t = ad_fma_s(A, ad_sqr(A, h.z), ad_sub_s(A, a2, 1.0), 1.0);
  ad D = ad_div(A, a2, ad_mul_s(A, ad_sqr(A, t), AD_PI));
  ad F = ad_add_s(A, ad_mul_s(A, ad_pow_s(A, ad_s_sub(A, 1.0, adv3_dot(A, wol, h)), 5.0), 0.96), 0.04);
  o[0] = ad_div(A, ad_mul(A, D, F), ad_mul_s(A, ad_mul(A, wil.z, wol.z), 4.0));
  o[1] = ad_add(A, ad_atan2(A, wil.z, wol.z), ad_erf(A, alpha));
}
static int s_comp(trng *r, double *u, double *len) {
  for (int j = 0; j < 5; j++) {
    u[j] = uni(r, 0.02, 0.98);
    len[j] = 1e-3;
  }
  /* keep away from grazing directions (where a local cosine changes sign) */
  double x[2];
  p_comp(u, x);
  return g_comp_cos > 0.05;
}

static void test_composite_n5(void **state) {
  const tcase c = {"ggx_n5", 5, 2, p_comp, d_comp, s_comp};
  run_cases_order(&c, 1, 5005, test_order(state));
}

/* Frame round trip: to_world(to_local(v)) = v, with identity derivative in v
 * and zero derivative in the normal. */
static void test_frame_roundtrip(void **state) {
  (void)state;
  trng r = {99};
  int checked = 0;
  for (int i = 0; i < 2000; i++) {
    ad_arena A;
    assert_int_equal(ad_arena_init(&A, g_arena_buf, sizeof g_arena_buf / sizeof(double), 6), 0);
    /* n on the sphere for every value of the variables: normalize(m) */
    vec3 n = v3_scale(rnd_dir(&r), uni(&r, 0.5, 2.0));
    adv3 dn = adv3_normalize(&A, adv3_var(&A, n.x, n.y, n.z, 0));
    adv3 v = adv3_var(&A, uni(&r, -1, 1), uni(&r, -1, 1), uni(&r, -1, 1), 3);
    ad_frame f = adv3_frame_from_z(&A, dn);
    adv3 back = adv3_to_world(&A, &f, adv3_to_local(&A, &f, v));
    ad c[3] = {back.x, back.y, back.z}, o[3] = {v.x, v.y, v.z};
    for (int k = 0; k < 3; k++) {
      assert_true(fabs(c[k].v - o[k].v) < 1e-14);
      for (int j = 0; j < 6; j++) {
        double expect = (j == 3 + k) ? 1.0 : 0.0;
        assert_true(fabs(ad_deriv(&A, c[k], j) - expect) < 1e-13);
        checked++;
      }
    }
    /* the frame is orthonormal in value and stays so to first order */
    ad st = adv3_dot(&A, f.s, f.t), ss = adv3_len2(&A, f.s);
    assert_true(fabs(st.v) < 1e-14 && fabs(ss.v - 1.0) < 1e-14);
    for (int j = 0; j < 3; j++) {
      /* orthonormality holds for all m, so its derivative vanishes */
      assert_true(fabs(ad_deriv(&A, st, j)) < 1e-12 && fabs(ad_deriv(&A, ss, j)) < 1e-12);
      checked++;
    }
  }
  assert_int_equal(checked, 2000 * 21);
}

/* ---- Arena behaviour, constants, lifting. ----------------------------------- */
static void test_arena(void **state) {
  (void)state;
  double buf[4 * 8];
  ad_arena A;
  assert_int_equal(ad_arena_init(&A, buf, 32, AD_CAPACITY + 1), -1);
  assert_int_equal(ad_arena_init(&A, buf, 32, 5), 0); /* lanes 8: zero + 3 duals */
  ad x = ad_var(&A, 2.0, 0), y = ad_var(&A, 3.0, 4);
  ad p = ad_mul(&A, x, y);
  assert_true(ad_arena_ok(&A));
  assert_true(ad_deriv(&A, p, 0) == 3.0 && ad_deriv(&A, p, 4) == 2.0 && ad_deriv(&A, p, 1) == 0.0);
  /* The next allocation overflows: the value stays exact, derivatives go. */
  ad q = ad_exp(&A, p);
  assert_false(ad_arena_ok(&A));
  assert_int_equal(ad_arena_n(&A), 0);
  assert_true(q.v == exp(6.0));
  ad s = ad_sin(&A, ad_add(&A, q, x));
  assert_true(s.v == sin(exp(6.0) + 2.0));
  assert_true(ad_deriv(&A, s, 0) == 0.0);
  ad_arena_reset(&A);
  assert_true(ad_arena_ok(&A));
  assert_int_equal(ad_arena_n(&A), 5);

  /* Rewind keeping one result: its tangent moves down to the mark. */
  double big[1024];
  assert_int_equal(ad_arena_init(&A, big, 1024, 3), 0);
  ad u = ad_var(&A, 0.7, 1);
  size_t mark = ad_arena_mark(&A);
  ad t = u;
  for (int i = 0; i < 50; i++) t = ad_mul_s(&A, ad_add_s(&A, t, 0.1), 0.9);
  double tv = t.v, td = ad_deriv(&A, t, 1);
  ad kept = ad_arena_rewind_keep(&A, mark, t);
  assert_true(kept.v == tv && ad_deriv(&A, kept, 1) == td && ad_deriv(&A, kept, 0) == 0.0);
  assert_int_equal(ad_arena_mark(&A), mark + 4);
  assert_true(fabs(td - pow(0.9, 50)) < 1e-15);
  /* An older dual is kept without a move. */
  ad old = ad_arena_rewind_keep(&A, mark, u);
  assert_true(old.d == u.d);
  assert_int_equal(ad_arena_mark(&A), mark);

  /* n = 0: plain values, no tangent storage. */
  double none[1];
  assert_int_equal(ad_arena_init(&A, none, 0, 0), 0);
  ad z = ad_div(&A, ad_sqrt(&A, ad_var(&A, 9.0, 0)), ad_const(&A, 2.0));
  assert_true(z.v == 1.5 && ad_arena_ok(&A) && ad_arena_n(&A) == 0);

  /* Lifting: a double becomes a constant, a dual passes through. */
  assert_int_equal(ad_arena_init(&A, big, 1024, 2), 0);
  ad a = ad_var(&A, 1.25, 1);
  ad l1 = AD_LIFT(&A, 4.0), l2 = AD_LIFT(&A, a);
  assert_true(l1.v == 4.0 && ad_deriv(&A, l1, 1) == 0.0);
  assert_true(l2.v == 1.25 && ad_deriv(&A, l2, 1) == 1.0);
  double tangent[2] = {0.5, -2.0};
  ad m = ad_make(&A, 3.0, tangent);
  assert_true(ad_deriv(&A, m, 0) == 0.5 && ad_deriv(&A, m, 1) == -2.0);
}

/* Edge values: safe_sqrt, fabs, pow at 0; erfinv's own accuracy. */
static void test_edges(void **state) {
  (void)state;
  double buf[64];
  ad_arena A;
  assert_int_equal(ad_arena_init(&A, buf, 64, 1), 0);
  ad z = ad_var(&A, 0.0, 0), m = ad_var(&A, -1e-3, 0);
  assert_true(ad_safe_sqrt(&A, z).v == 0.0 && ad_deriv(&A, ad_safe_sqrt(&A, z), 0) == 0.0);
  assert_true(ad_safe_sqrt(&A, m).v == 0.0 && ad_deriv(&A, ad_safe_sqrt(&A, m), 0) == 0.0);
  assert_true(isinf(ad_deriv(&A, ad_sqrt(&A, z), 0)));
  assert_true(ad_deriv(&A, ad_fabs(&A, z), 0) == 0.0);
  assert_true(ad_deriv(&A, ad_pow_s(&A, z, 2.0), 0) == 0.0);
  assert_true(ad_deriv(&A, ad_pow_s(&A, z, 0.0), 0) == 0.0);
  ad pz = ad_pow(&A, z, ad_const(&A, 3.0));
  assert_true(pz.v == 0.0 && ad_deriv(&A, pz, 0) == 0.0);
  assert_true(ad_deriv(&A, ad_floor(&A, ad_var(&A, 2.5, 0)), 0) == 0.0);
  ad_arena_reset(&A);

  /* erfinv: special values, round trips in the body and in the tails. */
  assert_true(ad_erfinv_scalar(0.0) == 0.0 && isinf(ad_erfinv_scalar(1.0)) &&
              ad_erfinv_scalar(-1.0) < 0.0 && isnan(ad_erfinv_scalar(1.5)) &&
              isnan(ad_erfinv_scalar(NAN)));
  assert_true(fabs(ad_erfinv_scalar(1e-300) / (AD_SQRTPI_2 * 1e-300) - 1.0) < 1e-15);
  trng r = {5};
  double worst_body = 0.0, worst_tail = 0.0;
  int count = 0;
  for (int i = 0; i < 20000; i++) {
    double y = uni(&r, -1.0, 1.0);
    double x = ad_erfinv_scalar(y);
    /* |erf(x) - y| relative to the conditioning: one ulp of x moves erf by
     * erf'(x) ulp(x); allow 4 of those plus 2 ulp of y. */
    double tol = 4.0 * AD_2_SQRTPI * exp(-x * x) * fabs(x) * 2.2e-16 + 4.5e-16 * fabs(y) + 1e-300;
    worst_body = fmax(worst_body, fabs(erf(x) - y) / tol);
    double q = logu(&r, -15.5, -0.31); /* 1 - y in (3e-16, 0.49) */
    double yt = 1.0 - q;
    q = 1.0 - yt; /* exact: the q that yt represents */
    double xt = ad_erfinv_scalar(yt);
    worst_tail = fmax(worst_tail, fabs(erfc(xt) - q) / (q * 1e-13));
    count++;
  }
  printf("  erfinv: worst body error %.2f of tolerance, tail %.2f\n", worst_body, worst_tail);
  assert_true(worst_body <= 1.0);
  assert_true(worst_tail <= 1.0);
  assert_int_equal(count, 20000);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_arena),        cmocka_unit_test(test_edges),
      cmocka_unit_test(test_unary),        cmocka_unit_test(test_binary),
      cmocka_unit_test(test_vec3),         cmocka_unit_test(test_refract),
      cmocka_unit_test(test_refract_tir),  cmocka_unit_test(test_composite_n5),
      cmocka_unit_test(test_frame_roundtrip),
      /* The same tables at second order: Hessians against differences of
       * the gradient. */
      cmocka_unit_test_prestate(test_unary, &k_order2),
      cmocka_unit_test_prestate(test_binary, &k_order2),
      cmocka_unit_test_prestate(test_vec3, &k_order2),
      cmocka_unit_test_prestate(test_refract, &k_order2),
      cmocka_unit_test_prestate(test_composite_n5, &k_order2),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
