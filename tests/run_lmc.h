/*
 * run_lmc.h: the command-line tests' way of running the lmc binary
 * (LMC_BINARY) through the shell.
 */
#ifndef LMC_TESTS_RUN_LMC_H
#define LMC_TESTS_RUN_LMC_H

#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>

#include "test_util.h"

/* Runs `lmc ARGS`, its stdout and stderr into the files out.txt and
 * err.txt of the folder tmp, read back into out and err (NULL: not read;
 * out_n, err_n their sizes). The exit status, -1 when it did not exit. */
static inline int run_lmc_in(const char *tmp, const char *args, char *out, size_t out_n,
                             char *err, size_t err_n) {
  char cmd[16384], out_path[1024], err_path[1024];
  snprintf(out_path, sizeof out_path, "%s/out.txt", tmp);
  snprintf(err_path, sizeof err_path, "%s/err.txt", tmp);
  snprintf(cmd, sizeof cmd, "'%s' %s > %s 2> %s", LMC_BINARY, args, out_path, err_path);
  int rc = system(cmd);
  if (out) slurp_text(out_path, out, out_n);
  if (err) slurp_text(err_path, err, err_n);
  if (rc == -1 || !WIFEXITED(rc)) return -1;
  return WEXITSTATUS(rc);
}

#endif
