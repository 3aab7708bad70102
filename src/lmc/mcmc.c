/* mcmc.c: placeholder until the MCMC integrators land (issue 4). */
#include "lmc/mcmc.h"

#include <string.h>

int mcmc_is_integrator(const char *name) {
  return !strcmp(name, "pssmlt") || !strcmp(name, "mmlt") || !strcmp(name, "lmc");
}

lmc_status mcmc_render_run(const scene *s, const render_settings *rs, film *out,
                           render_stats *st, lmc_error *err) {
  (void)s, (void)out, (void)st;
  return lmc_error_set(err, LMC_EUNSUPPORTED, NULL, 0, "integrator %s is not built yet",
                       rs->integrator);
}
