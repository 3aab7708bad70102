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
 * Second order. An arena made with ad_arena_init2 also records a tape from
 * which ad_hessian gives the Hessian H = d^2 v / du^2 of any of its duals.
 * Every tangent block then ends in a header lane group: the dual's width w
 * (the number of leading variables its value may depend on: 0 for
 * constants, index + 1 for variable `index`, the largest width of the
 * operands for a result; only the first pad(w) gradient entries are
 * written and read) and its node on the tape. Variables enter a path
 * evaluation in the order it draws its numbers, so the dual of an early
 * vertex has a small width and costs little. Each operation appends a
 * term per operand (its partial f_x) and one per non-zero second
 * derivative (f_xx through ad__h_sq, f_xy through ad__h_sym, added after
 * the linear kernel; nothing in a first-order arena, whose cost and results
 * do not change). ad_hessian then sweeps the tape backwards
 * (forward-over-reverse: the adjoints and their tangents, Griewank and
 * Walther, chapter 5), O(n) per term, where the second-order forward mode
 * this replaced carried w (w + 1) / 2 Hessian entries through every
 * operation. The arena keeps every dual until it is reset (the sweep reads
 * the operands' gradients), so rewinds do nothing there and it must hold a
 * whole evaluation; AD_H_CAPACITY = 96 bounds n.
 *
 * Model: Ceres' Jet (value plus tangent, derivative rule per operation,
 * comparisons on the value); see also Griewank and Walther, "Evaluating
 * Derivatives", 2nd ed., 2008, chapter 3 (the forward mode).
 */
#ifndef LMC_AD_DUAL_H
#define LMC_AD_DUAL_H

#include <stddef.h>
#include <stdint.h>
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
  int order;     /* 1: gradients; 2: gradients and the tape for Hessians */
  int overflow;  /* set when an allocation did not fit */
  /* Second order: the tape and the reverse sweep's storage, in buf past
   * the tangents (doubles throughout; node numbers are exact in them). */
  double *node_at; /* node -> offset in buf of its tangent block (ad__ld) */
  double *terms;   /* AD__TERM doubles per term (ad__term) */
  double *adj;     /* the sweep: adjoint per node */
  double *bw;      /* ... padded width of its B vector (0: untouched; ad__ld) */
  double *bv;      /* ... B vectors, glanes doubles per node */
  size_t n_nodes, node_cap, n_terms, term_cap;
} ad_arena;

/* n rounded up to a multiple of AD_LANES. */
static inline size_t ad__pad(size_t n) { return (n + AD_LANES - 1) & ~(size_t)(AD_LANES - 1); }

/* Second order keeps integers (a block's width and node, the node table,
 * the tape's node numbers and widths, the sweep's widths) in its double
 * storage as 64-bit patterns: they are only ever copied, never used in
 * arithmetic, so reading one back is a move rather than a conversion. */
static inline uint64_t ad__ld(const double *p) {
  uint64_t u;
  memcpy(&u, p, sizeof u);
  return u;
}
static inline void ad__st(double *p, uint64_t u) { memcpy(p, &u, sizeof u); }

/* Doubles of one tangent block of an arena of tangent length n and order:
 * the gradient, and at second order a header lane group (width, node). */
static inline size_t ad__block(int n, int order) {
  size_t m = (size_t)(n < 0 ? 0 : n);
  return ad__pad(m) + (order == 2 ? AD_LANES : 0);
}

#define AD__TERM 3      /* doubles per term of the tape (ad__term) */
#define AD__TERMS_PER 4 /* terms per dual the tape has room for (2.3 on paths) */

/* Second order: doubles per dual of the arena's storage (its tangent
 * block, node table, terms, and the sweep's adjoint, width and B). */
static inline size_t ad__per2(int n) {
  size_t g = ad__pad((size_t)(n < 0 ? 0 : n));
  return ad__block(n, 2) + 1 + AD__TERM * AD__TERMS_PER + 2 + g;
}

/* Doubles of arena storage needed for `count` duals of tangent length n
 * (plus the shared zero tangent). */
static inline size_t ad_arena_size(int n, size_t count) { return ad__block(n, 1) * (count + 1); }

/* The same for a second-order arena (gradients, the tape and the sweep's
 * storage for ad_hessian); count is every dual of an evaluation, as a
 * second-order arena never rewinds. */
static inline size_t ad_arena_size2(int n, size_t count) { return ad__per2(n) * (count + 1); }

