/*
 * test_loader.c: the Mitsuba XML scene loader (src/render/io/scene_xml*.c).
 *
 *  - malformed inputs: a table of small scenes written to /tmp, each of
 *    which must fail with the right status, naming the right file and line
 *    (among them bad <spectrum> pairs, intents and files, and bad
 *    <blackbody> temperatures);
 *  - warnings: unsupported things load, but each produces one warning
 *    (counted with lmc_warning_count);
 *  - spectra: <spectrum> (one value, three, wavelength:value pairs, a
 *    file) and <blackbody> load as Mitsuba 0.6 in RGB mode loads them, the
 *    same for reflectances and emitters; errors in a spectrum file name
 *    that file and line;
 *  - the happy path: tests/data/loader/happy.xml has every shape type,
 *    every BSDF, textures, an <include>, <default>s and emitters; its counts
 *    and values are checked, with and without a -D override;
 *  - the LMC reference scene (../shared/scenes/torus, skipped when absent).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "lmc/mcmc.h"
#include "render/io/io.h"
#include "render/sampler.h"
#include "render/spectrum.h"

#define DATA "data/loader/"

static void write_text(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
}

static int near(double a, double b, double tol) { return fabs(a - b) <= tol; }

/* Loads path with warnings silenced; *OUT_warnings: how many it raised.
 * Prints the error when the load fails. */
static lmc_status load_quiet(const char *path, scene **OUT_s, int *OUT_warnings) {
  lmc_warn_set_quiet(1);
  int before = lmc_warning_count();
  lmc_error err;
  lmc_error_clear(&err);
  *OUT_s = NULL;
  lmc_status st = scene_load_xml(path, NULL, 0, OUT_s, &err);
  *OUT_warnings = lmc_warning_count() - before;
  lmc_warn_set_quiet(0);
  if (st != LMC_OK) print_error("%s:%d: %s\n", err.file, err.line, err.msg);
  return st;
}

/* Writes `xml` to `path` and loads it with load_quiet; case i of a table,
 * whose load must succeed. */
static scene *load_case_ok(const char *path, const char *xml, size_t i, int *OUT_warnings) {
  write_text(path, xml);
  scene *s;
  lmc_status st = load_quiet(path, &s, OUT_warnings);
  if (st != LMC_OK) print_error("case %zu\n", i);
  assert_int_equal(st, LMC_OK);
  return s;
}

/* ---- Malformed inputs. -------------------------------------------------- */

typedef struct bad_case {
  const char *name;   /* file /tmp/lmc_loader_<name>.xml */
  const char *xml;
  lmc_status status;
  const char *file;   /* substring of err.file */
  int line;           /* expected err.line */
  const char *needle; /* substring of the message */
} bad_case;

#define HEAD "<?xml version=\"1.0\"?>\n<scene version=\"0.5.0\">\n" /* lines 1-2 */
#define SENSOR                                                         \
  "  <sensor type=\"perspective\">\n  <float name=\"fov\" value=\"40\"/>\n" \
  "  </sensor>\n" /* 3 lines */

