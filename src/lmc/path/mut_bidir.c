/*
 * mut_bidir.c: Veach's bidirectional mutation (Veach 1997, section 11.4.2;
 * Veach and Guibas 1997), its transition density and acceptance ratio.
 * mut_bidir.h states the move, its probabilities and the rules; Mitsuba
 * 0.6's BidirectionalMutator was read for the method's facts (the two-sided
 * base-2 length distributions, the sum over the ways a proposal could have
 * been made), not its structure: here the deletion length is drawn first
 * and the addition length around it, as in Veach's thesis.
 *
 * The walks are bdpt's (bdpt_camera_subpath, bdpt_light_subpath,
 * bdpt_continue_subpath) with Russian roulette off, so that a walk of the
 * wanted length has exactly the densities pathspace.c computes; the one
 * step bdpt has no function for, scattering at a kept vertex, samples its
 * BSDF (or its light's emission) here and hands the direction to
 * bdpt_continue_subpath. Random numbers come from the caller's rng.
 */
#include "lmc/path/mut_bidir.h"

#include <stdlib.h>
#include <string.h>

void mut_bidir_init(mut_bidir *mb, const ps_context *ctx) {
  mb->ctx = ctx;
  mb->test_bias_term = MUT_BIDIR_BIAS_NONE;
  mb->test_bias = 1.0;
}

/* ---- The move's discrete choices --------------------------------------------- */

/* Veach's weights of the deletion length. */
static double mut_bidir__w_kd(int kd) { return kd == 1 ? 0.25 : kd == 2 ? 0.5 : ldexp(1.0, -kd); }

double mut_bidir_pmf_kd(int k, int kd) {
  if (kd < 1 || kd > k + 2) return 0.0;
  double sum = 0.0;
  for (int j = 1; j <= k + 2; j++) sum += mut_bidir__w_kd(j);
  return mut_bidir__w_kd(kd) / sum;
}

int mut_bidir_ranges(int k, int kd, int *OUT_lmin) {
  int lmin = kd == 1 ? 0 : -1;
  int n = kd == 1 ? k : k + 3 - kd;
  if (kd < 1 || kd > k + 2) n = 0;
  if (OUT_lmin) *OUT_lmin = lmin;
  return n;
}

/* The addition lengths that keep the new length in [kmin, kmax]. */
static void mut_bidir__ka_bounds(const ps_context *ctx, int k, int kd, int *OUT_lo, int *OUT_hi) {
  int lo = ctx->kmin - k + kd;
  *OUT_lo = lo > 1 ? lo : 1;
  *OUT_hi = ctx->kmax - k + kd;
}

/* The weight of ka around kd: 2^-|ka - kd|, without the identity move. */
static double mut_bidir__w_ka(int kd, int ka) {
  if (kd == 1 && ka == 1) return 0.0;
  return ldexp(1.0, -abs(ka - kd));
}

double mut_bidir_pmf_ka(const ps_context *ctx, int k, int kd, int ka) {
  int lo, hi;
  mut_bidir__ka_bounds(ctx, k, kd, &lo, &hi);
  if (ka < lo || ka > hi) return 0.0;
  double sum = 0.0;
  for (int j = lo; j <= hi; j++) sum += mut_bidir__w_ka(kd, j);
  return sum > 0.0 ? mut_bidir__w_ka(kd, ka) / sum : 0.0;
}

int mut_bidir_splits(const ps_context *ctx, int l, int m_end, int ka, int *OUT_lc_lo,
                     int *OUT_lc_hi) {
  int lo = l == -1 ? 1 : 0, hi = ka - 1;
  if (m_end && !ctx->can_hit_emitter) hi--;
  if ((l == -1 || m_end) && ka < 2) hi = lo - 1;
  *OUT_lc_lo = lo;
  *OUT_lc_hi = hi;
  return hi >= lo ? hi - lo + 1 : 0;
}

/* ---- The transition density ------------------------------------------------ */

/* The test hook: the wrong factor on new vertex j's density (light_side:
 * sampled from y_{j+1}, else from y_{j-1}), or 1. */
static double mut_bidir__bias(const mut_bidir *mb, const ps_path *y, int j, int light_side) {
  switch (mb->test_bias_term) {
  case MUT_BIDIR_BIAS_LIGHT_BSDF:
    return light_side && j + 1 < y->k ? mb->test_bias : 1.0;
  case MUT_BIDIR_BIAS_DELTA:
    if (light_side) return j + 1 < y->k && y->x[j + 1].delta ? mb->test_bias : 1.0;
    return j >= 2 && y->x[j - 1].delta ? mb->test_bias : 1.0;
  default:
    return 1.0;
  }
}

