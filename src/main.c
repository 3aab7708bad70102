/*
 * main.c: the `lmc` command line.
 *
 *   lmc render SCENE.xml [flags]     render to OUT.exr (linear) and OUT.png (preview)
 *   lmc compare IMAGE.exr REF.exr    error metrics, one `name: value` per line
 *
 * Every flag is accepted as `--flag value` and `--flag=value`. Exit status:
 * 0 success, 1 usage or internal error... see lmc_usage for the table. Only
 * this file turns errors into exit codes and installs signal handlers.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/error.h"
#include "render/image.h"
#include "lmc/mcmc.h"
#include "render/integrator.h"
#include "render/io/io.h"
#include "render/options.h"
#include "render/scene.h"

#define LMC_VERSION "0.1.0"

/* Exit statuses. */
enum {
  EXIT_OK = 0,
  EXIT_FAIL = 1,      /* rendering or writing failed */
  EXIT_BADINPUT = 2,  /* bad flag, bad scene, images of different sizes */
  EXIT_SIGINT = 130,  /* interrupted by SIGINT (image of the samples so far written) */
  EXIT_SIGTERM = 143  /* interrupted by SIGTERM (likewise) */
};

static const char *lmc_usage =
    "usage: lmc <command> [arguments]\n"
    "\n"
    "commands:\n"
    "  render SCENE.xml [flags]        render a Mitsuba XML scene\n"
    "  compare IMAGE.exr REFERENCE.exr [--heatmap ERR.png]\n"
    "                                  print mse, relmse and mean_ratio\n"
    "  merge [--weight W] A.exr ... -o OUT.exr  average independent renders of one scene\n"
    "  convert IN.exr OUT.png [--exposure STOPS|auto]  sRGB PNG preview of an EXR\n"
    "  --help, -h                      this text (lmc render --help: the render flags)\n"
    "  --version                       the version\n"
    "\n"
    "exit status: 0 ok, 1 failure, 2 bad input (flags, scene, image sizes),\n"
    "130/143 interrupted by SIGINT/SIGTERM (the image so far is still written)\n";

static const char *lmc_render_usage =
    "usage: lmc render SCENE.xml [flags]   (every flag also as --flag=value)\n"
    "\n"
    "  -o, --output OUT.exr     output; OUT.png (sRGB preview) is written beside it\n"
    "                           (default: the scene's name in the current folder)\n"
    "  --integrator NAME        pt | bdpt | pssmlt | mmlt | lmc | h2mc\n"
    "                           (default: the scene's <integrator>/<dpt>, else pt)\n"
    "  --resolution WxH         film size (keeps the field of view)\n"
    "  -D name=value            override a <default> of the scene (repeatable)\n"
    "  --exposure STOPS|auto    the PNG preview: radiance times 2^STOPS, clamped, sRGB\n"
    "                           (default 0, as Mitsuba and tev show the EXR); auto: the\n"
    "                           99th percentile of luminance maps to white\n"
    "  -q, --quiet              no progress bar\n"
    "  -h, --help               this text\n"
    "  --help-markdown          the flags below as Markdown tables (the README's)\n"
    "\n";

/* Every table of flags: the renderer's, then the MCMC driver's, its
 * state spaces' and integrators' (mcmc.h). */
#define LMC_MAX_TABLES 32
static int lmc_option_tables(const lmc_opt_table **OUT) {
  OUT[0] = &lmc_render_options;
  return 1 + mcmc_option_tables(OUT + 1, LMC_MAX_TABLES - 1);
}

/* lmc render --help-markdown: the tables below as the README shows them. */
static void lmc_render_markdown(FILE *f) {
  const lmc_opt_table *t[LMC_MAX_TABLES];
  int n = lmc_option_tables(t);
  for (int i = 0; i < n; i++) {
    fprintf(f, "%s%s:\n\n", i ? "\n" : "", t[i]->title);
    lmc_opt_markdown(f, t[i]);
  }
}

/* lmc render --help. */
static void lmc_render_help(FILE *f) {
  const lmc_opt_table *t[LMC_MAX_TABLES];
  int n = lmc_option_tables(t);
  fputs(lmc_render_usage, f);
  for (int i = 0; i < n; i++) lmc_opt_help(f, t[i]);
}