static const bad_case bad_cases[] = {
    {"unclosed", HEAD "  <sensor type=\"perspective\">\n"  /* 3 */
                      "    <float name=\"fov\" value=\"40\"/>\n" /* 4 */
                      "  <shape type=\"cube\"/>\n"          /* 5 */
                      "</scene>\n",                         /* 6: mismatched tag */
     LMC_EPARSE, "lmc_loader_unclosed.xml", 6, "malformed XML"},
    {"badfloat", HEAD "  <sensor type=\"perspective\">\n" /* 3 */
                      "    <float name=\"fov\" value=\"1.2.3\"/>\n" /* 4 */
                      "  </sensor>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_badfloat.xml", 4, "1.2.3"},
    {"notnumber", HEAD "  <sensor type=\"perspective\">\n" /* 3 */
                       "    <float name=\"fov\" value=\"abc\"/>\n" /* 4 */
                       "  </sensor>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_notnumber.xml", 4, "abc"},
    {"wrongtype", HEAD "  <sensor type=\"perspective\">\n" /* 3 */
                       "    <string name=\"fov\" value=\"40\"/>\n" /* 4 */
                       "  </sensor>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_wrongtype.xml", 4, "fov"},
    {"badref", HEAD SENSOR /* 3-5 */
                    "  <shape type=\"cube\">\n" /* 6 */
                    "    <ref id=\"nope\"/>\n"   /* 7 */
                    "  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_badref.xml", 7, "nope"},
    {"nomesh", HEAD SENSOR /* 3-5 */
                    "  <shape type=\"obj\">\n" /* 6 */
                    "    <string name=\"filename\" value=\"lmc_nonexistent_mesh.obj\"/>\n" /* 7 */
                    "  </shape>\n</scene>\n",
     LMC_EIO, "lmc_loader_nomesh.xml", 7, "lmc_nonexistent_mesh.obj"},
    {"notexture", HEAD SENSOR /* 3-5 */
                       "  <shape type=\"cube\">\n"           /* 6 */
                       "    <bsdf type=\"diffuse\">\n"       /* 7 */
                       "      <texture type=\"bitmap\" name=\"reflectance\">\n" /* 8 */
                       "        <string name=\"filename\" value=\"lmc_nonexistent.png\"/>\n" /* 9 */
                       "      </texture>\n    </bsdf>\n  </shape>\n</scene>\n",
     LMC_EIO, "lmc_loader_notexture.xml", 9, "lmc_nonexistent.png"},
    {"nosensor", HEAD "  <shape type=\"cube\"/>\n</scene>\n", LMC_EPARSE,
     "lmc_loader_nosensor.xml", 2, "sensor"},
    {"undefined", HEAD "  <sensor type=\"perspective\">\n" /* 3 */
                       "    <float name=\"fov\" value=\"$myfov\"/>\n" /* 4 */
                       "  </sensor>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_undefined.xml", 4, "myfov"},
    {"noinclude", HEAD SENSOR "  <include filename=\"lmc_nonexistent_inc.xml\"/>\n" /* 6 */
                              "</scene>\n",
     LMC_EIO, "lmc_loader_noinclude.xml", 6, "lmc_nonexistent_inc.xml"},
    {"duplicate", HEAD SENSOR "  <bsdf type=\"diffuse\" id=\"a\"/>\n" /* 6 */
                              "  <bsdf type=\"diffuse\" id=\"a\"/>\n" /* 7 */
                              "</scene>\n",
     LMC_EPARSE, "lmc_loader_duplicate.xml", 7, "duplicate"},
    {"noradiance", HEAD SENSOR "  <shape type=\"cube\">\n" /* 6 */
                               "    <emitter type=\"area\"/>\n" /* 7 */
                               "  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_noradiance.xml", 7, "radiance"},
    {"zeroscale", HEAD SENSOR "  <shape type=\"cube\">\n" /* 6 */
                              "    <transform name=\"toWorld\">\n" /* 7 */
                              "      <scale x=\"0\"/>\n"           /* 8 */
                              "    </transform>\n  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_zeroscale.xml", 8, "scale"},
    {"badmatrix", HEAD SENSOR "  <shape type=\"cube\">\n" /* 6 */
                              "    <transform name=\"toWorld\">\n" /* 7 */
                              "      <matrix value=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 0\"/>\n" /* 8 */
                              "    </transform>\n  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_badmatrix.xml", 8, "16 numbers"},
    {"badroot", "<?xml version=\"1.0\"?>\n<scenery/>\n", LMC_EPARSE, "lmc_loader_badroot.xml", 2,
     "scene"},
    {"refnottex", HEAD SENSOR "  <bsdf type=\"diffuse\" id=\"b\"/>\n" /* 6 */
                              "  <bsdf type=\"diffuse\">\n"          /* 7 */
                              "    <ref name=\"reflectance\" id=\"b\"/>\n" /* 8 */
                              "  </bsdf>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_refnottex.xml", 8, "texture"},
    /* Sampled spectra, black bodies (Mitsuba 0.6's <spectrum>, <blackbody>). */
    {"spec_unsorted", HEAD SENSOR "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n" /* 6-7 */
                   "      <spectrum name=\"reflectance\" value=\"500:0.1, 400:0.2\"/>\n" /* 8 */
                   "    </bsdf>\n  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_spec_unsorted.xml", 8, "increase"},
    {"spec_negative", HEAD SENSOR "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n" /* 6-7 */
                   "      <spectrum name=\"reflectance\" value=\"-5:0.1, 400:0.2\"/>\n" /* 8 */
                   "    </bsdf>\n  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_spec_negative.xml", 8, "negative wavelength"},
    {"spec_nan", HEAD SENSOR "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n" /* 6-7 */
                   "      <spectrum name=\"reflectance\" value=\"400:nan, 500:0.2\"/>\n" /* 8 */
                   "    </bsdf>\n  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_spec_nan.xml", 8, "'400:nan' is not a wavelength:value pair"},
    {"spec_malformed", HEAD SENSOR "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n" /* 6-7 */
                   "      <spectrum name=\"reflectance\" value=\"400:0.1, 500\"/>\n" /* 8 */
                   "    </bsdf>\n  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_spec_malformed.xml", 8, "'500' is not a wavelength:value pair"},
    {"spec_onepair", HEAD SENSOR "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n" /* 6-7 */
                   "      <spectrum name=\"reflectance\" value=\"500:0.1\"/>\n" /* 8 */
                   "    </bsdf>\n  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_spec_onepair.xml", 8, "two"},
    {"spec_both", HEAD SENSOR "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n" /* 6-7 */
                   "      <spectrum name=\"reflectance\" value=\"0.5\" filename=\"a.spd\"/>\n" /* 8 */
                   "    </bsdf>\n  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_spec_both.xml", 8, "one of"},
    {"spec_intent", HEAD SENSOR "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n" /* 6-7 */
                   "      <spectrum name=\"reflectance\" value=\"0.5\" intent=\"glow\"/>\n" /* 8 */
                   "    </bsdf>\n  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_spec_intent.xml", 8, "intent"},
    {"spec_intentpairs", HEAD SENSOR "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n" /* 6-7 */
                   "      <spectrum name=\"reflectance\" value=\"400:1, 500:1\" intent=\"reflectance\"/>\n" /* 8 */
                   "    </bsdf>\n  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_spec_intentpairs.xml", 8, "single value"},
    {"bb_notemp", HEAD SENSOR "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n" /* 6-7 */
                   "      <blackbody name=\"reflectance\"/>\n" /* 8 */
                   "    </bsdf>\n  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_bb_notemp.xml", 8, "temperature"},
    {"bb_badtemp", HEAD SENSOR "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n" /* 6-7 */
                   "      <blackbody name=\"reflectance\" temperature=\"-300K\"/>\n" /* 8 */
                   "    </bsdf>\n  </shape>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_bb_badtemp.xml", 8, "temperature"},
    {"spec_nofile", HEAD SENSOR "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n" /* 6-7 */
                   "      <spectrum name=\"reflectance\" filename=\"lmc_nonexistent.spd\"/>\n" /* 8 */
                   "    </bsdf>\n  </shape>\n</scene>\n",
     LMC_EIO, "lmc_loader_spec_nofile.xml", 8, "lmc_nonexistent.spd"},
};