/* The split's densities from bdpt_path_pdfs on y re-split at its
 * connection (delta flags cleared: bdpt reads a delta vertex's density as
 * one; the delta lobes' own densities are pathspace.c's). */
static double mut_bidir__split_scratch(const mut_bidir *mb, const ps_path *y, int l, int ka,
                                       int lc) {
  const ps_context *ctx = mb->ctx;
  int k = y->k, a = l + lc, b = a + 1;
  int t = a + 1, s = k - b + 1;
  bdpt_vertex cam[PS_MAX_VERTICES], lp[PS_MAX_VERTICES];
  for (int i = 0; i < t; i++) {
    cam[i] = y->x[i].v;
    cam[i].delta = 0;
  }
  for (int j = 0; j < s; j++) {
    lp[j] = y->x[k - j].v;
    lp[j].delta = 0;
  }
  bdpt_path_pdfs(ctx->sc, cam, t, lp, s);
  double d = 1.0;
  for (int j = l + 1; j <= a; j++) {
    double pj = cam[j].pdf_fwd;
    if (j > 0 && ps_unhittable(ctx, y, j))
      pj = 0.0;
    else if (j >= 2 && y->x[j - 1].delta)
      pj = ps_density_cam(ctx, y, j);
    d *= pj * mut_bidir__bias(mb, y, j, 0);
  }
  for (int j = b; j <= l + ka - 1; j++) {
    double pj = lp[k - j].pdf_fwd;
    if (j + 2 <= k && y->x[j + 1].delta) pj = ps_density_light(ctx, y, j);
    d *= pj * mut_bidir__bias(mb, y, j, 1);
  }
  return d;
}

double mut_bidir_split_density(const mut_bidir *mb, const ps_path *y, int l, int ka, int lc,
                               int scratch) {
  int k = y->k, m_end = l + ka == k + 1;
  int mc = ka - 1 - lc, a = l + lc, b = a + 1;
  int joined = !(m_end && mc == 0);
  if (joined && (!ps_connectible(y, a) || !ps_connectible(y, b))) return 0.0;
  if (scratch) return mut_bidir__split_scratch(mb, y, l, ka, lc);
  double d = 1.0;
  for (int j = l + 1; j <= a; j++) d *= y->x[j].pdf_cam * mut_bidir__bias(mb, y, j, 0);
  for (int j = b; j <= l + ka - 1; j++) d *= y->x[j].pdf_light * mut_bidir__bias(mb, y, j, 1);
  return d;
}

double mut_bidir_density(const mut_bidir *mb, int k_from, const ps_path *y, int l, int kd, int ka,
                         int scratch) {
  const ps_context *ctx = mb->ctx;
  int nr = mut_bidir_ranges(k_from, kd, NULL);
  double pre = mut_bidir_pmf_kd(k_from, kd) * mut_bidir_pmf_ka(ctx, k_from, kd, ka);
  if (!(pre > 0.0) || nr == 0) return 0.0;
  int lo, hi;
  int n = mut_bidir_splits(ctx, l, l + ka == y->k + 1, ka, &lo, &hi);
  if (n == 0) return 0.0;
  double sum = 0.0;
  for (int lc = lo; lc <= hi; lc++) sum += mut_bidir_split_density(mb, y, l, ka, lc, scratch);
  return pre / nr * sum / n;
}

/* ---- Generating the proposal ---------------------------------------------------- */

/* bdpt's walks read their numbers from an lmc_sampler: one over the rng. */
typedef struct mut_bidir__smp {
  lmc_sampler base;
  rng *r;
} mut_bidir__smp;

static double mut_bidir__next(lmc_sampler *s) { return rng_uniform(((mut_bidir__smp *)s)->r); }
static void mut_bidir__stream(lmc_sampler *s, int stream) { (void)s, (void)stream; }

/* Samples a direction at the kept surface vertex pv whose other neighbour
 * lies along wo (BSDF sampling in `mode`); *OUT_delta: the lobe is a delta. */
