/*
 * dual.h: forward-mode automatic differentiation with dual numbers whose
 * tangent has a runtime length.
 *
 * A dual number x = (v, d) carries a value v and a tangent d = dv/du, the
 * derivatives of v with respect to n independent variables u_0 .. u_{n-1}
 * (for lmc: the primary sample coordinates of a path). Every operation
 * f(x, y) returns (f(v_x, v_y), f_x d_x + f_y d_y): the chain rule. Each
 * operation below documents its partial derivatives f_x, f_y next to its code.
 *
 * Representation. `ad` is { double v; const double *d; }: the tangent is a
 * view into an `ad_arena`, a caller-provided bump allocator that also holds
 * the tangent length n shared by all duals of one evaluation. We measured
 * the alternative (a fixed `double d[AD_CAPACITY]` inside each dual, returned
 * by value) in bench/bench_ad.c: every operation then copies the whole
 * 1 KB struct, which costs ~30x plain arithmetic even for n = 0 and stays
 * 2x slower than the arena at n = 96. With the arena, an operation costs one
 * pointer bump plus a loop over n, and n = 0 costs about twice plain doubles.
 *
 * Invariants and conventions:
 * - All duals combined in one operation come from the same arena.
 * - Tangents are immutable once made; operations may share them (ad_add_s
 *   returns the tangent of its argument), so never write through .d.
 * - Tangents are padded to a multiple of AD_LANES doubles. The loops run
 *   over blocks of AD_LANES with a constant inner trip count, so GCC -O2
 *   packs them into SIMD instructions without a scalar epilogue or alias
 *   checks (the kernels take `restrict` pointers: a fresh allocation never
 *   aliases its inputs).
 *   Padding lanes hold finite junk or zeros and are never meaningful.
 * - Branches look at .v only; comparisons are on values.
 * - If the arena runs out of room, it records the overflow, sets its tangent
 *   length to 0 and carries on: values stay exact, derivatives are lost
 *   until ad_arena_reset. Check ad_arena_ok before reading a gradient.
 * - Mixed forms carry a suffix: ad_mul_s(dual, scalar), ad_s_sub(scalar,
 *   dual). AD_LIFT is the one _Generic macro: it turns a double or an ad
 *   into an ad.
 *
 * AD_CAPACITY = 128 bounds n. A bidirectional (MMLT) state with up to 16
 * vertices in each subpath uses about 2 (film) + 16 x 3 (camera subpath:
 * direction pair and lobe choice per bounce) + 4 + 16 x 3 (light subpath:
 * emission position and direction, then per bounce) + a technique choice
 * ~ 103 primary sample coordinates; 128 is the next multiple of AD_LANES
 * with room to spare. The cost of an evaluation scales with the n actually
 * used, never with the capacity.
 *
 * Second order. An arena made with ad_arena_init2 gives every dual the
 * Hessian H = d^2 v / du^2 as well, stored after the gradient in the same
 * tangent block: the lower triangle, row by row (entry (i, j), i <= j, at
 * j (j + 1) / 2 + i), padded to AD_LANES, then a header lane group whose
 * first double is the dual's width w: the number of leading variables its
 * value may depend on (0 for constants, index + 1 for variable `index`, the
 * largest width of the operands for a result). Only the first pad(w)
 * gradient entries and pad(w (w + 1) / 2) Hessian entries of a block are
 * written and read (zero beyond w); with this layout a width-w Hessian is
 * the first entries of the block. Variables enter a path evaluation in
 * the order it draws its numbers, so the dual of an early vertex has a
 * small width, and an operation costs O(w^2), not O(n^2). The chain rule for
 * f(x, y) is
 *   H_f = f_x H_x + f_y H_y                                   (linear part)
 *       + f_xx g_x g_x^T + f_xy (g_x g_y^T + g_y g_x^T) + f_yy g_y g_y^T
 * with g the gradients. The linear part is the first-order rule applied to
 * the whole block, so the kernels below serve both orders; every operation
 * adds its second-order terms after the linear kernel through ad__h_sq and
 * ad__h_sym, which do nothing in a first-order arena (AD__H2 is false), so
 * the first-order cost and results do not change. One implementation of
 * each path formula thus gives value, gradient and, on request, Hessian
 * (Griewank and Walther, chapter 13, "Taylor and tensor coefficients":
 * the second-order forward mode with dense Hessians). Its cost grows as n^2
 * per nonlinear operation, so AD_H_CAPACITY = 96 bounds n there.
 *
 * Model: Ceres' Jet (value plus tangent, derivative rule per operation,
 * comparisons on the value); see also Griewank and Walther, "Evaluating
 * Derivatives", 2nd ed., 2008, chapter 3 (the forward mode).
 */