/* Integrators `--integrator` accepts. */
static int lmc_integrator_known(const char *name) {
  return !strcmp(name, "pt") || !strcmp(name, "bdpt") || mcmc_is_integrator(name);
}

/* --- flag parsing ------------------------------------------------------------ */

typedef struct lmc_args {
  int argc, i;
  char **argv;
  const char *inline_value; /* the part after '=' of the current flag */
} lmc_args;

/* Matches argv[i] against a flag name (with or without "=value"). */
static int lmc_flag_is(lmc_args *a, const char *name) {
  const char *arg = a->argv[a->i];
  size_t n = strlen(name);
  if (strncmp(arg, name, n) != 0) return 0;
  if (arg[n] == '\0') {
    a->inline_value = NULL;
    return 1;
  }
  if (arg[n] == '=') {
    a->inline_value = arg + n + 1;
    return 1;
  }
  return 0;
}

/* The value of the current flag, from "=value" or the next argument. */
static const char *lmc_flag_value(lmc_args *a) {
  if (a->inline_value) return a->inline_value;
  if (a->i + 1 >= a->argc) {
    fprintf(stderr, "lmc: flag %s needs a value\n", a->argv[a->i]);
    return NULL;
  }
  return a->argv[++a->i];
}

/* s as a whole finite number in [lo, hi]: 1 and *out, else 0 (silent). */
static int lmc_number_in(const char *s, double lo, double hi, double *out) {
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (errno || end == s || *end != '\0' || !isfinite(v) || v < lo || v > hi) return 0;
  *out = v;
  return 1;
}

static int lmc_parse_double(const char *flag, const char *s, double lo, double hi, double *out) {
  if (lmc_number_in(s, lo, hi, out)) return 1;
  fprintf(stderr, "lmc: flag %s: '%s' is not a number in [%g, %g]\n", flag, s, lo, hi);
  return 0;
}

/* The PNG preview's exposure: --exposure STOPS (linear radiance times
 * 2^STOPS, clamped, sRGB: how Mitsuba, pbrt and tev show an EXR; default 0)
 * or --exposure auto (the 99th percentile of luminance maps to white). */
typedef struct lmc_exposure {
  int is_auto;
  double stops;
} lmc_exposure;

static int lmc_parse_exposure(const char *s, lmc_exposure *out) {
  if (strcmp(s, "auto") == 0) {
    out->is_auto = 1;
    out->stops = 0.0;
    return 1;
  }
  if (!lmc_number_in(s, -64.0, 64.0, &out->stops)) {
    fprintf(stderr, "lmc: flag --exposure: '%s' is neither a number of stops in [-64, 64] nor 'auto'\n",
            s);
    return 0;
  }
  out->is_auto = 0;
  return 1;
}

/* --- lmc render --------------------------------------------------------------- */

static void lmc_on_signal(int sig) { render_request_stop(sig); }

static void lmc_install_signals(void) {
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = lmc_on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, NULL);
  sigaction(SIGTERM, &sa, NULL);
}

/* Default output name: the scene file's name without .xml, or its folder's
 * name when the file is called scene.xml. */
static void lmc_default_output(const char *scene_path, char *out, size_t size) {
  const char *slash = strrchr(scene_path, '/');
  const char *base = slash ? slash + 1 : scene_path;
  char stem[256];
  snprintf(stem, sizeof stem, "%s", base);
  char *dot = strrchr(stem, '.');
  if (dot) *dot = '\0';
  if (strcmp(stem, "scene") == 0 && slash) {
    const char *end = slash, *start = slash;
    while (start > scene_path && start[-1] != '/') start--;
    if (end > start) snprintf(stem, sizeof stem, "%.*s", (int)(end - start), start);
  }
  snprintf(out, size, "%s.exr", stem);
}

