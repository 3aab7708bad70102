/*
 * transform.c: 4x4 affine transforms and their inverses.
 *
 * A transform keeps its matrix m and the inverse inv side by side, so that
 * points, vectors and normals can go both ways without inverting at use time.
 * Matrices are row-major and act on column vectors: p' = m [p, 1]^T. The
 * constructors follow the elements of Mitsuba's <transform> block
 * (translate, scale, rotate, lookat, matrix); the loader composes them in
 * document order with xform_compose(new, old), i.e. M = M_new * M_old, so a
 * later element is applied after the earlier ones.
 *
 * Inverses: the elementary transforms have closed-form inverses (negated
 * translation, reciprocal scale, transposed rotation, and for lookat the
 * transposed orthonormal basis with the rotated, negated origin). A matrix
 * given by value is inverted with Gauss-Jordan elimination with partial
 * pivoting; a singular one is refused.
 *
 * Normals transform with the inverse transpose: n' = inv^T n, which keeps
 * them perpendicular to transformed tangents under non-uniform scale.
 */
#include "render/transform.h"

#include <math.h>
#include <string.h>

/* Row-major product r = a * b of 4x4 matrices. */
static void xform__mul(const double a[4][4], const double b[4][4], double r[4][4]) {
  for (int i = 0; i < 4; i++) {
    for (int j = 0; j < 4; j++) {
      double s = 0.0;
      for (int k = 0; k < 4; k++) s += a[i][k] * b[k][j];
      r[i][j] = s;
    }
  }
}

static void xform__set_identity(double m[4][4]) {
  memset(m, 0, sizeof(double) * 16);
  for (int i = 0; i < 4; i++) m[i][i] = 1.0;
}

/* General 4x4 inverse by Gauss-Jordan elimination with partial pivoting:
 * reduce [a | I] to [I | a^-1]. Returns 0 when a pivot is (numerically)
 * zero relative to the matrix's largest entry. */
static int xform__invert(const xform *t, double out[4][4]) {
  const double(*a)[4] = t->m;
  double w[4][8];
  double amax = 0.0;
  for (int i = 0; i < 4; i++) {
    for (int j = 0; j < 4; j++) {
      w[i][j] = a[i][j];
      w[i][j + 4] = (i == j) ? 1.0 : 0.0;
      if (fabs(a[i][j]) > amax) amax = fabs(a[i][j]);
      if (!isfinite(a[i][j])) return 0;
    }
  }
  if (!(amax > 0.0)) return 0;
  for (int c = 0; c < 4; c++) {
    /* Choose the row with the largest entry in column c as pivot. */
    int piv = c;
    for (int r = c + 1; r < 4; r++)
      if (fabs(w[r][c]) > fabs(w[piv][c])) piv = r;
    if (!(fabs(w[piv][c]) > 1e-12 * amax)) return 0;
    if (piv != c) {
      for (int j = 0; j < 8; j++) {
        double tmp = w[c][j];
        w[c][j] = w[piv][j];
        w[piv][j] = tmp;
      }
    }
    /* Normalise the pivot row, then clear column c in all other rows. */
    double inv_p = 1.0 / w[c][c];
    for (int j = 0; j < 8; j++) w[c][j] *= inv_p;
    for (int r = 0; r < 4; r++) {
      if (r == c) continue;
      double f = w[r][c];
      if (f == 0.0) continue;
      for (int j = 0; j < 8; j++) w[r][j] -= f * w[c][j];
    }
  }
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) out[i][j] = w[i][j + 4];
  return 1;
}

xform xform_identity(void) {
  xform t;
  xform__set_identity(t.m);
  xform__set_identity(t.inv);
  return t;
}

xform xform_translate(vec3 d) {
  xform t = xform_identity();
  t.m[0][3] = d.x;
  t.m[1][3] = d.y;
  t.m[2][3] = d.z;
  t.inv[0][3] = -d.x;
  t.inv[1][3] = -d.y;
  t.inv[2][3] = -d.z;
  return t;
}

xform xform_scale(vec3 s) {
  xform t = xform_identity();
  t.m[0][0] = s.x;
  t.m[1][1] = s.y;
  t.m[2][2] = s.z;
  /* A zero scale has no inverse; the reciprocal is then infinite, which
   * the loader refuses before it gets here. */
  t.inv[0][0] = 1.0 / s.x;
  t.inv[1][1] = 1.0 / s.y;
  t.inv[2][2] = 1.0 / s.z;
  return t;
}

