/*
 * test_loader.c: the Mitsuba XML scene loader (src/render/io/scene_xml*.c).
 *
 *  - malformed inputs: a table of small scenes written to /tmp, each of
 *    which must fail with the right status, naming the right file and line
 *    (among them bad <spectrum> pairs, intents and files, and bad
 *    <blackbody> temperatures);
 *  - warnings: unsupported things load, but each produces one warning
 *    (counted with lmc_warning_count);
 *  - roughdiffuse and ward: Mitsuba's names, variants and defaults load
 *    without a warning; a textured roughness warns; a bad variant or a
 *    negative alpha is an error with file and line;
 *  - roughplastic and thindielectric load as themselves, without warnings,
 *    with their parameters (roughplastic's table prepared); a textured
 *    roughness warns once;
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
/* A light, so that a scene is not warned about as black. */
#define LIGHT "  <emitter type=\"constant\"/>\n"

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
    {"wardvariant", HEAD SENSOR "  <bsdf type=\"ward\">\n"                  /* 6 */
                                "    <string name=\"variant\" value=\"phong\"/>\n" /* 7 */
                                "  </bsdf>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_wardvariant.xml", 7, "ward-duer"},
    {"rdalpha", HEAD SENSOR "  <bsdf type=\"roughdiffuse\">\n"            /* 6 */
                            "    <float name=\"alpha\" value=\"-0.1\"/>\n" /* 7 */
                            "  </bsdf>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_rdalpha.xml", 6, "alpha"},
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
    {"ldr_exposure", HEAD "  <sensor type=\"perspective\">\n" /* 3 */
                     "    <film type=\"ldrfilm\">\n"           /* 4 */
                     "      <float name=\"exposure\" value=\"bright\"/>\n" /* 5 */
                     "    </film>\n  </sensor>\n</scene>\n",
     LMC_EPARSE, "lmc_loader_ldr_exposure.xml", 5, "bright"},
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
             HEAD SENSOR LIGHT
             "  <medium type=\"heterogeneous\" id=\"fog\"/>\n"             /* 1: medium type */
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
      assert_true(bsdf_is(&s->bsdfs[i], "diffuse"));
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
  rgb bb = spectrum_blackbody_rgb(2856.0, 3.0, SPECTRUM_INTERP_LINEAR);
  assert_true(near(l2.r, bb.r, 1e-12 * bb.r) && near(l2.g, bb.g, 1e-12 * bb.g) &&
              near(l2.b, bb.b, 1e-12 * bb.b));
  checks += 4;
  scene_destroy(s);
  /* --spectra mitsuba-0.6.0 (scene_load_options) reaches the conversion:
   * the pairs as spectrum_sampled_rgb reads them that way, and differing
   * from the linear reading. */
  scene_load_options opts = {SPECTRUM_INTERP_MITSUBA_060};
  lmc_error err;
  lmc_error_clear(&err);
  lmc_warn_set_quiet(1);
  assert_int_equal(scene_load_xml_opts("/tmp/lmc_loader_spectra.xml", NULL, 0, &opts, &s, &err),
                   LMC_OK);
  lmc_warn_set_quiet(0);
  double wl[6] = {400.0, 700.0}, val[6] = {0.2, 0.2};
  rgb want = spectrum_sampled_rgb(wl, val, 2, SPECTRUM_INTERP_MITSUBA_060);
  rgb got = find_bsdf(s, "pairs")->diffuse.value;
  assert_memory_equal(&got, &want, sizeof got);
  assert_true(fabs(got.r - pairs.r) > 1e-4);
  checks += 2;
  scene_destroy(s);
  assert_int_equal(checks, 13);
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

/* The BSDF with XML id `id` (the test fails when there is none). */
static const bsdf *find_bsdf(const scene *s, const char *id) {
  for (int i = 0; i < s->n_bsdfs; i++)
    if (strcmp(s->bsdfs[i].id, id) == 0) return &s->bsdfs[i];
  print_error("no bsdf with id %s\n", id);
  fail();
  return NULL;
}

/* roughplastic and thindielectric load as themselves (no fallback, no
 * warning), with their parameters and roughplastic's transmittance table
 * prepared, also inside twosided; a textured roughness warns once and
 * keeps the default. */