#ifndef LMC_AD_DUAL_H
#define LMC_AD_DUAL_H

#include <stddef.h>
#include <string.h>

#define AD_CAPACITY 128  /* largest tangent length n */
#define AD_H_CAPACITY 96 /* largest n of a second-order (Hessian) arena */
#define AD_LANES 4      /* tangents are padded to a multiple of this (AVX width) */

/* A dual number: value and a borrowed view of its tangent in an arena. */
typedef struct ad {
  double v;
  const double *d; /* n derivatives (padded to a multiple of AD_LANES) */
} ad;

/* Bump allocator for tangents. The caller owns the buffer. */
typedef struct ad_arena {
  double *buf;  /* borrowed: cap doubles */
  size_t cap;   /* capacity of buf in doubles */
  size_t top;   /* doubles in use */
  size_t base;  /* buf[0, base) is the zero tangent shared by constants */
  size_t lanes; /* doubles per tangent block (gradient, then Hessian); 0 after overflow */
  size_t glanes; /* doubles of the gradient: n rounded up to AD_LANES */
  size_t woff;   /* second order: offset of the width in a block (after the Hessian) */
  int n;         /* tangent length given to ad_arena_init */
  int order;     /* 1: gradients; 2: gradients and Hessians */
  int overflow;  /* set when an allocation did not fit */
} ad_arena;

/* n rounded up to a multiple of AD_LANES. */
static inline size_t ad__pad(size_t n) { return (n + AD_LANES - 1) & ~(size_t)(AD_LANES - 1); }

/* Doubles of one tangent block of an arena of tangent length n and order. */
static inline size_t ad__block(int n, int order) {
  size_t m = (size_t)(n < 0 ? 0 : n);
  return ad__pad(m) + (order == 2 ? ad__pad(m * (m + 1) / 2) + AD_LANES : 0);
}

/* Doubles of arena storage needed for `count` duals of tangent length n
 * (plus the shared zero tangent). */
static inline size_t ad_arena_size(int n, size_t count) { return ad__block(n, 1) * (count + 1); }

/* The same for a second-order arena (gradients and Hessians). */
static inline size_t ad_arena_size2(int n, size_t count) { return ad__block(n, 2) * (count + 1); }

static inline int ad__arena_init(ad_arena *A, double *buf, size_t cap, int n, int order) {
  A->buf = buf;
  A->cap = cap;
  A->n = n;
  A->order = order;
  A->glanes = ad__pad((size_t)n);
  A->lanes = ad__block(n, order);
  A->woff = order == 2 ? A->lanes - AD_LANES : 0;
  if (cap < A->lanes) return -1;
  memset(buf, 0, A->lanes * sizeof(double));
  A->base = A->lanes;
  A->top = A->base;
  A->overflow = 0;
  return 0;
}

/* Set up A over buf (cap doubles, borrowed, non-NULL) for tangents of length
 * n, 0 <= n <= AD_CAPACITY. Returns 0, or -1 when the arguments are invalid
 * or buf cannot hold the zero tangent. */
static inline int ad_arena_init(ad_arena *A, double *buf, size_t cap, int n) {
  if (!A || !buf || n < 0 || n > AD_CAPACITY) return -1;
  return ad__arena_init(A, buf, cap, n, 1);
}

/* The same for a second-order arena, 0 <= n <= AD_H_CAPACITY: every dual
 * made from it carries its Hessian (ad_hess). */
static inline int ad_arena_init2(ad_arena *A, double *buf, size_t cap, int n) {
  if (!A || !buf || n < 0 || n > AD_H_CAPACITY) return -1;
  return ad__arena_init(A, buf, cap, n, 2);
}

/* Forget every dual made from A (start of a new evaluation). */
static inline void ad_arena_reset(ad_arena *A) {
  A->top = A->base;
  A->overflow = 0;
  A->lanes = ad__block(A->n, A->order);
}

