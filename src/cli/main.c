/*
 * main.c: the `lmc` command line: the command table and its usage.
 *
 *   lmc render SCENE.xml [flags]     render to OUT.exr (linear) and OUT.png (preview)
 *   lmc compare IMAGE.exr REF.exr    error metrics, one `name: value` per line
 *   lmc merge ..., lmc convert ...   (see lmc_usage)
 *
 * One file per command in this folder; cli.h is what they share.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "render/dist.h"

static const char *lmc_usage =
    "usage: lmc <command> [arguments]\n"
    "\n"
    "commands:\n"
    "  render SCENE.xml [flags]        render a Mitsuba XML scene\n"
    "  compare IMAGE.exr REFERENCE.exr [--heatmap ERR.png]\n"
    "                                  print mse, relmse and mean_ratio\n"
    "  merge [--weight W] A.exr ... -o OUT.exr  average independent renders of one scene\n"
    "  convert IN.exr OUT.png [--exposure STOPS|auto]  sRGB PNG preview of an EXR\n"
    "  --help, -h                      this text (lmc render --help: the render flags)\n"
    "  --version                       the version\n"
    "\n"
    "exit status: 0 ok, 1 failure, 2 bad input (flags, scene, image sizes),\n"
    "130/143 interrupted by SIGINT/SIGTERM (the image so far is still written)\n";

int main(int argc, char **argv) {
  /* Under an MPI launcher, one rank of the job (dist.h); rank 0 alone
   * speaks: the others' warnings would repeat its own. */
  if (argc > 1 && !strcmp(argv[1], "render")) lmc_render_catch_signals();
  dist_init(&argc, &argv);
  if (dist_rank() != 0) lmc_warn_set_quiet(1);
  if (argc < 2) {
    fputs(lmc_usage, stderr);
    return EXIT_BADINPUT;
  }
  if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
    fputs(lmc_usage, stdout);
    return EXIT_OK;
  }
  if (!strcmp(argv[1], "--version")) {
    printf("lmc %s\n", LMC_VERSION);
    return EXIT_OK;
  }
  if (!strcmp(argv[1], "render")) return lmc_cmd_render(argc, argv);
  if (!strcmp(argv[1], "compare")) return lmc_cmd_compare(argc, argv);
  if (!strcmp(argv[1], "merge")) return lmc_cmd_merge(argc, argv);
  if (!strcmp(argv[1], "convert")) return lmc_cmd_convert(argc, argv);
  fprintf(stderr, "lmc: unknown command '%s'\n%s", argv[1], lmc_usage);
  return EXIT_BADINPUT;
}
