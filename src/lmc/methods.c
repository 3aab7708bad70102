/*
 * methods.c: the MCMC integrators the driver runs, by name (method.h).
 */
#include <stddef.h>
#include <string.h>

#include "lmc/method.h"

static const mc_method *const mc__methods[] = {&mc_method_pssmlt, &mc_method_mmlt,
                                               &mc_method_lmc, &mc_method_h2mc};

const mc_method *mc_method_find(const char *name) {
  if (!name) return NULL;
  for (size_t i = 0; i < sizeof mc__methods / sizeof mc__methods[0]; i++)
    if (!strcmp(mc__methods[i]->name, name)) return mc__methods[i];
  return NULL;
}
