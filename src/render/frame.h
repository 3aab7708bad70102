/*
 * frame.h: orthonormal frames (the shading frame is z-up).
 *
 * frame_from_z builds a frame around a unit normal with the branchless
 * construction of Duff et al. 2017 ("Building an Orthonormal Basis,
 * Revisited"), which is continuous except on the n.z = -1 ... 0 switch of sign.
 */
#ifndef LMC_RENDER_FRAME_H
#define LMC_RENDER_FRAME_H

#include "render/vec3.h"

typedef struct frame {
  vec3 s, t, n;
} frame;

static inline frame frame_from_z(vec3 n) {
  double sign = copysign(1.0, n.z);
  double a = -1.0 / (sign + n.z);
  double b = n.x * n.y * a;
  frame f;
  f.s = v3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
  f.t = v3(b, sign + n.y * n.y * a, -n.y);
  f.n = n;
  return f;
}

/* Frame with normal n whose first axis is the component of dpdu orthogonal
 * to n (falls back to frame_from_z when dpdu is degenerate). */
static inline frame frame_from_zx(vec3 n, vec3 dpdu) {
  vec3 s = v3_sub(dpdu, v3_scale(n, v3_dot(n, dpdu)));
  double l = v3_len(s);
  if (!(l > 1e-12)) return frame_from_z(n);
  frame f;
  f.n = n;
  f.s = v3_scale(s, 1.0 / l);
  f.t = v3_cross(n, f.s);
  return f;
}

static inline vec3 frame_to_local(const frame *f, vec3 v) {
  return v3(v3_dot(v, f->s), v3_dot(v, f->t), v3_dot(v, f->n));
}

static inline vec3 frame_to_world(const frame *f, vec3 v) {
  return v3_add(v3_add(v3_scale(f->s, v.x), v3_scale(f->t, v.y)), v3_scale(f->n, v.z));
}

#endif