static void test_malformed(void **state) {
  (void)state;
  lmc_warn_set_quiet(1);
  int n = (int)(sizeof bad_cases / sizeof bad_cases[0]), ok = 0;
  for (int i = 0; i < n; i++) {
    const bad_case *c = &bad_cases[i];
    char path[256];
    snprintf(path, sizeof path, "/tmp/lmc_loader_%s.xml", c->name);
    write_text(path, c->xml);
    scene *s = (scene *)1;
    lmc_error err;
    lmc_error_clear(&err);
    lmc_status st = scene_load_xml(path, NULL, 0, &s, &err);
    char text[2048];
    lmc_error_format(&err, text, sizeof text);
    int good = st == c->status && s == NULL && strstr(err.file, c->file) != NULL &&
               err.line == c->line && strstr(err.msg, c->needle) != NULL;
    if (!good)
      print_error("case %s: status %d (want %d), line %d (want %d): %s\n", c->name, (int)st,
                  (int)c->status, err.line, c->line, text);
    ok += good;
    scene_destroy(s);
  }
  lmc_warn_set_quiet(0);
  assert_int_equal(ok, n);
}

/* An error inside an included file names that file and its line. */
static void test_error_in_include(void **state) {
  (void)state;
  write_text("/tmp/lmc_loader_inner.xml",
             "<scene version=\"0.5.0\">\n"
             "  <bsdf type=\"diffuse\">\n"
             "    <float name=\"reflectance\" value=\"x1\"/>\n" /* 3 */
             "  </bsdf>\n</scene>\n");
  write_text("/tmp/lmc_loader_outer.xml", HEAD SENSOR "  <include filename=\"lmc_loader_inner.xml\"/>\n"
                                          "</scene>\n");
  scene *s = NULL;
  lmc_error err;
  lmc_error_clear(&err);
  assert_int_equal(scene_load_xml("/tmp/lmc_loader_outer.xml", NULL, 0, &s, &err), LMC_EPARSE);
  assert_null(s);
  assert_non_null(strstr(err.file, "lmc_loader_inner.xml"));
  assert_int_equal(err.line, 3);
}

/* ---- Warnings. ---------------------------------------------------------- */

static void test_warnings(void **state) {
  (void)state;
  write_text("/tmp/lmc_loader_warn.xml",
             HEAD SENSOR
             "  <medium type=\"homogeneous\" id=\"fog\"/>\n"               /* 1: element */
             "  <bsdf type=\"weirdbsdf\" id=\"w\"/>\n"                     /* 2: plugin type */
             "  <shape type=\"cube\">\n"
             "    <bsdf type=\"diffuse\">\n"
             "      <float name=\"bogus\" value=\"1\"/>\n"                 /* 3: property */
             "    </bsdf>\n"
             "  </shape>\n"
             "  <shape type=\"cube\">\n"
             "    <bsdf type=\"diffuse\">\n"
             "      <texture type=\"wireframe\" name=\"reflectance\"/>\n"  /* 4: texture */
             "    </bsdf>\n"
             "  </shape>\n"
             "  <shape type=\"hair\"/>\n"                                   /* 5: shape type */
             "</scene>\n");
  scene *s;
  int warnings;
  lmc_status st = load_quiet("/tmp/lmc_loader_warn.xml", &s, &warnings);
  assert_int_equal(st, LMC_OK);
  assert_non_null(s);
  assert_int_equal(warnings, 5);
  /* Two cubes loaded, the hair skipped; the unknown BSDF became diffuse 0.5. */
  assert_int_equal(s->n_meshes, 2);
  int found = 0;
  for (int i = 0; i < s->n_bsdfs; i++)
    if (strcmp(s->bsdfs[i].id, "w") == 0) {
      found = 1;
      assert_int_equal(s->bsdfs[i].type, BSDF_DIFFUSE);
      assert_true(near(s->bsdfs[i].diffuse.value.g, 0.5, 1e-12));
    }
  assert_true(found);
  scene_destroy(s);
}

/* ---- Spectra. ------------------------------------------------------------ */

static const bsdf *find_bsdf(const scene *s, const char *id);

/* <spectrum> and <blackbody> as Mitsuba 0.6 in RGB mode loads them: one
 * number is that grey (reflectance and emitter alike, with or without an
 * intent); three are RGB; pairs, and the same pairs in a file (a third
 * column ignored, as by Mitsuba), go through the CIE 1931 functions after
 * Mitsuba's zero extension, the same for a reflectance and an emitter; a
 * black body is Planck's law times scale. */
