/*
 * bsdf_ad.c: the dual-number front end of the BSDFs (bsdf_ad.h): dispatch
 * on the model, the twosided flip, the Fresnel equations and the
 * cosine-weighted warp in dual arithmetic, and the arena bookkeeping.
 *
 * Every formula is the one of bsdf.c (see its opening comment for the
 * Fresnel equations of dielectrics and conductors), written over duals so
 * that each output carries its derivatives with respect to the primary
 * sample coordinates its inputs depend on. Branches look at values only: the
 * derivative is that of the branch taken (which side of the surface, total
 * internal reflection, which lobe).
 *
 * Arena. A rough dielectric sample makes a few hundred temporaries. The
 * three entry points mark the arena on entry and, on exit, move the duals
 * they return down to the mark (bsdf__ad_keep), so a call costs the arena
 * only what it hands back: 3 tangents for an eval, 1 for a pdf, 10 for a
 * sample.
 */
#include "render/bsdf_ad.h"

#include <math.h>
#include <string.h>

#include "render/bsdf_ad_internal.h"

/* ---- Arena bookkeeping --------------------------------------------------- */

/* Rewinds A to mark, keeping the duals *xs[0 .. count-1]: every kept tangent
 * that lives above the mark is first copied to fresh storage at the top,
 * then the copies are moved down to the mark in order. The first copy lies
 * at least one tangent above the mark (the kept dual it came from did), so
 * each move reads from above what it writes and never overlaps its source. */
static void bsdf__ad_keep(ad_arena *A, size_t mark, ad **xs, int count) {
  if (ad_arena_n(A) == 0 || mark < A->base || mark > A->top) {
    ad_arena_rewind(A, mark);
    return;
  }
  const double *lo = A->buf + mark;
  int moved[16];
  int n_moved = 0;
  for (int i = 0; i < count && n_moved < 16; i++)
    if (xs[i]->d >= lo) {
      *xs[i] = ad_copy(A, *xs[i]);
      moved[n_moved++] = i;
    }
  if (n_moved == 0 || !ad_arena_ok(A)) {
    ad_arena_rewind(A, mark);
    return;
  }
  ad_arena_rewind(A, mark);
  for (int j = 0; j < n_moved; j++) *xs[moved[j]] = ad_copy(A, *xs[moved[j]]);
}

/* ---- Small shared pieces --------------------------------------------------- */

ad adrgb_luminance(ad_arena *A, adrgb c) {
  /* 0.212671 r + 0.715160 g + 0.072169 b, in the order of rgb_luminance. */
  ad rg = ad_lincomb(A, 0.212671, c.r, 0.715160, c.g);
  return ad_add(A, rg, ad_mul_s(A, c.b, 0.072169));
}

int bsdf__finish_ad(ad_arena *A, bsdf_sample_ad *out, adv3 wi, adrgb f, ad pdf, double eta,
                    int flags) {
  out->wi = wi;
  out->f = f;
  out->pdf = pdf;
  out->eta = eta;
  out->flags = flags;
  out->weight = adrgb_zero(A);
  if (!(pdf.v > 0.0) || !isfinite(pdf.v) || !isfinite(wi.x.v) || !isfinite(wi.y.v) ||
      !isfinite(wi.z.v))
    return 0;
  /* weight = f (|cos wi| / pdf) */
  ad s = ad_div(A, ad_fabs(A, wi.z), pdf);
  adrgb w = adrgb_scale(A, f, s);
  rgb wv = adrgb_value(w);
  if (!rgb_isfinite(wv) || rgb_is_black(wv)) return 0;
  out->weight = w;
  return 1;
}

adv3 bsdf__ad_cosine_hemisphere(ad_arena *A, ad u1, ad u2) {
  /* Concentric map (Shirley and Chiu 1997): (a, b) in [-1, 1]^2 to the disk. */
  ad a = ad_sub_s(A, ad_mul_s(A, u1, 2.0), 1.0);
  ad b = ad_sub_s(A, ad_mul_s(A, u2, 2.0), 1.0);
  if (a.v == 0.0 && b.v == 0.0) return adv3_const(A, 0.0, 0.0, 1.0);
  ad r, phi;
  if (fabs(a.v) > fabs(b.v)) {
    /* r = a, phi = pi/4 (b / a) */
    r = a;
    phi = ad_mul_s(A, ad_div(A, b, a), M_PI / 4.0);
  } else {
    /* r = b, phi = pi/2 - pi/4 (a / b) */
    r = b;
    phi = ad_s_sub(A, M_PI / 2.0, ad_mul_s(A, ad_div(A, a, b), M_PI / 4.0));
  }
  ad x = ad_mul(A, r, ad_cos(A, phi));
  ad y = ad_mul(A, r, ad_sin(A, phi));
  /* Lift to the hemisphere: z = sqrt(max(0, 1 - x^2 - y^2)). */
  ad z = ad_safe_sqrt(A, ad_sub(A, ad_s_sub(A, 1.0, ad_sqr(A, x)), ad_sqr(A, y)));
  return adv3_make(x, y, z);
}

