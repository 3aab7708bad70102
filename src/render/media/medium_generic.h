/*
 * medium_generic.h: the homogeneous medium's transmittance and free flight
 * (medium.h), written once in render/real.h's vocabulary and compiled twice
 * by medium.c, in doubles and in duals. Not a header: no include guard.
 */

RRGB R_FN(medium_transmittance)(R_CTX const medium *m, REAL t) {
  /* exp(-sigma_t t) per channel; a clear channel's is 1 even over an
   * unbounded segment */
  const double st[3] = {m->sigma_t.r, m->sigma_t.g, m->sigma_t.b};
  REAL e[3];
  for (int c = 0; c < 3; c++) e[c] = st[c] > 0.0 ? R_EXP(R_MUL_S(t, -st[c])) : R_C(1.0);
  return RRGB_MAKE(e[0], e[1], e[2]);
}

REAL R_FN(medium_track_pdf)(R_CTX const medium *m, int scattered, RRGB T) {
  /* the channels' mean of sigma_t T (scattered at t) or of T (reached t) */
  REAL e[3] = {T.r, T.g, T.b};
  REAL sum = R_C(0.0);
  for (int c = 0; c < 3 && scattered; c++) {
    double st = c == 0 ? m->sigma_t.r : c == 1 ? m->sigma_t.g : m->sigma_t.b;
    sum = R_ADD(sum, R_MUL_S(e[c], st));
  }
  for (int c = 0; c < 3 && !scattered; c++) sum = R_ADD(sum, e[c]);
  return R_MUL_S(sum, 1.0 / 3.0);
}

void R_FN(medium_track_begin)(R_CTX REAL u_ch, REAL u_t, R_FN(medium_track) *k) {
  int c = (int)(R_V(u_ch) * 3.0);
  k->c = c > 2 ? 2 : c < 0 ? 0 : c;
  k->tau = R_NEG(R_LOG1P(R_NEG(u_t))); /* -log(1 - u_t): exponential of rate 1 */
  k->T = RRGB_CONST(rgb_gray(1.0));
}

int R_FN(medium_track_piece)(R_CTX const medium *m, REAL len, R_FN(medium_track) *k,
                             REAL *OUT_t) {
  if (!m) return 0;
  double sc = k->c == 0 ? m->sigma_t.r : k->c == 1 ? m->sigma_t.g : m->sigma_t.b;
  if (sc > 0.0 && R_V(k->tau) < sc * R_V(len)) {
    *OUT_t = R_DIV_S(k->tau, sc);
    k->T = RRGB_MUL(k->T, R_FN(medium_transmittance)(R_ARG m, *OUT_t));
    return 1;
  }
  if (sc > 0.0) k->tau = R_SUB(k->tau, R_MUL_S(len, sc));
  k->T = RRGB_MUL(k->T, R_FN(medium_transmittance)(R_ARG m, len));
  return 0;
}

REAL R_FN(medium_flight_pdf)(R_CTX const medium *m, int scattered, REAL t) {
  return R_FN(medium_track_pdf)(R_ARG m, scattered, R_FN(medium_transmittance)(R_ARG m, t));
}

int R_FN(medium_sample_flight)(R_CTX const medium *m, REAL t_max, REAL u_ch, REAL u_t,
                               R_FN(medium_flight) *out) {
  R_FN(medium_track) k;
  R_FN(medium_track_begin)(R_ARG u_ch, u_t, &k);
  REAL t = t_max;
  int inside = R_FN(medium_track_piece)(R_ARG m, t_max, &k, &t);
  if (!inside && !isfinite(R_V(t_max))) return 0;
  out->scattered = inside;
  out->t = t;
  out->pdf = R_FN(medium_track_pdf)(R_ARG m, inside, k.T);
  if (!(R_V(out->pdf) > 0.0) || !isfinite(R_V(out->pdf))) return 0;
  /* weight = T(t) (sigma_s when scattered) / pdf */
  RRGB w = inside ? RRGB_MUL(k.T, RRGB_CONST(m->sigma_s)) : k.T;
  out->weight = RRGB_SCALE(w, R_INV(out->pdf));
  return 1;
}