static void test_spectra(void **state) {
  (void)state;
  write_text("/tmp/lmc_loader_spec.spd", "# wavelength (nm)  value  (error)\n\n400 0.2 0.01\n  700 0.2 # end\n");
  static const char *const bsdfs[][2] = {
      {"pairs", "value=\"400:0.2, 700:0.2\""},
      {"padded", "value=\"100:0, 400:0.2, 700:0.2, 1000:0\""},
      {"flat", "value=\"360:0.2, 830:0.2\""},
      {"const", "value=\"0.5\""},
      {"constintent", "value=\"0.5\" intent=\"Illuminant\""},
      {"three", "value=\"0.1, 0.2, 0.3\""},
      {"file", "filename=\"lmc_loader_spec.spd\""},
  };
  char xml[8192];
  int len = snprintf(xml, sizeof xml, HEAD SENSOR);
  for (size_t i = 0; i < sizeof bsdfs / sizeof bsdfs[0]; i++)
    len += snprintf(xml + len, sizeof xml - (size_t)len,
                    "  <bsdf type=\"diffuse\" id=\"%s\"><spectrum name=\"reflectance\" %s/></bsdf>\n",
                    bsdfs[i][0], bsdfs[i][1]);
  static const char *const lights[] = {
      "<spectrum name=\"intensity\" value=\"0.5\"/>",
      "<spectrum name=\"intensity\" value=\"400:0.2, 700:0.2\"/>",
      "<blackbody name=\"intensity\" temperature=\"2856K\" scale=\"3\"/>",
  };
  for (size_t i = 0; i < sizeof lights / sizeof lights[0]; i++)
    len += snprintf(xml + len, sizeof xml - (size_t)len,
                    "  <emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"0\" "
                    "z=\"4\"/>%s</emitter>\n",
                    lights[i]);
  snprintf(xml + len, sizeof xml - (size_t)len, "  <shape type=\"cube\"/>\n</scene>\n");
  int warnings, checks = 0;
  scene *s = load_case_ok("/tmp/lmc_loader_spectra.xml", xml, 0, &warnings);
  assert_int_equal(warnings, 0);
  checks++;
  rgb pairs = find_bsdf(s, "pairs")->diffuse.value;
  /* Zero extension: the pairs as if written with zeros 300 nm beyond. */
  assert_memory_equal(&pairs, &find_bsdf(s, "padded")->diffuse.value, sizeof pairs);
  /* The file holds the same pairs. */
  assert_memory_equal(&pairs, &find_bsdf(s, "file")->diffuse.value, sizeof pairs);
  /* 0.2 over 360-830 nm: 0.2 times illuminant E in sRGB (IEC matrix on the
   * CIE sums 106.865, 106.857, 106.892 of xbar, ybar, zbar), not grey. */
  rgb flat = find_bsdf(s, "flat")->diffuse.value;
  assert_true(near(flat.r, 0.2 * 1.2049, 2e-4) && near(flat.g, 0.2 * 0.9483, 2e-4) &&
              near(flat.b, 0.2 * 0.9091, 2e-4));
  checks += 3;
  rgb c = find_bsdf(s, "const")->diffuse.value, ci = find_bsdf(s, "constintent")->diffuse.value;
  rgb three = find_bsdf(s, "three")->diffuse.value;
  assert_true(c.r == 0.5 && c.g == 0.5 && c.b == 0.5);
  assert_true(ci.r == 0.5 && ci.g == 0.5 && ci.b == 0.5);
  assert_true(three.r == 0.1 && three.g == 0.2 && three.b == 0.3);
  checks += 3;
  /* Emitters: the same conversions as reflectances. */
  assert_int_equal(s->n_lights, 3);
  rgb l0 = s->lights[0].value, l1 = s->lights[1].value, l2 = s->lights[2].value;
  assert_true(l0.r == 0.5 && l0.g == 0.5 && l0.b == 0.5);
  assert_memory_equal(&l1, &pairs, sizeof pairs);
  rgb bb = spectrum_blackbody_rgb(2856.0, 3.0);
  assert_true(near(l2.r, bb.r, 1e-12 * bb.r) && near(l2.g, bb.g, 1e-12 * bb.g) &&
              near(l2.b, bb.b, 1e-12 * bb.b));
  checks += 4;
  scene_destroy(s);
  assert_int_equal(checks, 11);
}

