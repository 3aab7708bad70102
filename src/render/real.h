/*
 * real.h: one vocabulary of arithmetic over plain doubles or over duals, so
 * that a formula of render/ (a microfacet distribution, a BSDF, a texture)
 * is written once and compiled twice: for the path tracers in plain
 * doubles, and for the differentiable path (lmc, h2mc) in dual numbers
 * (ad/dual.h) that carry gradients and, in a second-order arena, Hessians.
 *
 * Use. A ".c" file defines R_DUAL (0 or 1), includes this header, then the
 * body written in the vocabulary below (a "*_generic.h" file, which has no
 * include guard); it may then redefine R_DUAL, include this header again
 * (it undefines and redefines everything) and the body again, so that both
 * forms come out of one translation unit and share its static helpers:
 *
 *   #define R_DUAL 0
 *   #include "render/real.h"
 *   #include "render/bsdf/microfacet_generic.h"   (mf_D, mf_G1, ...)
 *   #undef R_DUAL
 *   #define R_DUAL 1
 *   #include "render/real.h"
 *   #include "render/bsdf/microfacet_generic.h"   (mf_D_ad, mf_G1_ad, ...)
 *
 * The vocabulary. REAL, REAL3, RRGB and RFRAME are double, vec3, rgb and
 * frame, or ad, adv3, adrgb and ad_frame. R_FN(name) names a function: name, or name_ad. A function
 * of the body declares its arena with R_CTX (nothing, or `ad_arena *A,`)
 * first in its parameters and passes it on with R_ARG; the dual operations
 * below use that `A`. R_V(x) is x's value (a double), R_C(c) a constant,
 * R3_V(a) a vector's value (a vec3), R3_DOT_C(e, a) the dot product with a
 * constant vec3 e.
 * The operations are named as ad/dual.h's, with the same suffixes for mixed
 * forms (R_MUL_S(dual, scalar), R_S_SUB(scalar, dual)); in the plain form
 * each expands to the C operator or libm function, so the plain code is what
 * one would write by hand and runs as fast (the plain path's speed is
 * measured in bench/: bench_rays).
 *
 * Rules for a body. Branch on R_V(...) only. Write each formula in the order
 * of operations the plain code should have: the plain form then rounds as
 * the hand-written code would, and the dual form computes its values with
 * the same operations in the same order (ad/dual.h: each dual operation's
 * value is the double operation's, but for division, which multiplies by
 * the reciprocal), so its values equal the plain ones to rounding and its
 * derivatives are those of the plain formula. What only one form needs (a
 * derivative rule that is not the chain rule through the values, as the
 * implicit-function tangent of an iterative solve) goes in `#if R_DUAL`
 * blocks.
 */
#ifndef R_DUAL
#error "define R_DUAL (0: plain doubles, 1: duals) before including render/real.h"
#endif

#include <math.h>

#include "render/frame.h"
#include "render/vec3.h"

#undef REAL
#undef REAL3
#undef RRGB
#undef R_FN
#undef R_CTX
#undef R_ARG
#undef R_V
#undef R_C
#undef R_ADD
#undef R_SUB
#undef R_MUL
#undef R_DIV
#undef R_NEG
#undef R_SQR
#undef R_INV
#undef R_ADD_S
#undef R_SUB_S
#undef R_S_SUB
#undef R_MUL_S
#undef R_DIV_S
#undef R_S_DIV
#undef R_SQRT
#undef R_SAFE_SQRT
#undef R_EXP
#undef R_LOG
#undef R_LOG1P
#undef R_ERFC
#undef R_SIN
#undef R_COS
#undef R_FABS
#undef R_POW_S
#undef R_ACOS
#undef R_ATAN2
#undef R_FLOOR
#undef R3_MAKE
#undef R3_CONST
#undef R3_ADD
#undef R3_SUB
#undef R3_NEG
#undef R3_SCALE
#undef R3_SCALE_S
#undef R3_FMA
#undef R3_DOT
#undef R3_LEN2
#undef R3_CROSS
#undef R3_NORMALIZE
#undef R3_REFLECT
#undef RFRAME
#undef R3_TO_LOCAL
#undef R3_V
#undef R3_DOT_C
#undef R3_FRAME_FROM_Z
#undef R3_TO_WORLD
#undef RRGB_CONST
#undef RRGB_ZERO
#undef RRGB_MAKE
#undef RRGB_ADD
#undef RRGB_MUL
#undef RRGB_SCALE
#undef RRGB_SCALE_S
#undef RRGB_LUMINANCE
#undef RRGB_IS_BLACK
#undef RRGB_IS_FINITE