/* Exposure of the preview: the 99th percentile of luminance maps to 1. */
static double lmc_preview_scale(const lmc_image *img) {
  size_t n = (size_t)img->width * (size_t)img->height;
  float *lum = malloc(n * sizeof(float));
  if (!lum || n == 0) {
    free(lum);
    return 1.0;
  }
  size_t k = 0;
  for (size_t i = 0; i < n; i++) {
    const float *p = img->data + 3 * i;
    double l = rgb_luminance(rgb_make(p[0], p[1], p[2]));
    if (isfinite(l) && l > 0.0) lum[k++] = (float)l;
  }
  double scale = 1.0;
  if (k > 0) {
    /* Partial selection of the percentile (nth element by quickselect). */
    size_t target = (size_t)(0.99 * (double)(k - 1));
    size_t lo = 0, hi = k - 1;
    while (lo < hi) {
      float pivot = lum[(lo + hi) / 2];
      size_t i = lo, j = hi;
      while (i <= j) {
        while (lum[i] < pivot) i++;
        while (lum[j] > pivot) j--;
        if (i <= j) {
          float t = lum[i];
          lum[i] = lum[j];
          lum[j] = t;
          i++;
          if (j == 0) break;
          j--;
        }
      }
      if (target <= j) hi = j;
      else if (target >= i) lo = i;
      else break;
    }
    double p = lum[target];
    if (p > 0.0 && isfinite(p)) scale = 1.0 / p;
  }
  free(lum);
  return scale;
}

/* The factor the preview multiplies radiance by. */
static double lmc_exposure_scale(const lmc_exposure *e, const lmc_image *img) {
  return e->is_auto ? lmc_preview_scale(img) : exp2(e->stops);
}

static int lmc_write_outputs(const film *f, const char *exr_path, char *png_path, size_t png_size,
                             const lmc_exposure *exposure) {
  lmc_error err;
  lmc_error_clear(&err);
  lmc_image img = {0};
  char msg[2048];
  if (film_develop(f, &img, &err) || image_write_exr(exr_path, &img, &err)) {
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
    image_free(&img);
    return 0;
  }
  snprintf(png_path, png_size, "%s", exr_path);
  size_t len = strlen(png_path);
  if (len > 4 && strcmp(png_path + len - 4, ".exr") == 0) png_path[len - 4] = '\0';
  strncat(png_path, ".png", png_size - strlen(png_path) - 1);
  if (image_write_png(png_path, &img, lmc_exposure_scale(exposure, &img), &err)) {
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
    image_free(&img);
    return 0;
  }
  image_free(&img);
  return 1;
}

/* --snapshot: writes OUTSTEM-<seconds>s.exr (safe write: temporary file
 * and rename, as the final output). */
typedef struct lmc_snapshot_ctx {
  const char *out_exr;
} lmc_snapshot_ctx;

static void lmc_write_snapshot(void *ctx, const struct film *f, double seconds) {
  const lmc_snapshot_ctx *sc = ctx;
  char path[1100], stem[1024];
  snprintf(stem, sizeof stem, "%s", sc->out_exr);
  size_t len = strlen(stem);
  if (len > 4 && strcmp(stem + len - 4, ".exr") == 0) stem[len - 4] = '\0';
  snprintf(path, sizeof path, "%s-%.1fs.exr", stem, seconds);
  lmc_error err;
  lmc_error_clear(&err);
  lmc_image img = {0};
  if (film_develop(f, &img, &err) || image_write_exr(path, &img, &err)) {
    char msg[2048];
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: snapshot: %s\n", msg);
  }
  image_free(&img);
}