xform xform_rotate(vec3 axis, double degrees) {
  /* Rodrigues' formula for a unit axis a and angle theta:
   *   R = cos(theta) I + sin(theta) [a]_x + (1 - cos(theta)) a a^T
   * where [a]_x is the cross-product matrix. R^-1 = R^T. */
  xform t = xform_identity();
  vec3 a = v3_normalize(axis);
  double th = degrees * (3.14159265358979323846 / 180.0);
  double s = sin(th), c = cos(th), oc = 1.0 - c;
  t.m[0][0] = c + oc * a.x * a.x;
  t.m[0][1] = oc * a.x * a.y - s * a.z;
  t.m[0][2] = oc * a.x * a.z + s * a.y;
  t.m[1][0] = oc * a.y * a.x + s * a.z;
  t.m[1][1] = c + oc * a.y * a.y;
  t.m[1][2] = oc * a.y * a.z - s * a.x;
  t.m[2][0] = oc * a.z * a.x - s * a.y;
  t.m[2][1] = oc * a.z * a.y + s * a.x;
  t.m[2][2] = c + oc * a.z * a.z;
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) t.inv[i][j] = t.m[j][i];
  return t;
}

int xform_lookat(vec3 origin, vec3 target, vec3 up, xform *out) {
  /* Mitsuba's lookAt: dir = normalize(target - origin),
   * left = normalize(cross(up, dir)), newUp = cross(dir, left);
   * the matrix has columns left, newUp, dir, origin. */
  vec3 d = v3_sub(target, origin);
  double dl = v3_len(d);
  if (!(dl > 0.0) || !v3_isfinite(d)) return 0;
  vec3 dir = v3_scale(d, 1.0 / dl);
  vec3 left = v3_cross(v3_normalize(up), dir);
  double ll = v3_len(left);
  if (!(ll > 1e-12)) return 0;
  left = v3_scale(left, 1.0 / ll);
  vec3 new_up = v3_cross(dir, left);
  xform t = xform_identity();
  vec3 cols[3] = {left, new_up, dir};
  for (int j = 0; j < 3; j++) {
    t.m[0][j] = cols[j].x;
    t.m[1][j] = cols[j].y;
    t.m[2][j] = cols[j].z;
  }
  t.m[0][3] = origin.x;
  t.m[1][3] = origin.y;
  t.m[2][3] = origin.z;
  /* Inverse of [R | o]: [R^T | -R^T o] (R orthonormal). */
  for (int i = 0; i < 3; i++) {
    for (int j = 0; j < 3; j++) t.inv[i][j] = t.m[j][i];
    t.inv[i][3] = -(t.inv[i][0] * origin.x + t.inv[i][1] * origin.y + t.inv[i][2] * origin.z);
  }
  *out = t;
  return 1;
}

int xform_from_matrix(const double v[16], xform *out) {
  xform t;
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) t.m[i][j] = v[4 * i + j];
  if (!xform__invert(&t, t.inv)) return 0;
  *out = t;
  return 1;
}

xform xform_compose(const xform *a, const xform *b) {
  /* (a b)^-1 = b^-1 a^-1 */
  xform t;
  xform__mul(a->m, b->m, t.m);
  xform__mul(b->inv, a->inv, t.inv);
  return t;
}

int xform_is_identity(const xform *t) {
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++)
      if (t->m[i][j] != (i == j ? 1.0 : 0.0)) return 0;
  return 1;
}

double xform_det3(const xform *t) {
  const double(*m)[4] = t->m;
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

vec3 xform_point(const xform *t, vec3 p) {
  const double(*m)[4] = t->m;
  double x = m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3];
  double y = m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3];
  double z = m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3];
  double w = m[3][0] * p.x + m[3][1] * p.y + m[3][2] * p.z + m[3][3];
  /* Affine transforms have w = 1; divide only for a projective matrix. */
  if (w != 1.0 && w != 0.0) return v3(x / w, y / w, z / w);
  return v3(x, y, z);
}

vec3 xform_vector(const xform *t, vec3 v) {
  const double(*m)[4] = t->m;
  return v3(m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
            m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z);
}

vec3 xform_normal(const xform *t, vec3 n) {
  /* n' = inv^T n */
  const double(*q)[4] = t->inv;
  return v3(q[0][0] * n.x + q[1][0] * n.y + q[2][0] * n.z,
            q[0][1] * n.x + q[1][1] * n.y + q[2][1] * n.z,
            q[0][2] * n.x + q[1][2] * n.y + q[2][2] * n.z);
}

vec3 xform_inv_vector(const xform *t, vec3 v) {
  const double(*q)[4] = t->inv;
  return v3(q[0][0] * v.x + q[0][1] * v.y + q[0][2] * v.z,
            q[1][0] * v.x + q[1][1] * v.y + q[1][2] * v.z,
            q[2][0] * v.x + q[2][1] * v.y + q[2][2] * v.z);
}

vec3 xform_inv_point(const xform *t, vec3 p) {
  const double(*q)[4] = t->inv;
  double x = q[0][0] * p.x + q[0][1] * p.y + q[0][2] * p.z + q[0][3];
  double y = q[1][0] * p.x + q[1][1] * p.y + q[1][2] * p.z + q[1][3];
  double z = q[2][0] * p.x + q[2][1] * p.y + q[2][2] * p.z + q[2][3];
  double w = q[3][0] * p.x + q[3][1] * p.y + q[3][2] * p.z + q[3][3];
  if (w != 1.0 && w != 0.0) return v3(x / w, y / w, z / w);
  return v3(x, y, z);
}