static inline int ad__arena_init(ad_arena *A, double *buf, size_t cap, int n, int order) {
  A->buf = buf;
  A->cap = cap;
  A->n = n;
  A->order = order;
  A->glanes = ad__pad((size_t)n);
  A->lanes = ad__block(n, order);
  A->woff = order == 2 ? A->glanes : 0;
  A->n_nodes = A->n_terms = A->node_cap = A->term_cap = 0;
  A->node_at = A->terms = A->adj = A->bw = A->bv = NULL;
  if (order == 2) {
    /* buf: the tangents of node_cap duals, then the node table, the
     * terms, the adjoints, the widths and the B vectors. */
    size_t nodes = cap / ad__per2(n);
    if (nodes > 0xffffffffu) nodes = 0xffffffffu; /* node numbers fit the tape's 32 bits */
    if (nodes < 2) return -1;
    A->cap = cap = nodes * A->lanes;
    A->node_cap = nodes;
    A->term_cap = nodes * AD__TERMS_PER;
    A->node_at = buf + cap;
    A->terms = A->node_at + nodes;
    A->adj = A->terms + AD__TERM * A->term_cap;
    A->bw = A->adj + nodes;
    A->bv = A->bw + nodes;
  }
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
  A->n_nodes = A->n_terms = 0;
  A->lanes = ad__block(A->n, A->order);
}

/* 1 while every tangent made since the last reset is valid. */
static inline int ad_arena_ok(const ad_arena *A) { return !A->overflow; }

/* Tangent length of the current evaluation: n, or 0 after an overflow. */
static inline int ad_arena_n(const ad_arena *A) { return A->overflow ? 0 : A->n; }

/* Position to rewind to; duals made after it die at ad_arena_rewind. */
static inline size_t ad_arena_mark(const ad_arena *A) { return A->top; }

/* 1 when A keeps every dual until ad_arena_reset (second order: the
 * reverse sweep reads the tangents of every operation); rewinds then do
 * nothing. */
static inline int ad_arena_keeps_all(const ad_arena *A) { return A->order == 2; }

static inline void ad_arena_rewind(ad_arena *A, size_t mark) {
  if (ad_arena_keeps_all(A)) return;
  if (mark >= A->base && mark <= A->top) A->top = mark;
}

/* Rewind to mark but keep x: its tangent moves to the mark when it lives
 * above it. Typical use: one bounce of a path makes hundreds of temporaries
 * and hands one throughput to the next bounce. x must come from A. */
