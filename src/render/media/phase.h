/*
 * phase.h: phase functions of participating media, Mitsuba 0.6's
 * `isotropic` and `hg` (Henyey and Greenstein 1941), each a record (as the
 * BSDF models are, bsdf_model.h) in one file of media/models/, its body
 * written once for doubles and duals (render/real.h).
 *
 * Conventions (those of bsdf.h): at a scattering point wo points towards
 * the previous vertex (the ray's origin: -ray direction) and wi is the new
 * direction, both unit and pointing away from the point; the light is
 * deflected by the angle theta between the ray's direction -wo and wi,
 * cos theta = -wo . wi. p(wo, wi) is a density in solid angle over wi that
 * integrates to 1 and is symmetric, so radiance and importance are alike.
 * Sampling draws wi with density exactly p (a sample's weight p / pdf is
 * 1) from two numbers: u1 the cosine of the deflection, u2 its azimuth
 * about -wo in frame_from_z(-wo). Inverting gives (u1, u2) back.
 */
#ifndef LMC_RENDER_PHASE_H
#define LMC_RENDER_PHASE_H

#include "ad/dual.h"
#include "ad/dual_vec3.h"
#include "render/error.h"
#include "render/plugin.h"
#include "render/vec3.h"

struct phase_model;

typedef struct phase_fn {
  const struct phase_model *model;
  double g; /* hg: the mean cosine of the deflection, in (-1, 1) (Mitsuba's default 0.8) */
} phase_fn;

typedef struct phase_model {
  const char *name; /* Mitsuba's plugin name */
  void (*defaults)(phase_fn *ph);
  lmc_status (*read)(phase_fn *ph, plugin_props *p);
  double (*eval)(const phase_fn *ph, vec3 wo, vec3 wi);
  int (*sample)(const phase_fn *ph, vec3 wo, double u1, double u2, vec3 *OUT_wi, double *OUT_pdf);
  int (*invert)(const phase_fn *ph, vec3 wo, vec3 wi, double OUT_u[2]);
  ad (*eval_ad)(ad_arena *A, const phase_fn *ph, adv3 wo, adv3 wi);
  int (*sample_ad)(ad_arena *A, const phase_fn *ph, adv3 wo, ad u1, ad u2, adv3 *OUT_wi,
                   ad *OUT_pdf);
} phase_model;

/* The model registered as `name`, or NULL; the registered ones. */
const phase_model *phase_model_find(const char *name);
const phase_model *const *phase_model_list(int *OUT_count);
/* Mitsuba's defaults for the model `name`; 0 (and isotropic) when unknown. */
int phase_init(phase_fn *ph, const char *name);

/* The front end: the model's operations (phase.c). p(wo, wi); a sample
 * and its density (0 when there is none); the numbers of a direction. */
double phase_eval(const phase_fn *ph, vec3 wo, vec3 wi);
int phase_sample(const phase_fn *ph, vec3 wo, double u1, double u2, vec3 *OUT_wi, double *OUT_pdf);
int phase_invert(const phase_fn *ph, vec3 wo, vec3 wi, double OUT_u[2]);
ad phase_eval_ad(ad_arena *A, const phase_fn *ph, adv3 wo, adv3 wi);
int phase_sample_ad(ad_arena *A, const phase_fn *ph, adv3 wo, ad u1, ad u2, adv3 *OUT_wi,
                    ad *OUT_pdf);

#endif