static int lmc_cmd_render(int argc, char **argv) {
  const char *scene_path = NULL, *output = NULL;
  const char **defines = calloc((size_t)argc + 1, sizeof(char *));
  int n_defines = 0;
  render_settings cli = render_settings_default();
  cli.set = 0;
  int res_w = 0, res_h = 0;
  lmc_exposure exposure = {0, 0.0};
  lmc_args a = {argc, 2, argv, NULL};
  if (!defines) return EXIT_FAIL;

  /* Parse the flags; the scene's own settings are merged below. The flags
   * of the tables are checked into cli now and applied to the scene's
   * settings after loading (given[]). */
  const lmc_opt_table *tables[LMC_MAX_TABLES];
  int n_tables = lmc_option_tables(tables);
  typedef struct lmc_given {
    const lmc_opt_table *table;
    const lmc_opt *opt;
    const char *value;
  } lmc_given;
  lmc_given *given = calloc((size_t)argc + 1, sizeof *given);
  int n_given = 0;
  if (!given) {
    free(defines);
    return EXIT_FAIL;
  }
  for (a.i = 2; a.i < argc; a.i++) {
    const char *arg = argv[a.i], *v;
    if (lmc_flag_is(&a, "--help") || lmc_flag_is(&a, "-h")) {
      lmc_render_help(stdout);
      free(defines), free(given);
      return EXIT_OK;
    } else if (lmc_flag_is(&a, "--help-markdown")) {
      lmc_render_markdown(stdout);
      free(defines), free(given);
      return EXIT_OK;
    } else if (lmc_flag_is(&a, "-o") || lmc_flag_is(&a, "--output")) {
      if (!(output = lmc_flag_value(&a))) goto bad;
    } else if (lmc_flag_is(&a, "--integrator")) {
      if (!(v = lmc_flag_value(&a))) goto bad;
      if (!lmc_integrator_known(v)) {
        const char *names[16];
        int n = mcmc_integrator_names(names, 16);
        fprintf(stderr, "lmc: flag --integrator: unknown integrator '%s' (valid: pt, bdpt", v);
        for (int i = 0; i < n; i++) fprintf(stderr, ", %s", names[i]);
        fprintf(stderr, ")\n");
        goto bad;
      }
      snprintf(cli.integrator, sizeof cli.integrator, "%s", v);
      cli.set |= SET_INTEGRATOR;
    } else if (lmc_flag_is(&a, "--resolution")) {
      if (!(v = lmc_flag_value(&a))) goto bad;
      char tail;
      if (sscanf(v, "%dx%d%c", &res_w, &res_h, &tail) != 2 || res_w <= 0 || res_h <= 0 ||
          res_w > 65536 || res_h > 65536) {
        fprintf(stderr, "lmc: flag --resolution: '%s' is not WIDTHxHEIGHT (e.g. 320x240)\n", v);
        goto bad;
      }
    } else if (strcmp(arg, "-D") == 0 || (strncmp(arg, "-D", 2) == 0 && arg[2] != '\0')) {
      const char *d = arg[2] ? arg + 2 : (a.i + 1 < argc ? argv[++a.i] : NULL);
      if (!d || !strchr(d, '=') || d[0] == '=') {
        fprintf(stderr, "lmc: flag -D needs name=value\n");
        goto bad;
      }
      defines[n_defines++] = d;
    } else if (lmc_flag_is(&a, "--exposure")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_exposure(v, &exposure)) goto bad;
    } else if (lmc_flag_is(&a, "-q") || lmc_flag_is(&a, "--quiet")) {
      cli.quiet = 1;
    } else if (!strncmp(arg, "--", 2)) {
      /* A flag of the tables: --name value or --name=value. */
      char name[64];
      size_t len = strcspn(arg + 2, "=");
      snprintf(name, sizeof name, "%.*s", (int)(len < sizeof name ? len : sizeof name - 1), arg + 2);
      const lmc_opt_table *ot = NULL;
      const lmc_opt *o = lmc_opt_find(tables, n_tables, name, &ot);
      if (!o) {
        fprintf(stderr, "lmc: unknown flag '%s' (see lmc render --help)\n", arg);
        goto bad;
      }
      a.inline_value = arg[2 + len] == '=' ? arg + 3 + len : NULL;
      if (!(v = lmc_flag_value(&a))) goto bad;
      char msg[512];
      if (!lmc_opt_set(ot, o, v, &cli, msg, sizeof msg)) {
        fprintf(stderr, "lmc: %s\n", msg);
        goto bad;
      }
      given[n_given++] = (lmc_given){ot, o, v};
    } else if (arg[0] == '-') {
      fprintf(stderr, "lmc: unknown flag '%s' (see lmc render --help)\n", arg);
      goto bad;
    } else if (!scene_path) {
      scene_path = arg;
    } else {
      fprintf(stderr, "lmc: unexpected argument '%s' (one scene at a time)\n", arg);
      goto bad;
    }
  }
  if (!scene_path) {
    fprintf(stderr, "lmc render: no scene given\n");
    lmc_render_help(stderr);
    goto bad;
  }

  /* Load the scene. */
  lmc_error err;
  lmc_error_clear(&err);
  scene *s = NULL;
  double t_load = omp_get_wtime();
  if (scene_load_xml(scene_path, defines, n_defines, &s, &err)) {
    char msg[2048];
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
    free(defines), free(given);
    return EXIT_BADINPUT;
  }
  free(defines);
  t_load = omp_get_wtime() - t_load;
  if (res_w > 0) {
    camera_set_resolution(&s->cam, res_w, res_h);
  }

  /* The scene's settings (with its <integrator>/<dpt> parameters through
   * the option tables), overridden by the command line. */
  render_settings rs;
  if (mcmc_scene_settings(s, &rs, &err) != LMC_OK) {
    char msg[2048];
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
    scene_destroy(s);
    free(given);
    return EXIT_BADINPUT;
  }
  if (!(rs.set & SET_INTEGRATOR)) snprintf(rs.integrator, sizeof rs.integrator, "pt");
  if (cli.set & SET_INTEGRATOR) memcpy(rs.integrator, cli.integrator, sizeof rs.integrator);
  /* The flags as given, in order, over the scene's settings. */
  int adapt_given = 0;
  for (int i = 0; i < n_given; i++) {
    char msg[512];
    lmc_opt_set(given[i].table, given[i].opt, given[i].value, &rs, msg, sizeof msg); /* (checked above) */
    adapt_given |= !strcmp(given[i].opt->name, "adapt");
  }
  free(given);
  given = NULL;
  if ((cli.set & SET_TIME) && !(cli.set & SET_SPP)) rs.set &= ~(unsigned)SET_SPP;
  /* The scene's directSamples is a sample count for its own spp: --spp
   * given here sets both passes. */
  if (cli.set & SET_SPP) rs.direct_spp = 0;
  rs.quiet = cli.quiet;
  if (!lmc_integrator_known(rs.integrator)) {
    lmc_warn(scene_path, 0,
             "the scene asks for integrator '%s', which lmc does not have; "
             "rendering with bdpt (choose with --integrator)",
             rs.integrator);
    snprintf(rs.integrator, sizeof rs.integrator, "bdpt");
  }
  if (adapt_given && strcmp(rs.integrator, "lmc"))
    lmc_warn(NULL, 0, "--adapt only applies to --integrator lmc; ignored for %s", rs.integrator);

  /* Render, then write what we have even when interrupted. */
  char out_exr[1024], out_png[1100];
  if (output)
    snprintf(out_exr, sizeof out_exr, "%s", output);
  else
    lmc_default_output(scene_path, out_exr, sizeof out_exr);
  lmc_install_signals();
  lmc_snapshot_ctx snap = {out_exr};
  if (rs.snapshot > 0.0) {
    rs.snapshot_fn = lmc_write_snapshot;
    rs.snapshot_ctx = &snap;
  }
  film f;
  render_stats st;
  lmc_status rst = mcmc_is_integrator(rs.integrator) ? mcmc_render_run(s, &rs, &f, &st, &err)
                                                       : render_run(s, &rs, &f, &st, &err);
  if (rst) {
    char msg[2048];
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
    scene_destroy(s);
    return EXIT_FAIL;
  }
  int ok = lmc_write_outputs(&f, out_exr, out_png, sizeof out_png, &exposure);
  fprintf(stderr,
          "lmc: %s %dx%d, %lld spp (%lld samples) in %.2f s (load %.2f s), %.3g rays, "
          "%.3g Mrays/s%s%s\n",
          rs.integrator, f.width, f.height, (long long)st.passes, (long long)st.samples,
          st.seconds, t_load, (double)st.rays, st.rays / fmax(st.seconds, 1e-9) / 1e6,
          st.interrupted ? ", interrupted" : "", st.timed_out ? ", time limit reached" : "");
  if (st.nan_samples > 0)
    fprintf(stderr, "lmc: dropped %lld non-finite samples\n", (long long)st.nan_samples);
  if (ok) printf("wrote %s\nwrote %s\n", out_exr, out_png);
  film_free(&f);
  scene_destroy(s);
  if (!ok) return EXIT_FAIL;
  if (st.interrupted) return render_stop_signal() == SIGTERM ? EXIT_SIGTERM : EXIT_SIGINT;
  return EXIT_OK;
