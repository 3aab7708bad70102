/*
 * options.c: parsing, formatting and help of option tables (options.h),
 * and the renderer's own table.
 */
#include "render/options.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "render/sampler.h"
#include "render/scene.h"

#define OPT_FIELD(base, off, type) ((type *)((char *)(base) + (off)))

static const char *const opt__samplers[] = {"independent", "sobol", NULL};
static const int opt__sampler_values[] = {LMC_SAMPLER_INDEPENDENT, LMC_SAMPLER_SOBOL};

const char *const lmc_opt_off_on[] = {"off", "on", NULL};

static const lmc_opt opt__render[] = {
    {"spp", LMC_OPT_INT64, offsetof(render_settings, spp), 0, 1, (double)(INT64_MAX / 2), NULL,
     NULL, SET_SPP, "N", "the scene's, else 16",
     "samples per pixel (MCMC: mutations per pixel)", NULL},
    {"time", LMC_OPT_DOUBLE, offsetof(render_settings, time_limit), 0, 1e-3, 1e9, NULL, NULL,
     SET_TIME, "SECONDS", "none", "stop after this long (with --spp: whichever comes first)", NULL},
    {"threads", LMC_OPT_INT, offsetof(render_settings, threads), 0, 1, 1024, NULL, NULL, 0, "N",
     "all cores", "worker threads", NULL},
    {"seed", LMC_OPT_INT64, offsetof(render_settings, seed), 0, 0, (double)INT64_MAX, NULL, NULL, 0,
     "S", NULL, "random seed; the same seed and --spp give the same image for any --threads", NULL},
    {"maxdepth", LMC_OPT_INT, offsetof(render_settings, maxdepth), 0, -1, 1000, NULL, NULL,
     SET_MAXDEPTH, "N", "the scene's, else -1",
     "longest path in segments, Mitsuba's maxDepth (-1: unbounded)", NULL},
    {"rrdepth", LMC_OPT_INT, offsetof(render_settings, rrdepth), 0, 1, 1000, NULL, NULL,
     SET_RRDEPTH, "N", NULL, "Russian roulette from this length on", NULL},
    {"sampler", LMC_OPT_CHOICE, offsetof(render_settings, sampler), 0, 0, 0, opt__samplers,
     opt__sampler_values, SET_SAMPLER, NULL, "the scene's, else independent",
     "pt, bdpt and MCMC's direct pass: independent numbers, or sobol (Owen-scrambled, "
     "stratified across a pixel's samples)", NULL},
    {"snapshot", LMC_OPT_DOUBLE, offsetof(render_settings, snapshot), 0, 1e-3, 1e9, NULL, NULL, 0,
     "S", "none", "also write OUT-<seconds>s.exr every S seconds", NULL},
    {"display-server", LMC_OPT_ADDRESS, offsetof(render_settings, display_server), 0, 1, 65535,
     NULL, NULL, 0, "HOST:PORT", "none",
     "show the image as it converges in the tev viewer listening there (port 14158 when "
     "omitted); the render never waits for it", NULL},
    {"display-interval", LMC_OPT_DOUBLE, offsetof(render_settings, display_interval), 0, 0.05,
     1e9, NULL, NULL, 0, "S", NULL, "seconds between the images --display-server sends", NULL},
    {"error", LMC_OPT_CHOICE, offsetof(render_settings, error), 0, 0, 0, lmc_opt_off_on, NULL, 0,
     NULL, "off",
     "each pixel's standard error as the EXR's channels error.R, error.G, error.B: from the "
     "spread of the passes (pt, bdpt) or of 16 groups of independent chains with b's own "
     "error (MCMC)", NULL},
};

const lmc_opt_table lmc_render_options = {
    "Rendering", opt__render, (int)(sizeof opt__render / sizeof opt__render[0]), NULL, 0};

const lmc_opt *lmc_opt_find(const lmc_opt_table *const *tables, int n, const char *name,
                            const lmc_opt_table **OUT_table) {
  for (int t = 0; t < n; t++)
    for (int i = 0; tables[t] && i < tables[t]->n; i++)
      if (!strcmp(tables[t]->opts[i].name, name)) {
        if (OUT_table) *OUT_table = tables[t];
        return &tables[t]->opts[i];
      }
  return NULL;
}

/* s as a whole finite number in [lo, hi]. */
static int opt__number(const char *s, double lo, double hi, double *out) {
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (errno || end == s || *end != '\0' || !isfinite(v) || v < lo || v > hi) return 0;
  *out = v;
  return 1;
}

