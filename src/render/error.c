/*
 * error.c: status strings, error records and warnings.
 */
#include "render/error.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

const char *lmc_status_str(lmc_status code) {
  switch (code) {
#define LMC__STATUS_STR(name, value, text) \
  case LMC_##name:                         \
    return text;
    LMC_STATUS_MAP(LMC__STATUS_STR)
#undef LMC__STATUS_STR
  }
  return "unknown error";
}

void lmc_error_clear(lmc_error *err) {
  if (!err) return;
  memset(err, 0, sizeof *err);
}

lmc_status lmc_error_set(lmc_error *err, lmc_status code, const char *file, int line,
                         const char *fmt, ...) {
  if (!err) return code;
  err->code = code;
  err->line = line;
  err->file[0] = '\0';
  if (file) snprintf(err->file, sizeof err->file, "%s", file);
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(err->msg, sizeof err->msg, fmt, ap);
  va_end(ap);
  return code;
}

void lmc_error_format(const lmc_error *err, char *buf, int size) {
  if (size <= 0) return;
  if (!err) {
    snprintf(buf, (size_t)size, "unknown error");
  } else if (err->file[0] && err->line > 0) {
    snprintf(buf, (size_t)size, "%s:%d: %s", err->file, err->line, err->msg);
  } else if (err->file[0]) {
    snprintf(buf, (size_t)size, "%s: %s", err->file, err->msg);
  } else {
    snprintf(buf, (size_t)size, "%s", err->msg);
  }
}

static int lmc__warnings;
static int lmc__quiet;

void lmc_warn_set_quiet(int quiet) { lmc__quiet = quiet; }

int lmc_warning_count(void) {
  int n;
#pragma omp atomic read
  n = lmc__warnings;
  return n;
}

void lmc_warn(const char *file, int line, const char *fmt, ...) {
#pragma omp atomic
  lmc__warnings++;
  if (lmc__quiet) return;
  char msg[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
#pragma omp critical(lmc_stderr)
  {
    if (file && line > 0)
      fprintf(stderr, "lmc: warning: %s:%d: %s\n", file, line, msg);
    else if (file)
      fprintf(stderr, "lmc: warning: %s: %s\n", file, msg);
    else
      fprintf(stderr, "lmc: warning: %s\n", msg);
  }
}
