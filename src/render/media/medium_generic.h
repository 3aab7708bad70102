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

/* The flight's density from the transmittance T(t): the channels' mean
 * of sigma_t T (scattered at t) or of T (reached t). */
static REAL R_FN(medium__pdf_of)(R_CTX const medium *m, int scattered, RRGB T) {
  REAL e[3] = {T.r, T.g, T.b};
  const double st[3] = {m->sigma_t.r, m->sigma_t.g, m->sigma_t.b};
  REAL sum = R_C(0.0);
  for (int c = 0; c < 3; c++) sum = R_ADD(sum, scattered ? R_MUL_S(e[c], st[c]) : e[c]);
  return R_MUL_S(sum, 1.0 / 3.0);
}

REAL R_FN(medium_flight_pdf)(R_CTX const medium *m, int scattered, REAL t) {
  return R_FN(medium__pdf_of)(R_ARG m, scattered, R_FN(medium_transmittance)(R_ARG m, t));
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
  RRGB w = R_FN(medium_transmittance)(R_ARG m, t);
  out->pdf = R_FN(medium__pdf_of)(R_ARG m, inside, w);
  if (!(R_V(out->pdf) > 0.0) || !isfinite(R_V(out->pdf))) return 0;
  /* weight = T(t) (sigma_s when scattered) / pdf */
  if (inside) w = RRGB_MUL(w, RRGB_CONST(m->sigma_s));
  out->weight = RRGB_SCALE(w, R_INV(out->pdf));
  return 1;
}
