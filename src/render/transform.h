/*
 * transform.h: 4x4 affine transforms with their inverses, as Mitsuba's
 * <transform> element builds them (lookat, translate, rotate, scale, matrix).
 * Composition follows Mitsuba: each nested element is applied after the
 * ones before it, i.e. M = M_new * M_old.
 */
#ifndef LMC_RENDER_TRANSFORM_H
#define LMC_RENDER_TRANSFORM_H

#include "render/vec3.h"

typedef struct xform {
  double m[4][4];   /* row-major: p' = m * [p, 1] */
  double inv[4][4]; /* inverse of m */
} xform;

xform xform_identity(void);
xform xform_translate(vec3 t);
xform xform_scale(vec3 s);
/* Rotation by `degrees` about `axis` (right-handed). */
xform xform_rotate(vec3 axis, double degrees);
/* Mitsuba's lookat: camera-to-world with local +z towards target, +y up,
 * +x = cross(up, dir) (to the left in the image). Returns 0 when degenerate. */
int xform_lookat(vec3 origin, vec3 target, vec3 up, xform *out);
/* From 16 row-major values; returns 0 when the matrix is singular. */
int xform_from_matrix(const double v[16], xform *out);
/* a * b: apply b first, then a. */
xform xform_compose(const xform *a, const xform *b);
int xform_is_identity(const xform *t);
/* Determinant of the upper 3x3 (negative when the transform mirrors). */
double xform_det3(const xform *t);

vec3 xform_point(const xform *t, vec3 p);
vec3 xform_vector(const xform *t, vec3 v);
/* Transforms a normal with the inverse transpose (not normalised). */
vec3 xform_normal(const xform *t, vec3 n);
vec3 xform_inv_vector(const xform *t, vec3 v);
vec3 xform_inv_point(const xform *t, vec3 p);

#endif
