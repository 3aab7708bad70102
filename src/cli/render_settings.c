/*
 * render_settings.c: the settings of one render, as `lmc render` and the
 * Python module (src/python/) both make them: the scene's own (its
 * <integrator>/<dpt> block through the option tables), then the flags
 * given, in order. One function, so that the same scene, seed and flags
 * render the same image from either.
 */
#include <stdio.h>
#include <string.h>

#include "cli/cli.h"

int lmc_integrator_known(const char *name) {
  return !strcmp(name, "pt") || !strcmp(name, "bdpt") || !strcmp(name, "direct") ||
         mcmc_is_integrator(name);
}

lmc_status lmc_render_settings(const scene *s, const char *scene_path, const render_settings *cli,
                               const lmc_given *given, int n_given, render_settings *OUT,
                               lmc_error *err) {
  render_settings rs;
  lmc_status st = mcmc_scene_settings(s, &rs, err);
  if (st) return st;
  if (!(rs.set & SET_INTEGRATOR)) snprintf(rs.integrator, sizeof rs.integrator, "pt");
  if (cli->set & SET_INTEGRATOR) memcpy(rs.integrator, cli->integrator, sizeof rs.integrator);
  /* The scene's directSamples is a sample count for its own spp: --spp
   * given here sets both passes (unless --direct-spp is given too). */
  if (cli->set & SET_SPP) lmc_opt_unset(&rs, "direct-spp");
  int adapt_given = 0;
  for (int i = 0; i < n_given; i++) {
    char msg[512];
    lmc_opt_set(given[i].table, given[i].opt, given[i].value, &rs, msg, sizeof msg); /* (checked) */
    adapt_given |= !strcmp(given[i].opt->name, "adapt");
  }
  if ((cli->set & SET_TIME) && !(cli->set & SET_SPP)) rs.set &= ~(unsigned)SET_SPP;
  rs.quiet = cli->quiet;
  rs.strict = cli->strict;
  if (!lmc_integrator_known(rs.integrator)) {
    lmc_warn(scene_path, 0,
             "the scene asks for integrator '%s', which lmc does not have; "
             "rendering with bdpt (choose with --integrator)",
             rs.integrator);
    snprintf(rs.integrator, sizeof rs.integrator, "bdpt");
  }
  if (adapt_given && strcmp(rs.integrator, "lmc"))
    lmc_warn(NULL, 0, "--adapt only applies to --integrator lmc; ignored for %s", rs.integrator);
  *OUT = rs;
  return LMC_OK;
}