/* Plain helpers that would evaluate an argument twice as macros. */
#ifndef LMC_RENDER_REAL_PLAIN_HELPERS
#define LMC_RENDER_REAL_PLAIN_HELPERS
static inline double r__sqr(double a) { return a * a; }
static inline double r__safe_sqrt(double a) { return sqrt(lmc_fmax(0.0, a)); }
#endif

#if R_DUAL

#include "ad/dual.h"
#include "ad/dual_math.h"
#include "ad/dual_vec3.h"
#include "render/rgb_ad.h"

#ifndef LMC_RENDER_REAL_DUAL_HELPERS
#define LMC_RENDER_REAL_DUAL_HELPERS
/* e . a for a constant vector e, in v3_dot's order. */
static inline ad r__dot_c(ad_arena *A, vec3 e, adv3 a) {
  return ad_add(A, ad_lincomb(A, e.x, a.x, e.y, a.y), ad_mul_s(A, a.z, e.z));
}
#endif

#define REAL ad
#define REAL3 adv3
#define RRGB adrgb
#define R_FN(name) name##_ad
#define R_CTX ad_arena *A,
#define R_ARG A,
#define R_V(x) ((x).v)
#define R_C(c) ad_const(A, (c))
#define R_ADD(a, b) ad_add(A, (a), (b))
#define R_SUB(a, b) ad_sub(A, (a), (b))
#define R_MUL(a, b) ad_mul(A, (a), (b))
#define R_DIV(a, b) ad_div(A, (a), (b))
#define R_NEG(a) ad_neg(A, (a))
#define R_SQR(a) ad_sqr(A, (a))
#define R_INV(a) ad_inv(A, (a))
#define R_ADD_S(a, s) ad_add_s(A, (a), (s))
#define R_SUB_S(a, s) ad_sub_s(A, (a), (s))
#define R_S_SUB(s, a) ad_s_sub(A, (s), (a))
#define R_MUL_S(a, s) ad_mul_s(A, (a), (s))
#define R_DIV_S(a, s) ad_div_s(A, (a), (s))
#define R_S_DIV(s, a) ad_s_div(A, (s), (a))
#define R_SQRT(a) ad_sqrt(A, (a))
#define R_SAFE_SQRT(a) ad_safe_sqrt(A, (a))
#define R_EXP(a) ad_exp(A, (a))
#define R_LOG(a) ad_log(A, (a))
#define R_LOG1P(a) ad_log1p(A, (a))
#define R_ERFC(a) ad_erfc(A, (a))
#define R_SIN(a) ad_sin(A, (a))
#define R_COS(a) ad_cos(A, (a))
#define R_FABS(a) ad_fabs(A, (a))
#define R_POW_S(a, p) ad_pow_s(A, (a), (p))
#define R_ACOS(a) ad_acos(A, (a))
#define R_ATAN2(y, x) ad_atan2(A, (y), (x))
#define R_FLOOR(a) ad_floor(A, (a))
#define R3_MAKE(x, y, z) adv3_make((x), (y), (z))
#define R3_CONST(x, y, z) adv3_const(A, (x), (y), (z))
#define R3_ADD(a, b) adv3_add(A, (a), (b))
#define R3_SUB(a, b) adv3_sub(A, (a), (b))
#define R3_NEG(a) adv3_neg(A, (a))
#define R3_SCALE(a, s) adv3_scale(A, (a), (s))
#define R3_SCALE_S(a, s) adv3_scale_s(A, (a), (s))
#define R3_FMA(a, b, s) adv3_fma(A, (a), (b), (s))
#define R3_DOT(a, b) adv3_dot(A, (a), (b))
#define R3_LEN2(a) adv3_len2(A, (a))
#define R3_CROSS(a, b) adv3_cross(A, (a), (b))
#define R3_NORMALIZE(a) adv3_normalize(A, (a))
#define R3_REFLECT(w, n) adv3_reflect(A, (w), (n))
#define RFRAME ad_frame
#define R3_FRAME_FROM_Z(n) adv3_frame_from_z(A, (n))
#define R3_TO_WORLD(f, v) adv3_to_world(A, (f), (v))
#define R3_TO_LOCAL(f, v) adv3_to_local(A, (f), (v))
#define R3_V(a) v3((a).x.v, (a).y.v, (a).z.v)
#define R3_DOT_C(e, a) r__dot_c(A, (e), (a))
#define RRGB_CONST(c) adrgb_const(A, (c))
#define RRGB_ZERO() adrgb_zero(A)
#define RRGB_MAKE(r, g, b) ((adrgb){(r), (g), (b)})
#define RRGB_ADD(a, b) adrgb_add(A, (a), (b))
#define RRGB_MUL(a, b) adrgb_mul(A, (a), (b))
#define RRGB_SCALE(a, s) adrgb_scale(A, (a), (s))
#define RRGB_SCALE_S(a, s) adrgb_scale_s(A, (a), (s))
#define RRGB_LUMINANCE(c) adrgb_luminance(A, (c))
#define RRGB_IS_BLACK(c) rgb_is_black(adrgb_value(c))
#define RRGB_IS_FINITE(c) rgb_isfinite(adrgb_value(c))

