/*
 * bsdf.c: the BSDF front end: the call through the model's record
 * (bsdf_model.h), the twosided flip and the mask, Fresnel equations, the
 * named IOR and conductor tables, and the defaults the models share. The
 * models live in models/, one file each, registered in bsdf_models.c.
 * The Fresnel equations, the sample record and the dispatch are written
 * once (bsdf_generic.h) and compiled here twice, in doubles (bsdf.h) and in
 * duals (bsdf_ad.h, for the gradients of lmc and h2mc); render/real.h says
 * how.
 *
 * Twosided (Mitsuba's `twosided` adapter): for the reflection-only models,
 * a query with wo below the surface is answered by the model with both
 * directions mirrored to the upper side (z negated), and a sampled wi is
 * mirrored back. Dielectrics already see both sides and ignore the flag.
 *
 * Fresnel. For a dielectric interface with relative IOR eta (transmitted
 * side over incident side, after swapping when cos_i < 0):
 *   cos_t^2 = 1 - (1 - cos_i^2) / eta^2   (<= 0: total internal reflection)
 *   r_s = (cos_i - eta cos_t) / (cos_i + eta cos_t)
 *   r_p = (eta cos_i - cos_t) / (eta cos_i + cos_t)
 *   F = (r_s^2 + r_p^2) / 2.
 * For a conductor with complex IOR eta + i k (unpolarised, exact):
 *   a^2 + b^2 = sqrt((eta^2 - k^2 - sin^2)^2 + 4 eta^2 k^2),
 *   a = sqrt((a^2 + b^2 + eta^2 - k^2 - sin^2) / 2),
 *   R_s = (a^2 + b^2 + cos^2 - 2 a cos) / (a^2 + b^2 + cos^2 + 2 a cos),
 *   R_p = R_s (cos^2 (a^2 + b^2) + sin^4 - 2 a cos sin^2)
 *             / (cos^2 (a^2 + b^2) + sin^4 + 2 a cos sin^2),
 *   F = (R_s + R_p) / 2.
 * With eta = 0, k = 1 ("none") this is exactly 1: a perfect mirror.
 */
#include "render/bsdf/bsdf.h"

#include <ctype.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "render/bsdf/bsdf_ad_internal.h"
#include "render/bsdf/bsdf_internal.h"
#include "render/bsdf/bsdf_model.h"
#include "render/warp.h"

/* ---- Fresnel (value-only parts) --------------------------------------- */

/* F_dr(eta) = int_0^1 F(c) 2 c dc. Below the critical cosine c_c (eta < 1)
 * F = 1, which contributes c_c^2; the rest is integrated with composite
 * Simpson after the substitution c = c_c + (1 - c_c) t^2, which removes
 * the square-root kink of F at c_c. */
static double bsdf__fdr_compute(double eta) {
  double cc = eta < 1.0 ? sqrt(fmax(0.0, 1.0 - eta * eta)) : 0.0;
  const int n = 512; /* even */
  double h = 1.0 / n, acc = 0.0;
  for (int i = 0; i <= n; i++) {
    double t = i * h;
    double c = cc + (1.0 - cc) * t * t;
    double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
    double fr = c > 0.0 ? fresnel_dielectric(c, eta, NULL) : 1.0;
    acc += w * fr * 2.0 * c * 2.0 * (1.0 - cc) * t;
  }
  return cc * cc + acc * h / 3.0;
}

double bsdf__fresnel_diffuse_reflectance(double eta) {
  /* A small per-thread cache: scenes have few distinct IORs. */
  static _Thread_local double cache_eta[4] = {-1.0, -1.0, -1.0, -1.0};
  static _Thread_local double cache_val[4];
  static _Thread_local int cache_next;
  for (int i = 0; i < 4; i++)
    if (cache_eta[i] == eta) return cache_val[i];
  double v = bsdf__fdr_compute(eta);
  cache_eta[cache_next] = eta;
  cache_val[cache_next] = v;
  cache_next = (cache_next + 1) & 3;
  return v;
}