static void test_rough_plastic_thin(void **state) {
  (void)state;
  write_text("/tmp/lmc_loader_rp.xml",
             HEAD SENSOR LIGHT
             "  <bsdf type=\"roughplastic\" id=\"rp\">\n"
             "    <string name=\"distribution\" value=\"ggx\"/>\n"
             "    <float name=\"alpha\" value=\"0.1\"/>\n"
             "    <boolean name=\"nonlinear\" value=\"true\"/>\n"
             "    <float name=\"intIOR\" value=\"1.6\"/>\n"
             "    <rgb name=\"diffuseReflectance\" value=\"0.2, 0.4, 0.6\"/>\n"
             "    <float name=\"specularReflectance\" value=\"0.7\"/>\n"
             "    <boolean name=\"sampleVisible\" value=\"false\"/>\n"
             "  </bsdf>\n"
             "  <bsdf type=\"twosided\" id=\"rp2\">\n"
             "    <bsdf type=\"roughplastic\"/>\n"
             "  </bsdf>\n"
             "  <bsdf type=\"thindielectric\" id=\"th\">\n"
             "    <string name=\"intIOR\" value=\"water\"/>\n"
             "    <float name=\"extIOR\" value=\"1.0\"/>\n"
             "    <rgb name=\"specularTransmittance\" value=\"0.9, 0.8, 0.7\"/>\n"
             "  </bsdf>\n"
             "  <shape type=\"cube\"><ref id=\"rp\"/></shape>\n"
             "  <shape type=\"cube\"><ref id=\"rp2\"/></shape>\n"
             "  <shape type=\"cube\"><ref id=\"th\"/></shape>\n"
             "</scene>\n");
  scene *s;
  int warnings;
  assert_int_equal(load_quiet("/tmp/lmc_loader_rp.xml", &s, &warnings), LMC_OK);
  assert_int_equal(warnings, 0);
  const bsdf *rp = find_bsdf(s, "rp");
  assert_true(bsdf_is(rp, "roughplastic"));
  assert_int_equal(rp->dist, MF_GGX);
  assert_true(near(rp->alpha, 0.1, 0));
  assert_int_equal(rp->nonlinear, 1);
  assert_int_equal(rp->sample_visible, 0);
  assert_true(near(rp->eta, 1.6 / 1.000277, 1e-12));
  assert_true(near(rp->diffuse.value.b, 0.6, 1e-15) && near(rp->specular.value.g, 0.7, 1e-15));
  assert_true(rp->rtrans.ready && rp->rtrans.dist == MF_GGX && rp->rtrans.alpha == 0.1 &&
              rp->rtrans.eta == rp->eta);
  const bsdf *rp2 = find_bsdf(s, "rp2");
  assert_true(bsdf_is(rp2, "roughplastic"));
  assert_int_equal(rp2->twosided, 1);
  assert_true(near(rp2->alpha, 0.1, 0) && rp2->dist == MF_BECKMANN && rp2->nonlinear == 0);
  assert_true(near(rp2->eta, 1.49 / 1.000277, 1e-12));
  assert_true(rp2->rtrans.ready && rp2->rtrans.alpha == rp2->alpha);
  const bsdf *th = find_bsdf(s, "th");
  assert_true(bsdf_is(th, "thindielectric"));
  assert_true(near(th->eta, 1.3330, 1e-12));
  assert_true(near(th->transmittance.value.r, 0.9, 1e-15) && near(th->specular.value.r, 1.0, 0));
  scene_destroy(s);

  /* A textured alpha: one warning, the default roughness. */
  write_text("/tmp/lmc_loader_rp_tex.xml",
             HEAD SENSOR LIGHT
             "  <bsdf type=\"roughplastic\" id=\"rp\">\n"
             "    <texture type=\"checkerboard\" name=\"alpha\"/>\n"
             "  </bsdf>\n"
             "  <shape type=\"cube\"><ref id=\"rp\"/></shape>\n"
             "</scene>\n");
  assert_int_equal(load_quiet("/tmp/lmc_loader_rp_tex.xml", &s, &warnings), LMC_OK);
  assert_int_equal(warnings, 1);
  rp = find_bsdf(s, "rp");
  assert_true(bsdf_is(rp, "roughplastic"));
  assert_true(near(rp->alpha, 0.1, 0));
  scene_destroy(s);
}

/* ---- The happy path. ---------------------------------------------------- */

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
             "  <shape type=\"cube\"/>\n" LIGHT "</scene>\n",
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

/* Mitsuba's ldrfilm is rendered as hdrfilm with one warning that says
 * what lmc writes (and names tonemapping lmc does not apply); hdrfilm
 * takes none; another film type one. */
