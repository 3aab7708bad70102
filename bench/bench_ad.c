/*
 * bench_ad.c: cost of forward-mode AD (src/ad) on a realistic formula.
 *
 * The formula is a GGX microfacet BSDF evaluation driven by five primary
 * samples u: wi from (u0, u1) (cosine-weighted mapping), wo from the tilted
 * vector (u2 - 1/2, u3 - 1/2, 1), roughness from u4; it computes the half
 * vector, the GGX distribution D, Smith's separable G1(wi) G1(wo), Schlick's
 * Fresnel F and f = D G F / (4 cos_i cos_o): about 70 elementary operations.
 *
 * It is written once (GGX_BODY, over a table of operation macros) and
 * instantiated three times:
 *   plain   doubles;
 *   arena   the chosen design of src/ad/dual.h: { v, const double *d } with
 *           tangents in an ad_arena, for n = 0, 3, 8, 32, 96;
 *   fixed   the rejected design: { v, n, d[AD_CAPACITY] } returned by value
 *           (same padded, vectorisable loops), for the same n.
 * Prints ns per evaluation and the ratio to plain doubles. Not part of ctest.
 */
#include <math.h>
#include <stdio.h>
#include <time.h>

#include "ad/dual.h"
#include "ad/dual_math.h"

/* ---- The formula, generic over the arithmetic. ---------------------------- */
#define GGX_BODY(T, X, MUL, ADD, DIV, SQRT, SIN, COS, MULS, ADDS, SSUB)                        \
  T phi = MULS(X[0], 2.0 * AD_PI);                                                             \
  T st = SQRT(X[1]), ct = SQRT(SSUB(1.0, X[1]));                                               \
  T wix = MUL(st, COS(phi)), wiy = MUL(st, SIN(phi)), wiz = ct;                                \
  /* wo = normalize(u2 - 1/2, u3 - 1/2, 1) */                                                  \
  T ox = ADDS(X[2], -0.5), oy = ADDS(X[3], -0.5);                                              \
  T ol = SQRT(ADDS(ADD(MUL(ox, ox), MUL(oy, oy)), 1.0));                                       \
  T wox = DIV(ox, ol), woy = DIV(oy, ol), woz = DIV(ADDS(MULS(ol, 0.0), 1.0), ol);             \
  /* half vector */                                                                            \
  T hx = ADD(wix, wox), hy = ADD(wiy, woy), hz = ADD(wiz, woz);                                \
  T hl = SQRT(ADD(ADD(MUL(hx, hx), MUL(hy, hy)), MUL(hz, hz)));                                \
  hx = DIV(hx, hl);                                                                            \
  hy = DIV(hy, hl);                                                                            \
  hz = DIV(hz, hl);                                                                            \
  /* D = a2 / (pi (hz^2 (a2 - 1) + 1)^2) */                                                    \
  T alpha = ADDS(MULS(X[4], 0.5), 0.1), a2 = MUL(alpha, alpha);                                \
  T t = ADDS(MUL(MUL(hz, hz), ADDS(a2, -1.0)), 1.0);                                           \
  T D = DIV(a2, MULS(MUL(t, t), AD_PI));                                                       \
  /* G1(w) = 2 / (1 + sqrt(1 + a2 (1 - c^2) / c^2)) */                                         \
  T ci2 = MUL(wiz, wiz), co2 = MUL(woz, woz);                                                  \
  T gi = DIV(MULS(ci2, 2.0), ADD(ci2, SQRT(ADD(ci2, MUL(a2, SSUB(1.0, ci2))))));               \
  T go = DIV(MULS(co2, 2.0), ADD(co2, SQRT(ADD(co2, MUL(a2, SSUB(1.0, co2))))));               \
  /* F = 0.04 + 0.96 (1 - wi . h)^5 */                                                         \
  T m = SSUB(1.0, ADD(ADD(MUL(wix, hx), MUL(wiy, hy)), MUL(wiz, hz)));                         \
  T m2 = MUL(m, m);                                                                            \
  T F = ADDS(MULS(MUL(MUL(m2, m2), m), 0.96), 0.04);                                           \
  T f = DIV(MUL(MUL(D, MUL(gi, go)), F), MULS(MUL(wiz, woz), 4.0));

/* ---- Plain doubles. -------------------------------------------------------- */
#define P_MUL(a, b) ((a) * (b))
#define P_ADD(a, b) ((a) + (b))
#define P_DIV(a, b) ((a) / (b))
#define P_MULS(a, s) ((a) * (s))
#define P_ADDS(a, s) ((a) + (s))
#define P_SSUB(s, a) ((s) - (a))

static double ggx_plain(const double *u) {
  GGX_BODY(double, u, P_MUL, P_ADD, P_DIV, sqrt, sin, cos, P_MULS, P_ADDS, P_SSUB)
  return f;
}

/* ---- The arena design (src/ad). ------------------------------------------- */
#define A_MUL(a, b) ad_mul(A, a, b)
#define A_ADD(a, b) ad_add(A, a, b)
#define A_DIV(a, b) ad_div(A, a, b)
#define A_SQRT(a) ad_sqrt(A, a)
#define A_SIN(a) ad_sin(A, a)
#define A_COS(a) ad_cos(A, a)
#define A_MULS(a, s) ad_mul_s(A, a, s)
#define A_ADDS(a, s) ad_add_s(A, a, s)
#define A_SSUB(s, a) ad_s_sub(A, s, a)

