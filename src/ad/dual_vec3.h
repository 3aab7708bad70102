/*
 * dual_vec3.h: 3-vectors of dual numbers and the geometry lmc differentiates
 * (dot, cross, normalisation, mirror reflection, refraction, orthonormal
 * frames).
 *
 * Conventions are those of src/render/vec3.h and frame.h, restated here
 * because src/ad may not include src/render: directions are unit vectors
 * pointing away from the surface, the shading frame is z-up, eta is the
 * relative index of refraction int/ext. Every function computes the same
 * value as its plain-double counterpart in src/render, with the tangent of
 * the exact derivative of that formula. Fused forms (dot, length, normalize,
 * refract, the frame) write the derivative of the whole expression as one
 * linear combination of input tangents, so they allocate one tangent per
 * output component instead of one per elementary step.
 *
 * In a second-order arena each function adds the second-order terms of its
 * formula (products' mixed partials, the curvature of length and of the
 * refraction's cos_t) to the Hessians, as the comments next to them say.
 *
 * The frame is the branchless construction of Duff et al. 2017 ("Building an
 * Orthonormal Basis, Revisited", JCGT 6(1)); the sign of n.z is a branch on
 * the value, so the derivative is that of the half-space the normal is in.
 */
#ifndef LMC_AD_DUAL_VEC3_H
#define LMC_AD_DUAL_VEC3_H

#include <math.h>

#include "ad/dual.h"
#include "ad/dual_math.h"

typedef struct adv3 {
  ad x, y, z;
} adv3;

/* Orthonormal frame (s, t, n) of dual vectors. */
typedef struct ad_frame {
  adv3 s, t, n;
} ad_frame;

static inline adv3 adv3_make(ad x, ad y, ad z) { return (adv3){x, y, z}; }

/* Constant vector (zero tangents). */
static inline adv3 adv3_const(const ad_arena *A, double x, double y, double z) {
  return (adv3){ad_const(A, x), ad_const(A, y), ad_const(A, z)};
}

/* Vector of independent variables first, first + 1, first + 2. */
static inline adv3 adv3_var(ad_arena *A, double x, double y, double z, int first) {
  return (adv3){ad_var(A, x, first), ad_var(A, y, first + 1), ad_var(A, z, first + 2)};
}

/* a + b */
static inline adv3 adv3_add(ad_arena *A, adv3 a, adv3 b) {
  return (adv3){ad_add(A, a.x, b.x), ad_add(A, a.y, b.y), ad_add(A, a.z, b.z)};
}

/* a - b */
static inline adv3 adv3_sub(ad_arena *A, adv3 a, adv3 b) {
  return (adv3){ad_sub(A, a.x, b.x), ad_sub(A, a.y, b.y), ad_sub(A, a.z, b.z)};
}

/* -a */
static inline adv3 adv3_neg(ad_arena *A, adv3 a) {
  return (adv3){ad_neg(A, a.x), ad_neg(A, a.y), ad_neg(A, a.z)};
}

/* a * s, s dual */
static inline adv3 adv3_scale(ad_arena *A, adv3 a, ad s) {
  return (adv3){ad_mul(A, a.x, s), ad_mul(A, a.y, s), ad_mul(A, a.z, s)};
}

/* a * s, s scalar */
static inline adv3 adv3_scale_s(ad_arena *A, adv3 a, double s) {
  return (adv3){ad_mul_s(A, a.x, s), ad_mul_s(A, a.y, s), ad_mul_s(A, a.z, s)};
}

/* a + b * s, s dual: per component d = d_a + s d_b + b d_s */
static inline adv3 adv3_fma(ad_arena *A, adv3 a, adv3 b, ad s) {
  return (adv3){ad_fma(A, b.x, s, a.x), ad_fma(A, b.y, s, a.y), ad_fma(A, b.z, s, a.z)};
}

/* a . b: d = sum_i (b_i d_ai + a_i d_bi) */
static inline ad adv3_dot(ad_arena *A, adv3 a, adv3 b) {
  const double c[6] = {b.x.v, b.y.v, b.z.v, a.x.v, a.y.v, a.z.v};
  double v = a.x.v * b.x.v + a.y.v * b.y.v + a.z.v * b.z.v;
  ad r = ad__lin6(A, v, c, a.x, a.y, a.z, b.x, b.y, b.z);
  if (AD__H2(A)) { /* d^2 / d a_i d b_i = 1 */
    ad__h_sym(A, r, 1.0, a.x, b.x);
    ad__h_sym(A, r, 1.0, a.y, b.y);
    ad__h_sym(A, r, 1.0, a.z, b.z);
  }
  return r;
}