static void test_film_types(void **state) {
  (void)state;
  static const struct {
    const char *film;
    int warnings;
  } cases[] = {
      {"<film type=\"hdrfilm\"/>", 0},
      {"<film type=\"ldrfilm\"/>", 1},
      {"<film type=\"ldrfilm\"><float name=\"exposure\" value=\"2\"/>"
       "<string name=\"tonemapMethod\" value=\"reinhard\"/></film>", 1},
      {"<film type=\"mfilm\"/>", 1},
  };
  int checked = 0;
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char xml[1024];
    snprintf(xml, sizeof xml,
             HEAD "  <sensor type=\"perspective\">%s</sensor>\n  <shape type=\"cube\"/>\n" LIGHT
                  "</scene>\n",
             cases[i].film);
    int warnings;
    scene *s = load_case_ok("/tmp/lmc_loader_film.xml", xml, i, &warnings);
    if (warnings != cases[i].warnings)
      fail_msg("case %zu: %d warnings, want %d", i, warnings, cases[i].warnings);
    scene_destroy(s);
    checked++;
  }
  assert_int_equal(checked, 4);
}

/* ---- Mitsuba's defaults. ------------------------------------------------ */

/* The mean x of a mesh's vertices. */
static double mesh_mean_x(const mesh *m) {
  double sum = 0.0;
  for (int64_t i = 0; i < m->n_vertices; i++) sum += m->p[3 * i];
  return sum / (double)m->n_vertices;
}

/* A shape that emits and names no BSDF is black (Mitsuba: diffuse of
 * reflectance 0), one that does not emit is diffuse 0.5; a shape that is
 * only a medium boundary is Mitsuba's index-matched interface (no BSDF:
 * bsdf -1, its medium inside), one with a BSDF keeps it (and its medium);
 * an <animation> renders its first keyframe (a warning), and an empty or
 * malformed one is an error at its line. */
static void test_mitsuba_defaults(void **state) {
  (void)state;
  int checks = 0;
  write_text("/tmp/lmc_loader_defaults.xml",
             HEAD SENSOR
             "  <shape type=\"sphere\" id=\"lamp\">\n"                              /* 6 */
             "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter>\n"
             "  </shape>\n"
             "  <shape type=\"cube\" id=\"plain\"/>\n"                              /* 9 */
             "  <medium type=\"homogeneous\" id=\"fog\"/>\n"                        /* 10 */
             "  <shape type=\"cube\" id=\"boundary\">\n"                            /* 11 */
             "    <ref name=\"interior\" id=\"fog\"/>\n"                            /* 12 */
             "  </shape>\n"
             "  <shape type=\"cube\" id=\"glassy\">\n"
             "    <bsdf type=\"dielectric\"/>\n"
             "    <medium type=\"homogeneous\" name=\"interior\"/>\n"               /* 16 */
             "  </shape>\n"
             "  <shape type=\"cube\" id=\"moving\">\n"
             "    <animation name=\"toWorld\">\n"                                   /* 19: w1 */
             "      <transform time=\"0\"><translate x=\"3\"/></transform>\n"
             "      <transform time=\"1\"><translate x=\"7\"/></transform>\n"
             "    </animation>\n"
             "  </shape>\n"
             "</scene>\n");
  scene *s;
  int warnings;
  assert_int_equal(load_quiet("/tmp/lmc_loader_defaults.xml", &s, &warnings), LMC_OK);
  assert_int_equal(warnings, 1);
  /* lamp, plain, boundary, glassy, moving. */
  assert_int_equal(s->n_meshes, 5);
  static const char *const names[5] = {"lamp", "plain", "boundary", "glassy", "moving"};
  for (int i = 0; i < 5; i++, checks++) assert_string_equal(s->meshes[i].name, names[i]);
  assert_int_equal(s->meshes[2].bsdf, -1);
  assert_int_equal(s->meshes[2].interior, 1);
  assert_int_equal(s->meshes[2].exterior, 0);
  assert_int_equal(s->meshes[3].interior, 2);
  assert_non_null(s->accel_media);
  checks += 4;
  const bsdf *lamp = &s->bsdfs[s->meshes[0].bsdf], *plain = &s->bsdfs[s->meshes[1].bsdf];
  assert_true(bsdf_is(lamp, "diffuse"));
  assert_true(rgb_is_black(lamp->diffuse.value) && lamp->diffuse.image == NULL);
  assert_true(bsdf_is(plain, "diffuse"));
  assert_true(near(plain->diffuse.value.r, 0.5, 0.0) && near(plain->diffuse.value.b, 0.5, 0.0));
  assert_true(bsdf_is(&s->bsdfs[s->meshes[3].bsdf], "dielectric"));
  checks += 5;
  /* The unit cube moved by the first keyframe (x + 3), not the second. */
  assert_true(near(mesh_mean_x(&s->meshes[4]), 3.0, 1e-6));
  assert_true(near(mesh_mean_x(&s->meshes[1]), 0.0, 1e-6));
  checks += 2;
  scene_destroy(s);

  /* Malformed animations: an error at the element's line. */
  static const struct {
    const char *body, *needle;
  } bad[] = {
      {"  <shape type=\"cube\">\n    <animation name=\"toWorld\">\n"
       "    </animation>\n  </shape>\n", "without a keyframe"},
      {"  <shape type=\"cube\">\n    <animation name=\"toWorld\">\n"
       "      <float name=\"x\" value=\"1\"/>\n    </animation>\n  </shape>\n", "inside <animation>"},
      {"  <shape type=\"cube\">\n    <animation>\n"
       "    </animation>\n  </shape>\n", "'name'"},
  };
  static const int bad_line[] = {8, 8, 7};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++, checks++) {
    char xml[2048];
    snprintf(xml, sizeof xml, HEAD SENSOR "%s</scene>\n", bad[i].body);
    write_text("/tmp/lmc_loader_anim.xml", xml);
    lmc_error err;
    lmc_error_clear(&err);
    lmc_warn_set_quiet(1);
    lmc_status st = scene_load_xml("/tmp/lmc_loader_anim.xml", NULL, 0, &s, &err);
    lmc_warn_set_quiet(0);
    if (st != LMC_EPARSE || err.line != bad_line[i] || !strstr(err.msg, bad[i].needle))
      fail_msg("animation case %zu: status %d, line %d (expected %d), message '%s'", i, (int)st,
               err.line, bad_line[i], err.msg);
  }
  assert_int_equal(checks, 19);
}

