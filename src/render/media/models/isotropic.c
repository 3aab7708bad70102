/*
 * isotropic.c: the isotropic phase function (Mitsuba 0.6's `isotropic`),
 * one phase model (phase.h). No parameters.
 *
 * p = 1 / (4 pi) for every pair of directions; sampling is uniform on the
 * sphere: the deflection's cosine 1 - 2 u1, the azimuth 2 pi u2 about -wo.
 *
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by render/model_twice.h, in doubles and in duals.
 */
#ifndef R_DUAL
#include "render/media/phase_model_file.h"

#define MODEL_BODY "render/media/models/isotropic.c"
#include "render/model_twice.h"

static int phase__isotropic_invert(const phase_fn *ph, vec3 wo, vec3 wi, double OUT_u[2]) {
  (void)ph;
  frame f = frame_from_z(v3_neg(wo));
  vec3 l = frame_to_local(&f, wi);
  OUT_u[0] = fmin(fmax(0.5 * (1.0 - l.z), 0.0), nextafter(1.0, 0.0));
  OUT_u[1] = warp_turn(atan2(l.y, l.x));
  return 1;
}

const phase_model phase_model_isotropic = {
    .name = "isotropic",
    .eval = phase__isotropic_eval,
    .sample = phase__isotropic_sample,
    .invert = phase__isotropic_invert,
    .eval_ad = phase__isotropic_eval_ad,
    .sample_ad = phase__isotropic_sample_ad,
};

#else /* the body, in render/real.h's vocabulary */

static REAL R_FN(phase__isotropic_eval)(R_CTX const phase_fn *ph, REAL3 wo, REAL3 wi) {
  (void)ph, (void)wo, (void)wi;
  return R_C(1.0 / (4.0 * M_PI));
}

static int R_FN(phase__isotropic_sample)(R_CTX const phase_fn *ph, REAL3 wo, REAL u1, REAL u2,
                                         REAL3 *OUT_wi, REAL *OUT_pdf) {
  (void)ph;
  /* cos theta = 1 - 2 u1, phi = 2 pi u2, about -wo */
  REAL c = R_S_SUB(1.0, R_MUL_S(u1, 2.0));
  REAL s = R_SAFE_SQRT(R_S_SUB(1.0, R_SQR(c)));
  REAL phi = R_MUL_S(u2, 2.0 * M_PI);
  RFRAME f = R3_FRAME_FROM_Z(R3_NEG(wo));
  *OUT_wi = R3_TO_WORLD(&f, R3_MAKE(R_MUL(s, R_COS(phi)), R_MUL(s, R_SIN(phi)), c));
  *OUT_pdf = R_C(1.0 / (4.0 * M_PI));
  return 1;
}

#endif