double bsdf__specular_weight(const texture *spec, const texture *diff) {
  double s = rgb_luminance(tex_mean(spec)), d = rgb_luminance(tex_mean(diff));
  if (!(s + d > 0.0)) return 0.5;
  return s / (s + d);
}

/* ---- Named IORs and conductors ---------------------------------------- */

typedef struct bsdf__ior_entry {
  const char *name;
  double value;
} bsdf__ior_entry;

/* Mitsuba 0.6's table (src/bsdfs/ior.h), after Hecht, "Optics", 4th ed.:
 * measurements near 589 nm between 0 and 20 degrees Celsius. */
static const bsdf__ior_entry bsdf__iors[] = {
    {"vacuum", 1.0},          {"helium", 1.000036},
    {"hydrogen", 1.000132},   {"air", 1.000277},
    {"carbon dioxide", 1.00045}, {"water", 1.3330},
    {"acetone", 1.36},        {"ethanol", 1.361},
    {"carbon tetrachloride", 1.461}, {"glycerol", 1.4729},
    {"benzene", 1.501},       {"silicone oil", 1.52045},
    {"bromine", 1.661},       {"water ice", 1.31},
    {"fused quartz", 1.458},  {"pyrex", 1.470},
    {"acrylic glass", 1.49},  {"polypropylene", 1.49},
    {"bk7", 1.5046},          {"sodium chloride", 1.544},
    {"amber", 1.55},          {"pet", 1.5750},
    {"diamond", 2.419},
};

/* Case-insensitive string equality (Mitsuba lower-cases IOR names). */
static int bsdf__streq_nocase(const char *a, const char *b) {
  for (; *a && *b; a++, b++)
    if (tolower((unsigned char)*a) != tolower((unsigned char)*b)) return 0;
  return *a == *b;
}

int ior_lookup(const char *name, double *out) {
  if (!name) return 0;
  for (size_t i = 0; i < sizeof bsdf__iors / sizeof bsdf__iors[0]; i++)
    if (bsdf__streq_nocase(name, bsdf__iors[i].name)) {
      if (out) *out = bsdf__iors[i].value;
      return 1;
    }
  return 0;
}

typedef struct bsdf__conductor_entry {
  const char *name;
  double eta[3], k[3];
} bsdf__conductor_entry;

/* RGB complex IORs of metals: the spectral data Mitsuba ships in
 * data/ior/<name>.{eta,k}.spd (from Palik, "Handbook of Optical Constants
 * of Solids", and the Sopra database) integrated against the sRGB colour
 * matching functions. The numbers are the ones tabulated by the Tungsten
 * renderer (src/core/bsdfs/ComplexIorData.hpp), which agree with the
 * values Mitsuba users quote (e.g. Cu 0.200438, 0.924033, 1.10221). Names
 * as in Mitsuba's table (case sensitive, like Mitsuba's file names). */
