/*
 * test_options.c: the flag tables (render/options.h) of the renderer, the
 * direct integrator, the MCMC driver, the state spaces and the MCMC
 * integrators, one table-driven test
 * over every flag of every table:
 *
 *  - lmc_opt_parse takes a valid value (inside the range, different from
 *    the default; a choice; a pair), stores it in the flag's field and
 *    marks its set bit; it refuses a bad value (not a number, out of
 *    range, an unknown choice, a reversed pair) with a message naming the
 *    flag;
 *  - `lmc render --help` mentions every flag;
 *  - a scene file sets every flag by its name as a parameter of
 *    <integrator type="lmc"> (the same field value as the command line's),
 *    and by the other names the tables give it in a <dpt> block (the LMC
 *    paper's scenes: largestepprob, numinitsamples, ...); a <boolean> sets
 *    an on/off flag; a bad value fails with the file, the line and the
 *    parameter named; an unknown parameter is a warning;
 *  - docs/flags.md's flag tables are `lmc render --help-markdown`,
 *    verbatim, between its markers (so they are made from the same tables),
 *    with every table under its title and every flag's row in it, in
 *    order; the README links that page;
 *  - the binary accepts the valid value as `--flag value` and as
 *    `--flag=value` (a tiny pt render of the furnace, exit 0), and exits 2
 *    on the bad one with a message naming the flag.
 * Each test counts what it checked and asserts the count against the
 * tables' sizes, counted apart (count_tables): every table has one flag at
 * least; no flag appears in two tables unless it reads the same values;
 * the scene names of the LMC paper's scenes and Mitsuba's mlt are there.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include "lmc/kernels/lmc_kernel.h"
#include "lmc/mcmc.h"
#include "lmc/driver/method.h"
#include "render/io/io.h"
#include "render/options.h"
#include "test_util.h"
#include "run_lmc.h"

#define TMP LMC_TEST_TMP "/lmc_test_options"
#define MAX_TABLES 32

static char out_text[1 << 16], err_text[1 << 14];

static int run_lmc(const char *args) {
  return run_lmc_in(TMP, args, out_text, sizeof out_text, err_text, sizeof err_text);
}

static int tables(const lmc_opt_table **t) {
  t[0] = &lmc_render_options;
  return 1 + mcmc_option_tables(t + 1, MAX_TABLES - 1);
}

/* What the tables hold, counted apart from the tests' loops (by the names
 * themselves, not lmc_opt_find): rows, every flag of every table; names,
 * the distinct ones (a flag in two tables, as --iso-prob in lmc's and
 * h2mc's, counts once); aliases, the scene names besides the flags' own
 * (the words of each distinct flag's `scene`). */
typedef struct table_counts {
  int tables, rows, names, aliases;
} table_counts;

static table_counts count_tables(void) {
  const lmc_opt_table *t[MAX_TABLES];
  table_counts c = {tables(t), 0, 0, 0};
  assert_true(c.tables >= 4); /* render, direct, driver, bdpt states, lmc, h2mc, ... */
  for (int ti = 0; ti < c.tables; ti++)
    for (int i = 0; i < t[ti]->n; i++) {
      const lmc_opt *o = &t[ti]->opts[i];
      c.rows++;
      /* Seen before, in this table or an earlier one? */
      int seen = 0;
      for (int tj = 0; tj <= ti && !seen; tj++)
        for (int j = 0; j < (tj == ti ? i : t[tj]->n); j++)
          if (!strcmp(t[tj]->opts[j].name, o->name)) seen = 1;
      if (seen) continue;
      c.names++;
      for (const char *p = o->scene ? o->scene : ""; *p;) {
        size_t n = strcspn(p, " ");
        if (n) c.aliases++;
        p += n + strspn(p + n, " ");
      }
    }
  assert_true(c.rows > 0 && c.names > 0 && c.names <= c.rows);
  return c;
}

/* The struct that holds o's value for settings rs: rs itself, or (a
 * plugin's own table) its settings read from rs into buf. */