bad:
  free(defines), free(given);
  return EXIT_BADINPUT;
}

/* --- lmc compare ---------------------------------------------------------------- */

/* A false-colour ramp (dark blue - cyan - yellow - red) for t in [0, 1]. */
static rgb lmc_heat_color(double t) {
  static const double stops[5][3] = {
      {0.05, 0.05, 0.25}, {0.0, 0.45, 0.85}, {0.1, 0.85, 0.75}, {0.95, 0.9, 0.1}, {0.85, 0.1, 0.05}};
  t = fmin(1.0, fmax(0.0, t)) * 4.0;
  int i = (int)t;
  if (i >= 4) i = 3;
  double f = t - i;
  return rgb_make(stops[i][0] + f * (stops[i + 1][0] - stops[i][0]),
                  stops[i][1] + f * (stops[i + 1][1] - stops[i][1]),
                  stops[i][2] + f * (stops[i + 1][2] - stops[i][2]));
}

/* Ascending order of doubles, for qsort. */
static int lmc_cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static int lmc_cmd_compare(int argc, char **argv) {
  const char *paths[2] = {NULL, NULL}, *heatmap = NULL;
  int n_paths = 0;
  lmc_args a = {argc, 2, argv, NULL};
  for (a.i = 2; a.i < argc; a.i++) {
    if (lmc_flag_is(&a, "--heatmap")) {
      if (!(heatmap = lmc_flag_value(&a))) return EXIT_BADINPUT;
    } else if (lmc_flag_is(&a, "--help") || lmc_flag_is(&a, "-h")) {
      printf("usage: lmc compare IMAGE.exr REFERENCE.exr [--heatmap ERR.png]\n"
             "prints mse, relmse (mean of (I-R)^2 / (R^2 + 0.01)), relmse_trimmed\n"
             "(the same without the 0.1%% of pixels with the largest error) and\n"
             "mean_ratio (mean luminance of IMAGE over REFERENCE); exit 2 if the\n"
             "sizes differ\n");
      return EXIT_OK;
    } else if (argv[a.i][0] == '-') {
      fprintf(stderr, "lmc: unknown flag '%s' (see lmc compare --help)\n", argv[a.i]);
      return EXIT_BADINPUT;
    } else if (n_paths < 2) {
      paths[n_paths++] = argv[a.i];
    } else {
      fprintf(stderr, "lmc compare: too many arguments\n");
      return EXIT_BADINPUT;
    }
  }
  if (n_paths != 2) {
    fprintf(stderr, "usage: lmc compare IMAGE.exr REFERENCE.exr [--heatmap ERR.png]\n");
    return EXIT_BADINPUT;
  }
  lmc_image img[2] = {{0}, {0}};
  lmc_error err;
  lmc_error_clear(&err);
  char msg[2048];
  for (int k = 0; k < 2; k++) {
    if (image_read(paths[k], 0, &img[k], &err) || image_to_rgb(&img[k], &err)) {
      lmc_error_format(&err, msg, sizeof msg);
      fprintf(stderr, "lmc: %s\n", msg);
      image_free(&img[0]);
      image_free(&img[1]);
      return EXIT_BADINPUT;
    }
  }
  if (img[0].width != img[1].width || img[0].height != img[1].height) {
    fprintf(stderr, "lmc: %s is %dx%d but %s is %dx%d\n", paths[0], img[0].width, img[0].height,
            paths[1], img[1].width, img[1].height);
    image_free(&img[0]);
    image_free(&img[1]);
    return EXIT_BADINPUT;
  }

  /* The metrics, over pixels and channels; rel[] keeps each pixel's
   * relative squared error for the trimmed mean. */
  size_t n = (size_t)img[0].width * (size_t)img[0].height;
  double mse = 0.0, relmse = 0.0, lum_i = 0.0, lum_r = 0.0;
  double *rel = malloc(n * sizeof *rel);
  if (!rel) {
    fprintf(stderr, "lmc: out of memory\n");
    image_free(&img[0]);
    image_free(&img[1]);
    return EXIT_FAIL;
  }
  for (size_t p = 0; p < n; p++) {
    const float *I = img[0].data + 3 * p, *R = img[1].data + 3 * p;
    rel[p] = 0.0;
    for (int c = 0; c < 3; c++) {
      double d = (double)I[c] - (double)R[c];
      mse += d * d;
      rel[p] += d * d / ((double)R[c] * R[c] + 0.01) / 3.0;
    }
    relmse += rel[p];
    lum_i += rgb_luminance(rgb_make(I[0], I[1], I[2]));
    lum_r += rgb_luminance(rgb_make(R[0], R[1], R[2]));
  }
  mse /= 3.0 * (double)n;
  relmse /= (double)n;
  /* The trimmed relative MSE: the mean over the pixels left when the
   * largest 0.1% of the per-pixel errors are dropped (one firefly of a
   * short render can outweigh the rest of the image). */
  size_t drop = n / 1000;
  qsort(rel, n, sizeof *rel, lmc_cmp_double);
  double trimmed = 0.0;
  for (size_t p = 0; p + drop < n; p++) trimmed += rel[p];
  trimmed /= (double)(n - drop);
  free(rel);
  printf("mse: %.9g\nrelmse: %.9g\nrelmse_trimmed: %.9g\nmean_ratio: %.9g\n", mse, relmse, trimmed,
         lum_r != 0.0 ? lum_i / lum_r : (lum_i == 0.0 ? 1.0 : INFINITY));

  /* The heatmap: per-pixel relative error, log scale from 1e-4 to 1. */
  int status = EXIT_OK;
  if (heatmap) {
    lmc_image hm = {0};
    if (image_init(&hm, img[0].width, img[0].height, 3, &err) == LMC_OK) {
      for (size_t p = 0; p < n; p++) {
        const float *I = img[0].data + 3 * p, *R = img[1].data + 3 * p;
        double e = 0.0;
        for (int c = 0; c < 3; c++) {
          double d = (double)I[c] - (double)R[c];
          e += d * d / ((double)R[c] * R[c] + 0.01) / 3.0;
        }
        double t = (log10(fmax(e, 1e-4)) + 4.0) / 4.0;
        rgb col = lmc_heat_color(t);
        hm.data[3 * p] = (float)srgb_to_linear(col.r);
        hm.data[3 * p + 1] = (float)srgb_to_linear(col.g);
        hm.data[3 * p + 2] = (float)srgb_to_linear(col.b);
      }
      if (image_write_png(heatmap, &hm, 1.0, &err)) status = EXIT_FAIL;
    } else {
      status = EXIT_FAIL;
    }
    if (status != EXIT_OK) {
      lmc_error_format(&err, msg, sizeof msg);
      fprintf(stderr, "lmc: %s\n", msg);
    }
    image_free(&hm);
  }
  image_free(&img[0]);
  image_free(&img[1]);
  return status;
}