static const bsdf__conductor_entry bsdf__conductors[] = {
    {"Ag", {0.1552646489, 0.1167232965, 0.1383806959}, {4.8283433224, 3.1222459278, 2.1469504455}},
    {"Al", {1.6574599595, 0.8803689579, 0.5212287346}, {9.2238691996, 6.2695232477, 4.8370012281}},
    {"Au", {0.1431189557, 0.3749570432, 1.4424785571}, {3.9831604247, 2.3857207478, 1.6032152899}},
    {"Be", {4.1850592788, 3.1850604423, 2.7840913457}, {3.8354398268, 3.0101260162, 2.8690088743}},
    {"Cr", {4.3696828663, 2.9167024892, 1.6547005413}, {5.2064337956, 4.2313645277, 3.7549467933}},
    {"Cu", {0.2004376970, 0.9240334304, 1.1022119527}, {3.9129485033, 2.4528477015, 2.1421879552}},
    {"Cu_palik", {0.2126840430, 0.9199880064, 1.1024078212}, {3.9215626225, 2.4571489948, 2.1366534268}},
    {"Hg", {2.3989314904, 1.4400254917, 0.9095512090}, {6.3276269444, 4.3719414152, 3.4217899270}},
    {"Ir", {3.0864098394, 2.0821938440, 1.6178866805}, {5.5921510077, 4.0671757150, 3.2672611269}},
    {"K", {0.0640493070, 0.0464100621, 0.0381842017}, {2.1042155920, 1.3489364357, 0.9132113889}},
    {"Li", {0.2657871942, 0.1956102432, 0.2209198538}, {3.5401743407, 2.3111306542, 1.6685930000}},
    {"Mo", {4.4837010280, 3.5254578255, 2.7760769438}, {4.1111307988, 3.4208716252, 3.1506031404}},
    {"Na_palik", {0.0602665320, 0.0561412435, 0.0619909494}, {3.1792906496, 2.1124800781, 1.5790940266}},
    {"Nb", {3.4201353595, 2.7901921379, 2.3955856658}, {3.4413817900, 2.7376437930, 2.5799132708}},
    {"Ni_palik", {2.3672753521, 1.6633583302, 1.4670554172}, {4.4988329911, 3.0501643957, 2.3454274399}},
    {"Rh", {2.5857954933, 1.8601866068, 1.5544279524}, {6.7822927110, 4.7029501026, 3.9760892461}},
    {"Ta", {2.0625846607, 2.3930915569, 2.6280684948}, {2.4080467973, 1.7413705864, 1.9470377016}},
    {"TiN", {1.6484691607, 1.1504482522, 1.3797795097}, {3.3684596226, 1.9434888540, 1.1020123347}},
    {"V_palik", {4.2775126218, 3.5131538236, 2.7611257461}, {3.4911844504, 2.8893580874, 3.1116965117}},
    {"W", {4.3707029924, 3.3002972445, 2.9982666528}, {3.5006778591, 2.6048652781, 2.2731930614}},
    /* A perfect mirror: Fresnel reflectance exactly 1 at every angle. */
    {"none", {0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}},
};

int conductor_lookup(const char *name, rgb *eta, rgb *k) {
  if (!name) return 0;
  for (size_t i = 0; i < sizeof bsdf__conductors / sizeof bsdf__conductors[0]; i++) {
    const bsdf__conductor_entry *c = &bsdf__conductors[i];
    if (strcmp(name, c->name) == 0) {
      if (eta) *eta = rgb_make(c->eta[0], c->eta[1], c->eta[2]);
      if (k) *k = rgb_make(c->k[0], c->k[1], c->k[2]);
      return 1;
    }
  }
  return 0;
}

/* ---- Defaults, flags: read from the model's record ------------------------- */

void bsdf_init_model(bsdf *b, const bsdf_model *m) {
  memset(b, 0, sizeof *b);
  b->model = m;
  b->twosided = 0;
  b->diffuse = tex_constant(rgb_gray(0.5));
  b->specular = tex_constant(rgb_gray(1.0));
  b->transmittance = tex_constant(rgb_gray(1.0));
  b->exponent = 30.0;
  b->dist = MF_BECKMANN;
  b->alpha = 0.1;
  b->sample_visible = 1;
  b->nonlinear = 0;
  b->fast_approx = 0;
  b->alpha_u = b->alpha_v = 0.1;
  b->variant = WARD_BALANCED;
  b->eta = 1.0;
  b->nested[0] = b->nested[1] = -1;
  /* Conductors: Cu against air (Mitsuba divides eta and k by extEta). */
  rgb ce = rgb_gray(0.0), ck = rgb_gray(0.0); /* (Cu is in the table) */
  conductor_lookup("Cu", &ce, &ck);
  b->cond_eta = rgb_scale(ce, 1.0 / BSDF_AIR_IOR);
  b->cond_k = rgb_scale(ck, 1.0 / BSDF_AIR_IOR);
  if (m->defaults) m->defaults(b);
}

