/*
 * cli.h: what the commands of the `lmc` command line share (src/cli/):
 * the exit statuses, flag parsing (every flag is accepted as
 * `--flag value` and `--flag=value`) and the PNG preview's exposure. Only
 * the command line turns errors into exit codes and installs signal
 * handlers.
 */
#ifndef LMC_CLI_CLI_H
#define LMC_CLI_CLI_H

#include "lmc/mcmc.h"
#include "render/error.h"
#include "render/image.h"
#include "render/integrators/integrator.h"
#include "render/io/io.h"
#include "render/options.h"
#include "render/scene.h"

#define LMC_VERSION "0.1.0"

/* Exit statuses. */
enum {
  EXIT_OK = 0,
  EXIT_FAIL = 1,      /* rendering or writing failed */
  EXIT_BADINPUT = 2,  /* bad flag, bad scene, images of different sizes */
  EXIT_SIGINT = 130,  /* interrupted by SIGINT (image of the samples so far written) */
  EXIT_SIGTERM = 143  /* interrupted by SIGTERM (likewise) */
};

typedef struct lmc_args {
  int argc, i;
  char **argv;
  const char *inline_value; /* the part after '=' of the current flag */
} lmc_args;

/* Matches argv[i] against a flag name (with or without "=value"). */
int lmc_flag_is(lmc_args *a, const char *name);
/* The value of the current flag, from "=value" or the next argument
 * (NULL and a message when there is none). */
const char *lmc_flag_value(lmc_args *a);
/* s as a whole finite number in [lo, hi]: 1 and *out, else 0 (silent). */
int lmc_number_in(const char *s, double lo, double hi, double *out);
/* The same, with a message naming the flag when it fails. */
int lmc_parse_double(const char *flag, const char *s, double lo, double hi, double *out);

/* The PNG preview's exposure: --exposure STOPS (linear radiance times
 * 2^STOPS, clamped, sRGB: how Mitsuba, pbrt and tev show an EXR; default 0)
 * or --exposure auto (the 99th percentile of luminance maps to white). */
typedef struct lmc_exposure {
  int is_auto;
  double stops;
} lmc_exposure;

int lmc_parse_exposure(const char *s, lmc_exposure *out);
/* The factor on radiance of the preview of img. */
double lmc_exposure_scale(const lmc_exposure *e, const lmc_image *img);

/* The integrators `--integrator` accepts: pt, bdpt, direct and the MCMC ones. */
int lmc_integrator_known(const char *name);

/* A flag of the tables as given (checked with lmc_opt_set). */
typedef struct lmc_given {
  const lmc_opt_table *table;
  const lmc_opt *opt;
  const char *value; /* borrowed */
} lmc_given;

/* The settings of a render of scene s (render_settings.c; lmc render's and
 * the Python module's): the scene's own (mcmc_scene_settings), pt when it
 * names none, then what cli sets (its integrator, and whether --spp and
 * --time were given, by its SET_ bits; its quiet and strict) and the flags
 * given[0 .. n_given-1] in order, into *OUT. An integrator lmc lacks is
 * warned about (naming scene_path) and replaced by bdpt. Fails only on a
 * bad value in the scene (file, line). */
lmc_status lmc_render_settings(const scene *s, const char *scene_path, const render_settings *cli,
                               const lmc_given *given, int n_given, render_settings *OUT,
                               lmc_error *err);

/* The commands (argv[1] is the command's name). */
int lmc_cmd_render(int argc, char **argv);
/* SIGINT and SIGTERM ask a render to stop (render_request_stop) from now
 * on; `lmc render` calls it before joining an MPI job, whose start-up can
 * take seconds, so that a Ctrl-C then still ends with the image. */
void lmc_render_catch_signals(void);
int lmc_cmd_compare(int argc, char **argv);
/* A false-colour PNG of per-pixel squared relative errors e (width *
 * height), log scale from 1e-4 (dark blue) to 1 (red): lmc compare's
 * heat map of the true error, lmc convert --channel error's of the
 * estimated one. */
lmc_status lmc_write_heat_png(const char *path, int width, int height, const double *e,
                              lmc_error *err);
int lmc_cmd_merge(int argc, char **argv);
int lmc_cmd_convert(int argc, char **argv);

#endif