/* 1 while every tangent made since the last reset is valid. */
static inline int ad_arena_ok(const ad_arena *A) { return !A->overflow; }

/* Tangent length of the current evaluation: n, or 0 after an overflow. */
static inline int ad_arena_n(const ad_arena *A) { return A->overflow ? 0 : A->n; }

/* Position to rewind to; duals made after it die at ad_arena_rewind. */
static inline size_t ad_arena_mark(const ad_arena *A) { return A->top; }

static inline void ad_arena_rewind(ad_arena *A, size_t mark) {
  if (mark >= A->base && mark <= A->top) A->top = mark;
}

/* Rewind to mark but keep x: its tangent moves to the mark when it lives
 * above it. Typical use: one bounce of a path makes hundreds of temporaries
 * and hands one throughput to the next bounce. x must come from A. */
static inline ad ad_arena_rewind_keep(ad_arena *A, size_t mark, ad x) {
  if (mark < A->base || mark > A->top) return x;
  size_t at = (size_t)(x.d - A->buf);
  if (at < mark) {
    A->top = mark;
    return x;
  }
  double *dst = A->buf + mark;
  memmove(dst, x.d, A->lanes * sizeof(double));
  A->top = mark + A->lanes;
  return (ad){x.v, dst};
}

/* ---- Internal kernels. Every derivative rule reduces to a linear ---------
 * combination of input tangents, r = c_a d_a + c_b d_b (+ ...), so five
 * loops serve all operations. */

static inline double *ad__alloc(ad_arena *A) {
  if (A->cap - A->top < A->lanes) {
    A->overflow = 1;
    A->lanes = 0;
  }
  double *r = A->buf + A->top;
  A->top += A->lanes;
  return r;
}

/* Tangent length in blocks of AD_LANES doubles. The kernels loop over
 * blocks whose body is written out lane by lane: GCC's SLP vectoriser packs
 * it into SIMD instructions whatever it knows about the block count (a plain
 * loop to n is not vectorised at -O2, and a loop to a masked multiple of 4
 * only where the compiler could still prove the multiple after inlining). */
static inline size_t ad__nb(const ad_arena *A) { return A->lanes / AD_LANES; }

/* One block of AD_LANES (= 4) lanes: EXPR(k) for k = i .. i + 3, written out
 * so that GCC's basic-block (SLP) vectoriser packs it at -O2. */
#define AD__BLOCK(i, STMT) \
  do {                     \
    size_t k_ = (i);       \
    STMT;                  \
    k_++;                  \
    STMT;                  \
    k_++;                  \
    STMT;                  \
    k_++;                  \
    STMT;                  \
  } while (0)

static inline void ad__k1(size_t nb, double *restrict r, double ca, const double *restrict a) {
  for (size_t b = 0; b < nb * AD_LANES; b += AD_LANES)
    AD__BLOCK(b, r[k_] = ca * a[k_]);
}

static inline void ad__k2(size_t nb, double *restrict r, double ca, const double *restrict a,
                          double cb, const double *restrict b) {
  for (size_t i = 0; i < nb * AD_LANES; i += AD_LANES)
    AD__BLOCK(i, r[k_] = ca * a[k_] + cb * b[k_]);
}

static inline void ad__k3(size_t nb, double *restrict r, double ca, const double *restrict a,
                          double cb, const double *restrict b, double cc,
                          const double *restrict c) {
  for (size_t i = 0; i < nb * AD_LANES; i += AD_LANES)
    AD__BLOCK(i, r[k_] = ca * a[k_] + cb * b[k_] + cc * c[k_]);
}

static inline void ad__k4(size_t nb, double *restrict r, const double c[4],
                          const double *restrict a, const double *restrict b,
                          const double *restrict e, const double *restrict f) {
  double c0 = c[0], c1 = c[1], c2 = c[2], c3 = c[3];
  for (size_t i = 0; i < nb * AD_LANES; i += AD_LANES)
    AD__BLOCK(i, r[k_] = c0 * a[k_] + c1 * b[k_] + c2 * e[k_] + c3 * f[k_]);
}

