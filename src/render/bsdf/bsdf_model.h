/*
 * bsdf_model.h: a BSDF model as a record (pbrt-v4's BxDF interface, read
 * as Mitsuba's plugins read their properties): its name as Mitsuba spells
 * it, its lobes and traits, its defaults, `read` for its own parameters
 * (render/plugin.h), and its operations in doubles and in duals from one
 * source (render/real.h). bsdf.c's front end (the twosided flip, the mask,
 * the dual arena's bookkeeping) calls a model through its record only;
 * bsdf_models.c registers the records by name.
 *
 * A model's operations get their arguments in the conventions of bsdf.h,
 * with wo and wi already flipped by twosided; `eval_pdf` (optional) gives
 * eval and pdf of one pair bit for bit as the two calls would, sharing
 * their work; `invert` is bsdf_invert's contract for the model alone
 * (*OUT_pmf: the probability of the delta lobe found).
 */
#ifndef LMC_RENDER_BSDF_MODEL_H
#define LMC_RENDER_BSDF_MODEL_H

#include "render/bsdf/bsdf.h"
#include "render/bsdf/bsdf_ad.h"
#include "render/plugin.h"

typedef struct bsdf_model {
  const char *name; /* Mitsuba's plugin name */
  int flags;        /* its lobes (bsdf.h's BSDF_REFLECTION, ...); a mask adds its own */
  int refracts;     /* transmission bends by eta (a dielectric interface) */
  int chain;        /* a vertex that may stand in a glossy chain when its lobe is
                       narrow (path/pathspace.h's ps_glossy) */
  /* Mitsuba's defaults beyond the common ones of bsdf_init_defaults (NULL: none). */
  void (*defaults)(bsdf *b);
  /* Its parameters from the scene (NULL: none). */
  lmc_status (*read)(bsdf *b, plugin_props *p);
  /* Precomputation after its parameters are set (NULL: none). */
  void (*prepare)(bsdf *b);
  /* The width of its lobes for bsdf_is_rough (NULL: a delta lobe, never rough). */
  double (*roughness)(const bsdf *b);
  /* 1 when its lobe is anisotropic for b's parameters (NULL: never). */
  int (*anisotropic)(const bsdf *b);
  /* Its lobes for b's parameters, when they are not always `flags` (a
   * model made of others: NULL, flags). */
  int (*lobes)(const bsdf *b);

  rgb (*eval)(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode);
  double (*pdf)(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi);
  rgb (*eval_pdf)(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, transport_mode mode,
                  double *OUT_pdf);
  int (*sample)(const bsdf *b, double tu, double tv, vec3 wo, double u_lobe, double u1, double u2,
                transport_mode mode, bsdf_sample *OUT);
  int (*invert)(const bsdf *b, double tu, double tv, vec3 wo, vec3 wi, int delta, const double r[4],
                double OUT_u[3], double *OUT_pmf);

  adrgb (*eval_ad)(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi, transport_mode mode);
  ad (*pdf_ad)(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi);
  adrgb (*eval_pdf_ad)(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, adv3 wi,
                       transport_mode mode, ad *OUT_pdf);
  int (*sample_ad)(ad_arena *A, const bsdf *b, ad tu, ad tv, adv3 wo, ad u_lobe, ad u1, ad u2,
                   transport_mode mode, bsdf_sample_ad *OUT);
} bsdf_model;

/* A record's operations, for a model file whose functions are named
 * bsdf__NAME_eval, _pdf, _sample, _invert (and _eval_pdf), each with its
 * dual _ad form. */
#define BSDF_MODEL_OPS(NAME)                                                               \
  .eval = bsdf__##NAME##_eval, .pdf = bsdf__##NAME##_pdf, .sample = bsdf__##NAME##_sample, \
  .invert = bsdf__##NAME##_invert, .eval_ad = bsdf__##NAME##_eval_ad,                      \
  .pdf_ad = bsdf__##NAME##_pdf_ad, .sample_ad = bsdf__##NAME##_sample_ad
#define BSDF_MODEL_EVAL_PDF(NAME) \
  .eval_pdf = bsdf__##NAME##_eval_pdf, .eval_pdf_ad = bsdf__##NAME##_eval_pdf_ad

/* The model registered as `name` (Mitsuba's spelling), or NULL. */
const bsdf_model *bsdf_model_find(const char *name);
/* The registered models: *OUT_count of them. */
const bsdf_model *const *bsdf_model_list(int *OUT_count);

/* Readers the models share (bsdf_read.c; render/plugin.h's conventions). */
enum { BSDF_TEX_DIFFUSE = 1, BSDF_TEX_SPECULAR = 2, BSDF_TEX_TRANSMITTANCE = 4 };
/* The textures `which` (diffuseReflectance, specularReflectance,
 * specularTransmittance), each defaulting to the model's own value. */
lmc_status bsdf_read_textures(bsdf *b, plugin_props *p, int which);
/* eta = intIOR / extIOR (Mitsuba's defaults: the named material
 * int_default inside, air outside); eta = 1 warns with `at_one`, what it
 * means for the model. */
lmc_status bsdf_read_eta(bsdf *b, plugin_props *p, const char *int_default, const char *at_one);
/* The microfacet parameters: distribution, alpha (alphaU and alphaV
 * averaged, with a warning when they differ), sampleVisible. */
lmc_status bsdf_read_microfacet(bsdf *b, plugin_props *p);
/* A conductor's eta and k: `material` (conductor_lookup), eta, k, extEta. */
lmc_status bsdf_read_conductor(bsdf *b, plugin_props *p);

#endif