static const void *values(const lmc_opt_table *t, const render_settings *rs, void *buf) {
  if (!t->defaults) return rs;
  lmc_error err;
  assert_true(t->size <= 4096);
  assert_int_equal(lmc_opt_read(t, rs, buf, &err), LMC_OK);
  return buf;
}

/* The table's defaults. */
static const void *defaults_of(const lmc_opt_table *t, const render_settings *d) {
  return t->defaults ? t->defaults : (const void *)d;
}

/* The field's bytes (for comparing before and after). */
static size_t field_size(const lmc_opt *o) {
  switch (o->kind) {
  case LMC_OPT_INT64: return sizeof(int64_t);
  case LMC_OPT_DOUBLE: return sizeof(double);
  case LMC_OPT_PAIR: return sizeof(double);
  case LMC_OPT_ADDRESS: return LMC_ADDRESS_MAX;
  default: return sizeof(int);
  }
}

/* A valid value of o other than its default (in the struct at d), into out. */
static void good_value(const lmc_opt *o, const void *d, char *out, size_t n) {
  const char *f = (const char *)d + o->offset;
  switch (o->kind) {
  case LMC_OPT_INT:
  case LMC_OPT_INT64: {
    int64_t def = o->kind == LMC_OPT_INT ? *(const int *)f : *(const int64_t *)f;
    int64_t v = (int64_t)o->lo;
    if (v == def) v++;
    snprintf(out, n, "%lld", (long long)v);
    break;
  }
  case LMC_OPT_DOUBLE: {
    double v = 0.5 * (o->lo + fmin(o->hi, o->lo + 1.0));
    if (v == *(const double *)f) v = 0.25 * (o->lo + fmin(o->hi, o->lo + 1.0)) + 0.5 * o->lo;
    snprintf(out, n, "%.17g", v);
    break;
  }
  case LMC_OPT_CHOICE: {
    int def = *(const int *)f, k = 0;
    while (o->choices[k]) k++;
    int pick = k - 1;
    if ((o->values ? o->values[pick] : pick) == def) pick = 0;
    snprintf(out, n, "%s", o->choices[pick]);
    break;
  }
  case LMC_OPT_PAIR: snprintf(out, n, "0.5,2"); break;
  /* (a closed port of this machine: the binary's render warns and goes on) */
  case LMC_OPT_ADDRESS: snprintf(out, n, "127.0.0.1:1"); break;
  }
}

/* A bad value of o. */
static void bad_value(const lmc_opt *o, int which, char *out, size_t n) {
  if (o->kind == LMC_OPT_CHOICE) snprintf(out, n, "%s", which ? "bogus" : "");
  else if (o->kind == LMC_OPT_PAIR) snprintf(out, n, "%s", which ? "2,0.5" : "x");
  else if (o->kind == LMC_OPT_ADDRESS) snprintf(out, n, "%s", which ? "localhost:70000" : "a b:1");
  else if (which && isfinite(o->hi) && o->hi < 1e15) snprintf(out, n, "%.17g", o->hi * 2.0 + 1.0);
  else snprintf(out, n, "%s", which ? "1e999" : "x1");
}

static void test_parse(void **state) {
  (void)state;
  const lmc_opt_table *t[MAX_TABLES];
  int nt = tables(t), flags = 0, checks = 0;
  table_counts tc = count_tables();
  assert_int_equal(nt, tc.tables);
  render_settings d = render_settings_default();
  for (int ti = 0; ti < nt; ti++) {
    assert_true(t[ti]->n >= 1);
    for (int i = 0; i < t[ti]->n; i++) {
      const lmc_opt *o = &t[ti]->opts[i];
      flags++;
      /* A name in two tables must read the same values. */
      const lmc_opt *first = lmc_opt_find(t, nt, o->name, NULL);
      assert_ptr_not_equal(first, NULL);
      assert_true(first->kind == o->kind && first->lo == o->lo && first->hi == o->hi);
      char v[128], msg[512];
      const void *dflt = defaults_of(t[ti], &d);
      good_value(o, dflt, v, sizeof v);
      render_settings rs = render_settings_default();
      rs.set = 0;
      if (!lmc_opt_set(t[ti], o, v, &rs, msg, sizeof msg))
        fail_msg("--%s %s refused: %s", o->name, v, msg);
      static char buf[4096];
      const void *got = values(t[ti], &rs, buf);
      if (!memcmp((const char *)got + o->offset, (const char *)dflt + o->offset, field_size(o)))
        fail_msg("--%s %s left its field at the default", o->name, v);
      if (!t[ti]->defaults) assert_true((rs.set & o->set_bit) == o->set_bit);
      checks++;
      for (int w = 0; w < 2; w++) {
        bad_value(o, w, v, sizeof v);
        rs = render_settings_default();
        msg[0] = '\0';
        if (lmc_opt_set(t[ti], o, v, &rs, msg, sizeof msg)) fail_msg("--%s '%s' accepted", o->name, v);
        char want[80];
        snprintf(want, sizeof want, "--%s", o->name);
        if (!strstr(msg, want)) fail_msg("message for --%s '%s' does not name it: %s", o->name, v, msg);
        checks++;
      }
    }
  }
  fprintf(stderr, "  %d flags in %d tables, %d parse checks\n", flags, nt, checks);
  assert_int_equal(checks, 3 * flags);
  assert_int_equal(flags, tc.rows);
}

