/*
 * fuzz_util.c: the private temporary folder of a fuzz target (see
 * fuzz_util.h). Files written there are removed at exit together with the
 * folder, so neither libFuzzer nor the corpus replay leave anything behind.
 */
#define _POSIX_C_SOURCE 200809L
#include "fuzz_util.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char fuzz__dir[256];
static char fuzz__path[512];

/* Removes the folder's files, then the folder (it has no subfolders). */
static void fuzz__cleanup(void) {
  if (!fuzz__dir[0]) return;
  DIR *d = opendir(fuzz__dir);
  if (d) {
    struct dirent *e;
    char p[512];
    while ((e = readdir(d)) != NULL) {
      if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
      snprintf(p, sizeof p, "%s/%s", fuzz__dir, e->d_name);
      unlink(p);
    }
    closedir(d);
  }
  rmdir(fuzz__dir);
}

const char *fuzz_dir(void) {
  if (fuzz__dir[0]) return fuzz__dir;
  const char *tmp = getenv("TMPDIR");
  if (!tmp || !tmp[0]) tmp = "/tmp";
  snprintf(fuzz__dir, sizeof fuzz__dir, "%s/lmc-fuzz-XXXXXX", tmp);
  if (!mkdtemp(fuzz__dir)) {
    perror("fuzz: mkdtemp");
    abort();
  }
  atexit(fuzz__cleanup);
  return fuzz__dir;
}

const char *fuzz_write(const char *name, const void *data, size_t size) {
  snprintf(fuzz__path, sizeof fuzz__path, "%s/%s", fuzz_dir(), name);
  FILE *f = fopen(fuzz__path, "wb");
  if (!f || (size > 0 && fwrite(data, 1, size, f) != size) || fclose(f) != 0) {
    perror("fuzz: cannot write the input file");
    abort();
  }
  return fuzz__path;
}