/* A bad line in a spectrum file names that file and its line. */
static void test_spectrum_file_errors(void **state) {
  (void)state;
  static const struct {
    const char *text;
    int line;
    const char *needle;
  } cases[] = {
      {"# measured\n400 0.2\n\n500 x\n", 4, "wavelength value"},
      {"400 0.2\n300 0.1\n", 2, "increase"},
      {"400\n500 0.1\n", 1, "wavelength value"},
      {"400 0.2\n500 0.1x\n", 2, "wavelength value"},
      {"400 0.2\n-500 0.1\n", 2, "negative"},
      {"# nothing\n", 1, "two lines"},
  };
  int ok = 0;
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    write_text("/tmp/lmc_loader_badspec.spd", cases[i].text);
    write_text("/tmp/lmc_loader_badspec.xml",
               HEAD SENSOR "  <bsdf type=\"diffuse\">\n"
                           "    <spectrum name=\"reflectance\" filename=\"lmc_loader_badspec.spd\"/>\n"
                           "  </bsdf>\n</scene>\n");
    scene *s = NULL;
    lmc_error err;
    lmc_error_clear(&err);
    lmc_status st = scene_load_xml("/tmp/lmc_loader_badspec.xml", NULL, 0, &s, &err);
    int good = st == LMC_EPARSE && s == NULL && strstr(err.file, "lmc_loader_badspec.spd") &&
               err.line == cases[i].line && strstr(err.msg, cases[i].needle);
    if (!good)
      print_error("case %zu: status %d, %s:%d: %s\n", i, (int)st, err.file, err.line, err.msg);
    ok += good;
    scene_destroy(s);
  }
  assert_int_equal(ok, 6);
}

/* ---- The happy path. ---------------------------------------------------- */

static const bsdf *find_bsdf(const scene *s, const char *id) {
  for (int i = 0; i < s->n_bsdfs; i++)
    if (strcmp(s->bsdfs[i].id, id) == 0) return &s->bsdfs[i];
  print_error("no bsdf with id %s\n", id);
  fail();
  return NULL;
}

static int find_light(const scene *s, light_type t) {
  for (int i = 0; i < s->n_lights; i++)
    if (s->lights[i].type == t) return i;
  print_error("no light of type %d\n", (int)t);
  fail();
  return -1;
}

/* The bitmap texture of happy.xml: a 4x4 grey ramp written at run time (no
 * image in the repository), passed in with -D texfile=... */
#define TEXFILE "/tmp/lmc_loader_tex.png"
static const char *happy_defs[] = {"texfile=" TEXFILE};

static int write_texture(void **state) {
  (void)state;
  lmc_image img;
  lmc_error err;
  if (image_init(&img, 4, 4, 3, &err)) return -1;
  for (int i = 0; i < 4 * 4 * 3; i++) img.data[i] = (float)(i % 12) / 12.0f;
  lmc_status st = image_write_png(TEXFILE, &img, 1.0, &err);
  image_free(&img);
  return st == LMC_OK ? 0 : -1;
}

/* Mitsuba's directSamples / separateDirect on an MLT integrator map to
 * --direct: absent, the default (separate, the scene's spp); N >= 1:
 * separate with N samples per pixel for pt's pass; -1: MLT renders every
 * path; 0 (Mitsuba hides direct light) is a warning and renders it
 * separately; separateDirect false: MLT renders every path. */
static void test_direct_samples(void **state) {
  (void)state;
  static const struct {
    const char *prop;   /* the integrator's property, or "" */
    const char *direct; /* --direct as passed on (NULL: not given) */
    const char *spp;    /* --direct-spp as passed on (NULL: not given) */
    int warnings;
  } cases[] = {
      {"", NULL, NULL, 0},
      {"<integer name=\"directSamples\" value=\"32\"/>", "separate", "32", 0},
      {"<integer name=\"directSamples\" value=\"-1\"/>", "mcmc", NULL, 0},
      {"<integer name=\"directSamples\" value=\"0\"/>", "separate", "0", 1},
      {"<boolean name=\"separateDirect\" value=\"false\"/>", "mcmc", NULL, 0},
  };
  int checked = 0;
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char xml[1024];
    snprintf(xml, sizeof xml,
             HEAD "  <integrator type=\"pssmlt\">%s</integrator>\n" SENSOR
             "  <shape type=\"cube\"/>\n</scene>\n",
             cases[i].prop);
    int warnings;
    scene *s = load_case_ok("/tmp/lmc_loader_direct.xml", xml, i, &warnings);
    render_settings rs;
    lmc_error err;
    assert_int_equal(mcmc_scene_settings(s, &rs, &err), LMC_OK);
    const char *direct = lmc_opt_value(&rs, "direct"), *spp = lmc_opt_value(&rs, "direct-spp");
    assert_true(cases[i].direct ? direct && !strcmp(direct, cases[i].direct) : !direct);
    assert_true(cases[i].spp ? spp && !strcmp(spp, cases[i].spp) : !spp);
    assert_int_equal(warnings, cases[i].warnings);
    scene_destroy(s);
    checked++;
  }
  assert_int_equal(checked, 5);
}

/* <lookAt>, Mitsuba 0.6's other spelling of <lookat>: the same camera,
 * its pinhole at the origin given and the matrix the same to the bit. */
static void test_lookat_spelling(void **state) {
  (void)state;
  static const char *const tags[2] = {"lookat", "lookAt"};
  scene *s[2];
  for (int k = 0; k < 2; k++) {
    char xml[1024];
    snprintf(xml, sizeof xml,
             HEAD "  <sensor type=\"perspective\">\n  <float name=\"fov\" value=\"40\"/>\n"
                  "  <transform name=\"toWorld\"><%s origin=\"1, 2, 3\" target=\"0, 0, 0\" "
                  "up=\"0, 1, 0\"/></transform>\n  </sensor>\n"
                  "  <shape type=\"cube\"/>\n</scene>\n",
             tags[k]);
    int warnings;
    s[k] = load_case_ok("/tmp/lmc_loader_lookat.xml", xml, (size_t)k, &warnings);
    assert_int_equal(warnings, 0);
    assert_true(near(s[k]->cam.pos.x, 1.0, 1e-12) && near(s[k]->cam.pos.y, 2.0, 1e-12) &&
                near(s[k]->cam.pos.z, 3.0, 1e-12));
  }
  assert_memory_equal(&s[0]->cam.to_world, &s[1]->cam.to_world, sizeof s[0]->cam.to_world);
  scene_destroy(s[0]);
  scene_destroy(s[1]);
}