static void test_binary(void **state) {
  (void)state;
  mkdir(TMP, 0755);
  const lmc_opt_table *t[MAX_TABLES];
  int nt = tables(t), checks = 0, flags = 0;
  table_counts tc = count_tables();
  render_settings d = render_settings_default();
  assert_int_equal(run_lmc("render --help"), 0);
  char help[sizeof out_text];
  memcpy(help, out_text, sizeof help);
  char base[1024];
  snprintf(base, sizeof base,
           "render '%s/tests/data/analytic/furnace.xml' --integrator pt --spp 1 --resolution 4x4 "
           "-q -o " TMP "/out.exr",
           LMC_SOURCE_DIR);
  for (int ti = 0; ti < nt; ti++)
    for (int i = 0; i < t[ti]->n; i++) {
      const lmc_opt *o = &t[ti]->opts[i];
      if (lmc_opt_find(t, nt, o->name, NULL) != o) continue; /* (listed once) */
      flags++;
      char flag[80], v[128], args[2048];
      snprintf(flag, sizeof flag, "--%s", o->name);
      /* The help names it at the start of a line. */
      char line[96];
      snprintf(line, sizeof line, "\n  %s ", flag);
      if (!strstr(help, line)) fail_msg("render --help does not list %s", flag);
      good_value(o, defaults_of(t[ti], &d), v, sizeof v);
      snprintf(args, sizeof args, "%s %s '%s'", base, flag, v);
      if (run_lmc(args) != 0) fail_msg("%s %s: exit not 0: %s", flag, v, err_text);
      snprintf(args, sizeof args, "%s '%s=%s'", base, flag, v);
      if (run_lmc(args) != 0) fail_msg("%s=%s: exit not 0: %s", flag, v, err_text);
      bad_value(o, 1, v, sizeof v);
      snprintf(args, sizeof args, "%s %s '%s'", base, flag, v);
      if (run_lmc(args) != 2) fail_msg("%s %s: exit not 2", flag, v);
      if (!strstr(err_text, flag)) fail_msg("%s %s: the message does not name it: %s", flag, v, err_text);
      checks += 4;
    }
  fprintf(stderr, "  %d flags, %d checks of the binary\n", flags, checks);
  assert_int_equal(checks, 4 * flags);
  assert_int_equal(flags, tc.names); /* (a flag in two tables once) */
}

/* Writes a scene with `block` (an <integrator> or <dpt> element) to path. */
static void write_scene(const char *path, const char *block) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fprintf(f,
          "<scene version=\"0.6.0\">\n"
          "%s\n"
          "  <sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" "
          "value=\"4\"/><integer name=\"height\" value=\"4\"/></film></sensor>\n"
          "  <emitter type=\"constant\"/>\n"
          "</scene>\n",
          block);
  fclose(f);
}

/* Loads path and applies its parameters; the status of the latter. */
static lmc_status scene_settings(const char *path, render_settings *rs, lmc_error *err) {
  scene *s = NULL;
  lmc_error_clear(err);
  assert_int_equal(scene_load_xml(path, NULL, 0, &s, err), LMC_OK);
  lmc_status st = mcmc_scene_settings(s, rs, err);
  scene_destroy(s);
  return st;
}