static int mut_bidir__scatter(const ps_vertex *pv, vec3 wo, transport_mode mode, rng *r,
                              vec3 *OUT_dir, double *OUT_pdf, int *OUT_delta) {
  const surface_hit *h = &pv->v.hit;
  vec3 wo_l = frame_to_local(&h->sh, wo);
  if (!(v3_dot(wo, h->ng) * wo_l.z > 0.0)) return 0;
  double u_lobe = rng_uniform(r), u1 = rng_uniform(r), u2 = rng_uniform(r);
  bsdf_sample bs;
  if (!bsdf_sample_f(h->bsdf, h->tu, h->tv, wo_l, u_lobe, u1, u2, mode, &bs)) return 0;
  *OUT_delta = (bs.flags & BSDF_DELTA) != 0;
  vec3 wi = v3_normalize(frame_to_world(&h->sh, bs.wi));
  if (!(v3_dot(wi, h->ng) * frame_to_local(&h->sh, wi).z > 0.0)) return 0;
  *OUT_dir = wi;
  *OUT_pdf = bs.pdf;
  return 1;
}

/* The camera side: y_{l+1} .. y_{l+lc} (from y_0, the pinhole, when l = -1). */
static int mut_bidir__camera_side(const mut_bidir *mb, mut_bidir__smp *smp, ps_path *y, int l,
                                  int lc, render_counters *cnt) {
  const ps_context *ctx = mb->ctx;
  const scene *sc = ctx->sc;
  bdpt_vertex tmp[PS_MAX_VERTICES + 1];
  if (lc == 0) return 1;
  if (l <= 0) {
    /* A raster point uniform over the film, then bdpt's camera walk. */
    double rx = rng_uniform(smp->r) * sc->cam.width, ry = rng_uniform(smp->r) * sc->cam.height;
    int want = l == -1 ? lc : lc + 1;
    if (bdpt_camera_subpath(sc, &ctx->rs, &smp->base, rx, ry, want, tmp, cnt) != want) return 0;
    for (int i = 0; i < want; i++) y->x[i].v = tmp[i];
  } else {
    vec3 wo = v3_normalize(v3_sub(y->x[l - 1].v.p, y->x[l].v.p)), dir;
    double pdf;
    int delta;
    if (!mut_bidir__scatter(&y->x[l], wo, TRANSPORT_RADIANCE, smp->r, &dir, &pdf, &delta))
      return 0;
    y->x[l].v.delta = delta;
    tmp[0] = y->x[l].v;
    int n = bdpt_continue_subpath(sc, &ctx->rs, &smp->base, TRANSPORT_RADIANCE, tmp[0].p, dir,
                                  pdf, tmp, 1, lc + 1, cnt);
    if (n != lc + 1) return 0;
    for (int i = 1; i <= lc; i++) y->x[l + i].v = tmp[i];
  }
  return 1;
}

/* The light side: mc new vertices ending at y index `last` (nearest the
 * light), from a fresh light endpoint (x NULL or m = k + 1) or from x_m. */
static int mut_bidir__light_side(const mut_bidir *mb, mut_bidir__smp *smp, const ps_path *x,
                                 int m, ps_path *y, int last, int mc, render_counters *cnt) {
  const ps_context *ctx = mb->ctx;
  const scene *sc = ctx->sc;
  bdpt_vertex tmp[PS_MAX_VERTICES + 1];
  if (mc == 0) return 1;
  if (!x || m == x->k + 1) {
    if (bdpt_light_subpath(sc, &ctx->rs, &smp->base, mc, tmp, cnt) != mc) return 0;
    for (int j = 0; j < mc; j++) y->x[last - j].v = tmp[j];
    return 1;
  }
  /* From the kept x_m: its light's emission, or its BSDF. */
  const ps_vertex *xm = &x->x[m];
  vec3 dir;
  double pdf;
  vec3 org = xm->v.p;
  if (m == x->k && xm->inf) {
    /* A kept direction at infinity: a fresh origin on the disk its rays
     * leave from, as light_sample_le's. */
    double u1 = rng_uniform(smp->r), u2 = rng_uniform(smp->r);
    dir = xm->v.dir;
    org = light_disk_point(sc, dir, u1, u2);
    pdf = light_disk_pdf(sc);
  } else if (m == x->k) {
    const light *lt = &sc->lights[xm->v.light];
    double u3 = rng_uniform(smp->r), u4 = rng_uniform(smp->r);
    if (!light_sample_dir(lt, xm->v.n, u3, u4, &dir, &pdf)) return 0;
  } else {
    vec3 wo = ps_dir(x, m, m + 1);
    int delta;
    if (!mut_bidir__scatter(xm, wo, TRANSPORT_IMPORTANCE, smp->r, &dir, &pdf, &delta)) return 0;
    y->x[last + 1].v.delta = delta;
  }
  tmp[0] = xm->v;
  int n = bdpt_continue_subpath(sc, &ctx->rs, &smp->base, TRANSPORT_IMPORTANCE, org, dir, pdf,
                                tmp, 1, mc + 1, cnt);
  if (n != mc + 1) return 0;
  for (int j = 1; j <= mc; j++) y->x[last - j + 1].v = tmp[j];
  return 1;
}