/* a x b, e.g. x = a_y b_z - a_z b_y: d = b_z d_ay + a_y d_bz - b_y d_az - a_z d_by */
static inline adv3 adv3_cross(ad_arena *A, adv3 a, adv3 b) {
  const double cx[4] = {b.z.v, a.y.v, -b.y.v, -a.z.v};
  const double cy[4] = {b.x.v, a.z.v, -b.z.v, -a.x.v};
  const double cz[4] = {b.y.v, a.x.v, -b.x.v, -a.y.v};
  adv3 r;
  r.x = ad__lin4(A, a.y.v * b.z.v - a.z.v * b.y.v, cx, a.y, b.z, a.z, b.y);
  r.y = ad__lin4(A, a.z.v * b.x.v - a.x.v * b.z.v, cy, a.z, b.x, a.x, b.z);
  r.z = ad__lin4(A, a.x.v * b.y.v - a.y.v * b.x.v, cz, a.x, b.y, a.y, b.x);
  if (AD__H2(A)) { /* each component is a_i b_j - a_j b_i: mixed partials +-1 */
    ad__h_sym(A, r.x, 1.0, a.y, b.z);
    ad__h_sym(A, r.x, -1.0, a.z, b.y);
    ad__h_sym(A, r.y, 1.0, a.z, b.x);
    ad__h_sym(A, r.y, -1.0, a.x, b.z);
    ad__h_sym(A, r.z, 1.0, a.x, b.y);
    ad__h_sym(A, r.z, -1.0, a.y, b.x);
  }
  return r;
}

/* |a|^2: d = 2 (a_x d_ax + a_y d_ay + a_z d_az) */
static inline ad adv3_len2(ad_arena *A, adv3 a) {
  double v = a.x.v * a.x.v + a.y.v * a.y.v + a.z.v * a.z.v;
  ad r = ad__lin3(A, v, 2.0 * a.x.v, a.x, 2.0 * a.y.v, a.y, 2.0 * a.z.v, a.z);
  if (AD__H2(A)) { /* d^2 / d a_i^2 = 2 */
    ad__h_sq(A, r, 2.0, a.x);
    ad__h_sq(A, r, 2.0, a.y);
    ad__h_sq(A, r, 2.0, a.z);
  }
  return r;
}

/* |a| = l: d = (a_x d_ax + a_y d_ay + a_z d_az) / l (NaN at a = 0) */
static inline ad adv3_length(ad_arena *A, adv3 a) {
  double l = sqrt(a.x.v * a.x.v + a.y.v * a.y.v + a.z.v * a.z.v);
  double il = 1.0 / l;
  ad r = ad__lin3(A, l, a.x.v * il, a.x, a.y.v * il, a.y, a.z.v * il, a.z);
  if (AD__H2(A)) { /* d^2 l / d a_i d a_j = (delta_ij - a_i a_j / l^2) / l */
    double il3 = il * il * il;
    ad__h_sq(A, r, il - a.x.v * a.x.v * il3, a.x);
    ad__h_sq(A, r, il - a.y.v * a.y.v * il3, a.y);
    ad__h_sq(A, r, il - a.z.v * a.z.v * il3, a.z);
    ad__h_sym(A, r, -a.x.v * a.y.v * il3, a.x, a.y);
    ad__h_sym(A, r, -a.x.v * a.z.v * il3, a.x, a.z);
    ad__h_sym(A, r, -a.y.v * a.z.v * il3, a.y, a.z);
  }
  return r;
}

/* a / |a| (a unchanged when |a| = 0, as v3_normalize).
 * With l = |a| and its tangent d_l (adv3_length):
 *   d(a_i / l) = d_ai / l - a_i / l^2 d_l. */
static inline adv3 adv3_normalize(ad_arena *A, adv3 a) {
  ad l = adv3_length(A, a);
  if (!(l.v > 0.0)) return a;
  double il = 1.0 / l.v;
  adv3 r;
  r.x = ad__lin2(A, a.x.v * il, il, a.x, -a.x.v * il * il, l);
  r.y = ad__lin2(A, a.y.v * il, il, a.y, -a.y.v * il * il, l);
  r.z = ad__lin2(A, a.z.v * il, il, a.z, -a.z.v * il * il, l);
  if (AD__H2(A)) { /* f(a_i, l) = a_i / l: f_al = -1 / l^2, f_ll = 2 a_i / l^3 */
    double il2 = il * il, il3 = il2 * il;
    ad__h_sym(A, r.x, -il2, a.x, l);
    ad__h_sym(A, r.y, -il2, a.y, l);
    ad__h_sym(A, r.z, -il2, a.z, l);
    ad__h_sq(A, r.x, 2.0 * a.x.v * il3, l);
    ad__h_sq(A, r.y, 2.0 * a.y.v * il3, l);
    ad__h_sq(A, r.z, 2.0 * a.z.v * il3, l);
  }
  return r;
}