static inline void ad__k6(size_t nb, double *restrict r, const double c[6],
                          const double *restrict a, const double *restrict b,
                          const double *restrict c2, const double *restrict e,
                          const double *restrict f, const double *restrict g) {
  double c0 = c[0], c1 = c[1], c2s = c[2], c3 = c[3], c4 = c[4], c5 = c[5];
  for (size_t i = 0; i < nb * AD_LANES; i += AD_LANES)
    AD__BLOCK(i, r[k_] = c0 * a[k_] + c1 * b[k_] + c2s * c2[k_] + c3 * e[k_] + c4 * f[k_] +
                         c5 * g[k_]);
}

/* True when A carries Hessians (second order, no overflow). */
#define AD__H2(A) ((A)->order == 2 && (A)->lanes != 0)

/* w (w + 1) / 2: Hessian entries of width w. */
static inline size_t ad__tri(size_t w) { return w * (w + 1) / 2; }

/* Width of a tangent of a second-order arena (AD__H2). */
static inline size_t ad__w(const ad_arena *A, const double *d) { return (size_t)d[A->woff]; }

/* Second order: zeroes r's gradient and Hessian entries from width `from`
 * up to width `to` (padded lengths) and gives r width `to`. */
static inline void ad__zero_w(const ad_arena *A, double *r, size_t from, size_t to) {
  for (size_t k = ad__pad(from); k < ad__pad(to); k++) r[k] = 0.0;
  double *H = r + A->glanes;
  for (size_t k = ad__pad(ad__tri(from)); k < ad__pad(ad__tri(to)); k++) H[k] = 0.0;
  r[A->woff] = (double)to;
}

/* Second order: r = sum_i c_i d_i over m <= 6 tangents, gradient and
 * Hessian, each over its operands' widths: the part every operand covers
 * in one pass, the rest operand by operand. */
static inline void ad__lin_w(const ad_arena *A, double *restrict r, int m, const double *c,
                             const double *const *d) {
  size_t w[6], lo = (size_t)-1, hi = 0;
  for (int i = 0; i < m; i++) {
    w[i] = ad__w(A, d[i]);
    if (w[i] < lo) lo = w[i];
    if (w[i] > hi) hi = w[i];
  }
  for (int part = 0; part < 2; part++) {
    size_t off = part ? A->glanes : 0;
    size_t a = part ? ad__pad(ad__tri(lo)) : ad__pad(lo);
    size_t b = part ? ad__pad(ad__tri(hi)) : ad__pad(hi);
    double *restrict rr = r + off;
    size_t nb = a / AD_LANES;
    switch (m) {
    case 1: ad__k1(nb, rr, c[0], d[0] + off); break;
    case 2: ad__k2(nb, rr, c[0], d[0] + off, c[1], d[1] + off); break;
    case 3: ad__k3(nb, rr, c[0], d[0] + off, c[1], d[1] + off, c[2], d[2] + off); break;
    case 4: ad__k4(nb, rr, c, d[0] + off, d[1] + off, d[2] + off, d[3] + off); break;
    default: ad__k6(nb, rr, c, d[0] + off, d[1] + off, d[2] + off, d[3] + off, d[4] + off, d[5] + off);
    }
    if (b > a) {
      /* Summed in the operands' order, as the fused kernels do (the same
       * value up to the sign of a zero). */
      for (size_t k = a; k < b; k += AD_LANES) AD__BLOCK(k, rr[k_] = 0.0);
      for (int i = 0; i < m; i++) {
        size_t e = part ? ad__pad(ad__tri(w[i])) : ad__pad(w[i]);
        const double *restrict di = d[i] + off;
        double ci = c[i];
        for (size_t k = a; k < e; k += AD_LANES) AD__BLOCK(k, rr[k_] += ci * di[k_]);
      }
    }
  }
  r[A->woff] = (double)hi;
}

/* (v, ca d_a) */
static inline ad ad__lin1(ad_arena *A, double v, double ca, ad a) {
  double *r = ad__alloc(A);
  if (AD__H2(A)) {
    const double *d[1] = {a.d};
    ad__lin_w(A, r, 1, &ca, d);
  } else {
    ad__k1(ad__nb(A), r, ca, a.d);
  }
  return (ad){v, r};
}

/* (v, ca d_a + cb d_b) */
static inline ad ad__lin2(ad_arena *A, double v, double ca, ad a, double cb, ad b) {
  double *r = ad__alloc(A);
  if (AD__H2(A)) {
    const double c[2] = {ca, cb}, *d[2] = {a.d, b.d};
    ad__lin_w(A, r, 2, c, d);
  } else {
    ad__k2(ad__nb(A), r, ca, a.d, cb, b.d);
  }
  return (ad){v, r};
}