/* s as a whole integer in [lo, hi]. */
static int opt__integer(const char *s, double lo, double hi, int64_t *out) {
  char *end;
  errno = 0;
  long long v = strtoll(s, &end, 10);
  if (errno || end == s || *end != '\0' || (double)v < lo || (double)v > hi) return 0;
  *out = v;
  return 1;
}

int lmc_address_parse(const char *s, int port_lo, int port_hi, char *host, size_t n,
                      int *OUT_port) {
  /* The host: labels of letters, digits and hyphens joined by dots (a
   * dotted IPv4 address is one such name); then an optional ":PORT". */
  size_t len = strcspn(s, ":");
  if (len == 0 || len >= n || len >= LMC_ADDRESS_MAX - 7) return 0;
  for (size_t i = 0; i < len; i++) {
    unsigned char c = (unsigned char)s[i];
    if (!isalnum(c) && c != '-' && c != '.') return 0;
    if (c == '.' && (i == 0 || s[i - 1] == '.' || i + 1 == len)) return 0;
  }
  int port = 0;
  if (s[len] == ':') {
    const char *p = s + len + 1;
    if (!*p || strlen(p) > 5) return 0;
    for (const char *q = p; *q; q++)
      if (!isdigit((unsigned char)*q)) return 0;
    port = atoi(p);
    if (port < port_lo || port > port_hi) return 0;
  }
  memcpy(host, s, len);
  host[len] = '\0';
  *OUT_port = port;
  return 1;
}

/* The choices as "a, b or c". */
static void opt__choices(const lmc_opt *o, char *out, size_t n) {
  size_t k = 0;
  out[0] = '\0';
  int count = 0;
  while (o->choices[count]) count++;
  for (int i = 0; i < count && k < n; i++)
    k += (size_t)snprintf(out + k, n - k, "%s%s", i == 0 ? "" : i == count - 1 ? " or " : ", ",
                          o->choices[i]);
}

int lmc_opt_parse(const lmc_opt *o, const char *s, void *base, char *msg, size_t n) {
  int64_t iv;
  double dv;
  switch (o->kind) {
  case LMC_OPT_INT:
  case LMC_OPT_INT64:
    if (!opt__integer(s, o->lo, o->hi, &iv)) {
      snprintf(msg, n, "flag --%s: '%s' is not an integer in [%.0f, %.0f]", o->name, s, o->lo, o->hi);
      return 0;
    }
    if (o->kind == LMC_OPT_INT) *OPT_FIELD(base, o->offset, int) = (int)iv;
    else *OPT_FIELD(base, o->offset, int64_t) = iv;
    break;
  case LMC_OPT_DOUBLE:
    if (!opt__number(s, o->lo, o->hi, &dv)) {
      snprintf(msg, n, "flag --%s: '%s' is not a number in [%g, %g]", o->name, s, o->lo, o->hi);
      return 0;
    }
    *OPT_FIELD(base, o->offset, double) = dv;
    break;
  case LMC_OPT_CHOICE: {
    int i = 0;
    while (o->choices[i] && strcmp(o->choices[i], s)) i++;
    if (!o->choices[i]) {
      char list[256];
      opt__choices(o, list, sizeof list);
      snprintf(msg, n, "flag --%s: '%s' is not one of %s", o->name, s, list);
      return 0;
    }
    *OPT_FIELD(base, o->offset, int) = o->values ? o->values[i] : i;
    break;
  }
  case LMC_OPT_PAIR: {
    char a[64], b[64];
    double x = 0.0, y = 0.0;
    const char *comma = strchr(s, ',');
    size_t la = comma ? (size_t)(comma - s) : 0;
    int ok = comma && la < sizeof a && strlen(comma + 1) < sizeof b;
    if (ok) {
      memcpy(a, s, la), a[la] = '\0';
      snprintf(b, sizeof b, "%s", comma + 1);
      ok = opt__number(a, o->lo, o->hi, &x) && opt__number(b, o->lo, o->hi, &y) && x <= y;
    }
    if (!ok) {
      snprintf(msg, n, "flag --%s: '%s' is not %s, two numbers in [%g, %g] with the first the smaller",
               o->name, s, o->arg ? o->arg : "A,B", o->lo, o->hi);
      return 0;
    }
    *OPT_FIELD(base, o->offset, double) = x;
    *OPT_FIELD(base, o->offset2, double) = y;
    break;
  }
  case LMC_OPT_ADDRESS: {
    char host[LMC_ADDRESS_MAX];
    int port;
    if (!lmc_address_parse(s, (int)o->lo, (int)o->hi, host, sizeof host, &port)) {
      snprintf(msg, n,
               "flag --%s: '%s' is not HOST or HOST:PORT (a host name or IPv4 address, a port "
               "in [%.0f, %.0f])",
               o->name, s, o->lo, o->hi);
      return 0;
    }
    snprintf(OPT_FIELD(base, o->offset, char), LMC_ADDRESS_MAX, "%s", s);
    break;
  }
  }
  if (o->set_bit) ((render_settings *)base)->set |= o->set_bit;
  return 1;
}

