/*
 * tmp_dir.h: a scratch folder of its own for a test program, made in its
 * group setup and removed with everything in it in its group teardown.
 * mkdtemp is POSIX 2008: define _POSIX_C_SOURCE 200809L before any
 * include.
 */
#ifndef LMC_TESTS_TMP_DIR_H
#define LMC_TESTS_TMP_DIR_H

#include <stdio.h>
#include <stdlib.h>

/* Makes the folder $TMPDIR/<prefix>-XXXXXX (TMPDIR unset or empty: /tmp)
 * and writes its name into dir (size n). 0, or -1 when it cannot. */
static inline int tmp_dir_make(char *dir, size_t n, const char *prefix) {
  const char *tmp = getenv("TMPDIR");
  snprintf(dir, n, "%s/%s-XXXXXX", tmp && tmp[0] ? tmp : "/tmp", prefix);
  return mkdtemp(dir) ? 0 : -1;
}

/* Removes the folder dir and everything in it. 0, or -1 when rm fails. */
static inline int tmp_dir_remove(const char *dir) {
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  return system(cmd) == 0 ? 0 : -1;
}

#endif