/* --- lmc merge ------------------------------------------------------------------ */

/* Averages renders of the same scene made with different seeds: equal
 * weights, or the weights given with --weight (inverse variances, for
 * renders of unequal effort). */
static int lmc_cmd_merge(int argc, char **argv) {
  static const char usage[] = "usage: lmc merge [--weight W] A.exr [--weight W] B.exr ... -o OUT.exr";
  const char *out = NULL;
  lmc_image acc = {0}, img = {0};
  lmc_error err;
  lmc_error_clear(&err);
  char msg[2048];
  int n = 0, status = EXIT_OK, weight_pending = 0;
  double weight = 1.0, total = 0.0;
  lmc_args a = {argc, 2, argv, NULL};
  for (a.i = 2; a.i < argc && status == EXIT_OK; a.i++) {
    const char *v;
    if (lmc_flag_is(&a, "-o") || lmc_flag_is(&a, "--output")) {
      if (!(out = lmc_flag_value(&a))) status = EXIT_BADINPUT;
      continue;
    }
    if (lmc_flag_is(&a, "--weight")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_double("--weight", v, 1e-9, 1e9, &weight))
        status = EXIT_BADINPUT;
      weight_pending = 1;
      continue;
    }
    if (lmc_flag_is(&a, "--help") || lmc_flag_is(&a, "-h")) {
      printf("%s\n"
             "writes the per-pixel weighted mean of the images (all the same size) to\n"
             "OUT.exr, for independent renders of one scene. --weight W applies to the\n"
             "image after it (default 1): give renders of unequal effort weights in\n"
             "inverse proportion to their variance, e.g. their sample counts\n",
             usage);
      image_free(&acc);
      return EXIT_OK;
    }
    if (argv[a.i][0] == '-') {
      fprintf(stderr, "lmc: unknown flag '%s' (%s)\n", argv[a.i], usage);
      status = EXIT_BADINPUT;
      continue;
    }
    double w = weight;
    weight = 1.0;
    weight_pending = 0;
    if (image_read(argv[a.i], 0, &img, &err) || image_to_rgb(&img, &err)) {
      lmc_error_format(&err, msg, sizeof msg);
      fprintf(stderr, "lmc: %s\n", msg);
      status = EXIT_BADINPUT;
    } else if (n == 0) {
      acc = img;
      memset(&img, 0, sizeof img);
      n = 1;
      total = w;
    } else if (img.width != acc.width || img.height != acc.height) {
      fprintf(stderr, "lmc: %s is %dx%d, the first image %dx%d\n", argv[a.i], img.width,
              img.height, acc.width, acc.height);
      status = EXIT_BADINPUT;
    } else {
      /* Running weighted mean, in place. */
      n++;
      total += w;
      float f = (float)(w / total);
      for (size_t k = 0; k < (size_t)acc.width * acc.height * 3; k++)
        acc.data[k] += (img.data[k] - acc.data[k]) * f;
    }
    image_free(&img);
  }
  if (status == EXIT_OK && weight_pending) {
    fprintf(stderr, "lmc: flag --weight: no image after it\n");
    status = EXIT_BADINPUT;
  }
  if (status == EXIT_OK && (n < 1 || !out)) {
    fprintf(stderr, "%s\n", usage);
    status = EXIT_BADINPUT;
  }
  if (status == EXIT_OK && image_write_exr(out, &acc, &err)) {
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
    status = EXIT_FAIL;
  }
  if (status == EXIT_OK) printf("wrote %s (weighted mean of %d images, total weight %g)\n", out, n, total);
  image_free(&acc);
  return status;
}

