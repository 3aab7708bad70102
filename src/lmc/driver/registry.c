/*
 * registry.c: the MCMC integrators (method.h) and the state spaces
 * (space.h) the driver runs, by name. Adding one is a line here.
 */
#include <stddef.h>
#include <string.h>

#include "lmc/mcmc.h"
#include "lmc/driver/method.h"
#include "lmc/driver/space.h"

extern const mc_method mc_method_pssmlt, mc_method_mmlt, mc_method_lmc, mc_method_h2mc,
    mc_method_mlt;

static const mc_method *const mc__methods[] = {&mc_method_pssmlt, &mc_method_mmlt,
                                               &mc_method_lmc,    &mc_method_h2mc,
                                               &mc_method_mlt};

static const mc_space_type mc__spaces[] = {
    {"bdpt", MCMC_STATES_BDPT, mc_space_bdpt_create, &mc_space_bdpt_options},
    {"mmlt", MCMC_STATES_MMLT, mc_space_mmlt_create, NULL},
    {"pt", MCMC_STATES_PT, mc_space_pt_create, NULL},
    {"path", MCMC_STATES_PATH, mc_space_path_create, &mc_space_path_options},
};

const char *const mc_space_names[] = {"bdpt", "mmlt", "pt", "path", NULL};
const int mc_space_ids[] = {MCMC_STATES_BDPT, MCMC_STATES_MMLT, MCMC_STATES_PT,
                            MCMC_STATES_PATH};

/* Integrators registered at run time (mc_method_register). */
#define MC__MAX_EXTRA 8
static const mc_method *mc__extra[MC__MAX_EXTRA];
static int mc__n_extra;

const mc_method *mc_method_find(const char *name) {
  if (!name) return NULL;
  for (size_t i = 0; i < sizeof mc__methods / sizeof mc__methods[0]; i++)
    if (!strcmp(mc__methods[i]->name, name)) return mc__methods[i];
  for (int i = 0; i < mc__n_extra; i++)
    if (!strcmp(mc__extra[i]->name, name)) return mc__extra[i];
  return NULL;
}

lmc_status mc_method_register(const mc_method *m, lmc_error *err) {
  if (!m || !m->name || !m->chain_kernels)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "an integrator needs a name and chain_kernels");
  if (mc_method_find(m->name))
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "integrator %s exists already", m->name);
  if (mc__n_extra == MC__MAX_EXTRA)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "no room for integrator %s", m->name);
  mc__extra[mc__n_extra++] = m;
  return LMC_OK;
}

const mc_space_type *mc_space_find(int id) {
  for (size_t i = 0; i < sizeof mc__spaces / sizeof mc__spaces[0]; i++)
    if (mc__spaces[i].id == id) return &mc__spaces[i];
  return NULL;
}

/* The driver's flags (mcmc.c). */
extern const lmc_opt_table mcmc_driver_options;

int mcmc_option_tables(const lmc_opt_table **OUT, int max) {
  int n = 0;
  /* (direct's own first: a pixel-sample integrator of render/, listed
   * with the plugins' tables since its values travel as they do) */
  if (n < max) OUT[n++] = &direct_options;
  if (n < max) OUT[n++] = &mcmc_driver_options;
  for (size_t i = 0; i < sizeof mc__spaces / sizeof mc__spaces[0]; i++)
    if (mc__spaces[i].opts && n < max) OUT[n++] = mc__spaces[i].opts;
  for (size_t i = 0; i < sizeof mc__methods / sizeof mc__methods[0]; i++)
    if (mc__methods[i]->opts && n < max) OUT[n++] = mc__methods[i]->opts;
  for (int i = 0; i < mc__n_extra; i++)
    if (mc__extra[i]->opts && n < max) OUT[n++] = mc__extra[i]->opts;
  return n;
}

lmc_status mcmc_set(render_settings *rs, const char *name, const char *value, lmc_error *err) {
  const lmc_opt_table *t[32], *ot = NULL;
  t[0] = &lmc_render_options;
  int n = 1 + mcmc_option_tables(t + 1, 31);
  const lmc_opt *o = lmc_opt_find(t, n, name, &ot);
  if (!o) return lmc_error_set(err, LMC_EINVAL, NULL, 0, "unknown flag --%s", name);
  char msg[512];
  if (!lmc_opt_set(ot, o, value, rs, msg, sizeof msg))
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "%s", msg);
  return LMC_OK;
}

lmc_status mcmc_scene_settings(const scene *s, render_settings *OUT, lmc_error *err) {
  const lmc_opt_table *t[32];
  t[0] = &lmc_render_options;
  int n = 1 + mcmc_option_tables(t + 1, 31);
  *OUT = s->settings;
  return lmc_opt_apply_scene(t, n, s, OUT, err);
}

int mcmc_integrator_names(const char **OUT, int max) {
  int n = 0;
  for (size_t i = 0; i < sizeof mc__methods / sizeof mc__methods[0] && n < max; i++)
    OUT[n++] = mc__methods[i]->name;
  for (int i = 0; i < mc__n_extra && n < max; i++) OUT[n++] = mc__extra[i]->name;
  return n;
}

void mc_space_free(mc_space *sp) {
  if (!sp) return;
  if (sp->destroy && sp->ctx) sp->destroy(sp);
  sp->ctx = NULL;
  sp->fam = NULL;
  sp->n_fam = 0;
}