static void test_scene(void **state) {
  (void)state;
  mkdir(TMP, 0755);
  const lmc_opt_table *t[MAX_TABLES];
  int nt = tables(t), flags = 0, aliases = 0, checks = 0;
  table_counts tc = count_tables();
  /* The other names the LMC paper's scenes (dpt's) and Mitsuba's mlt use:
   * each must be among those checked. */
  static const char *const known[] = {
      "pLarge", "largestepprob", "largestepscale", "numchains", "numinitsamples",
      "roughnessthreshold", "bidirectionalMutation", "lensPerturbation",
      "multiChainPerturbation", "causticPerturbation"};
  enum { N_KNOWN = sizeof known / sizeof known[0] };
  int known_seen[N_KNOWN] = {0};
  render_settings d = render_settings_default();
  const char *path = TMP "/scene.xml";
  lmc_warn_set_quiet(1);
  for (int ti = 0; ti < nt; ti++)
    for (int i = 0; i < t[ti]->n; i++) {
      const lmc_opt *o = &t[ti]->opts[i];
      if (lmc_opt_find(t, nt, o->name, NULL) != o) continue;
      char v[128], block[1024], msg[512];
      good_value(o, defaults_of(t[ti], &d), v, sizeof v);
      render_settings want = render_settings_default(), got;
      assert_true(lmc_opt_set(t[ti], o, v, &want, msg, sizeof msg));
      static char want_buf[4096], got_buf[4096];
      const void *wv = values(t[ti], &want, want_buf);
      /* By its flag's name, and by each scene name in a <dpt>. */
      for (int form = 0;; form++) {
        const char *name = o->name;
        char alias[64];
        if (form > 0) {
          const char *p = o->scene;
          for (int k = 1; p && *p && k < form; k++) {
            p += strcspn(p, " ");
            while (*p == ' ') p++;
          }
          if (!p || !*p) break;
          snprintf(alias, sizeof alias, "%.*s", (int)strcspn(p, " "), p);
          name = alias;
          aliases++;
          for (int k = 0; k < N_KNOWN; k++) known_seen[k] += !strcmp(alias, known[k]);
        }
        snprintf(block, sizeof block,
                 form ? "  <dpt><string name=\"integrator\" value=\"mcmc\"/><string name=\"%s\" value=\"%s\"/></dpt>"
                      : "  <integrator type=\"lmc\"><string name=\"%s\" value=\"%s\"/></integrator>",
                 name, v);
        write_scene(path, block);
        lmc_error err;
        if (scene_settings(path, &got, &err) != LMC_OK) fail_msg("%s = %s: %s", name, v, err.msg);
        const void *gv = values(t[ti], &got, got_buf);
        if (memcmp((const char *)gv + o->offset, (const char *)wv + o->offset, field_size(o)))
          fail_msg("scene parameter %s = %s does not set --%s's field", name, v, o->name);
        if (!t[ti]->defaults) assert_true((got.set & o->set_bit) == o->set_bit);
        checks++;
      }
      /* A bad value: file, line and name. */
      bad_value(o, 1, v, sizeof v);
      snprintf(block, sizeof block,
               "  <integrator type=\"lmc\">\n    <string name=\"%s\" value=\"%s\"/></integrator>",
               o->name, v);
      write_scene(path, block);
      lmc_error err;
      assert_int_equal(scene_settings(path, &got, &err), LMC_EPARSE);
      assert_int_equal(err.line, 3);
      assert_non_null(strstr(err.file, "scene.xml"));
      if (!strstr(err.msg, o->name)) fail_msg("message does not name %s: %s", o->name, err.msg);
      checks++;
      flags++;
    }
  /* <boolean> on an on/off flag, and an unknown parameter. */
  render_settings got;
  lmc_error err;
  write_scene(path, "  <integrator type=\"lmc\"><boolean name=\"delayed\" value=\"true\"/>"
                    "<boolean name=\"cache-drift\" value=\"false\"/></integrator>");
  assert_int_equal(scene_settings(path, &got, &err), LMC_OK);
  const lmc_opt_table *lt = mc_method_find("lmc")->opts;
  lmc_settings ls;
  assert_int_equal(lmc_opt_read(lt, &got, &ls, &err), LMC_OK);
  assert_int_equal(ls.delayed, 1);
  assert_int_equal(ls.cache_no_drift, 1);
  int w0 = lmc_warning_count();
  write_scene(path, "  <integrator type=\"lmc\"><float name=\"no-such-flag\" value=\"1\"/></integrator>");
  assert_int_equal(scene_settings(path, &got, &err), LMC_OK);
  assert_int_equal(lmc_warning_count() - w0, 1);
  lmc_warn_set_quiet(0);
  fprintf(stderr, "  %d flags, %d scene names besides them, %d checks\n", flags, aliases, checks);
  assert_int_equal(flags, tc.names);
  assert_int_equal(aliases, tc.aliases);
  for (int k = 0; k < N_KNOWN; k++)
    if (known_seen[k] != 1) fail_msg("scene name %s checked %d times, not once", known[k], known_seen[k]);
  assert_int_equal(checks, 2 * flags + aliases);
}

