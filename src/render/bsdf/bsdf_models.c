/*
 * bsdf_models.c: the registry of BSDF models (bsdf_model.h), one line per
 * model file of models/, and the property readers the models share.
 */
#include <math.h>
#include <string.h>

#include "render/bsdf/bsdf_internal.h"
#include "render/bsdf/bsdf_model.h"

/* ---- The registry: one X(name) per model file ------------------------------ */

#define BSDF__MODELS(X) \
  X(diffuse)            \
  X(phong)              \
  X(conductor)          \
  X(roughconductor)     \
  X(dielectric)         \
  X(roughdielectric)    \
  X(thindielectric)     \
  X(plastic)            \
  X(roughplastic)       \
  X(roughdiffuse)       \
  X(ward)               \
  X(difftrans)          \
  X(blendbsdf)

#define BSDF__DECLARE(NAME) extern const bsdf_model bsdf_model_##NAME;
BSDF__MODELS(BSDF__DECLARE)
#undef BSDF__DECLARE

#define BSDF__ENTRY(NAME) &bsdf_model_##NAME,
static const bsdf_model *const bsdf__models[] = {BSDF__MODELS(BSDF__ENTRY)};
#undef BSDF__ENTRY
#define BSDF__N_MODELS ((int)(sizeof bsdf__models / sizeof bsdf__models[0]))

const bsdf_model *bsdf_model_find(const char *name) {
  if (!name) return NULL;
  for (int i = 0; i < BSDF__N_MODELS; i++)
    if (strcmp(bsdf__models[i]->name, name) == 0) return bsdf__models[i];
  return NULL;
}

const bsdf_model *const *bsdf_model_list(int *OUT_count) {
  *OUT_count = BSDF__N_MODELS;
  return bsdf__models;
}

/* ---- Readers the models share ----------------------------------------------- */

lmc_status bsdf_read_textures(bsdf *b, plugin_props *p, int which) {
  static const char *const names[3] = {"diffuseReflectance", "specularReflectance",
                                       "specularTransmittance"};
  texture *tex[3] = {&b->diffuse, &b->specular, &b->transmittance};
  for (int i = 0; i < 3; i++) {
    if (!(which & (1 << i))) continue;
    lmc_status st = props_texture(p, names[i], tex_mean(tex[i]), tex[i]);
    if (st != LMC_OK) return st;
  }
  return LMC_OK;
}

lmc_status bsdf_read_eta(bsdf *b, plugin_props *p, const char *int_default, const char *at_one) {
  lmc_status st;
  double int_ior, ext_ior, def_int = 1.5, air = BSDF_AIR_IOR;
  ior_lookup(int_default, &def_int);
  if ((st = props_ior(p, "intIOR", def_int, &int_ior)) != LMC_OK) return st;
  if ((st = props_ior(p, "extIOR", air, &ext_ior)) != LMC_OK) return st;
  b->eta = int_ior / ext_ior;
  if (b->eta == 1.0)
    props_warn(p, NULL, "%s with intIOR = extIOR (eta = 1): %s", props_type(p), at_one);
  return LMC_OK;
}

lmc_status bsdf_read_microfacet(bsdf *b, plugin_props *p) {
  lmc_status st;
  const char *d;
  if ((st = props_string(p, "distribution", "beckmann", &d)) != LMC_OK) return st;
  if (strcmp(d, "beckmann") == 0)
    b->dist = MF_BECKMANN;
  else if (strcmp(d, "ggx") == 0)
    b->dist = MF_GGX;
  else {
    props_warn(p, "distribution", "microfacet distribution \"%s\" is not supported: using beckmann",
               d);
    b->dist = MF_BECKMANN;
  }
  double alpha, au, av;
  int has_a, has_u, has_v;
  if ((st = props_roughness(p, "alpha", b->alpha, &alpha, &has_a)) != LMC_OK) return st;
  if ((st = props_roughness(p, "alphaU", alpha, &au, &has_u)) != LMC_OK) return st;
  if ((st = props_roughness(p, "alphaV", alpha, &av, &has_v)) != LMC_OK) return st;
  if ((has_u || has_v) && au != av)
    props_warn(p, NULL,
               "anisotropic roughness (alphaU %g, alphaV %g) is not supported: using their mean",
               au, av);
  b->alpha = 0.5 * (au + av);
  if (!(b->alpha > 0.0)) return props_fail(p, NULL, "roughness alpha must be positive");
  return props_bool(p, "sampleVisible", b->sample_visible, &b->sample_visible);
}

lmc_status bsdf_read_conductor(bsdf *b, plugin_props *p) {
  lmc_status st;
  rgb eta = b->cond_eta, k = b->cond_k;
  const char *mat;
  if ((st = props_string(p, "material", NULL, &mat)) != LMC_OK) return st;
  if (mat && !conductor_lookup(mat, &eta, &k))
    return props_fail(p, "material", "unknown conductor material '%s'", mat);
  if ((st = props_rgb(p, "eta", eta, &eta)) != LMC_OK) return st;
  if ((st = props_rgb(p, "k", k, &k)) != LMC_OK) return st;
  double ext;
  if ((st = props_ior(p, "extEta", 1.0, &ext)) != LMC_OK) return st;
  b->cond_eta = rgb_scale(eta, 1.0 / ext);
  b->cond_k = rgb_scale(k, 1.0 / ext);
  return LMC_OK;
}