/* ---- Fresnel ----------------------------------------------------------------- */

ad fresnel_dielectric_ad(ad_arena *A, ad cos_i, double eta, ad *OUT_cos_t) {
  ad dummy;
  if (!OUT_cos_t) OUT_cos_t = &dummy;
  if (eta == 1.0) {
    *OUT_cos_t = ad_neg(A, cos_i);
    return ad_const(A, 0.0);
  }
  /* Swap the sides when the incident direction is inside. */
  double e = cos_i.v > 0.0 ? eta : 1.0 / eta;
  ad ci = ad_fabs(A, cos_i);
  /* cos_t^2 = 1 - (1 - ci^2) / e^2 */
  ad ct2 = ad_s_sub(A, 1.0, ad_div_s(A, ad_s_sub(A, 1.0, ad_sqr(A, ci)), e * e));
  if (ct2.v <= 0.0) {
    *OUT_cos_t = ad_const(A, 0.0);
    return ad_const(A, 1.0);
  }
  ad ct = ad_sqrt(A, ct2);
  /* r_s = (ci - e ct) / (ci + e ct),  r_p = (e ci - ct) / (e ci + ct) */
  ad ect = ad_mul_s(A, ct, e), eci = ad_mul_s(A, ci, e);
  ad rs = ad_div(A, ad_sub(A, ci, ect), ad_add(A, ci, ect));
  ad rp = ad_div(A, ad_sub(A, eci, ct), ad_add(A, eci, ct));
  *OUT_cos_t = cos_i.v > 0.0 ? ad_neg(A, ct) : ct;
  /* F = (r_s^2 + r_p^2) / 2 */
  return ad_mul_s(A, ad_add(A, ad_sqr(A, rs), ad_sqr(A, rp)), 0.5);
}

/* One channel of the exact conductor reflectance (see bsdf.c). */
static ad fresnel_conductor1_ad(ad_arena *A, ad c, double eta, double k) {
  ad c2 = ad_sqr(A, c);
  ad s2 = ad_s_sub(A, 1.0, c2);
  /* t = eta^2 - k^2 - sin^2,  a^2 + b^2 = sqrt(t^2 + 4 eta^2 k^2) */
  ad t = ad_s_sub(A, eta * eta - k * k, s2);
  ad a2pb2 = ad_sqrt(A, ad_add_s(A, ad_sqr(A, t), 4.0 * eta * eta * k * k));
  /* a = sqrt(max(0, (a^2 + b^2 + t) / 2)) */
  ad a = ad_safe_sqrt(A, ad_mul_s(A, ad_add(A, a2pb2, t), 0.5));
  ad t1 = ad_add(A, a2pb2, c2);
  ad t2 = ad_mul(A, ad_mul_s(A, a, 2.0), c);
  if (!(t1.v + t2.v > 0.0)) return ad_const(A, 1.0);
  /* R_s = (t1 - t2) / (t1 + t2) */
  ad rs = ad_div(A, ad_sub(A, t1, t2), ad_add(A, t1, t2));
  /* R_p = R_s (t3 - t4) / (t3 + t4),  t3 = (a^2 + b^2) cos^2 + sin^4,  t4 = t2 sin^2 */
  ad t3 = ad_add(A, ad_mul(A, a2pb2, c2), ad_sqr(A, s2));
  ad t4 = ad_mul(A, t2, s2);
  ad rp = t3.v + t4.v > 0.0 ? ad_div(A, ad_mul(A, rs, ad_sub(A, t3, t4)), ad_add(A, t3, t4)) : rs;
  return ad_mul_s(A, ad_add(A, rs, rp), 0.5);
}

adrgb fresnel_conductor_ad(ad_arena *A, ad cos_i, rgb eta, rgb k) {
  ad c = ad_fabs(A, cos_i);
  if (c.v > 1.0) c = ad_const(A, 1.0);
  return (adrgb){fresnel_conductor1_ad(A, c, eta.r, k.r), fresnel_conductor1_ad(A, c, eta.g, k.g),
                 fresnel_conductor1_ad(A, c, eta.b, k.b)};
}

/* ---- Dispatch ------------------------------------------------------------------ */

/* 1 when the model is reflection-only and the twosided flip applies to wo. */
static int bsdf__ad_flip(const bsdf *b, adv3 wo) {
  return b->twosided && wo.z.v < 0.0 && b->type != BSDF_DIELECTRIC &&
         b->type != BSDF_ROUGHDIELECTRIC;
}

