/*
 * fuzz_replay.c: runs a fuzz target's LLVMFuzzerTestOneInput on files,
 * without libFuzzer, so that any compiler can replay the committed corpus
 * (seeds and regression cases) in every ctest run.
 *
 *   fuzz_replay_<target> PATH...   each PATH a file or a folder of files
 *
 * Files of a folder are run in name order. Prints how many inputs ran and
 * fails (exit status 1) when there was none, so an emptied or misnamed
 * corpus folder does not pass silently. A crash is the sanitizers' (or the
 * kernel's) business: the test fails.
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "fuzz_util.h"

/* Runs one file; returns 1 when it ran. */
static int replay__file(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "fuzz_replay: cannot open %s\n", path);
    return 0;
  }
  size_t cap = 4096, len = 0;
  unsigned char *buf = malloc(cap);
  size_t got;
  while (buf && (got = fread(buf + len, 1, cap - len, f)) > 0) {
    len += got;
    if (len == cap) {
      unsigned char *b = realloc(buf, 2 * cap);
      if (!b) {
        free(buf);
        buf = NULL;
        break;
      }
      buf = b;
      cap *= 2;
    }
  }
  fclose(f);
  if (!buf) {
    fprintf(stderr, "fuzz_replay: out of memory reading %s\n", path);
    return 0;
  }
  LLVMFuzzerTestOneInput(buf, len);
  free(buf);
  return 1;
}

static int replay__cmp(const void *a, const void *b) {
  return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Runs every regular file of a folder in name order; returns the count. */
static int replay__dir(const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return 0;
  char **names = NULL;
  int n = 0, cap = 0;
  struct dirent *e;
  while ((e = readdir(d)) != NULL) {
    if (e->d_name[0] == '.') continue;
    if (n == cap) {
      cap = cap ? 2 * cap : 64;
      char **nn = realloc(names, (size_t)cap * sizeof *nn);
      if (!nn) break;
      names = nn;
    }
    size_t len = strlen(dir) + strlen(e->d_name) + 2;
    names[n] = malloc(len);
    if (!names[n]) break;
    snprintf(names[n], len, "%s/%s", dir, e->d_name);
    n++;
  }
  closedir(d);
  qsort(names, (size_t)n, sizeof *names, replay__cmp);
  int ran = 0;
  for (int i = 0; i < n; i++) {
    struct stat sb;
    if (stat(names[i], &sb) == 0 && S_ISREG(sb.st_mode)) ran += replay__file(names[i]);
    free(names[i]);
  }
  free(names);
  return ran;
}

int main(int argc, char **argv) {
  int ran = 0;
  for (int i = 1; i < argc; i++) {
    struct stat sb;
    if (stat(argv[i], &sb) != 0) {
      fprintf(stderr, "fuzz_replay: %s does not exist\n", argv[i]);
      return 1;
    }
    ran += S_ISDIR(sb.st_mode) ? replay__dir(argv[i]) : replay__file(argv[i]);
  }
  printf("fuzz_replay: %d inputs ran\n", ran);
  return ran > 0 ? 0 : 1;
}