/* (v, ca d_a + cb d_b + cc d_c) */
static inline ad ad__lin3(ad_arena *A, double v, double ca, ad a, double cb, ad b, double cc,
                          ad c) {
  double *r = ad__alloc(A);
  if (AD__H2(A)) {
    const double cs[3] = {ca, cb, cc}, *d[3] = {a.d, b.d, c.d};
    ad__lin_w(A, r, 3, cs, d);
  } else {
    ad__k3(ad__nb(A), r, ca, a.d, cb, b.d, cc, c.d);
  }
  return (ad){v, r};
}

/* (v, sum_i c_i d_i) over four duals (cross products). */
static inline ad ad__lin4(ad_arena *A, double v, const double c[4], ad a, ad b, ad e, ad f) {
  double *r = ad__alloc(A);
  if (AD__H2(A)) {
    const double *d[4] = {a.d, b.d, e.d, f.d};
    ad__lin_w(A, r, 4, c, d);
  } else {
    ad__k4(ad__nb(A), r, c, a.d, b.d, e.d, f.d);
  }
  return (ad){v, r};
}

/* (v, sum_i c_i d_i) over six duals (dot products). */
static inline ad ad__lin6(ad_arena *A, double v, const double c[6], ad a, ad b, ad cc, ad e,
                          ad f, ad g) {
  double *r = ad__alloc(A);
  if (AD__H2(A)) {
    const double *d[6] = {a.d, b.d, cc.d, e.d, f.d, g.d};
    ad__lin_w(A, r, 6, c, d);
  } else {
    ad__k6(ad__nb(A), r, c, a.d, b.d, cc.d, e.d, f.d, g.d);
  }
  return (ad){v, r};
}

/* ---- Second-order terms ---------------------------------------------------
 * Added to a freshly made result r after its linear kernel; r's block is
 * the caller's own (just allocated), so writing through it is safe. */

/* A loop GCC should vectorise (OpenMP's simd; clang, which reports the
 * loops it cannot vectorise as warnings, goes without). */
#if defined(_OPENMP) && !defined(__clang__)
#define AD__SIMD _Pragma("omp simd")
#else
#define AD__SIMD
#endif

/* Widens r (fresh, the caller's own) to width w: zero gradient and
 * Hessian entries up to w's padded lengths. */
static inline void ad__widen(const ad_arena *A, double *r, size_t w) {
  size_t wr = ad__w(A, r);
  if (wr >= w) return;
  ad__zero_w(A, r, wr, w);
}

/* H_r += c g_x g_x^T (a second derivative f_xx = c). */
static inline void ad__h_sq(const ad_arena *A, ad r, double c, ad x) {
  if (!AD__H2(A) || c == 0.0) return;
  size_t w = ad__w(A, x.d);
  ad__widen(A, (double *)r.d, w);
  double *restrict H = (double *)r.d + A->glanes;
  const double *restrict g = x.d;
  for (size_t j = 0; j < w; j++) {
    double cj = c * g[j];
    if (cj == 0.0) continue;
    double *restrict row = H + ad__tri(j);
    AD__SIMD
    for (size_t i = 0; i <= j; i++) row[i] += cj * g[i];
  }
}

/* H_r += c (g_x g_y^T + g_y g_x^T) (a mixed second derivative f_xy = c). */
static inline void ad__h_sym(const ad_arena *A, ad r, double c, ad x, ad y) {
  if (!AD__H2(A) || c == 0.0) return;
  size_t wx = ad__w(A, x.d), wy = ad__w(A, y.d), w = wx > wy ? wx : wy;
  ad__widen(A, (double *)r.d, w);
  double *restrict H = (double *)r.d + A->glanes;
  /* The narrower gradient, zero up to w (its block holds junk past its width). */
  double pad[AD_H_CAPACITY];
  const double *gx = x.d, *gy = y.d;
  if (wx < w) {
    for (size_t k = 0; k < w; k++) pad[k] = k < wx ? gx[k] : 0.0;
    gx = pad;
  } else if (wy < w) {
    for (size_t k = 0; k < w; k++) pad[k] = k < wy ? gy[k] : 0.0;
    gy = pad;
  }
  for (size_t j = 0; j < w; j++) {
    double a = c * gx[j], b = c * gy[j];
    if (a == 0.0 && b == 0.0) continue;
    double *restrict row = H + ad__tri(j);
    AD__SIMD
    for (size_t i = 0; i <= j; i++) row[i] += a * gy[i] + b * gx[i];
  }
}

