/*
 * medium_generic.h: the homogeneous medium's transmittance and free flight
 * (medium.h), written once in render/real.h's vocabulary and compiled twice
 * by medium.c, in doubles and in duals. Not a header: no include guard.
 */

RRGB R_FN(medium_transmittance)(R_CTX const medium *m, REAL t) {
  /* exp(-sigma_t t) per channel */
  return RRGB_MAKE(R_EXP(R_MUL_S(t, -m->sigma_t.r)), R_EXP(R_MUL_S(t, -m->sigma_t.g)),
                   R_EXP(R_MUL_S(t, -m->sigma_t.b)));
}

REAL R_FN(medium_flight_pdf)(R_CTX const medium *m, int scattered, REAL t) {
  const double st[3] = {m->sigma_t.r, m->sigma_t.g, m->sigma_t.b};
  REAL sum = R_C(0.0);
  for (int c = 0; c < 3; c++) {
    /* scattering: sigma_t exp(-sigma_t t); reaching t: exp(-sigma_t t) */
    REAL e = R_EXP(R_MUL_S(t, -st[c]));
    sum = R_ADD(sum, scattered ? R_MUL_S(e, st[c]) : e);
  }
  return R_MUL_S(sum, 1.0 / 3.0);
}

int R_FN(medium_sample_flight)(R_CTX const medium *m, REAL t_max, REAL u_ch, REAL u_t,
                               R_FN(medium_flight) *out) {
  const double st[3] = {m->sigma_t.r, m->sigma_t.g, m->sigma_t.b};
  int c = (int)(R_V(u_ch) * 3.0);
  if (c > 2) c = 2;
  if (c < 0) c = 0;
  /* t = -log(1 - u_t) / sigma_t[c] (infinite when the channel is clear) */
  int inside = 0;
  REAL t = t_max;
  if (st[c] > 0.0) {
    REAL d = R_DIV_S(R_NEG(R_LOG1P(R_NEG(u_t))), st[c]);
    if (R_V(d) < R_V(t_max)) inside = 1, t = d;
  }
  if (!inside && !isfinite(R_V(t_max))) return 0;
  out->scattered = inside;
  out->t = t;
  out->pdf = R_FN(medium_flight_pdf)(R_ARG m, inside, t);
  if (!(R_V(out->pdf) > 0.0) || !isfinite(R_V(out->pdf))) return 0;
  /* weight = T(t) (sigma_s when scattered) / pdf */
  RRGB w = R_FN(medium_transmittance)(R_ARG m, t);
  if (inside) w = RRGB_MUL(w, RRGB_CONST(m->sigma_s));
  out->weight = RRGB_SCALE(w, R_INV(out->pdf));
  return 1;
}