/* <sampler type>: independent and Mitsuba's ldsampler/sobol map without a
 * word, the other stratifying samplers to sobol with a warning, an unknown
 * one to independent with a warning; no <sampler>: independent. */
static void test_sampler_type(void **state) {
  (void)state;
  static const struct {
    const char *type; /* "" for no <sampler> */
    int sampler, warnings;
  } cases[] = {
      {"", LMC_SAMPLER_INDEPENDENT, 0},           {"independent", LMC_SAMPLER_INDEPENDENT, 0},
      {"ldsampler", LMC_SAMPLER_SOBOL, 0},        {"sobol", LMC_SAMPLER_SOBOL, 0},
      {"stratified", LMC_SAMPLER_SOBOL, 1},       {"halton", LMC_SAMPLER_SOBOL, 1},
      {"hammersley", LMC_SAMPLER_SOBOL, 1},       {"magic", LMC_SAMPLER_INDEPENDENT, 1},
  };
  int checked = 0;
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char smp[256] = "", xml[1024];
    if (cases[i].type[0])
      snprintf(smp, sizeof smp,
               "<sampler type=\"%s\"><integer name=\"sampleCount\" value=\"8\"/></sampler>",
               cases[i].type);
    snprintf(xml, sizeof xml,
             HEAD "  <sensor type=\"perspective\">%s</sensor>\n"
                  "  <shape type=\"cube\"/>\n</scene>\n",
             smp);
    int warnings;
    scene *s = load_case_ok("/tmp/lmc_loader_sampler.xml", xml, i, &warnings);
    assert_int_equal(s->settings.sampler, cases[i].sampler);
    assert_int_equal(warnings, cases[i].warnings);
    if (cases[i].type[0]) assert_int_equal(s->settings.spp, 8);
    scene_destroy(s);
    checked++;
  }
  assert_int_equal(checked, 8);
}