mut_bidir_status mut_bidir_generate(const mut_bidir *mb, rng *r, const ps_path *x, int k_from,
                                    int l, int m, int ka, int lc, ps_path *OUT_y) {
  const ps_context *ctx = mb->ctx;
  int k = x ? x->k : k_from;
  int k2 = k - (m - l) + ka, mc = ka - 1 - lc;
  if (k2 < 1 || k2 + 1 > PS_MAX_VERTICES || lc < 0 || mc < 0) return MUT_BIDIR_NO_SPLIT;
  ps_path *y = OUT_y;
  y->k = k2;
  y->rx = x ? x->rx : 0.0;
  y->ry = x ? x->ry : 0.0;

  /* The kept prefix x_0 .. x_l and suffix x_m .. x_k. */
  for (int i = 0; i <= l; i++) y->x[i] = x->x[i];
  for (int i = m; i <= k; i++) y->x[i - m + l + ka] = x->x[i];

  /* The two walks; every new vertex must fit its place. */
  mut_bidir__smp smp = {{mut_bidir__next, mut_bidir__stream, NULL}, r};
  render_counters cnt;
  memset(&cnt, 0, sizeof cnt);
  int ok = mut_bidir__camera_side(mb, &smp, y, l, lc, &cnt) &&
           mut_bidir__light_side(mb, &smp, x, m, y, l + ka - 1, mc, &cnt);
  y->rays = cnt.rays;
  if (!ok) return MUT_BIDIR_WALK_FAILED;
  /* The connection's ends scatter through smooth lobes. */
  if (!(l + ka == k2 + 1 && mc == 0)) y->x[l + lc].v.delta = y->x[l + lc + 1].v.delta = 0;
  int lo = l + 1 > 0 ? l + 1 : 0, hi = l + ka - 1 < k2 ? l + ka - 1 : k2;
  for (int i = lo; i <= hi; i++)
    if (!ps_vertex_fits(ctx, &y->x[i].v, i, k2)) return MUT_BIDIR_WALK_FAILED;

  /* The caches of the changed range and its neighbours, and the density of
   * the split that made y (zero: not a proposal, mut_bidir.h). */
  ps_update(ctx, y, l - 1, l + ka + 1);
  if (!(mut_bidir_split_density(mb, y, l, ka, lc, 0) > 0.0)) return MUT_BIDIR_ZERO_DENSITY;
  return MUT_BIDIR_OK;
}

void mut_bidir_finish(const mut_bidir *mb, const ps_path *x, const mut_bidir_record *rec,
                      ps_path *y) {
  int l = rec->l, ka = rec->ka, k2 = y->k;
  int a = l + rec->lc;
  int joined = !(l + ka == k2 + 1 && rec->mc == 0);
  y->rays += joined;
  if (joined && ps_edge_blocked(mb->ctx, y, a)) {
    y->f = rgb_zero();
    y->lum = 0.0;
    return;
  }
  if (!x) {
    ps_total(y);
    return;
  }
  /* f(y) = f(x) (factors of y's range) / (factors of x's range). */
  int lo = l > 0 ? l : 0, hy = l + ka < k2 ? l + ka : k2, hx = rec->m < x->k ? rec->m : x->k;
  rgb num = rgb_gray(1.0), den = rgb_gray(1.0);
  for (int i = lo; i <= hy; i++) {
    num = rgb_mul(num, y->x[i].fac);
    if (i < hy) num = rgb_scale(num, y->x[i].g);
  }
  for (int i = lo; i <= hx; i++) {
    den = rgb_mul(den, x->x[i].fac);
    if (i < hx) den = rgb_scale(den, x->x[i].g);
  }
  if (!(den.r != 0.0 && den.g != 0.0 && den.b != 0.0)) {
    ps_total(y);
    return;
  }
  rgb f = rgb_make(x->f.r / den.r * num.r, x->f.g / den.g * num.g, x->f.b / den.b * num.b);
  if (!rgb_isfinite(f)) f = rgb_zero();
  y->f = f;
  y->lum = rgb_luminance(f);
}

/* ---- The proposal ------------------------------------------------------------------ */