#else

#define REAL double
#define REAL3 vec3
#define RRGB rgb
#define R_FN(name) name
#define R_CTX
#define R_ARG
#define R_V(x) (x)
#define R_C(c) (c)
#define R_ADD(a, b) ((a) + (b))
#define R_SUB(a, b) ((a) - (b))
#define R_MUL(a, b) ((a) * (b))
#define R_DIV(a, b) ((a) / (b))
#define R_NEG(a) (-(a))
#define R_SQR(a) r__sqr(a)
#define R_INV(a) (1.0 / (a))
#define R_ADD_S(a, s) ((a) + (s))
#define R_SUB_S(a, s) ((a) - (s))
#define R_S_SUB(s, a) ((s) - (a))
#define R_MUL_S(a, s) ((a) * (s))
#define R_DIV_S(a, s) ((a) / (s))
#define R_S_DIV(s, a) ((s) / (a))
#define R_SQRT(a) sqrt(a)
#define R_SAFE_SQRT(a) r__safe_sqrt(a)
#define R_EXP(a) exp(a)
#define R_LOG(a) log(a)
#define R_LOG1P(a) log1p(a)
#define R_ERFC(a) erfc(a)
#define R_SIN(a) sin(a)
#define R_COS(a) cos(a)
#define R_FABS(a) fabs(a)
#define R_POW_S(a, p) pow((a), (p))
#define R_ACOS(a) acos(a)
#define R_ATAN2(y, x) atan2((y), (x))
#define R_FLOOR(a) floor(a)
#define R3_MAKE(x, y, z) v3((x), (y), (z))
#define R3_CONST(x, y, z) v3((x), (y), (z))
#define R3_ADD(a, b) v3_add((a), (b))
#define R3_SUB(a, b) v3_sub((a), (b))
#define R3_NEG(a) v3_neg(a)
#define R3_SCALE(a, s) v3_scale((a), (s))
#define R3_SCALE_S(a, s) v3_scale((a), (s))
#define R3_FMA(a, b, s) v3_fma((a), (b), (s))
#define R3_DOT(a, b) v3_dot((a), (b))
#define R3_LEN2(a) v3_len2(a)
#define R3_CROSS(a, b) v3_cross((a), (b))
#define R3_NORMALIZE(a) v3_normalize(a)
#define R3_REFLECT(w, n) v3_reflect((w), (n))
#define RFRAME frame
#define R3_FRAME_FROM_Z(n) frame_from_z(n)
#define R3_TO_WORLD(f, v) frame_to_world((f), (v))
#define R3_TO_LOCAL(f, v) frame_to_local((f), (v))
#define R3_V(a) (a)
#define R3_DOT_C(e, a) v3_dot((e), (a))
#define RRGB_CONST(c) (c)
#define RRGB_ZERO() rgb_zero()
#define RRGB_MAKE(r, g, b) rgb_make((r), (g), (b))
#define RRGB_ADD(a, b) rgb_add((a), (b))
#define RRGB_MUL(a, b) rgb_mul((a), (b))
#define RRGB_SCALE(a, s) rgb_scale((a), (s))
#define RRGB_SCALE_S(a, s) rgb_scale((a), (s))
#define RRGB_LUMINANCE(c) rgb_luminance(c)
#define RRGB_IS_BLACK(c) rgb_is_black(c)
#define RRGB_IS_FINITE(c) rgb_isfinite(c)

#endif