/* Mitsuba's mask: the wrapped BSDF with the flag and its opacity (0.5 by
 * default, a colour, or a bitmap's channel: "g" of the test texture is its
 * green channel repeated); an opacity outside [0, 1], an unknown channel,
 * alpha from a file without one, and a mask in a mask are errors at their
 * line. */
static void test_mask_loader(void **state) {
  (void)state;
  int checks = 0;
  char xml[4096];
  snprintf(xml, sizeof xml,
           HEAD SENSOR LIGHT
           "  <bsdf type=\"mask\" id=\"half\">\n"
           "    <bsdf type=\"twosided\"><bsdf type=\"roughconductor\"/></bsdf>\n"
           "  </bsdf>\n"
           "  <bsdf type=\"mask\" id=\"tinted\">\n"
           "    <rgb name=\"opacity\" value=\"0.1, 0.2, 0.3\"/>\n"
           "    <bsdf type=\"diffuse\"/>\n"
           "  </bsdf>\n"
           "  <bsdf type=\"mask\" id=\"leaf\">\n"
           "    <texture type=\"bitmap\" name=\"opacity\">\n"
           "      <string name=\"filename\" value=\"" TEXFILE "\"/>\n"
           "      <string name=\"channel\" value=\"g\"/>\n"
           "    </texture>\n"
           "    <bsdf type=\"diffuse\"/>\n"
           "  </bsdf>\n"
           "  <shape type=\"cube\"><ref id=\"leaf\"/></shape>\n"
           "</scene>\n");
  int warnings;
  scene *s = load_case_ok("/tmp/lmc_loader_mask.xml", xml, 0, &warnings);
  assert_int_equal(warnings, 0);
  const bsdf *half = find_bsdf(s, "half"), *tinted = find_bsdf(s, "tinted");
  const bsdf *leaf = find_bsdf(s, "leaf");
  assert_true(half->masked && half->twosided && bsdf_is(half, "roughconductor"));
  assert_true(half->opacity.type == TEX_CONSTANT && half->opacity.value.g == 0.5);
  assert_true(tinted->masked && bsdf_is(tinted, "diffuse"));
  assert_true(tinted->opacity.value.r == 0.1 && tinted->opacity.value.b == 0.3);
  checks += 4;
  /* The leaf's opacity: the texture file's green channel, in all three. */
  assert_true(leaf->masked && leaf->opacity.type == TEX_BITMAP && leaf->opacity.image);
  lmc_image ref = {0};
  lmc_error err;
  lmc_error_clear(&err);
  assert_int_equal(image_read(TEXFILE, 1, &ref, &err), LMC_OK);
  assert_int_equal(image_to_rgb(&ref, &err), LMC_OK);
  const lmc_image *op = leaf->opacity.image;
  assert_true(op->width == ref.width && op->height == ref.height && op->channels == 3);
  int texels = 0;
  for (int i = 0; i < ref.width * ref.height; i++, texels++)
    for (int c = 0; c < 3; c++) assert_true(op->data[3 * i + c] == ref.data[3 * i + 1]);
  assert_int_equal(texels, 16);
  image_free(&ref);
  scene_destroy(s);
  checks++;

  static const struct {
    const char *body, *needle;
    int line;
  } bad[] = {
      {"  <bsdf type=\"mask\">\n    <float name=\"opacity\" value=\"1.5\"/>\n"
       "    <bsdf type=\"diffuse\"/>\n  </bsdf>\n", "in [0, 1]", 7},
      {"  <bsdf type=\"mask\">\n    <texture type=\"bitmap\" name=\"opacity\">\n"
       "      <string name=\"filename\" value=\"" TEXFILE "\"/>\n"
       "      <string name=\"channel\" value=\"q\"/>\n    </texture>\n"
       "    <bsdf type=\"diffuse\"/>\n  </bsdf>\n", "channel", 9},
      {"  <bsdf type=\"mask\">\n    <texture type=\"bitmap\" name=\"opacity\">\n"
       "      <string name=\"filename\" value=\"" TEXFILE "\"/>\n"
       "      <string name=\"channel\" value=\"a\"/>\n    </texture>\n"
       "    <bsdf type=\"diffuse\"/>\n  </bsdf>\n", "no alpha", 8},
      {"  <bsdf type=\"mask\">\n    <bsdf type=\"mask\">\n"
       "      <bsdf type=\"diffuse\"/>\n    </bsdf>\n  </bsdf>\n", "mask inside a mask", 6},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++, checks++) {
    snprintf(xml, sizeof xml, HEAD SENSOR "%s</scene>\n", bad[i].body);
    write_text("/tmp/lmc_loader_mask_bad.xml", xml);
    lmc_error_clear(&err);
    lmc_warn_set_quiet(1);
    lmc_status st = scene_load_xml("/tmp/lmc_loader_mask_bad.xml", NULL, 0, &s, &err);
    lmc_warn_set_quiet(0);
    if (st == LMC_OK || err.line != bad[i].line || !strstr(err.msg, bad[i].needle))
      fail_msg("mask case %zu: status %d, line %d (expected %d), message '%s'", i, (int)st,
               err.line, bad[i].line, err.msg);
  }
  assert_int_equal(checks, 5 + 4);
}