/* Mirror reflection of w about n (both away from the surface), as v3_reflect:
 *   r = 2 (w . n) n - w,  d r_i = 2 c d_ni + 2 n_i d_c - d_wi,  c = w . n. */
static inline adv3 adv3_reflect(ad_arena *A, adv3 w, adv3 n) {
  ad c = adv3_dot(A, w, n);
  double c2 = 2.0 * c.v;
  adv3 r;
  r.x = ad__lin3(A, c2 * n.x.v - w.x.v, c2, n.x, 2.0 * n.x.v, c, -1.0, w.x);
  r.y = ad__lin3(A, c2 * n.y.v - w.y.v, c2, n.y, 2.0 * n.y.v, c, -1.0, w.y);
  r.z = ad__lin3(A, c2 * n.z.v - w.z.v, c2, n.z, 2.0 * n.z.v, c, -1.0, w.z);
  if (AD__H2(A)) { /* f(c, n_i) = 2 c n_i: f_cn = 2 */
    ad__h_sym(A, r.x, 2.0, c, n.x);
    ad__h_sym(A, r.y, 2.0, c, n.y);
    ad__h_sym(A, r.z, 2.0, c, n.z);
  }
  return r;
}

/* Refraction of wi (unit, pointing away from the surface) through the
 * surface with unit normal n and relative IOR eta = int/ext, n pointing to
 * the ext side. When wi is on the int side (wi . n < 0), the roles swap:
 * e = 1/eta and the normal flips (sigma = -1); otherwise e = eta, sigma = 1.
 * With c = sigma (wi . n) >= 0 (cosine on the incident side):
 *   cos_t^2 = 1 - (1 - c^2) / e^2    (<= 0: total internal reflection)
 *   wt = -wi / e + (c / e - cos_t) sigma n
 * and with k = c / e - cos_t,  d k = (1/e - c / (e^2 cos_t)) d_c,
 *   d wt_i = -d_wi / e + sigma k d_ni + sigma n_i d_k.
 * Returns 1 and writes *wt (pointing away on the other side), or returns 0
 * on total internal reflection (then *wt is the zero constant). */
static inline int adv3_refract(ad_arena *A, adv3 wi, adv3 n, double eta, adv3 *wt /* OUT */) {
  ad cos_wn = adv3_dot(A, wi, n);
  double sigma = cos_wn.v < 0.0 ? -1.0 : 1.0;
  double e = sigma > 0.0 ? eta : 1.0 / eta;
  double c = sigma * cos_wn.v;
  double cos_t2 = 1.0 - (1.0 - c * c) / (e * e);
  if (!(cos_t2 > 0.0)) {
    *wt = adv3_const(A, 0.0, 0.0, 0.0);
    return 0;
  }
  double cos_t = sqrt(cos_t2);
  double ie = 1.0 / e;

  /* Tangent of k = c/e - cos_t, through c = sigma (wi . n). */
  double k_v = c * ie - cos_t;
  /* With d cos_t / d c = c / (e^2 cos_t):
   *   d^2 k / d c^2 = -(1 / e^2) (1 / cos_t - c^2 / (e^2 cos_t^3)),
   * the same with respect to wi . n (sigma^2 = 1). */
  double kcc = -ie * ie * (1.0 - c * c * ie * ie / cos_t2) / cos_t;
  ad k = ad__op1(A, k_v, sigma * (ie - c * ie * ie / cos_t), kcc, cos_wn);

  /* Assemble wt = -wi/e + sigma k n component by component. */
  double sk = sigma * k_v;
  wt->x = ad__lin3(A, -wi.x.v * ie + sk * n.x.v, -ie, wi.x, sk, n.x, sigma * n.x.v, k);
  wt->y = ad__lin3(A, -wi.y.v * ie + sk * n.y.v, -ie, wi.y, sk, n.y, sigma * n.y.v, k);
  wt->z = ad__lin3(A, -wi.z.v * ie + sk * n.z.v, -ie, wi.z, sk, n.z, sigma * n.z.v, k);
  if (AD__H2(A)) { /* f(k, n_i) = sigma k n_i: f_kn = sigma */
    ad__h_sym(A, wt->x, sigma, k, n.x);
    ad__h_sym(A, wt->y, sigma, k, n.y);
    ad__h_sym(A, wt->z, sigma, k, n.z);
  }
  return 1;
}

/* Orthonormal frame around the unit normal n (Duff et al. 2017), the dual
 * form of frame_from_z in src/render/frame.h:
 *   sign = copysign(1, n_z),  a = -1 / (sign + n_z),  b = n_x n_y a
 *   s = (1 + sign n_x^2 a, sign b, -sign n_x),  t = (b, sign + n_y^2 a, -n_y)
 * with  d a = a^2 d_nz,  d b = n_y a d_nx + n_x a d_ny + n_x n_y d_a. */
