/*
 * light_ad.h: the emitters' direct sampling, emission and densities of
 * light.h in dual numbers, for the differentiable path (lmc, h2mc): the
 * same source as the plain routines (light_generic.h, compiled twice by
 * light.c), so the values equal light.h's and the derivatives are those of
 * the same formulas. A number reused inside a discrete choice (the
 * triangle of an area light, the pixel of an environment map) carries its
 * derivative at the scale of the choice's cell; the choice is reported
 * (`tri`, `cell`) so that the caller can hold it fixed.
 */
#ifndef LMC_RENDER_LIGHT_AD_H
#define LMC_RENDER_LIGHT_AD_H

#include "ad/dual.h"
#include "ad/dual_vec3.h"
#include "render/lights/light.h"
#include "render/rgb_ad.h"

/* light_li_sample in duals. */
typedef struct light_li_sample_ad {
  adv3 wi;         /* unit, from the receiver towards the light */
  double dist;     /* INFINITY for infinite and directional lights */
  vec3 p;          /* the light point's value (for the shadow ray) */
  adv3 pd;         /* the light point (area lights; the constant p otherwise) */
  vec3 n;          /* area lights: the emitting side's normal; zero otherwise */
  adrgb li;
  ad pdf;          /* solid angle (1 for delta lights) */
  int delta;
  int64_t tri;     /* area lights: the triangle chosen; else -1 */
  int64_t cell[2]; /* envmap: the pixel's row and column chosen; else -1 */
} light_li_sample_ad;

/* light_le_sample in duals (n zero but for area lights). */
typedef struct light_le_sample_ad {
  adv3 p;
  vec3 n;
  adv3 dir;
  adrgb le;
  double pdf_pos; /* constant for every light */
  ad pdf_dir;
  int delta_pos, delta_dir;
  int64_t tri;
  int64_t cell[2];
} light_le_sample_ad;

int light_sample_li_ad(ad_arena *A, const light *l, const struct scene *s, adv3 ref, ad u1, ad u2,
                       light_li_sample_ad *OUT);
ad light_pdf_li_ad(ad_arena *A, const light *l, const struct scene *s, adv3 ref, adv3 wi, adv3 p,
                   vec3 n);
int light_sample_le_ad(ad_arena *A, const light *l, const struct scene *s, ad u1, ad u2, ad u3,
                       ad u4, light_le_sample_ad *OUT);
/* The solid-angle density of emission along the unit travel direction dir
 * from p (normal n): light_pdf_le's pdf_dir. */
ad light_pdf_le_dir_ad(ad_arena *A, const light *l, const struct scene *s, adv3 p, vec3 n,
                       adv3 dir);

#endif