static inline ad ad_arena_rewind_keep(ad_arena *A, size_t mark, ad x) {
  if (ad_arena_keeps_all(A) || mark < A->base || mark > A->top) return x;
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
  if (A->order == 2 && A->lanes) {
    /* A new node of the tape (at most one per block: never past node_cap). */
    size_t k = ++A->n_nodes;
    ad__st(A->node_at + k, (uint64_t)(r - A->buf));
    ad__st(r + A->woff + 1, k);
  }
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

/* True when A records the tape for Hessians (second order, no overflow). */
#define AD__H2(A) ((A)->order == 2 && (A)->lanes != 0)

/* Width of a tangent of a second-order arena (AD__H2). */
static inline size_t ad__w(const ad_arena *A, const double *d) { return (size_t)ad__ld(d + A->woff); }

/* Its node on the tape (0: a constant, the shared zero tangent). */
static inline size_t ad__node(const ad_arena *A, const double *d) {
  return (size_t)ad__ld(d + A->woff + 1);
}

/* Second order: zeroes r's gradient entries from width `from` up to
 * width `to` (padded lengths) and gives r width `to`. */
static inline void ad__zero_w(const ad_arena *A, double *r, size_t from, size_t to) {
  for (size_t k = ad__pad(from); k < ad__pad(to); k++) r[k] = 0.0;
  ad__st(r + A->woff, to);
}

/* Appends a term to the tape: node k's result depends on node x (and y),
 * of widths wx (and wy), as kind says, with coefficient c. Stored in three
 * doubles: c, then the bit patterns k + 2^32 x and
 * y + 2^32 wx + 2^40 wy + 2^48 kind (node numbers < 2^32, as the arena's
 * node_cap; widths <= AD_H_CAPACITY < 2^8), so that the sweep finds the
 * widths without visiting the operands' blocks. A full tape counts as an
 * overflow. */
enum { AD__LIN, AD__SQ, AD__SYM, AD__VAR, AD__SEED };
static inline void ad__term(ad_arena *A, int kind, double c, size_t k, size_t x, size_t wx,
                            size_t y, size_t wy) {
  if (A->n_terms >= A->term_cap) {
    A->overflow = 1;
    A->lanes = 0;
    return;
  }
  double *t = A->terms + AD__TERM * A->n_terms++;
  t[0] = c;
  ad__st(t + 1, (uint64_t)k | (uint64_t)x << 32);
  ad__st(t + 2, (uint64_t)y | (uint64_t)wx << 32 | (uint64_t)wy << 40 | (uint64_t)kind << 48);
}

/* Second order: r = sum_i c_i d_i over m <= 6 tangents, each over its
 * operand's width (the part every operand covers in one pass, the rest
 * operand by operand), and a linear term on the tape per operand. */
static inline void ad__lin_w(ad_arena *A, double *restrict r, int m, const double *c,
                             const double *const *d) {
  size_t w[6], lo = (size_t)-1, hi = 0;
  for (int i = 0; i < m; i++) {
    w[i] = ad__w(A, d[i]);
    if (w[i] < lo) lo = w[i];
    if (w[i] > hi) hi = w[i];
  }
  size_t a = ad__pad(lo), b = ad__pad(hi), nb = a / AD_LANES;
  switch (m) {
  case 1: ad__k1(nb, r, c[0], d[0]); break;
  case 2: ad__k2(nb, r, c[0], d[0], c[1], d[1]); break;
  case 3: ad__k3(nb, r, c[0], d[0], c[1], d[1], c[2], d[2]); break;
  case 4: ad__k4(nb, r, c, d[0], d[1], d[2], d[3]); break;
  default: ad__k6(nb, r, c, d[0], d[1], d[2], d[3], d[4], d[5]);
  }
  if (b > a) {
    /* Summed in the operands' order, as the fused kernels do (the same
     * value up to the sign of a zero). */
    for (size_t k = a; k < b; k += AD_LANES) AD__BLOCK(k, r[k_] = 0.0);
    for (int i = 0; i < m; i++) {
      size_t e = ad__pad(w[i]);
      const double *restrict di = d[i];
      double ci = c[i];
      for (size_t k = a; k < e; k += AD_LANES) AD__BLOCK(k, r[k_] += ci * di[k_]);
    }
  }
  ad__st(r + A->woff, hi);
  size_t kr = ad__node(A, r);
  for (int i = 0; i < m; i++) {
    size_t x = ad__node(A, d[i]);
    if (x && c[i] != 0.0) ad__term(A, AD__LIN, c[i], kr, x, w[i], 0, 0);
  }
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
 * Recorded for a freshly made result r after its linear kernel, before
 * anything uses r (the reverse sweep relies on that order). */

/* r's second derivative f_xx = c: H_r gains c g_x g_x^T. */
static inline void ad__h_sq(ad_arena *A, ad r, double c, ad x) {
  if (!AD__H2(A) || c == 0.0) return;
  size_t nx = ad__node(A, x.d);
  if (nx) ad__term(A, AD__SQ, c, ad__node(A, r.d), nx, ad__w(A, x.d), 0, 0);
}

/* r's mixed second derivative f_xy = c: H_r gains c (g_x g_y^T + g_y g_x^T). */
static inline void ad__h_sym(ad_arena *A, ad r, double c, ad x, ad y) {
  if (!AD__H2(A) || c == 0.0) return;
  size_t nx = ad__node(A, x.d), ny = ad__node(A, y.d);
  if (nx && ny)
    ad__term(A, AD__SYM, c, ad__node(A, r.d), nx, ad__w(A, x.d), ny, ad__w(A, y.d));
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
    if (w) {
      r[index] = 1.0;
      ad__term(A, AD__VAR, 1.0, ad__node(A, r), (size_t)index, 0, 0, 0);
    }
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
    if (w) {
      memcpy(r, tangent, w * sizeof(double));
      ad__term(A, AD__SEED, 1.0, ad__node(A, r), 0, 0, 0, 0);
    }
    return (ad){v, r};
  }
  size_t m = A->lanes;
  size_t n = (size_t)A->n < m ? (size_t)A->n : m;
  for (size_t k = 0; k < m; k++) r[k] = 0.0;
  if (n) memcpy(r, tangent, n * sizeof(double));
  return (ad){v, r};
}

/* Dual with value v and the whole tangent block (A->lanes doubles; at
 * second order its header too, so the copy is the same node of the tape)
 * copied from block, which may lie in A above the top or outside it. For
 * duals saved across a rewind. */
static inline ad ad_from_block(ad_arena *A, double v, const double *block) {
  double *r = ad__alloc(A);
  if (A->lanes) memmove(r, block, A->lanes * sizeof(double));
  return (ad){v, r};
}

/* Copy of x (value and whole tangent block, Hessian included) in fresh
 * storage at the top of A; x must come from A. */
static inline ad ad_copy(ad_arena *A, ad x) { return ad_from_block(A, x.v, x.d); }

/* The tangent block of node x (second order). */
static inline const double *ad__block_of(const ad_arena *A, size_t x) {
  return A->buf + ad__ld(A->node_at + x);
}

/* B_x (the sweep's vector of node x) widened to w padded entries, the
 * entries past its width zeroed first. */
static inline double *ad__bgrow(ad_arena *A, size_t x, size_t w) {
  double *b = A->bv + x * A->glanes;
  size_t have = (size_t)ad__ld(A->bw + x);
  if (have < w) {
    for (size_t k = have; k < w; k += AD_LANES) AD__BLOCK(k, b[k_] = 0.0);
    ad__st(A->bw + x, w);
  }
  return b;
}

/* B_x += c v over v's first w entries (padded), cut to x's own width wx
 * (padded): entries of B_x past it reach only Hessian entries above the
 * diagonal (ad_hessian). */
static inline void ad__badd(ad_arena *A, size_t x, size_t wx, size_t w, double c,
                            const double *restrict v) {
  wx = ad__pad(wx);
  if (w > wx) w = wx;
  double *restrict b = ad__bgrow(A, x, w);
  for (size_t k = 0; k < w; k += AD_LANES) AD__BLOCK(k, b[k_] += c * v[k_]);
}

/* The Hessian d^2 x / du^2 of a dual of a second-order arena into H (n x n,
 * row-major, symmetric; n = ad_arena_n). Returns 0, or -1 (H untouched)
 * for a first-order arena or after an overflow.
 *
 * The reverse sweep over the tape (forward-over-reverse, Griewank and
 * Walther, chapter 5): with a_k = dx / dv_k, the adjoint of node k, and
 * B_k = da_k / du its tangent, a term of node k whose result depends on x
 * with coefficient c (a linear term) gives a_x += c a_k and
 * B_x += c B_k; a second derivative f_xx = c gives B_x += a_k c g_x, a
 * mixed one f_xy = c gives B_x += a_k c g_y and B_y += a_k c g_x (g the
 * forward tangents); variable i gives row i of the Hessian, B_i, and a
 * dual made with ad_make (gradient g, Hessian 0) gives g B^T. Terms are
 * visited from the last, so every term of a node's users comes before the
 * node's own. Only the lower triangle is swept (H_ij, j <= i, then
 * mirrored): B_x ends in rows i below x's width w_x, so its entries from
 * w_x on are never read and B_x is kept to w_x entries. A term costs
 * O(w) with w its node's width; the Hessian's entries O(n^2) once. */
static inline int ad_hessian(ad_arena *A, ad x, double *H) {
  if (A->order != 2 || !ad_arena_ok(A)) return -1;
  size_t n = (size_t)A->n, g = A->glanes;
  memset(H, 0, n * n * sizeof *H);
  size_t k0 = ad__node(A, x.d);
  if (k0 == 0) return 0;
  size_t nn = A->n_nodes + 1;
  memset(A->adj, 0, nn * sizeof *A->adj);
  memset(A->bw, 0, nn * sizeof *A->bw);
  A->adj[k0] = 1.0;
  for (size_t t = A->n_terms; t-- > 0;) {
    const double *T = A->terms + AD__TERM * t;
    uint64_t t1 = ad__ld(T + 1);
    size_t k = (size_t)(t1 & 0xffffffffu);
    if (k > k0) continue; /* made after x: x does not depend on it */
    double a = A->adj[k];
    size_t wb = (size_t)ad__ld(A->bw + k);
    if (a == 0.0 && wb == 0) continue;
    double c = T[0];
    uint64_t t2 = ad__ld(T + 2);
    size_t xk = (size_t)(t1 >> 32), yk = (size_t)(t2 & 0xffffffffu);
    size_t wx = (size_t)(t2 >> 32) & 0xffu, wy = (size_t)(t2 >> 40) & 0xffu;
    const double *bk = A->bv + k * g;
    switch ((int)(t2 >> 48)) {
    case AD__LIN:
      A->adj[xk] += c * a;
      if (wb) ad__badd(A, xk, wx, wb, c, bk);
      break;
    case AD__SQ:
      if (a != 0.0) ad__badd(A, xk, wx, ad__pad(wx), a * c, ad__block_of(A, xk));
      break;
    case AD__SYM:
      if (a != 0.0) {
        ad__badd(A, xk, wx, ad__pad(wy), a * c, ad__block_of(A, yk));
        ad__badd(A, yk, wy, ad__pad(wx), a * c, ad__block_of(A, xk));
      }
      break;
    case AD__VAR: /* row xk of the Hessian, up to the diagonal */
      for (size_t j = 0; j < wb && j <= xk; j++) H[xk * n + j] += bk[j];
      break;
    default: { /* AD__SEED: g_k B_k^T */
      const double *gk = ad__block_of(A, k);
      size_t w = ad__w(A, gk);
      for (size_t i = 0; i < w && i < n; i++)
        for (size_t j = 0; j < wb && j <= i; j++) H[i * n + j] += gk[i] * bk[j];
    }
    }
  }
  for (size_t i = 0; i < n; i++)
    for (size_t j = 0; j < i; j++) H[j * n + i] = H[i * n + j];
  return 0;
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