static void test_happy(void **state) {
  (void)state;
  scene *s = NULL;
  lmc_error err;
  lmc_error_clear(&err);
  int before = lmc_warning_count();
  lmc_status st = scene_load_xml(DATA "happy.xml", happy_defs, 1, &s, &err);
  if (st != LMC_OK) print_error("%s:%d: %s\n", err.file, err.line, err.msg);
  assert_int_equal(st, LMC_OK);
  assert_int_equal(lmc_warning_count() - before, 0);
  assert_true(s->finalized);

  /* Counts: 9 shapes; 7 top-level BSDFs + the included one + the default. */
  assert_int_equal(s->n_meshes, 9);
  assert_int_equal(s->n_bsdfs, 9);
  assert_int_equal(s->n_lights, 6);
  assert_int_equal(s->n_images, 1);
  assert_int_equal(s->n_infinite, 2);

  /* Sensor, film and filter; the default fov (45) and width (64). */
  assert_int_equal(s->cam.width, 64);
  assert_int_equal(s->cam.height, 48);
  assert_true(near(s->cam.fov_deg, 45.0, 1e-12));
  assert_string_equal(s->cam.fov_axis, "y");
  assert_true(near(s->cam.tan_half_y, tan(22.5 * 3.14159265358979323846 / 180.0), 1e-12));
  assert_true(near(s->cam.near_clip, 0.1, 1e-15) && near(s->cam.far_clip, 500.0, 1e-12));
  assert_true(near(s->cam.pos.z, 10.0, 1e-12) && near(s->cam.forward.z, -1.0, 1e-12));
  assert_int_equal(s->filter.type, FILTER_TENT);

  /* Settings: pssmlt with its own maxDepth; rrDepth from the nested path;
   * pLarge passed on to the option tables (the --largestep flag's). */
  render_settings rset;
  assert_int_equal(mcmc_scene_settings(s, &rset, &err), LMC_OK);
  const render_settings *r = &rset;
  assert_string_equal(r->integrator, "pssmlt");
  assert_int_equal(r->maxdepth, 7);
  assert_int_equal(r->rrdepth, 3);
  const char *large = lmc_opt_value(r, "largestep");
  assert_non_null(large);
  assert_true(near(strtod(large, NULL), 0.25, 1e-15));
  assert_int_equal((int)r->spp, 32);
  unsigned want = SET_INTEGRATOR | SET_MAXDEPTH | SET_RRDEPTH | SET_SPP;
  assert_int_equal(r->set, want);

  /* BSDFs. */
  const bsdf *d = find_bsdf(s, "d");
  assert_int_equal(d->type, BSDF_DIFFUSE);
  assert_int_equal(d->diffuse.type, TEX_BITMAP);
  assert_ptr_equal(d->diffuse.image, &s->images[0]);
  assert_int_equal(s->images[0].channels, 3);
  assert_true(near(d->diffuse.uscale, 2.0, 0) && near(d->diffuse.vscale, 1.0, 0));
  assert_true(near(d->diffuse.voffset, 0.5, 0));
  const bsdf *ph = find_bsdf(s, "ph");
  assert_int_equal(ph->type, BSDF_PHONG);
  assert_true(near(ph->exponent, 40.0, 0));
  assert_true(near(ph->specular.value.r, 0.3, 1e-15));
  assert_int_equal(ph->diffuse.type, TEX_CHECKERBOARD);
  assert_true(near(ph->diffuse.color0.r, 0.4, 1e-15) && near(ph->diffuse.color1.r, 0.2, 1e-15));
  assert_true(near(ph->diffuse.uscale, 3.0, 0));
  const bsdf *rc = find_bsdf(s, "rc");
  assert_int_equal(rc->type, BSDF_ROUGHCONDUCTOR);
  assert_int_equal(rc->dist, MF_GGX);
  assert_true(near(rc->alpha, 0.2, 1e-15));
  assert_true(near(rc->cond_eta.r, 0.1, 1e-15) && near(rc->cond_eta.b, 0.55, 1e-15));
  assert_true(near(rc->cond_k.g, 1.25, 1e-15));
  assert_int_equal(rc->specular.type, TEX_CHECKERBOARD);
  assert_true(near(rc->specular.color0.r, 0.9, 1e-15) && near(rc->specular.uscale, 4.0, 0));
  const bsdf *gl = find_bsdf(s, "gl");
  double water = 0.0;
  assert_true(ior_lookup("water", &water));
  assert_int_equal(gl->type, BSDF_DIELECTRIC);
  assert_true(near(gl->eta, water, 1e-12));
  const bsdf *rg = find_bsdf(s, "rg");
  assert_int_equal(rg->type, BSDF_ROUGHDIELECTRIC);
  assert_int_equal(rg->dist, MF_BECKMANN);
  assert_true(near(rg->eta, 1.2, 1e-12) && near(rg->alpha, 0.3, 1e-15));
  assert_int_equal(rg->sample_visible, 0);
  const bsdf *pl = find_bsdf(s, "pl");
  assert_int_equal(pl->type, BSDF_PLASTIC);
  assert_true(near(pl->eta, 1.5, 1e-15));
  assert_int_equal(pl->nonlinear, 1);
  /* sRGB 128/255 decodes to 0.2158605. */
  assert_true(near(pl->diffuse.value.g, 0.2158605, 1e-6));
  const bsdf *ts = find_bsdf(s, "ts");
  assert_int_equal(ts->type, BSDF_DIFFUSE);
  assert_int_equal(ts->twosided, 1);
  assert_true(near(ts->diffuse.value.b, 0.6, 1e-15));
  const bsdf *incl = find_bsdf(s, "incl");
  rgb au_eta, au_k;
  assert_true(conductor_lookup("Au", &au_eta, &au_k));
  assert_int_equal(incl->type, BSDF_CONDUCTOR);
  assert_true(near(incl->cond_eta.r, au_eta.r, 1e-12) && near(incl->cond_k.b, au_k.b, 1e-12));

  /* Shapes: names, flags, transforms, default BSDF, the area light. */
  int checked = 0;
  for (int i = 0; i < s->n_meshes; i++) {
    const mesh *m = &s->meshes[i];
    const bsdf *b = &s->bsdfs[m->bsdf];
    if (strcmp(m->name, "the_obj") == 0) {
      /* Scaled by 2 then moved by x+1: the quad spans x in [1, 3]. */
      double xmin = 1e9, xmax = -1e9;
      for (int64_t v = 0; v < m->n_vertices; v++) {
        xmin = fmin(xmin, m->p[3 * v]);
        xmax = fmax(xmax, m->p[3 * v]);
      }
      assert_true(near(xmin, 1.0, 1e-6) && near(xmax, 3.0, 1e-6));
      assert_ptr_equal(b, d);
      checked++;
    } else if (strcmp(m->name, "lamp") == 0) {
      assert_true(m->light >= 0);
      const light *l = &s->lights[m->light];
      assert_int_equal(l->type, LIGHT_AREA);
      assert_int_equal(l->mesh, i);
      assert_true(near(l->value.r, 5.0, 0) && near(l->value.b, 3.0, 0));
      /* rotate x 90 maps the rectangle's +z normal to -y, then y += 3. */
      assert_true(near(mesh_face_normal(m, 0).y, -1.0, 1e-6));
      assert_true(near(m->p[1], 3.0, 1e-6));
      assert_ptr_equal(b, rc);
      checked++;
    } else if (strcmp(m->name, "plain") == 0) {
      assert_int_equal(b->type, BSDF_DIFFUSE);
      assert_true(near(b->diffuse.value.r, 0.5, 0));
      assert_int_equal(m->light, -1);
      assert_true(near(m->p[2], 7.0, 1e-6)); /* the <matrix> moved it to z = 7 */
      checked++;
    } else if (strcmp(m->name, "quad.ply") == 0) {
      assert_int_equal(m->flip_normals, 1);
      assert_ptr_equal(b, ph);
      checked++;
    } else if (b == pl) {
      assert_int_equal(m->face_normals, 1);
      checked++;
    }
  }
  assert_int_equal(checked, 5);

  /* Emitters. */
  const light *pt = &s->lights[find_light(s, LIGHT_POINT)];
  assert_true(near(pt->pos.x, 1, 0) && near(pt->pos.y, 2, 0) && near(pt->pos.z, 3, 0));
  assert_true(near(pt->value.g, 10.0, 0));
  const light *sp = &s->lights[find_light(s, LIGHT_SPOT)];
  assert_true(near(sp->pos.y, 5.0, 1e-12) && near(sp->frm.n.y, -1.0, 1e-12));
  assert_true(near(sp->cutoff, 40.0 * 3.14159265358979323846 / 180.0, 1e-12));
  assert_true(near(sp->beam_width, 30.0 * 3.14159265358979323846 / 180.0, 1e-12));
  assert_true(near(sp->cos_cutoff, cos(sp->cutoff), 1e-15));
  const light *dl = &s->lights[find_light(s, LIGHT_DIRECTIONAL)];
  assert_true(near(dl->frm.n.y, -1.0, 1e-12) && near(dl->value.r, 2.0, 0));
  const light *cl = &s->lights[find_light(s, LIGHT_CONSTANT)];
  assert_true(near(cl->value.g, 0.1, 1e-15));
  const light *el = &s->lights[find_light(s, LIGHT_ENVMAP)];
  assert_true(near(el->scale, 3.0, 0));
  assert_int_equal(el->image.width, 4);
  assert_int_equal(el->image.channels, 3);
  scene_destroy(s);
}

