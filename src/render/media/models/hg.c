/*
 * hg.c: the Henyey-Greenstein phase function (Henyey and Greenstein 1941,
 * Mitsuba 0.6's `hg`), one phase model (phase.h).
 * Parameters (Mitsuba's names and defaults): g (0.8), in (-1, 1): the mean
 * cosine of the deflection (> 0 forward, < 0 backward, 0 isotropic).
 *
 * With cos theta = -wo . wi the cosine of the deflection,
 *   p = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos theta)^(3/2)).
 * Sampling inverts the distribution of cos theta (Mitsuba's formula):
 *   s = (1 - g^2) / (1 - g + 2 g u1),  cos theta = (1 + g^2 - s^2) / (2 g)
 * (1 - 2 u1 when |g| is below 1e-4, as Mitsuba's Epsilon), the azimuth
 * 2 pi u2 about -wo; the sample's density is p. The inverse:
 *   s = sqrt(1 + g^2 - 2 g cos theta),  u1 = ((1 - g^2) / s - 1 + g) / (2 g).
 *
 * The body below the #else is written once in render/real.h's vocabulary
 * and compiled twice by render/model_twice.h, in doubles and in duals.
 */
#ifndef PHASE__HG_EPS
#define PHASE__HG_EPS 1e-4 /* Mitsuba's Epsilon: below it hg samples as isotropic */
#endif

#ifndef R_DUAL
#include "render/media/phase_model_file.h"

#define MODEL_BODY "render/media/models/hg.c"
#include "render/model_twice.h"

static int phase__hg_invert(const phase_fn *ph, vec3 wo, vec3 wi, double OUT_u[2]) {
  double g = ph->g;
  frame f = frame_from_z(v3_neg(wo));
  vec3 l = frame_to_local(&f, wi);
  double c = fmin(fmax(l.z, -1.0), 1.0), u1;
  if (fabs(g) < PHASE__HG_EPS) {
    u1 = 0.5 * (1.0 - c);
  } else {
    double s = sqrt(fmax(0.0, 1.0 + g * g - 2.0 * g * c));
    if (!(s > 0.0)) return 0;
    u1 = ((1.0 - g * g) / s - 1.0 + g) / (2.0 * g);
  }
  OUT_u[0] = fmin(fmax(u1, 0.0), nextafter(1.0, 0.0));
  OUT_u[1] = warp_turn(atan2(l.y, l.x));
  return 1;
}

static void phase__hg_defaults(phase_fn *ph) { ph->g = 0.8; }

static lmc_status phase__hg_read(phase_fn *ph, plugin_props *p) {
  lmc_status st = props_float(p, "g", ph->g, &ph->g, NULL);
  if (st != LMC_OK) return st;
  if (!(ph->g > -1.0 && ph->g < 1.0))
    return props_fail(p, "g", "hg's g must lie in (-1, 1) (it is %g)", ph->g);
  return LMC_OK;
}

const phase_model phase_model_hg = {
    .name = "hg",
    .defaults = phase__hg_defaults,
    .read = phase__hg_read,
    .eval = phase__hg_eval,
    .sample = phase__hg_sample,
    .invert = phase__hg_invert,
    .eval_ad = phase__hg_eval_ad,
    .sample_ad = phase__hg_sample_ad,
};

#else /* the body, in render/real.h's vocabulary */

/* p of the deflection's cosine c. */
static REAL R_FN(phase__hg_p)(R_CTX double g, REAL c) {
  /* (1 - g^2) / (4 pi t^(3/2)), t = 1 + g^2 - 2 g c */
  REAL t = R_S_SUB(1.0 + g * g, R_MUL_S(c, 2.0 * g));
  return R_S_DIV((1.0 - g * g) / (4.0 * M_PI), R_MUL(t, R_SQRT(t)));
}

static REAL R_FN(phase__hg_eval)(R_CTX const phase_fn *ph, REAL3 wo, REAL3 wi) {
  return R_FN(phase__hg_p)(R_ARG ph->g, R_NEG(R3_DOT(wo, wi)));
}

static int R_FN(phase__hg_sample)(R_CTX const phase_fn *ph, REAL3 wo, REAL u1, REAL u2,
                                  REAL3 *OUT_wi, REAL *OUT_pdf) {
  double g = ph->g;
  REAL c;
  if (fabs(g) < PHASE__HG_EPS) {
    c = R_S_SUB(1.0, R_MUL_S(u1, 2.0));
  } else {
    /* s = (1 - g^2) / (1 - g + 2 g u1), c = (1 + g^2 - s^2) / (2 g) */
    REAL s = R_S_DIV(1.0 - g * g, R_ADD_S(R_MUL_S(u1, 2.0 * g), 1.0 - g));
    c = R_DIV_S(R_S_SUB(1.0 + g * g, R_SQR(s)), 2.0 * g);
  }
  if (R_V(c) > 1.0) c = R_C(1.0);
  if (R_V(c) < -1.0) c = R_C(-1.0);
  REAL sn = R_SAFE_SQRT(R_S_SUB(1.0, R_SQR(c)));
  REAL phi = R_MUL_S(u2, 2.0 * M_PI);
  RFRAME f = R3_FRAME_FROM_Z(R3_NEG(wo));
  *OUT_wi = R3_TO_WORLD(&f, R3_MAKE(R_MUL(sn, R_COS(phi)), R_MUL(sn, R_SIN(phi)), c));
  *OUT_pdf = R_FN(phase__hg_p)(R_ARG g, c);
  return R_V(*OUT_pdf) > 0.0 && isfinite(R_V(*OUT_pdf));
}

#endif