static inline ad_frame adv3_frame_from_z(ad_arena *A, adv3 n) {
  double sign = copysign(1.0, n.z.v);
  double nx = n.x.v, ny = n.y.v;

  /* The two shared scalars a and b. */
  double a_v = -1.0 / (sign + n.z.v);
  ad a = ad__op1(A, a_v, a_v * a_v, 2.0 * a_v * a_v * a_v, n.z); /* d^2 a / d n_z^2 = 2 a^3 */
  ad b = ad__lin3(A, nx * ny * a_v, ny * a_v, n.x, nx * a_v, n.y, nx * ny, a);
  if (AD__H2(A)) { /* b = n_x n_y a: b_xy = a, b_xa = n_y, b_ya = n_x */
    ad__h_sym(A, b, a_v, n.x, n.y);
    ad__h_sym(A, b, ny, n.x, a);
    ad__h_sym(A, b, nx, n.y, a);
  }

  /* The tangent vectors s and t. */
  ad_frame f;
  f.s.x = ad__lin2(A, 1.0 + sign * nx * nx * a_v, 2.0 * sign * nx * a_v, n.x, sign * nx * nx, a);
  f.s.y = ad__lin1(A, sign * b.v, sign, b);
  f.s.z = ad__lin1(A, -sign * nx, -sign, n.x);
  f.t.x = b;
  f.t.y = ad__lin2(A, sign + ny * ny * a_v, 2.0 * ny * a_v, n.y, ny * ny, a);
  f.t.z = ad__lin1(A, -ny, -1.0, n.y);
  if (AD__H2(A)) { /* s_x = 1 + sign n_x^2 a, t_y = sign + n_y^2 a */
    ad__h_sq(A, f.s.x, 2.0 * sign * a_v, n.x);
    ad__h_sym(A, f.s.x, 2.0 * sign * nx, n.x, a);
    ad__h_sq(A, f.t.y, 2.0 * a_v, n.y);
    ad__h_sym(A, f.t.y, 2.0 * ny, n.y, a);
  }
  f.n = n;
  return f;
}

/* Coordinates of v in frame f: (v . s, v . t, v . n). */
static inline adv3 adv3_to_local(ad_arena *A, const ad_frame *f, adv3 v) {
  return (adv3){adv3_dot(A, v, f->s), adv3_dot(A, v, f->t), adv3_dot(A, v, f->n)};
}

/* World vector with coordinates v in frame f: s v_x + t v_y + n v_z, e.g.
 *   d r_x = v_x d_sx + s_x d_vx + v_y d_tx + t_x d_vy + v_z d_nx + n_x d_vz. */
static inline adv3 adv3_to_world(ad_arena *A, const ad_frame *f, adv3 v) {
  adv3 r;
  const double cx[6] = {v.x.v, f->s.x.v, v.y.v, f->t.x.v, v.z.v, f->n.x.v};
  const double cy[6] = {v.x.v, f->s.y.v, v.y.v, f->t.y.v, v.z.v, f->n.y.v};
  const double cz[6] = {v.x.v, f->s.z.v, v.y.v, f->t.z.v, v.z.v, f->n.z.v};
  r.x = ad__lin6(A, f->s.x.v * v.x.v + f->t.x.v * v.y.v + f->n.x.v * v.z.v, cx, f->s.x, v.x,
                 f->t.x, v.y, f->n.x, v.z);
  r.y = ad__lin6(A, f->s.y.v * v.x.v + f->t.y.v * v.y.v + f->n.y.v * v.z.v, cy, f->s.y, v.x,
                 f->t.y, v.y, f->n.y, v.z);
  r.z = ad__lin6(A, f->s.z.v * v.x.v + f->t.z.v * v.y.v + f->n.z.v * v.z.v, cz, f->s.z, v.x,
                 f->t.z, v.y, f->n.z, v.z);
  if (AD__H2(A)) { /* products s_i v_x + t_i v_y + n_i v_z: mixed partials 1 */
    ad__h_sym(A, r.x, 1.0, f->s.x, v.x);
    ad__h_sym(A, r.x, 1.0, f->t.x, v.y);
    ad__h_sym(A, r.x, 1.0, f->n.x, v.z);
    ad__h_sym(A, r.y, 1.0, f->s.y, v.x);
    ad__h_sym(A, r.y, 1.0, f->t.y, v.y);
    ad__h_sym(A, r.y, 1.0, f->n.y, v.z);
    ad__h_sym(A, r.z, 1.0, f->s.z, v.x);
    ad__h_sym(A, r.z, 1.0, f->t.z, v.y);
    ad__h_sym(A, r.z, 1.0, f->n.z, v.z);
  }
  return r;
}

#endif