adrgb bsdf_eval_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi,
                   transport_mode mode) {
  size_t mark = ad_arena_mark(A);
  if (bsdf__ad_flip(b, wo)) {
    wo.z = ad_neg(A, wo.z);
    wi.z = ad_neg(A, wi.z);
  }
  adrgb f;
  switch (b->type) {
  case BSDF_DIFFUSE:
    f = bsdf__diffuse_eval_ad(A, b, tu, tv, wo, wi, mode);
    break;
  case BSDF_PHONG:
    f = bsdf__phong_eval_ad(A, b, tu, tv, wo, wi, mode);
    break;
  case BSDF_CONDUCTOR:
    f = bsdf__conductor_eval_ad(A, b, tu, tv, wo, wi, mode);
    break;
  case BSDF_ROUGHCONDUCTOR:
    f = bsdf__roughconductor_eval_ad(A, b, tu, tv, wo, wi, mode);
    break;
  case BSDF_DIELECTRIC:
    f = bsdf__dielectric_eval_ad(A, b, tu, tv, wo, wi, mode);
    break;
  case BSDF_ROUGHDIELECTRIC:
    f = bsdf__roughdielectric_eval_ad(A, b, tu, tv, wo, wi, mode);
    break;
  case BSDF_PLASTIC:
    f = bsdf__plastic_eval_ad(A, b, tu, tv, wo, wi, mode);
    break;
  default:
    f = adrgb_zero(A);
    break;
  }
  ad *keep[3] = {&f.r, &f.g, &f.b};
  bsdf__ad_keep(A, mark, keep, 3);
  return f;
}

ad bsdf_pdf_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi) {
  size_t mark = ad_arena_mark(A);
  if (bsdf__ad_flip(b, wo)) {
    wo.z = ad_neg(A, wo.z);
    wi.z = ad_neg(A, wi.z);
  }
  ad p;
  switch (b->type) {
  case BSDF_DIFFUSE:
    p = bsdf__diffuse_pdf_ad(A, b, tu, tv, wo, wi);
    break;
  case BSDF_PHONG:
    p = bsdf__phong_pdf_ad(A, b, tu, tv, wo, wi);
    break;
  case BSDF_CONDUCTOR:
    p = bsdf__conductor_pdf_ad(A, b, tu, tv, wo, wi);
    break;
  case BSDF_ROUGHCONDUCTOR:
    p = bsdf__roughconductor_pdf_ad(A, b, tu, tv, wo, wi);
    break;
  case BSDF_DIELECTRIC:
    p = bsdf__dielectric_pdf_ad(A, b, tu, tv, wo, wi);
    break;
  case BSDF_ROUGHDIELECTRIC:
    p = bsdf__roughdielectric_pdf_ad(A, b, tu, tv, wo, wi);
    break;
  case BSDF_PLASTIC:
    p = bsdf__plastic_pdf_ad(A, b, tu, tv, wo, wi);
    break;
  default:
    p = ad_const(A, 0.0);
    break;
  }
  ad *keep[1] = {&p};
  bsdf__ad_keep(A, mark, keep, 1);
  return p;
}

int bsdf_sample_f_ad(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, ad u_lobe, ad u1, ad u2,
                   transport_mode mode, bsdf_sample_ad *OUT_sample) {
  size_t mark = ad_arena_mark(A);
  bsdf_sample_ad *out = OUT_sample;
  int flip = bsdf__ad_flip(b, wo);
  if (flip) wo.z = ad_neg(A, wo.z);
  out->wi = adv3_const(A, 0.0, 0.0, 0.0);
  out->f = adrgb_zero(A);
  out->pdf = ad_const(A, 0.0);
  out->weight = adrgb_zero(A);
  out->eta = 0.0;
  out->flags = 0;
  int ok = 0;
  switch (b->type) {
  case BSDF_DIFFUSE:
    ok = bsdf__diffuse_sample_ad(A, b, tu, tv, wo, u_lobe, u1, u2, mode, out);
    break;
  case BSDF_PHONG:
    ok = bsdf__phong_sample_ad(A, b, tu, tv, wo, u_lobe, u1, u2, mode, out);
    break;
  case BSDF_CONDUCTOR:
    ok = bsdf__conductor_sample_ad(A, b, tu, tv, wo, u_lobe, u1, u2, mode, out);
    break;
  case BSDF_ROUGHCONDUCTOR:
    ok = bsdf__roughconductor_sample_ad(A, b, tu, tv, wo, u_lobe, u1, u2, mode, out);
    break;
  case BSDF_DIELECTRIC:
    ok = bsdf__dielectric_sample_ad(A, b, tu, tv, wo, u_lobe, u1, u2, mode, out);
    break;
  case BSDF_ROUGHDIELECTRIC:
    ok = bsdf__roughdielectric_sample_ad(A, b, tu, tv, wo, u_lobe, u1, u2, mode, out);
    break;
  case BSDF_PLASTIC:
    ok = bsdf__plastic_sample_ad(A, b, tu, tv, wo, u_lobe, u1, u2, mode, out);
    break;
  default:
    break;
  }
  if (flip) out->wi.z = ad_neg(A, out->wi.z);
  ad *keep[10] = {&out->wi.x, &out->wi.y, &out->wi.z, &out->f.r,      &out->f.g,
                  &out->f.b,  &out->pdf,  &out->weight.r, &out->weight.g, &out->weight.b};
  bsdf__ad_keep(A, mark, keep, 10);
  return ok;
}