/* A unary operation's result with f' = c and f'' = h: (v, c d_a), plus
 * h g_a g_a^T in a second-order arena. */
static inline ad ad__op1(ad_arena *A, double v, double c, double h, ad a) {
  ad r = ad__lin1(A, v, c, a);
  ad__h_sq(A, r, h, a);
  return r;
}

/* ---- Constants and variables --------------------------------------------- */

/* Constant: tangent 0 (shares the arena's zero tangent, allocates nothing). */
static inline ad ad_const(const ad_arena *A, double v) { return (ad){v, A->buf}; }

/* Independent variable number `index`: tangent e_index. An index outside
 * [0, n) gives a constant-like zero tangent. */
static inline ad ad_var(ad_arena *A, double v, int index) {
  double *r = ad__alloc(A);
  if (AD__H2(A)) {
    size_t w = index >= 0 && index < A->n ? (size_t)index + 1 : 0;
    ad__zero_w(A, r, 0, w);
    if (w) r[index] = 1.0;
    return (ad){v, r};
  }
  size_t m = A->lanes;
  for (size_t k = 0; k < m; k++) r[k] = 0.0;
  if (index >= 0 && (size_t)index < m && index < A->n) r[index] = 1.0;
  return (ad){v, r};
}

/* Dual with a given value and gradient (n doubles, copied; Hessian 0), for
 * derivatives computed elsewhere by the chain rule. */
static inline ad ad_make(ad_arena *A, double v, const double *tangent) {
  double *r = ad__alloc(A);
  if (AD__H2(A)) {
    size_t w = (size_t)A->n;
    while (w > 0 && tangent[w - 1] == 0.0) w--;
    ad__zero_w(A, r, 0, w);
    if (w) memcpy(r, tangent, w * sizeof(double));
    return (ad){v, r};
  }
  size_t m = A->lanes;
  size_t n = (size_t)A->n < m ? (size_t)A->n : m;
  for (size_t k = 0; k < m; k++) r[k] = 0.0;
  if (n) memcpy(r, tangent, n * sizeof(double));
  return (ad){v, r};
}

/* Dual with value v and the whole tangent block (gradient and, in a
 * second-order arena, Hessian: A->lanes doubles) copied from block, which
 * may lie in A above the top or outside it. For duals saved across a
 * rewind; ad_make would drop their Hessians. */
static inline ad ad_from_block(ad_arena *A, double v, const double *block) {
  double *r = ad__alloc(A);
  if (A->lanes) memmove(r, block, A->lanes * sizeof(double));
  return (ad){v, r};
}

/* Copy of x (value and whole tangent block, Hessian included) in fresh
 * storage at the top of A; x must come from A. */
static inline ad ad_copy(ad_arena *A, ad x) { return ad_from_block(A, x.v, x.d); }

/* Second derivative d^2 x / du_i du_j of a dual from a second-order arena
 * (0 outside [0, n) or in a first-order arena). */
static inline double ad_hess(const ad_arena *A, ad x, int i, int j) {
  int n = ad_arena_n(A);
  if (A->order != 2 || i < 0 || j < 0 || i >= n || j >= n) return 0.0;
  if (i > j) {
    int t = i;
    i = j;
    j = t;
  }
  if ((size_t)j >= ad__w(A, x.d)) return 0.0;
  return x.d[A->glanes + ad__tri((size_t)j) + (size_t)i];
}

/* Derivative of x with respect to variable i (0 outside [0, n), and in a
 * second-order arena past x's width). */
static inline double ad_deriv(const ad_arena *A, ad x, int i) {
  if (!(i >= 0 && i < ad_arena_n(A))) return 0.0;
  if (AD__H2(A) && (size_t)i >= ad__w(A, x.d)) return 0.0;
  return x.d[i];
}

/* Identity (the dual branch of AD_LIFT). */
static inline ad ad_id(const ad_arena *A, ad x) {
  (void)A;
  return x;
}

/* AD_LIFT(A, x): x as a dual, whether it is a double (a constant) or an ad. */
#define AD_LIFT(A, x) _Generic((x), ad: ad_id, default: ad_const)((A), (x))

