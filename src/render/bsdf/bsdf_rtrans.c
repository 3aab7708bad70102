/*
 * bsdf_rtrans.c: roughplastic's rough transmittance (models/roughplastic.c
 * says what it is and how it is used): T(c) at BSDF_RTRANS_NODES nodes
 * uniform in cos^(1/4), by a product Gauss-Legendre rule over the visible
 * normals of each direction, and the interface's diffuse reflectance seen
 * from inside, by Gauss-Legendre in the cosine. Values only.
 */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "render/bsdf/bsdf_internal.h"
#include "render/bsdf/microfacet.h"

/* ---- roughplastic's rough transmittance (values only) ------------------- */

/* Order of the Gauss-Legendre rules: over the visible normals of one
 * direction (per axis; even), and over the cosine in each of the two
 * pieces of the diffuse integral. Doubling both changes T by under 1e-5
 * and F_dr by under 1e-3 (7e-4 at GGX, alpha 1, eta 1.005). */
#define BSDF__RT_ORDER_M 40
#define BSDF__RT_ORDER_C 24

/* Gauss-Legendre nodes x and weights w of order n on [0, 1]: Newton's
 * method on the Legendre polynomial P_n (three-term recurrence) from the
 * usual guesses cos(pi (i + 3/4) / (n + 1/2)). */
static void bsdf__gauss_legendre(int n, double *x, double *w) {
  for (int i = 0; i < (n + 1) / 2; i++) {
    double z = cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; it++) {
      double p1 = 1.0, p0 = 0.0;
      for (int j = 1; j <= n; j++) {
        double pm = p0;
        p0 = p1;
        p1 = ((2.0 * j - 1.0) * z * p0 - (j - 1.0) * pm) / j;
      }
      /* P_n'(z) = n (z P_n - P_{n-1}) / (z^2 - 1) */
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      double step = p1 / dp;
      z -= step;
      if (fabs(step) < 1e-15) break;
    }
    /* On [-1, 1] the weight is 2 / ((1 - z^2) P_n'(z)^2); halved on [0, 1]. */
    x[i] = 0.5 * (1.0 - z);
    x[n - 1 - i] = 0.5 * (1.0 + z);
    w[i] = w[n - 1 - i] = 1.0 / ((1.0 - z * z) * dp * dp);
  }
}

/* T(c) = int f_t(wo, wi) |cos wi| dwi: the energy that light arriving at
 * cosine c on the side of relative IOR eta (eta < 1: from inside) carries
 * through the rough interface, importance transport (no 1/eta^2), as
 * models/roughdielectric.c's refraction defines f_t. With wi refracted
 * through the normal m, the refraction Jacobian cancels f_t's and
 *   T = int D_wo(m) (1 - F(wo.m)) G1(wi, m) dm,
 * D_wo the visible normals of wo (microfacet.h). The integral is taken
 * over the sample space (u1, u2) of mf_sample's visible normals, which
 * maps the unit square onto D_wo, with a product rule (x, w of order n):
 * the integrand is bounded by 1 and the rule adapts to any alpha. */
static double bsdf__rtrans_dir(mf_dist dist, double alpha, double eta, double c, int n,
                               const double *x, const double *w) {
  if (!(c > 0.0)) return 0.0;
  if (c > 1.0) c = 1.0;
  vec3 wo = v3(sqrt(fmax(0.0, 1.0 - c * c)), 0.0, c);
  /* Beckmann's sampler maps u2 and 1 - u2 to normals mirrored in y, which
   * see the same integrand (wo lies in the xz-plane), and the rule's nodes
   * are symmetric: half the columns, counted twice (n is even). */
  int nj = dist == MF_BECKMANN ? n / 2 : n;
  double wj_scale = dist == MF_BECKMANN ? 2.0 : 1.0;
  double acc = 0.0;
  for (int i = 0; i < n; i++)
    for (int j = 0; j < nj; j++) {
      vec3 m = mf_sample(dist, alpha, wo, 1, x[i], x[j]);
      double wom = v3_dot(wo, m), cos_t;
      if (!(wom > 0.0)) continue;
      double fr = fresnel_dielectric(wom, eta, &cos_t);
      if (cos_t == 0.0) continue; /* total internal reflection */
      /* wi = m (wo.m s + cos_t) - wo s, s = 1 / eta (roughdielectric's refraction) */
      double s = 1.0 / eta;
      vec3 wi = v3_normalize(v3_sub(v3_scale(m, wom * s + cos_t), v3_scale(wo, s)));
      acc += w[i] * w[j] * wj_scale * (1.0 - fr) * mf_G1(dist, alpha, wi, m);
    }
  return acc;
}

