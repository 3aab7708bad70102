/*
 * phase.c: the phase functions' registry (one X(name) per model file of
 * media/models/) and the front end that calls a model through its record.
 */
#include "render/media/phase.h"

#include <stddef.h>
#include <string.h>

#define PHASE__MODELS(X) \
  X(isotropic)           \
  X(hg)

#define PHASE__DECLARE(NAME) extern const phase_model phase_model_##NAME;
PHASE__MODELS(PHASE__DECLARE)
#undef PHASE__DECLARE

#define PHASE__ENTRY(NAME) &phase_model_##NAME,
static const phase_model *const phase__models[] = {PHASE__MODELS(PHASE__ENTRY)};
#undef PHASE__ENTRY
#define PHASE__N_MODELS ((int)(sizeof phase__models / sizeof phase__models[0]))

const phase_model *phase_model_find(const char *name) {
  if (!name) return NULL;
  for (int i = 0; i < PHASE__N_MODELS; i++)
    if (strcmp(phase__models[i]->name, name) == 0) return phase__models[i];
  return NULL;
}

const phase_model *const *phase_model_list(int *OUT_count) {
  *OUT_count = PHASE__N_MODELS;
  return phase__models;
}

int phase_init(phase_fn *ph, const char *name) {
  const phase_model *m = phase_model_find(name);
  memset(ph, 0, sizeof *ph);
  ph->model = m ? m : phase_model_find("isotropic");
  if (ph->model->defaults) ph->model->defaults(ph);
  return m != NULL;
}

double phase_eval(const phase_fn *ph, vec3 wo, vec3 wi) { return ph->model->eval(ph, wo, wi); }

int phase_sample(const phase_fn *ph, vec3 wo, double u1, double u2, vec3 *OUT_wi, double *OUT_pdf) {
  return ph->model->sample(ph, wo, u1, u2, OUT_wi, OUT_pdf);
}

int phase_invert(const phase_fn *ph, vec3 wo, vec3 wi, double OUT_u[2]) {
  return ph->model->invert(ph, wo, wi, OUT_u);
}

ad phase_eval_ad(ad_arena *A, const phase_fn *ph, adv3 wo, adv3 wi) {
  return ph->model->eval_ad(A, ph, wo, wi);
}

int phase_sample_ad(ad_arena *A, const phase_fn *ph, adv3 wo, ad u1, ad u2, adv3 *OUT_wi,
                    ad *OUT_pdf) {
  return ph->model->sample_ad(A, ph, wo, u1, u2, OUT_wi, OUT_pdf);
}