/* --- lmc convert ---------------------------------------------------------------- */

static int lmc_cmd_convert(int argc, char **argv) {
  const char *paths[2] = {NULL, NULL};
  int n = 0;
  lmc_exposure exposure = {0, 0.0};
  lmc_args a = {argc, 2, argv, NULL};
  for (a.i = 2; a.i < argc; a.i++) {
    const char *v;
    if (lmc_flag_is(&a, "--exposure")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_exposure(v, &exposure)) return EXIT_BADINPUT;
    } else if (lmc_flag_is(&a, "--help") || lmc_flag_is(&a, "-h")) {
      printf("usage: lmc convert IN.exr OUT.png [--exposure STOPS|auto]\n"
             "writes an sRGB PNG preview of a linear image: radiance times 2^STOPS\n"
             "(default 0), clamped, with the sRGB curve; 'auto' maps the 99th\n"
             "percentile of luminance to white\n");
      return EXIT_OK;
    } else if (argv[a.i][0] == '-') {
      fprintf(stderr, "lmc: unknown flag '%s' (usage: lmc convert IN.exr OUT.png [--exposure STOPS|auto])\n",
              argv[a.i]);
      return EXIT_BADINPUT;
    } else if (n < 2) {
      paths[n++] = argv[a.i];
    } else {
      fprintf(stderr, "lmc convert: too many arguments\n");
      return EXIT_BADINPUT;
    }
  }
  if (n != 2) {
    fprintf(stderr, "usage: lmc convert IN.exr OUT.png [--exposure STOPS|auto]\n");
    return EXIT_BADINPUT;
  }
  lmc_image img = {0};
  lmc_error err;
  lmc_error_clear(&err);
  char msg[2048];
  int status = EXIT_OK;
  if (image_read(paths[0], 0, &img, &err) || image_to_rgb(&img, &err)) {
    status = EXIT_BADINPUT;
  } else if (image_write_png(paths[1], &img, lmc_exposure_scale(&exposure, &img), &err)) {
    status = EXIT_FAIL;
  }
  if (status != EXIT_OK) {
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
  } else {
    printf("wrote %s\n", paths[1]);
  }
  image_free(&img);
  return status;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fputs(lmc_usage, stderr);
    return EXIT_BADINPUT;
  }
  if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
    fputs(lmc_usage, stdout);
    return EXIT_OK;
  }
  if (!strcmp(argv[1], "--version")) {
    printf("lmc %s\n", LMC_VERSION);
    return EXIT_OK;
  }
  if (!strcmp(argv[1], "render")) return lmc_cmd_render(argc, argv);
  if (!strcmp(argv[1], "compare")) return lmc_cmd_compare(argc, argv);
  if (!strcmp(argv[1], "merge")) return lmc_cmd_merge(argc, argv);
  if (!strcmp(argv[1], "convert")) return lmc_cmd_convert(argc, argv);
  fprintf(stderr, "lmc: unknown command '%s'\n%s", argv[1], lmc_usage);
  return EXIT_BADINPUT;
}