#define FLAGS_BEGIN "<!-- flags: lmc render --help-markdown -->\n"
#define FLAGS_END "<!-- /flags -->"

static void test_flags_doc(void **state) {
  (void)state;
  mkdir(TMP, 0755);
  assert_int_equal(run_lmc("render --help-markdown"), 0);
  static char doc[1 << 17];
  slurp_text(LMC_SOURCE_DIR "/docs/flags.md", doc, sizeof doc);
  const char *begin = strstr(doc, FLAGS_BEGIN);
  const char *end = strstr(doc, FLAGS_END);
  assert_non_null(begin);
  assert_non_null(end);
  begin += strlen(FLAGS_BEGIN);
  assert_true(begin <= end);
  size_t n = (size_t)(end - begin);
  if (n != strlen(out_text) || memcmp(begin, out_text, n))
    fail_msg("docs/flags.md's flag tables differ from `lmc render --help-markdown`:\n%s", out_text);
  /* Every table's title, then every flag's row under it, in order. */
  const lmc_opt_table *t[MAX_TABLES];
  int nt = tables(t), rows = 0;
  table_counts tc = count_tables();
  const char *at = out_text;
  for (int ti = 0; ti < nt; ti++) {
    char title[256];
    snprintf(title, sizeof title, "%s:\n\n| flag |", t[ti]->title);
    at = strstr(at, title);
    if (!at) fail_msg("no table titled \"%s\" (or out of order)", t[ti]->title);
    const char *section_end = at + strlen(at);
    if (ti + 1 < nt) {
      snprintf(title, sizeof title, "%s:\n\n| flag |", t[ti + 1]->title);
      const char *next = strstr(at, title);
      if (next) section_end = next;
    }
    for (int i = 0; i < t[ti]->n; i++) {
      const char *name = t[ti]->opts[i].name;
      char row[96];
      snprintf(row, sizeof row, "\n| `--%s", name);
      const char *p = at;
      while ((p = strstr(p, row)) != NULL && p[strlen(row)] != ' ' && p[strlen(row)] != '`') p++;
      if (!p || p >= section_end) fail_msg("no row for --%s in \"%s\" (or out of order)", name, t[ti]->title);
      at = p + 1;
      rows++;
    }
  }
  assert_int_equal(rows, tc.rows);
  /* No other row: the page's rows are the tables' rows. */
  int page_rows = 0;
  for (const char *p = out_text; (p = strstr(p, "\n| `")) != NULL; p++) page_rows++;
  assert_int_equal(page_rows, tc.rows);
  /* The README links the page. */
  static char readme[1 << 17];
  slurp_text(LMC_SOURCE_DIR "/README.md", readme, sizeof readme);
  assert_non_null(strstr(readme, "](docs/flags.md)"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_parse),
      cmocka_unit_test(test_binary),
      cmocka_unit_test(test_flags_doc),
      cmocka_unit_test(test_scene),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