static double ggx_arena(ad_arena *A, const double *u) {
  ad_arena_reset(A);
  ad x[5];
  for (int i = 0; i < 5; i++) x[i] = ad_var(A, u[i], i);
  GGX_BODY(ad, x, A_MUL, A_ADD, A_DIV, A_SQRT, A_SIN, A_COS, A_MULS, A_ADDS, A_SSUB)
  double s = f.v;
  for (int k = 0; k < ad_arena_n(A); k++) s += f.d[k];
  return s;
}

/* ---- The fixed-array design (for comparison only). ------------------------ */
typedef struct fx {
  double v;
  int n;
  double d[AD_CAPACITY];
} fx;

static inline size_t fx_m(int n) { return ((size_t)n + AD_LANES - 1) & ~(size_t)(AD_LANES - 1); }
static inline fx fx_lin2(double v, double ca, const fx *a, double cb, const fx *b) {
  fx r;
  r.v = v;
  r.n = a->n;
  size_t m = fx_m(a->n);
  for (size_t k = 0; k < m; k++) r.d[k] = ca * a->d[k] + cb * b->d[k];
  return r;
}
static inline fx fx_lin1(double v, double ca, const fx *a) {
  fx r;
  r.v = v;
  r.n = a->n;
  size_t m = fx_m(a->n);
  for (size_t k = 0; k < m; k++) r.d[k] = ca * a->d[k];
  return r;
}
static inline fx fx_var(double v, int i, int n) {
  fx r;
  r.v = v;
  r.n = n;
  size_t m = fx_m(n);
  for (size_t k = 0; k < m; k++) r.d[k] = 0.0;
  if (i < n) r.d[i] = 1.0;
  return r;
}
static inline fx fx_mul(fx a, fx b) { return fx_lin2(a.v * b.v, b.v, &a, a.v, &b); }
static inline fx fx_add(fx a, fx b) { return fx_lin2(a.v + b.v, 1.0, &a, 1.0, &b); }
static inline fx fx_div(fx a, fx b) {
  double q = a.v / b.v;
  return fx_lin2(q, 1.0 / b.v, &a, -q / b.v, &b);
}
static inline fx fx_sqrt(fx a) {
  double r = sqrt(a.v);
  return fx_lin1(r, 0.5 / r, &a);
}
static inline fx fx_sin(fx a) { return fx_lin1(sin(a.v), cos(a.v), &a); }
static inline fx fx_cos(fx a) { return fx_lin1(cos(a.v), -sin(a.v), &a); }
static inline fx fx_muls(fx a, double s) { return fx_lin1(a.v * s, s, &a); }
static inline fx fx_adds(fx a, double s) {
  a.v += s;
  return a;
}
static inline fx fx_ssub(double s, fx a) { return fx_lin1(s - a.v, -1.0, &a); }

static double ggx_fixed(const double *u, int n) {
  fx x[5];
  for (int i = 0; i < 5; i++) x[i] = fx_var(u[i], i, n);
  GGX_BODY(fx, x, fx_mul, fx_add, fx_div, fx_sqrt, fx_sin, fx_cos, fx_muls, fx_adds,
           fx_ssub)
  double s = f.v;
  for (int k = 0; k < n; k++) s += f.d[k];
  return s;
}

/* ---- Timing. --------------------------------------------------------------- */
static double now(void) {
  struct timespec ts;
  timespec_get(&ts, TIME_UTC);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The 5 inputs of evaluation i: a cheap low-discrepancy walk in [0.05, 0.95). */
static void inputs(long i, double *u) {
  static const double step[5] = {0.6180339887, 0.7548776662, 0.5698402910, 0.4142135624,
                                 0.3247179572};
  for (int j = 0; j < 5; j++) {
    double t = (double)i * step[j];
    u[j] = 0.05 + 0.9 * (t - floor(t));
  }
}

static double g_sink;

int main(void) {
  static double buf[1 << 16];
  const int ns[] = {0, 3, 8, 32, 96};
  const long N = 200000;
  double u[5], acc = 0.0;

  /* Plain doubles, best of 3 runs. */
  double t_plain = 1e30;
  for (int rep = 0; rep < 3; rep++) {
    double t0 = now();
    for (long i = 0; i < N; i++) {
      inputs(i, u);
      acc += ggx_plain(u);
    }
    t_plain = fmin(t_plain, (now() - t0) / (double)N * 1e9);
  }
  printf("GGX BSDF evaluation (~70 operations), ns per evaluation (best of 3, %ld evals)\n", N);
  printf("%-8s %10s %8s %10s %8s\n", "n", "arena", "x plain", "fixed", "x plain");
  printf("%-8s %10.1f %8.2f\n", "plain", t_plain, 1.0);

  for (size_t c = 0; c < sizeof ns / sizeof ns[0]; c++) {
    int n = ns[c];
    ad_arena A;
    if (ad_arena_init(&A, buf, sizeof buf / sizeof buf[0], n) != 0) return 1;
    double t_arena = 1e30, t_fixed = 1e30;
    for (int rep = 0; rep < 3; rep++) {
      double t0 = now();
      for (long i = 0; i < N; i++) {
        inputs(i, u);
        acc += ggx_arena(&A, u);
      }
      t_arena = fmin(t_arena, (now() - t0) / (double)N * 1e9);
      t0 = now();
      for (long i = 0; i < N / 4; i++) {
        inputs(i, u);
        acc += ggx_fixed(u, n);
      }
      t_fixed = fmin(t_fixed, (now() - t0) / (double)(N / 4) * 1e9);
    }
    if (!ad_arena_ok(&A)) return 1;
    printf("%-8d %10.1f %8.2f %10.1f %8.2f\n", n, t_arena, t_arena / t_plain, t_fixed,
           t_fixed / t_plain);
  }
  g_sink = acc;
  printf("(checksum %g)\n", g_sink);
  return 0;
}
