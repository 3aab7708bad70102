/*
 * medium.c: the homogeneous medium (medium.h): its free flight and
 * transmittance written once (medium_generic.h) and compiled here in
 * doubles and in duals, and the flight's inverse (values only).
 */
#include "render/media/medium.h"

#include <math.h>
#include <string.h>

#include "ad/dual_math.h"
#include "render/warp.h"

void medium_set(medium *m, rgb sigma_a, rgb sigma_s) {
  memset(m, 0, sizeof *m);
  m->sigma_a = sigma_a;
  m->sigma_s = sigma_s;
  m->sigma_t = rgb_add(sigma_a, sigma_s);
  phase_init(&m->ph, "isotropic");
}

#define R_DUAL 0
#include "render/real.h"
#include "render/media/medium_generic.h"
#undef R_DUAL
#define R_DUAL 1
#include "render/real.h"
#include "render/media/medium_generic.h"
#undef R_DUAL

int medium_invert_flight(const medium *m, int scattered, double t, const double r[2],
                         double OUT_u[2]) {
  const double st[3] = {m->sigma_t.r, m->sigma_t.g, m->sigma_t.b};
  /* Each channel's share of the density of this outcome (the sampler's
   * choice of a channel is uniform). */
  double share[3], sum = 0.0;
  for (int c = 0; c < 3; c++) {
    double e = st[c] > 0.0 ? exp(-st[c] * t) : (scattered ? 0.0 : 1.0);
    share[c] = scattered ? st[c] * e : e;
    sum += share[c];
  }
  if (!(sum > 0.0) || !(t >= 0.0) || !isfinite(t)) return 0;
  double x = r[0] * sum;
  int c = 0;
  while (c < 2 && !(x < share[c])) x -= share[c++];
  if (!(share[c] > 0.0)) return 0;
  /* u_ch inside the channel's third, at r[0]'s place within its share. */
  double within = fmin(fmax(x / share[c], 0.0), nextafter(1.0, 0.0));
  OUT_u[0] = warp_uniform_in(c / 3.0, (c + 1) / 3.0, within);
  if (scattered) {
    /* u_t = 1 - exp(-sigma_t t) */
    OUT_u[1] = -expm1(-st[c] * t);
  } else {
    /* any u_t whose distance reaches t: [1 - exp(-sigma_t t), 1) */
    double lo = st[c] > 0.0 ? -expm1(-st[c] * t) : 0.0;
    OUT_u[1] = warp_uniform_in(lo, 1.0, r[1]);
  }
  /* Refused where the sampler does not make it back (a u_t at the edge of
   * its interval, rounded to the other side of t). */
  medium_flight f;
  return OUT_u[1] < 1.0 &&
         medium_sample_flight(m, scattered ? INFINITY : t, OUT_u[0], OUT_u[1], &f) &&
         f.scattered == scattered && (!scattered || fabs(f.t - t) <= 1e-9 * (1.0 + t));
}