/* Mitsuba's bumpmap: the wrapped BSDF with the flag and its displacement
 * (here a `scale` texture of 10 around a linear bitmap: the bitmap's
 * values times 10); on a shape without texture coordinates (the PLY quad)
 * it is ignored with a warning, as Mitsuba does; a bumpmap without a
 * texture is an error at its line. */
static void test_bump_loader(void **state) {
  (void)state;
  char xml[4096];
  snprintf(xml, sizeof xml,
           HEAD SENSOR LIGHT
           "  <bsdf type=\"bumpmap\" id=\"bumpy\">\n"
           "    <texture type=\"scale\">\n"
           "      <float name=\"scale\" value=\"10\"/>\n"
           "      <texture type=\"bitmap\">\n"
           "        <string name=\"filename\" value=\"" TEXFILE "\"/>\n"
           "        <float name=\"gamma\" value=\"1\"/>\n"
           "      </texture>\n"
           "    </texture>\n"
           "    <bsdf type=\"roughconductor\"/>\n"
           "  </bsdf>\n"
           "  <shape type=\"rectangle\"><ref id=\"bumpy\"/></shape>\n"
           "  <shape type=\"ply\">\n" /* line 18: no uv */
           "    <string name=\"filename\" value=\"" LMC_SOURCE_DIR "/tests/data/loader/quad.ply\"/>\n"
           "    <ref id=\"bumpy\"/>\n"
           "  </shape>\n"
           "</scene>\n");
  write_text("/tmp/lmc_loader_bump.xml", xml);
  scene *s;
  int warnings;
  assert_int_equal(load_quiet("/tmp/lmc_loader_bump.xml", &s, &warnings), LMC_OK);
  assert_int_equal(warnings, 1); /* the PLY quad */
  const bsdf *b = find_bsdf(s, "bumpy");
  assert_true(b->bumped && bsdf_is(b, "roughconductor") && b->bump.type == TEX_BITMAP);
  lmc_image ref = {0};
  lmc_error err;
  lmc_error_clear(&err);
  assert_int_equal(image_read(TEXFILE, 0, &ref, &err), LMC_OK);
  assert_int_equal(image_to_rgb(&ref, &err), LMC_OK);
  const lmc_image *im = b->bump.image;
  assert_true(im && im->width == ref.width && im->height == ref.height);
  int texels = 0;
  for (int i = 0; i < 3 * ref.width * ref.height; i++, texels++)
    assert_true(fabsf(im->data[i] - 10.0f * ref.data[i]) <= 1e-6f * fmaxf(1.0f, im->data[i]));
  assert_int_equal(texels, 48);
  image_free(&ref);
  scene_destroy(s);
  /* No displacement texture. */
  snprintf(xml, sizeof xml,
           HEAD SENSOR "  <bsdf type=\"bumpmap\">\n    <bsdf type=\"diffuse\"/>\n  </bsdf>\n</scene>\n");
  write_text("/tmp/lmc_loader_bump.xml", xml);
  lmc_warn_set_quiet(1);
  lmc_status st = scene_load_xml("/tmp/lmc_loader_bump.xml", NULL, 0, &s, &err);
  lmc_warn_set_quiet(0);
  assert_int_equal(st, LMC_EPARSE);
  assert_int_equal(err.line, 6);
  assert_non_null(strstr(err.msg, "displacement"));
}