int lmc_opt_set(const lmc_opt_table *t, const lmc_opt *o, const char *s, render_settings *rs,
                char *msg, size_t n) {
  if (!t->defaults) return lmc_opt_parse(o, s, rs, msg, n);
  /* A plugin's own: checked on a copy of its defaults, kept as text. */
  char scratch[4096];
  if (t->size > sizeof scratch) {
    snprintf(msg, n, "flag --%s: its table's settings are too large", o->name);
    return 0;
  }
  memcpy(scratch, t->defaults, t->size);
  if (!lmc_opt_parse(o, s, scratch, msg, n)) return 0;
  if (strlen(o->name) >= sizeof rs->params[0].name || strlen(s) >= sizeof rs->params[0].value) {
    snprintf(msg, n, "flag --%s: '%s' is too long", o->name, s);
    return 0;
  }
  int k = 0;
  while (k < rs->n_params && strcmp(rs->params[k].name, o->name)) k++;
  if (k == rs->n_params) {
    if (k == LMC_MAX_PARAMS) {
      snprintf(msg, n, "flag --%s: more than %d plugin settings", o->name, LMC_MAX_PARAMS);
      return 0;
    }
    rs->n_params++;
  }
  snprintf(rs->params[k].name, sizeof rs->params[k].name, "%s", o->name);
  snprintf(rs->params[k].value, sizeof rs->params[k].value, "%s", s);
  return 1;
}

lmc_status lmc_opt_read(const lmc_opt_table *t, const render_settings *rs, void *OUT,
                        lmc_error *err) {
  memcpy(OUT, t->defaults, t->size);
  for (int k = 0; k < rs->n_params; k++)
    for (int i = 0; i < t->n; i++) {
      if (strcmp(t->opts[i].name, rs->params[k].name)) continue;
      char msg[512];
      if (!lmc_opt_parse(&t->opts[i], rs->params[k].value, OUT, msg, sizeof msg))
        return lmc_error_set(err, LMC_EINVAL, NULL, 0, "%s", msg);
    }
  return LMC_OK;
}

const char *lmc_opt_value(const render_settings *rs, const char *name) {
  for (int k = 0; k < rs->n_params; k++)
    if (!strcmp(rs->params[k].name, name)) return rs->params[k].value;
  return NULL;
}

void lmc_opt_unset(render_settings *rs, const char *name) {
  int k = 0;
  while (k < rs->n_params && strcmp(rs->params[k].name, name)) k++;
  if (k == rs->n_params) return;
  memmove(&rs->params[k], &rs->params[k + 1], (size_t)(rs->n_params - k - 1) * sizeof rs->params[0]);
  rs->n_params--;
}

/* 1 when `name` is one of o's names in a scene. */
static int opt__scene_name(const lmc_opt *o, const char *name) {
  if (!strcmp(o->name, name)) return 1;
  size_t n = strlen(name);
  for (const char *p = o->scene; p && *p;) {
    size_t len = strcspn(p, " ");
    if (len == n && !strncmp(p, name, n)) return 1;
    p += len;
    while (*p == ' ') p++;
  }
  return 0;
}

lmc_status lmc_opt_apply_scene(const lmc_opt_table *const *tables, int n, const scene *s,
                               render_settings *rs, lmc_error *err) {
  for (int k = 0; k < s->n_params; k++) {
    const scene_param *p = &s->params[k];
    const lmc_opt *o = NULL;
    const lmc_opt_table *ot = NULL;
    for (int t = 0; t < n && !o; t++)
      for (int i = 0; tables[t] && i < tables[t]->n && !o; i++)
        if (opt__scene_name(&tables[t]->opts[i], p->name)) o = &tables[t]->opts[i], ot = tables[t];
    if (!o) {
      lmc_warn(p->file, p->line, "parameter '%s' is not used by lmc: ignored", p->name);
      continue;
    }
    /* A <boolean> of an on/off choice. */
    const char *v = p->value;
    if (p->is_bool && o->kind == LMC_OPT_CHOICE)
      for (int i = 0; o->choices[i]; i++)
        if (!strcmp(o->choices[i], "on")) v = !strcmp(p->value, "true") ? "on" : "off";
    char msg[512];
    if (!lmc_opt_set(ot, o, v, rs, msg, sizeof msg)) {
      const char *why = strstr(msg, ": ");
      return lmc_error_set(err, LMC_EPARSE, p->file, p->line, "parameter '%s' (--%s): %s",
                           p->name, o->name, why ? why + 2 : msg);
    }
  }
  return LMC_OK;
}