/* ---- Arithmetic ----------------------------------------------------------- */

/* a + b: d = d_a + d_b */
static inline ad ad_add(ad_arena *A, ad a, ad b) { return ad__lin2(A, a.v + b.v, 1.0, a, 1.0, b); }

/* a - b: d = d_a - d_b */
static inline ad ad_sub(ad_arena *A, ad a, ad b) { return ad__lin2(A, a.v - b.v, 1.0, a, -1.0, b); }

/* a * b: d = b d_a + a d_b */
static inline ad ad_mul(ad_arena *A, ad a, ad b) {
  ad r = ad__lin2(A, a.v * b.v, b.v, a, a.v, b);
  ad__h_sym(A, r, 1.0, a, b); /* f_ab = 1 */
  return r;
}

/* a / b = q: d = d_a / b - q d_b / b; f_ab = -1 / b^2, f_bb = 2 q / b^2 */
static inline ad ad_div(ad_arena *A, ad a, ad b) {
  double inv = 1.0 / b.v;
  double q = a.v * inv;
  ad r = ad__lin2(A, q, inv, a, -q * inv, b);
  if (AD__H2(A)) {
    ad__h_sym(A, r, -inv * inv, a, b);
    ad__h_sq(A, r, 2.0 * q * inv * inv, b);
  }
  return r;
}

/* -a: d = -d_a */
static inline ad ad_neg(ad_arena *A, ad a) { return ad__lin1(A, -a.v, -1.0, a); }

/* a^2: d = 2 a d_a; f'' = 2 */
static inline ad ad_sqr(ad_arena *A, ad a) { return ad__op1(A, a.v * a.v, 2.0 * a.v, 2.0, a); }

/* 1 / a: d = -d_a / a^2; f'' = 2 / a^3 */
static inline ad ad_inv(ad_arena *A, ad a) {
  double r = 1.0 / a.v;
  return ad__op1(A, r, -r * r, 2.0 * r * r * r, a);
}

/* a * b + c: d = b d_a + a d_b + d_c */
static inline ad ad_fma(ad_arena *A, ad a, ad b, ad c) {
  ad r = ad__lin3(A, a.v * b.v + c.v, b.v, a, a.v, b, 1.0, c);
  ad__h_sym(A, r, 1.0, a, b); /* f_ab = 1 */
  return r;
}

/* a + s: d = d_a (the tangent is shared, nothing is allocated) */
static inline ad ad_add_s(const ad_arena *A, ad a, double s) {
  (void)A;
  return (ad){a.v + s, a.d};
}

/* a - s: d = d_a (shared) */
static inline ad ad_sub_s(const ad_arena *A, ad a, double s) {
  (void)A;
  return (ad){a.v - s, a.d};
}

/* s - a: d = -d_a */
static inline ad ad_s_sub(ad_arena *A, double s, ad a) { return ad__lin1(A, s - a.v, -1.0, a); }

/* a * s: d = s d_a */
static inline ad ad_mul_s(ad_arena *A, ad a, double s) { return ad__lin1(A, a.v * s, s, a); }

/* a / s: d = d_a / s */
static inline ad ad_div_s(ad_arena *A, ad a, double s) {
  double inv = 1.0 / s;
  return ad__lin1(A, a.v * inv, inv, a);
}

/* s / a = q: d = -q d_a / a; f'' = 2 q / a^2 */
static inline ad ad_s_div(ad_arena *A, double s, ad a) {
  double inv = 1.0 / a.v;
  double q = s * inv;
  return ad__op1(A, q, -q * inv, 2.0 * q * inv * inv, a);
}

/* a * b + s (common in polynomial steps): d = b d_a + a d_b */
static inline ad ad_fma_s(ad_arena *A, ad a, ad b, double s) {
  ad r = ad__lin2(A, a.v * b.v + s, b.v, a, a.v, b);
  ad__h_sym(A, r, 1.0, a, b); /* f_ab = 1 */
  return r;
}

/* ca a + cb b, a linear combination with scalar weights: d = ca d_a + cb d_b */
static inline ad ad_lincomb(ad_arena *A, double ca, ad a, double cb, ad b) {
  return ad__lin2(A, ca * a.v + cb * b.v, ca, a, cb, b);
}

#endif