/* -D overrides a <default>. */
static void test_define_override(void **state) {
  (void)state;
  const char *defs[] = {"fov=30", "width=80", ("texfile=" TEXFILE)};
  scene *s = NULL;
  lmc_error err;
  lmc_error_clear(&err);
  lmc_status st = scene_load_xml(DATA "happy.xml", defs, 3, &s, &err);
  if (st != LMC_OK) print_error("%s:%d: %s\n", err.file, err.line, err.msg);
  assert_int_equal(st, LMC_OK);
  assert_true(near(s->cam.fov_deg, 30.0, 1e-12));
  assert_int_equal(s->cam.width, 80);
  scene_destroy(s);
  /* A malformed define is refused. */
  const char *bad[] = {"novalue"};
  assert_int_equal(scene_load_xml(DATA "happy.xml", bad, 1, &s, &err), LMC_EINVAL);
  assert_null(s);
}

/* ---- The LMC reference scene. ------------------------------------------- */

static void check_torus(const char *name, int h2mc) {
  char path[1024];
  snprintf(path, sizeof path, "%s/scenes/torus/%s", LMC_SHARED_DIR, name);
  FILE *f = fopen(path, "rb");
  if (!f) skip();
  fclose(f);
  scene *s = NULL;
  lmc_error err;
  lmc_error_clear(&err);
  lmc_warn_set_quiet(1);
  lmc_status st = scene_load_xml(path, NULL, 0, &s, &err);
  lmc_warn_set_quiet(0);
  if (st != LMC_OK) print_error("%s:%d: %s\n", err.file, err.line, err.msg);
  assert_int_equal(st, LMC_OK);
  assert_int_equal(s->n_meshes, 5);
  assert_int_equal(s->n_lights, 1);
  assert_int_equal(s->lights[0].type, LIGHT_ENVMAP);
  assert_true(near(s->cam.fov_deg, 34.6222, 1e-9));
  assert_int_equal(s->cam.width, 1024);
  assert_int_equal(s->cam.height, 768);
  assert_int_equal(s->filter.type, FILTER_BOX);
  assert_string_equal(s->settings.integrator, h2mc ? "h2mc" : "lmc");
  assert_int_equal(s->settings.maxdepth, 8);
  assert_int_equal(s->settings.mindepth, -1);
  assert_int_equal((int)s->settings.spp, h2mc ? 67 : 245);
  /* The floor's phong uses the checker bitmap with uvscale 100. */
  int bitmaps = 0;
  for (int i = 0; i < s->n_bsdfs; i++)
    if (s->bsdfs[i].diffuse.type == TEX_BITMAP) {
      bitmaps++;
      assert_true(near(s->bsdfs[i].diffuse.uscale, 100.0, 0));
      assert_non_null(s->bsdfs[i].diffuse.image);
    }
  assert_int_equal(bitmaps, 1);
  scene_destroy(s);
}

static void test_torus_lmc(void **state) {
  (void)state;
  check_torus("lmc.xml", 0);
}

static void test_torus_h2mc(void **state) {
  (void)state;
  check_torus("h2mc.xml", 1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_malformed),       cmocka_unit_test(test_error_in_include),
      cmocka_unit_test(test_warnings),        cmocka_unit_test(test_happy),
      cmocka_unit_test(test_define_override), cmocka_unit_test(test_torus_lmc),
      cmocka_unit_test(test_torus_h2mc),      cmocka_unit_test(test_direct_samples),
      cmocka_unit_test(test_lookat_spelling),
      cmocka_unit_test(test_sampler_type),
      cmocka_unit_test(test_spectra),
      cmocka_unit_test(test_spectrum_file_errors),
  };
  return cmocka_run_group_tests(tests, write_texture, NULL);
}