void lmc_opt_format(const lmc_opt *o, const void *rs, char *out, size_t n) {
  if (o->def) {
    snprintf(out, n, "%s", o->def);
    return;
  }
  switch (o->kind) {
  case LMC_OPT_INT: snprintf(out, n, "%d", *OPT_FIELD((void *)rs, o->offset, int)); break;
  case LMC_OPT_INT64:
    snprintf(out, n, "%lld", (long long)*OPT_FIELD((void *)rs, o->offset, int64_t));
    break;
  case LMC_OPT_DOUBLE: snprintf(out, n, "%g", *OPT_FIELD((void *)rs, o->offset, double)); break;
  case LMC_OPT_CHOICE: {
    int v = *OPT_FIELD((void *)rs, o->offset, int);
    const char *name = "?";
    for (int i = 0; o->choices[i]; i++)
      if ((o->values ? o->values[i] : i) == v) name = o->choices[i];
    snprintf(out, n, "%s", name);
    break;
  }
  case LMC_OPT_PAIR:
    snprintf(out, n, "%g,%g", *OPT_FIELD((void *)rs, o->offset, double),
             *OPT_FIELD((void *)rs, o->offset2, double));
    break;
  case LMC_OPT_ADDRESS: {
    const char *a = OPT_FIELD((void *)rs, o->offset, char);
    snprintf(out, n, "%s", a[0] ? a : "none");
    break;
  }
  }
}

/* The flag and its argument as the help shows them: "--sigma S",
 * "--direct separate|mcmc". */
static void opt__usage(const lmc_opt *o, char *out, size_t n) {
  size_t k = (size_t)snprintf(out, n, "--%s", o->name);
  if (o->kind == LMC_OPT_CHOICE && !o->arg) {
    for (int i = 0; o->choices[i] && k < n; i++)
      k += (size_t)snprintf(out + k, n - k, "%s%s", i ? "|" : " ", o->choices[i]);
  } else if (k < n) {
    snprintf(out + k, n - k, " %s", o->arg ? o->arg : "X");
  }
}

#define OPT_HELP_COL 27
#define OPT_HELP_WIDTH 92

void lmc_opt_help(FILE *f, const lmc_opt_table *t) {
  render_settings rd = render_settings_default();
  const void *d = t->defaults ? t->defaults : (const void *)&rd;
  fprintf(f, "%s:\n", t->title);
  for (int i = 0; i < t->n; i++) {
    const lmc_opt *o = &t->opts[i];
    char use[128], def[96], text[1024];
    opt__usage(o, use, sizeof use);
    lmc_opt_format(o, d, def, sizeof def);
    snprintf(text, sizeof text, "%s (default %s)", o->help, def);
    /* The flag, then the text wrapped at OPT_HELP_WIDTH from column OPT_HELP_COL. */
    int col = fprintf(f, "  %s", use);
    const char *p = text;
    if (col >= OPT_HELP_COL - 1) {
      fputc('\n', f);
      col = 0;
    }
    while (*p) {
      fprintf(f, "%*s", OPT_HELP_COL - col, "");
      int room = OPT_HELP_WIDTH - OPT_HELP_COL, len = (int)strlen(p);
      int cut = len;
      if (len > room) {
        cut = room;
        while (cut > 0 && p[cut] != ' ') cut--;
        if (cut == 0) cut = room;
      }
      fprintf(f, "%.*s\n", cut, p);
      p += cut;
      while (*p == ' ') p++;
      col = 0;
    }
  }
  fputc('\n', f);
}

void lmc_opt_markdown(FILE *f, const lmc_opt_table *t) {
  render_settings rd = render_settings_default();
  const void *d = t->defaults ? t->defaults : (const void *)&rd;
  fprintf(f, "| flag | meaning | default |\n| --- | --- | --- |\n");
  for (int i = 0; i < t->n; i++) {
    const lmc_opt *o = &t->opts[i];
    char use[128], def[96];
    opt__usage(o, use, sizeof use);
    lmc_opt_format(o, d, def, sizeof def);
    fputs("| `", f);
    for (const char *c = use; *c; c++) fputs(*c == '|' ? "\\|" : (char[2]){*c, 0}, f);
    fputs("` | ", f);
    /* (a | would end the cell; a < would open an HTML tag) */
    for (const char *c = o->help; *c; c++) fputs(*c == '|' ? "\\|" : *c == '<' ? "&lt;" : (char[2]){*c, 0}, f);
    fprintf(f, " | %s |\n", def);
  }
}