void bsdf__rtrans_fill(bsdf_rtrans *rt, mf_dist dist, double alpha, double eta) {
  double xm[BSDF__RT_ORDER_M], wm[BSDF__RT_ORDER_M], xc[BSDF__RT_ORDER_C], wc[BSDF__RT_ORDER_C];
  bsdf__gauss_legendre(BSDF__RT_ORDER_M, xm, wm);
  bsdf__gauss_legendre(BSDF__RT_ORDER_C, xc, wc);
  memset(rt, 0, sizeof *rt);
  rt->dist = dist;
  rt->alpha = alpha;
  rt->eta = eta;
  /* T from outside at the nodes c = (k / (N - 1))^4; at grazing, T's limit
   * (nonzero on a rough surface: the facets that face wo stay visible). */
  const int last = BSDF_RTRANS_NODES - 1;
  for (int k = 0; k <= last; k++) {
    double s = (double)k / last, c = k > 0 ? s * s * s * s : 1e-12;
    rt->t_ext[k] = bsdf__rtrans_dir(dist, alpha, eta, c, BSDF__RT_ORDER_M, xm, wm);
  }
  /* The diffuse transmittance from inside, int_0^1 2 c T_int(c) dc at
   * 1 / eta, in two pieces split at the smooth critical cosine c_c, where
   * T_int has a square-root kink when alpha is small: [0, c_c] plainly,
   * [c_c, 1] after c = c_c + (1 - c_c) t^2 (as bsdf__fdr_compute). */
  double ei = 1.0 / eta;
  double cc = ei < 1.0 ? sqrt(fmax(0.0, 1.0 - ei * ei)) : 0.0;
  double td = 0.0;
  for (int k = 0; k < BSDF__RT_ORDER_C; k++) {
    if (cc > 0.0) {
      double c = cc * xc[k];
      td += wc[k] * cc * 2.0 * c * bsdf__rtrans_dir(dist, alpha, ei, c, BSDF__RT_ORDER_M, xm, wm);
    }
    double t = xc[k], c = cc + (1.0 - cc) * t * t;
    double jac = 2.0 * (1.0 - cc) * t;
    td += wc[k] * jac * 2.0 * c * bsdf__rtrans_dir(dist, alpha, ei, c, BSDF__RT_ORDER_M, xm, wm);
  }
  rt->fdr_int = 1.0 - td;
  rt->ready = 1;
}

const bsdf_rtrans *bsdf__rtrans_get(const bsdf *b) {
  const bsdf_rtrans *own = &b->rtrans;
  if (own->ready && own->dist == b->dist && own->alpha == b->alpha && own->eta == b->eta)
    return own;
  /* Not prepared (or prepared for other parameters): a small per-thread
   * cache, filled on first use. */
  static _Thread_local bsdf_rtrans cache[4];
  static _Thread_local int cache_next;
  for (int i = 0; i < 4; i++)
    if (cache[i].ready && cache[i].dist == b->dist && cache[i].alpha == b->alpha &&
        cache[i].eta == b->eta)
      return &cache[i];
  bsdf_rtrans *rt = &cache[cache_next];
  cache_next = (cache_next + 1) & 3;
  bsdf__rtrans_fill(rt, b->dist, b->alpha, b->eta);
  return rt;
}
