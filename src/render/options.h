/*
 * options.h: settings as tables. Each part of lmc that has settings (the
 * renderer, the MCMC driver, each state space and each MCMC integrator)
 * declares its flags once, as an lmc_opt table: name, kind, the field of
 * render_settings it sets, its range or choices, its default and its help.
 * The command line parses with the tables (lmc_opt_parse) and prints
 * `lmc render --help` from them (lmc_opt_help), so a flag is accepted
 * exactly when it is documented, and its range is checked in one place.
 *
 * A flag is given as `--name value` or `--name=value`. A bad value is
 * refused with a message that names the flag and what it accepts.
 *
 * Where a setting's value lives. The renderer's table sets fields of
 * render_settings. A plugin's table (the MCMC driver's, a state space's,
 * an integrator's) sets fields of its own struct, which render/ never
 * sees: its values travel in render_settings.params as checked text
 * (name, value), and the plugin reads them into its struct with
 * lmc_opt_read when it starts.
 */
#ifndef LMC_RENDER_OPTIONS_H
#define LMC_RENDER_OPTIONS_H

#include <stddef.h>
#include <stdio.h>

#include "render/error.h"
#include "render/settings.h"

typedef enum lmc_opt_kind {
  LMC_OPT_INT = 0, /* an int in [lo, hi] */
  LMC_OPT_INT64,   /* an int64_t in [lo, hi] */
  LMC_OPT_DOUBLE,  /* a finite double in [lo, hi] */
  LMC_OPT_CHOICE,  /* one of choices[]: stores values[i] (or i) as an int */
  LMC_OPT_PAIR,    /* "A,B": two doubles in [lo, hi] with A <= B, at offset and offset2 */
  LMC_OPT_ADDRESS  /* "HOST[:PORT]" (lmc_address_parse), the port in [lo, hi]: kept as given,
                      in a char[LMC_ADDRESS_MAX] field */
} lmc_opt_kind;

typedef struct lmc_opt {
  const char *name;            /* the flag without its dashes: "sigma" for --sigma */
  lmc_opt_kind kind;
  size_t offset;               /* the field of render_settings */
  size_t offset2;              /* LMC_OPT_PAIR: the second field */
  double lo, hi;               /* the range of numbers (inclusive) */
  const char *const *choices;  /* LMC_OPT_CHOICE: the names, NULL-terminated */
  const int *values;           /* LMC_OPT_CHOICE: the value of each name (NULL: its index) */
  unsigned set_bit;            /* SET_* marked when given (0: none) */
  const char *arg;             /* the value's name in the help ("S"); choices: NULL */
  const char *def;             /* the default as the help says it (NULL: from
                                  render_settings_default) */
  const char *help;            /* one sentence or two; wrapped by lmc_opt_help */
  const char *scene;           /* other names of it in a scene's <integrator> or <dpt>,
                                  space-separated (NULL: none; its own name always works) */
} lmc_opt;

/* One part's flags, under a title in the help. */
typedef struct lmc_opt_table {
  const char *title; /* "MCMC (pssmlt, mmlt, lmc, h2mc, mlt; --spp counts mutations per pixel)" */
  const lmc_opt *opts;
  int n;
  const void *defaults; /* a plugin's own struct with its defaults (offsets are into it), or
                           NULL: the offsets are into render_settings */
  size_t size;          /* sizeof that struct */
} lmc_opt_table;

/* The renderer's own flags (options.c): --spp, --time, --threads, --seed,
 * --maxdepth, --rrdepth, --sampler, --snapshot, --display-server,
 * --display-interval, --error. */
extern const lmc_opt_table lmc_render_options;
/* The names of an off/on choice (LMC_OPT_CHOICE: 0 off, 1 on), for every table. */
extern const char *const lmc_opt_off_on[];

/* Splits "HOST[:PORT]" (a network address: a host name or a dotted IPv4
 * address, then optionally a colon and a decimal port in [port_lo,
 * port_hi]) into host (room for n bytes, n <= LMC_ADDRESS_MAX) and
 * *OUT_port (0 when no port is given). Returns 1, or 0 when s is not of
 * that form. */
int lmc_address_parse(const char *s, int port_lo, int port_hi, char *host, size_t n,
                      int *OUT_port);

/* The option `name` (without dashes) among tables[0 .. n-1], the first
 * that has it, and its table in *OUT_table (may be NULL); NULL when none
 * does. */
const lmc_opt *lmc_opt_find(const lmc_opt_table *const *tables, int n, const char *name,
                            const lmc_opt_table **OUT_table);

/* Parses s as the value of option o into the struct at base (render_settings
 * or the table's own) and marks its set bit (render_settings only).
 * Returns 1, or 0 with a message naming the flag and what it accepts in
 * msg (room for n). */
int lmc_opt_parse(const lmc_opt *o, const char *s, void *base, char *msg, size_t n);

/* Sets option o of table t to s in *rs: into its field (the renderer's
 * and driver's tables) or, checked, into rs->params (a plugin's own).
 * Returns 1, or 0 with a message as lmc_opt_parse. */
int lmc_opt_set(const lmc_opt_table *t, const lmc_opt *o, const char *s, render_settings *rs,
                char *msg, size_t n);

/* A plugin's settings: t's defaults, then rs->params of t's options, into
 * OUT (t->size bytes). Fails (LMC_EINVAL, the flag named) on a value that
 * does not parse. */
lmc_status lmc_opt_read(const lmc_opt_table *t, const render_settings *rs, void *OUT,
                        lmc_error *err);

/* The value given to the setting `name` (a plugin's, without dashes) in
 * rs->params, as checked text; NULL when it was not given. */
const char *lmc_opt_value(const render_settings *rs, const char *name);

/* Forgets the setting `name` given in rs->params (nothing when none). */
void lmc_opt_unset(render_settings *rs, const char *name);

/* The option's value in the struct at base as the help shows it (o->def
 * when given). */
void lmc_opt_format(const lmc_opt *o, const void *base, char *out, size_t n);

/* Applies the scene's passed-on parameters (scene.h's params: the
 * <integrator> and <dpt> values the loader did not read) to *rs with the
 * tables: each by its flag's name or one of its scene names. A bad value
 * fails with LMC_EPARSE, its file and line and the parameter named; an
 * unknown parameter is warned about and ignored. */
struct scene;
lmc_status lmc_opt_apply_scene(const lmc_opt_table *const *tables, int n, const struct scene *s,
                               render_settings *rs, lmc_error *err);

/* Writes a table's flags as help text: `  --name ARG   help (default D)`. */
void lmc_opt_help(FILE *f, const lmc_opt_table *t);

/* Writes a table's flags as a Markdown table (the README's). */
void lmc_opt_markdown(FILE *f, const lmc_opt_table *t);

#endif