/* maxSmoothAngle on a mesh (Mitsuba's rebuildTopology, tested in
 * test_mesh_io): no warning, smooth normals made; outside [0, 180] an error
 * at the shape's line. */
static void test_max_smooth_angle(void **state) {
  (void)state;
  static const double angles[2] = {45.0, 200.0};
  for (int k = 0; k < 2; k++) {
    char xml[2048];
    snprintf(xml, sizeof xml,
             HEAD SENSOR LIGHT
             "  <shape type=\"ply\">\n"
             "    <string name=\"filename\" value=\"" LMC_SOURCE_DIR "/tests/data/loader/quad.ply\"/>\n"
             "    <float name=\"maxSmoothAngle\" value=\"%g\"/>\n"
             "  </shape>\n"
             "</scene>\n",
             angles[k]);
    write_text("/tmp/lmc_loader_msa.xml", xml);
    scene *s = NULL;
    int warnings;
    if (!k) {
      assert_int_equal(load_quiet("/tmp/lmc_loader_msa.xml", &s, &warnings), LMC_OK);
      assert_int_equal(warnings, 0);
      assert_int_equal(s->n_meshes, 1);
      assert_non_null(s->meshes[0].n);
      scene_destroy(s);
    } else {
      lmc_error err;
      lmc_error_clear(&err);
      lmc_warn_set_quiet(1);
      lmc_status st = scene_load_xml("/tmp/lmc_loader_msa.xml", NULL, 0, &s, &err);
      lmc_warn_set_quiet(0);
      assert_int_equal(st, LMC_EPARSE);
      assert_int_equal(err.line, 7);
      assert_non_null(strstr(err.msg, "maxSmoothAngle"));
    }
  }
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
                  "  <shape type=\"cube\"/>\n" LIGHT "</scene>\n",
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

/* roughdiffuse and ward with Mitsuba's names and defaults, without a
 * warning: roughdiffuse's own reflectance, alpha, useFastApprox and its
 * other name diffuseReflectance; ward's variants (any case), alphaU/alphaV
 * and alpha, its two reflectances. A textured roughness warns once and
 * takes the default. */
static void test_roughdiffuse_ward(void **state) {
  (void)state;
  static const char *const xml =
      HEAD SENSOR LIGHT
      "  <shape type=\"cube\"><bsdf type=\"roughdiffuse\" id=\"rd\">\n"
      "    <spectrum name=\"reflectance\" value=\"0.3\"/>\n"
      "    <float name=\"alpha\" value=\"0.4\"/>\n"
      "  </bsdf></shape>\n"
      "  <shape type=\"cube\"><bsdf type=\"roughdiffuse\" id=\"rd2\">\n"
      "    <rgb name=\"diffuseReflectance\" value=\"0.1, 0.2, 0.7\"/>\n"
      "    <boolean name=\"useFastApprox\" value=\"true\"/>\n"
      "  </bsdf></shape>\n"
      "  <shape type=\"cube\"><bsdf type=\"ward\" id=\"wd\">\n"
      "    <string name=\"variant\" value=\"ward-duer\"/>\n"
      "    <float name=\"alphaU\" value=\"0.1\"/>\n"
      "    <float name=\"alphaV\" value=\"0.3\"/>\n"
      "    <spectrum name=\"specularReflectance\" value=\"0.25\"/>\n"
      "    <spectrum name=\"diffuseReflectance\" value=\"0.6\"/>\n"
      "  </bsdf></shape>\n"
      "  <shape type=\"cube\"><bsdf type=\"ward\" id=\"wd2\">\n"
      "    <string name=\"variant\" value=\"Ward\"/>\n"
      "    <float name=\"alpha\" value=\"0.2\"/>\n"
      "  </bsdf></shape>\n"
      "  <shape type=\"cube\"><bsdf type=\"ward\" id=\"wd3\"/></shape>\n"
      "</scene>\n";
  int warnings;
  scene *s = load_case_ok("/tmp/lmc_loader_rdward.xml", xml, 0, &warnings);
  assert_int_equal(warnings, 0);
  const bsdf *rd = find_bsdf(s, "rd");
  assert_true(bsdf_is(rd, "roughdiffuse"));
  assert_int_equal(rd->diffuse.type, TEX_CONSTANT);
  assert_true(near(rd->diffuse.value.r, 0.3, 1e-15) && near(rd->diffuse.value.b, 0.3, 1e-15));
  assert_true(near(rd->alpha, 0.4, 0));
  assert_int_equal(rd->fast_approx, 0);
  const bsdf *rd2 = find_bsdf(s, "rd2");
  assert_true(bsdf_is(rd2, "roughdiffuse"));
  assert_true(near(rd2->diffuse.value.b, 0.7, 1e-15) && near(rd2->diffuse.value.r, 0.1, 1e-15));
  assert_true(near(rd2->alpha, 0.2, 0)); /* Mitsuba's default */
  assert_int_equal(rd2->fast_approx, 1);
  const bsdf *wd = find_bsdf(s, "wd");
  assert_true(bsdf_is(wd, "ward"));
  assert_int_equal(wd->variant, WARD_DUER);
  assert_true(near(wd->alpha_u, 0.1, 0) && near(wd->alpha_v, 0.3, 0));
  assert_true(near(wd->specular.value.g, 0.25, 1e-15) && near(wd->diffuse.value.g, 0.6, 1e-15));
  const bsdf *wd2 = find_bsdf(s, "wd2");
  assert_int_equal(wd2->variant, WARD_ORIGINAL);
  assert_true(near(wd2->alpha_u, 0.2, 0) && near(wd2->alpha_v, 0.2, 0));
  const bsdf *wd3 = find_bsdf(s, "wd3");
  assert_int_equal(wd3->variant, WARD_BALANCED);
  assert_true(near(wd3->alpha_u, 0.1, 0) && near(wd3->alpha_v, 0.1, 0));
  assert_true(near(wd3->specular.value.r, 0.2, 1e-15) && near(wd3->diffuse.value.r, 0.5, 1e-15));
  scene_destroy(s);

  /* A textured alpha: one warning, the default roughness. */
  static const char *const xml_tex =
      HEAD SENSOR LIGHT
      "  <shape type=\"cube\"><bsdf type=\"roughdiffuse\" id=\"rt\">\n"
      "    <texture type=\"checkerboard\" name=\"alpha\"/>\n"
      "  </bsdf></shape>\n"
      "</scene>\n";
  s = load_case_ok("/tmp/lmc_loader_rdtex.xml", xml_tex, 1, &warnings);
  assert_int_equal(warnings, 1);
  const bsdf *rt = find_bsdf(s, "rt");
  assert_true(bsdf_is(rt, "roughdiffuse"));
  assert_true(near(rt->alpha, 0.2, 0));
  scene_destroy(s);
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
                  "  <shape type=\"cube\"/>\n" LIGHT "</scene>\n",
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
  /* One texture image and its MIP levels (the bitmap's default filter, EWA). */
  assert_true(s->n_images > 1);
  assert_int_equal(s->n_images, tex_mip_levels(s->images[0].width, s->images[0].height));
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
  assert_true(bsdf_is(d, "diffuse"));
  assert_int_equal(d->diffuse.type, TEX_BITMAP);
  assert_ptr_equal(d->diffuse.image, &s->images[0]);
  assert_int_equal(s->images[0].channels, 3);
  assert_true(near(d->diffuse.uscale, 2.0, 0) && near(d->diffuse.vscale, 1.0, 0));
  assert_true(near(d->diffuse.voffset, 0.5, 0));
  const bsdf *ph = find_bsdf(s, "ph");
  assert_true(bsdf_is(ph, "phong"));
  assert_true(near(ph->exponent, 40.0, 0));
  assert_true(near(ph->specular.value.r, 0.3, 1e-15));
  assert_int_equal(ph->diffuse.type, TEX_CHECKERBOARD);
  assert_true(near(ph->diffuse.color0.r, 0.4, 1e-15) && near(ph->diffuse.color1.r, 0.2, 1e-15));
  assert_true(near(ph->diffuse.uscale, 3.0, 0));
  const bsdf *rc = find_bsdf(s, "rc");
  assert_true(bsdf_is(rc, "roughconductor"));
  assert_int_equal(rc->dist, MF_GGX);
  assert_true(near(rc->alpha, 0.2, 1e-15));
  assert_true(near(rc->cond_eta.r, 0.1, 1e-15) && near(rc->cond_eta.b, 0.55, 1e-15));
  assert_true(near(rc->cond_k.g, 1.25, 1e-15));
  assert_int_equal(rc->specular.type, TEX_CHECKERBOARD);
  assert_true(near(rc->specular.color0.r, 0.9, 1e-15) && near(rc->specular.uscale, 4.0, 0));
  const bsdf *gl = find_bsdf(s, "gl");
  double water = 0.0;
  assert_true(ior_lookup("water", &water));
  assert_true(bsdf_is(gl, "dielectric"));
  assert_true(near(gl->eta, water, 1e-12));
  const bsdf *rg = find_bsdf(s, "rg");
  assert_true(bsdf_is(rg, "roughdielectric"));
  assert_int_equal(rg->dist, MF_BECKMANN);
  assert_true(near(rg->eta, 1.2, 1e-12) && near(rg->alpha, 0.3, 1e-15));
  assert_int_equal(rg->sample_visible, 0);
  const bsdf *pl = find_bsdf(s, "pl");
  assert_true(bsdf_is(pl, "plastic"));
  assert_true(near(pl->eta, 1.5, 1e-15));
  assert_int_equal(pl->nonlinear, 1);
  /* sRGB 128/255 decodes to 0.2158605. */
  assert_true(near(pl->diffuse.value.g, 0.2158605, 1e-6));
  const bsdf *ts = find_bsdf(s, "ts");
  assert_true(bsdf_is(ts, "diffuse"));
  assert_int_equal(ts->twosided, 1);
  assert_true(near(ts->diffuse.value.b, 0.6, 1e-15));
  const bsdf *incl = find_bsdf(s, "incl");
  rgb au_eta, au_k;
  assert_true(conductor_lookup("Au", &au_eta, &au_k));
  assert_true(bsdf_is(incl, "conductor"));
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
      assert_true(bsdf_is(b, "diffuse"));
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
      cmocka_unit_test(test_warnings),        cmocka_unit_test(test_rough_plastic_thin),
      cmocka_unit_test(test_happy),
      cmocka_unit_test(test_define_override), cmocka_unit_test(test_torus_lmc),
      cmocka_unit_test(test_torus_h2mc),      cmocka_unit_test(test_direct_samples),
      cmocka_unit_test(test_lookat_spelling),
      cmocka_unit_test(test_sampler_type),    cmocka_unit_test(test_mitsuba_defaults),
      cmocka_unit_test(test_mask_loader),
      cmocka_unit_test(test_bump_loader),
      cmocka_unit_test(test_max_smooth_angle),
      cmocka_unit_test(test_roughdiffuse_ward),
      cmocka_unit_test(test_spectra),
      cmocka_unit_test(test_spectrum_file_errors),
      cmocka_unit_test(test_film_types),
  };
  return cmocka_run_group_tests(tests, write_texture, NULL);
}