mut_bidir_status mut_bidir_propose(const mut_bidir *mb, rng *r, const ps_path *x, ps_path *OUT_y,
                                   mut_bidir_record *OUT_rec, double *OUT_ratio) {
  const ps_context *ctx = mb->ctx;
  mut_bidir_record *rec = OUT_rec;
  int k = x->k;
  *OUT_ratio = 0.0;
  memset(rec, 0, sizeof *rec);

  /* The deletion length, then its range. */
  double u = rng_uniform(r), acc = 0.0;
  int kd = k + 2;
  for (int j = 1; j <= k + 2; j++) {
    acc += mut_bidir_pmf_kd(k, j);
    if (u < acc) {
      kd = j;
      break;
    }
  }
  int lmin, nr = mut_bidir_ranges(k, kd, &lmin);
  int pos = (int)(rng_uniform(r) * nr);
  int l = lmin + (pos < nr ? pos : nr - 1), m = l + kd;

  /* The addition length around it, then the split. */
  int ka_lo, ka_hi, ka = kd;
  mut_bidir__ka_bounds(ctx, k, kd, &ka_lo, &ka_hi);
  u = rng_uniform(r), acc = 0.0;
  for (int j = ka_lo; j <= ka_hi; j++) {
    acc += mut_bidir_pmf_ka(ctx, k, kd, j);
    if (u < acc) {
      ka = j;
      break;
    }
  }
  rec->l = l, rec->m = m, rec->kd = kd, rec->ka = ka;
  if (!(mut_bidir_pmf_ka(ctx, k, kd, ka) > 0.0)) return rec->status = MUT_BIDIR_NO_SPLIT;
  int lc_lo, lc_hi, ns = mut_bidir_splits(ctx, l, m == k + 1, ka, &lc_lo, &lc_hi);
  if (ns == 0) return rec->status = MUT_BIDIR_NO_SPLIT;
  int j = (int)(rng_uniform(r) * ns);
  rec->lc = lc_lo + (j < ns ? j : ns - 1);
  rec->mc = ka - 1 - rec->lc;

  /* Generate, evaluate, and the ratio with both directions' densities. */
  rec->status = mut_bidir_generate(mb, r, x, k, l, m, ka, rec->lc, OUT_y);
  if (rec->status != MUT_BIDIR_OK) return rec->status;
  mut_bidir_finish(mb, x, rec, OUT_y);
  *OUT_ratio = mut_bidir_ratio(mb, x, OUT_y, rec, 0);
  return MUT_BIDIR_OK;
}

double mut_bidir_ratio(const mut_bidir *mb, const ps_path *x, const ps_path *y,
                       const mut_bidir_record *rec, int scratch) {
  if (!(y->lum > 0.0) || !(x->lum > 0.0)) return 0.0;
  double t_fwd = mut_bidir_density(mb, x->k, y, rec->l, rec->kd, rec->ka, scratch);
  double t_rev = mut_bidir_density(mb, y->k, x, rec->l, rec->ka, rec->kd, scratch);
  if (!(t_fwd > 0.0)) return 0.0;
  double ratio = y->lum * t_rev / (x->lum * t_fwd);
  return isfinite(ratio) ? ratio : 0.0;
}

/* ---- Independent whole paths ------------------------------------------------------ */

mut_bidir_status mut_bidir_sample_whole(const mut_bidir *mb, rng *r, int k, ps_path *OUT_y) {
  int lo, hi, n = mut_bidir_splits(mb->ctx, -1, 1, k + 2, &lo, &hi);
  if (n == 0) return MUT_BIDIR_NO_SPLIT;
  int j = (int)(rng_uniform(r) * n);
  int lc = lo + (j < n ? j : n - 1);
  /* The whole range of a path of length 1 (any length would do): l = -1,
   * m = 2, kd = 3, and ka = k + 2 edges added. */
  mut_bidir_record rec = {-1, 2, 3, k + 2, lc, k + 1 - lc, MUT_BIDIR_OK};
  rec.status = mut_bidir_generate(mb, r, NULL, 1, rec.l, rec.m, rec.ka, rec.lc, OUT_y);
  if (rec.status != MUT_BIDIR_OK) return rec.status;
  mut_bidir_finish(mb, NULL, &rec, OUT_y);
  return MUT_BIDIR_OK;
}

double mut_bidir_whole_pdf(const mut_bidir *mb, const ps_path *y, int scratch) {
  int lo, hi, n = mut_bidir_splits(mb->ctx, -1, 1, y->k + 2, &lo, &hi);
  double sum = 0.0;
  for (int lc = lo; lc <= hi; lc++)
    sum += mut_bidir_split_density(mb, y, -1, y->k + 2, lc, scratch);
  return n > 0 ? sum / n : 0.0;
}
