/*
 * error.h: status codes and the caller-owned error record.
 *
 * Every fallible function in lmc returns an lmc_status (0 on success, a
 * negative code otherwise) and fills the lmc_error passed as its last
 * argument with a one-line message and, where the error comes from a file,
 * the file name and line. There is no global error state: each thread owns
 * its records, so this works under OpenMP. Only main() turns an error into
 * an exit status.
 */
#ifndef LMC_RENDER_ERROR_H
#define LMC_RENDER_ERROR_H

/* The status table: name, value, description. */
#define LMC_STATUS_MAP(X)                                   \
  X(OK, 0, "success")                                       \
  X(EIO, -1, "input/output error")                          \
  X(EPARSE, -2, "malformed input")                          \
  X(ENOMEM, -3, "out of memory")                            \
  X(EUNSUPPORTED, -4, "unsupported feature")                \
  X(EINVAL, -5, "invalid argument")                         \
  X(EINTERRUPTED, -6, "interrupted")                       \
  X(ESTRICT, -7, "refused under --strict")

typedef enum lmc_status {
#define LMC__STATUS_ENUM(name, value, text) LMC_##name = value,
  LMC_STATUS_MAP(LMC__STATUS_ENUM)
#undef LMC__STATUS_ENUM
} lmc_status;

/* A one-line description of an error: file and line are empty/0 when the
 * error does not come from a file. */
typedef struct lmc_error {
  lmc_status code;
  int line;
  char file[512];
  char msg[1024];
} lmc_error;

/* Text for a status code ("malformed input"). */
const char *lmc_status_str(lmc_status code);

/* Clears an error record (err may be NULL). */
void lmc_error_clear(lmc_error *err);

/* Fills err (may be NULL) and returns code, so callers can write
 * `return lmc_error_set(err, LMC_EPARSE, file, line, "bad %s", x);`.
 * file may be NULL, line 0 when unknown. */
lmc_status lmc_error_set(lmc_error *err, lmc_status code, const char *file, int line,
                         const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

/* Formats "file:line: message" (or just the message) into buf. */
void lmc_error_format(const lmc_error *err, char *buf, int size);

/* Prints a warning "lmc: warning: file:line: message" to stderr. Thread safe.
 * Warnings are also counted (lmc_warning_count) so tests can assert them. */
void lmc_warn(const char *file, int line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
int lmc_warning_count(void);
/* When quiet, warnings are counted but not printed. */
void lmc_warn_set_quiet(int quiet);

#endif