int bsdf_init_defaults(bsdf *b, const char *name) {
  const bsdf_model *m = bsdf_model_find(name);
  bsdf_init_model(b, m ? m : bsdf_model_find("diffuse"));
  return m != NULL;
}

int bsdf_is(const bsdf *b, const char *name) {
  return b->model && strcmp(b->model->name, name) == 0;
}

void bsdf_link(bsdf *b, const bsdf *all) {
  for (int k = 0; k < 2; k++) b->nested_bsdf[k] = b->nested[k] >= 0 ? &all[b->nested[k]] : NULL;
}

/* The model's own lobes (without the mask). */
static int bsdf__lobes(const bsdf *b) {
  return b->model->lobes ? b->model->lobes(b) : b->model->flags;
}

int bsdf_flags(const bsdf *b) {
  /* A mask adds its pass-through: a delta transmission. */
  return bsdf__lobes(b) | (b->masked ? BSDF_TRANSMISSION | BSDF_DELTA : 0);
}

/* (A mask's pass-through is a delta lobe: the wrapped model decides.) */
int bsdf_is_delta(const bsdf *b) {
  return (bsdf__lobes(b) & (BSDF_DIFFUSE_LOBE | BSDF_GLOSSY)) == 0;
}

int bsdf_is_anisotropic(const bsdf *b) {
  return b->model->anisotropic && b->model->anisotropic(b);
}

void bsdf_prepare(bsdf *b) {
  if (b->model->prepare) b->model->prepare(b);
}

int bsdf_is_rough(const bsdf *b, double rough_min) {
  if (b->masked) return 0; /* the pass-through is a delta lobe */
  return b->model->roughness && b->model->roughness(b) > rough_min;
}

/* ---- Arena bookkeeping of the dual entry points ------------------------------ */

/* Rewinds A to mark, keeping the duals *xs[0 .. count-1]: every kept tangent
 * that lives above the mark is first copied to fresh storage at the top,
 * then the copies are moved down to the mark in order. The first copy lies
 * at least one tangent above the mark (the kept dual it came from did), so
 * each move reads from above what it writes and never overlaps its source. */
static void bsdf__ad_keep(ad_arena *A, size_t mark, ad **xs, int count) {
  if (ad_arena_keeps_all(A)) return; /* second order: no rewinds */
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

/* ---- Fresnel, the sample record and the dispatch, in doubles then in duals -- */

#define R_DUAL 0
#include "render/real.h"
#include "render/bsdf/bsdf_generic.h"
#undef R_DUAL
#define R_DUAL 1
#include "render/real.h"
#include "render/bsdf/bsdf_generic.h"

/* Where b's textures are (the slots of bsdf.h). */
static const size_t bsdf__tex_offsets[] = {offsetof(bsdf, diffuse), offsetof(bsdf, specular),
                                           offsetof(bsdf, transmittance), offsetof(bsdf, bump),
                                           offsetof(bsdf, opacity)};
#define BSDF__N_TEX (sizeof bsdf__tex_offsets / sizeof bsdf__tex_offsets[0])

int bsdf_is_tex_filtered(const bsdf *b) {
  for (size_t k = 0; k < BSDF__N_TEX; k++)
    if (tex_is_filtered((const texture *)((const char *)b + bsdf__tex_offsets[k]))) return 1;
  return 0;
}

const bsdf *bsdf_with_footprint(const bsdf *b, const tex_footprint *fp, bsdf *OUT_copy) {
  if (!bsdf_is_tex_filtered(b)) return b;
  *OUT_copy = *b;
  for (size_t k = 0; k < BSDF__N_TEX; k++) {
    texture *t = (texture *)((char *)OUT_copy + bsdf__tex_offsets[k]);
    if (tex_is_filtered(t)) tex_set_footprint(t, fp);
  }
  return OUT_copy;
}
