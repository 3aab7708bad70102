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
    "  --spp N                  samples per pixel (default: the scene's, else 16)\n"
    "  --time SECONDS           stop after this long (with --spp: whichever comes first)\n"
    "  --threads N              worker threads (default: all cores)\n"
    "  --seed S                 random seed (default 1); same seed and threads: same image\n"
    "  --maxdepth N             longest path in segments, Mitsuba's maxDepth (-1: unbounded)\n"
    "  --rrdepth N              Russian roulette from this length on (default 5)\n"
    "  --resolution WxH         film size (keeps the field of view)\n"
    "  --sampler NAME           pt, bdpt, MCMC's direct pass: independent | sobol (Owen-scrambled,\n"
    "                           stratified across a pixel's samples) (default: the scene's,\n"
    "                           else independent)\n"
    "  -D name=value            override a <default> of the scene (repeatable)\n"
    "  --snapshot S             also write OUT-<seconds>s.exr every S seconds\n"
    "  --exposure STOPS|auto    the PNG preview: radiance times 2^STOPS, clamped, sRGB\n"
    "                           (default 0, as Mitsuba and tev show the EXR); auto: the\n"
    "                           99th percentile of luminance maps to white\n"
    "\n";
/* (in two parts: C caps a string literal's guaranteed length) */
static const char *lmc_render_usage_mcmc =
    "MCMC (pssmlt, mmlt, lmc, h2mc; --spp counts mutations per pixel):\n"
    "  --states KIND            the chains' states: bdpt (a BDPT sample and one of its\n"
    "                           strategies, every length in one family; pssmlt's and lmc's\n"
    "                           default) | mmlt (one family per length; mmlt's default) |\n"
    "                           pt (a path tracer's samples)\n"
    "  --roughness-threshold R  bdpt states: directions of BSDFs rougher than R are moved\n"
    "                           as absolute world directions (default 0.3; 1: never)\n"
    "  --largestep P            large-step probability (default 0.3)\n"
    "  --largestep-scale X      the large-step probability times X after the first tenth of\n"
    "                           the budget (the LMC paper's largestepscale; default 1)\n"
    "  --small-step KIND        kelemen (offsets log-uniform in (1/1024, S]) | gauss (normal\n"
    "                           offsets of standard deviation S) (default kelemen)\n"
    "  --sigma S                small-step scale (default 1/64; mmlt 0.05; gauss 0.01)\n"
    "  --chains N               Markov chains (default 256)\n"
    "  --bootstrap N            independent paths used to estimate b (default: 10% of --time,\n"
    "                           or under --spp enough for 1%)\n"
    "  --bootstrap-error E      without --bootstrap, under --spp: b's target relative error (0.01)\n"
    "  --direct separate|mcmc   separate: pt renders paths of <= 2 segments, MCMC the longer\n"
    "                           ones (default); mcmc: MCMC renders every path\n"
    "  --allocate b|even        mmlt, lmc: mutations per path length in proportion to its b\n"
    "                           (default), or the same for every chain\n"
    "\n"
    "LMC (--integrator lmc):\n"
    "  --adapt MODE             none | adam | diminish | cache (default cache; adam is biased)\n"
    "  --step S                 Langevin step s: y ~ N(x + s/2 M g, s M) (default 1e-5)\n"
    "  --step-range R           each Langevin step draws s log-uniformly from [S/R, S R] (default 1)\n"
    "  --adam-eps E             M = clamp(1 / (E + sqrt(v)), LO, HI) (default 1e-8)\n"
    "  --precond-clamp LO,HI    the clamp of M (default 1e-3,1e3)\n"
    "  --grad-bound B           truncate |grad log f| to B (default 1e3)\n"
    "  --cache-fraction F       --adapt cache: share of the budget for stage 1 (default 0.1)\n"
    "  --iso-prob P             probability of Kelemen's isotropic small step (default 0.4)\n"
    "  --lmc-states KIND        the same as --states\n"
    "  --cache-gradient on|off  --adapt cache, bdpt states: stage 2 evaluates gradients (MALA\n"
    "                           with the cached M) instead of the cached walk (default off)\n"
    "  --cache-step S           the cached walk: cov = 1 / (1 / (S^2 (M + 1)) + 1 / P^2)\n"
    "                           (default 0.005)\n"
    "  --cache-prior P          its prior standard deviation, the width where no entry is\n"
    "                           near (default 0.005)\n"
    "  --cache-radius R         its neighbours lie within R sqrt(n) (default 0.01)\n"
    "  --cache-k K              its neighbours (default 5)\n"
    "  --cache-drift on|off     drift from the cached first moment (default on)\n"
    "  --delayed on|off         Langevin proposals first tested without their gradient\n"
    "                           (delayed acceptance, exact; default off)\n"
    "\n"
    "H2MC (--integrator h2mc, bdpt states; --largestep and --iso-prob as for lmc):\n"
    "  --h2mc-sigma S           the prior's standard deviation on the proposal's offset\n"
    "                           (default 0.01)\n"
    "  -q, --quiet              no progress bar\n"
    "  -h, --help               this text\n";

/* Integrators `--integrator` accepts. */
static int lmc_integrator_known(const char *name) {
  return !strcmp(name, "pt") || !strcmp(name, "bdpt") || mcmc_is_integrator(name);
}

/* --adapt values. */
static int lmc_parse_adapt(const char *v, lmc_adapt *out) {
  static const struct {
    const char *name;
    lmc_adapt mode;
  } modes[] = {{"none", LMC_ADAPT_NONE},
               {"adam", LMC_ADAPT_ADAM},
               {"diminish", LMC_ADAPT_DIMINISH},
               {"cache", LMC_ADAPT_CACHE}};
  for (size_t i = 0; i < sizeof modes / sizeof modes[0]; i++)
    if (!strcmp(v, modes[i].name)) {
      *out = modes[i].mode;
      return 1;
    }
  return 0;
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

static int lmc_parse_int64(const char *flag, const char *s, int64_t lo, int64_t hi, int64_t *out) {
  char *end;
  errno = 0;
  long long v = strtoll(s, &end, 10);
  if (errno || end == s || *end != '\0' || v < lo || v > hi) {
    fprintf(stderr, "lmc: flag %s: '%s' is not an integer in [%lld, %lld]\n", flag, s,
            (long long)lo, (long long)hi);
    return 0;
  }
  *out = v;
  return 1;
}

/* A flag with two values: *out = 0 for `first`, 1 for `second`. */
static int lmc_parse_choice(const char *flag, const char *s, const char *first,
                            const char *second, int *out) {
  if (strcmp(s, first) && strcmp(s, second)) {
    fprintf(stderr, "lmc: flag %s: '%s' is not one of %s, %s\n", flag, s, first, second);
    return 0;
  }
  *out = strcmp(s, second) == 0;
  return 1;
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

  /* Parse the flags; the scene's own settings are merged below. */
  for (a.i = 2; a.i < argc; a.i++) {
    const char *arg = argv[a.i], *v;
    int64_t iv;
    if (lmc_flag_is(&a, "--help") || lmc_flag_is(&a, "-h")) {
      fputs(lmc_render_usage, stdout);
      fputs(lmc_render_usage_mcmc, stdout);
      free(defines);
      return EXIT_OK;
    } else if (lmc_flag_is(&a, "-o") || lmc_flag_is(&a, "--output")) {
      if (!(output = lmc_flag_value(&a))) goto bad;
    } else if (lmc_flag_is(&a, "--integrator")) {
      if (!(v = lmc_flag_value(&a))) goto bad;
      if (!lmc_integrator_known(v)) {
        fprintf(stderr,
                "lmc: flag --integrator: unknown integrator '%s' "
                "(valid: pt, bdpt, pssmlt, mmlt, lmc, h2mc)\n",
                v);
        goto bad;
      }
      snprintf(cli.integrator, sizeof cli.integrator, "%s", v);
      cli.set |= SET_INTEGRATOR;
    } else if (lmc_flag_is(&a, "--spp")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_int64("--spp", v, 1, INT64_MAX / 2, &cli.spp))
        goto bad;
      cli.set |= SET_SPP;
    } else if (lmc_flag_is(&a, "--time")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_double("--time", v, 1e-3, 1e9, &cli.time_limit))
        goto bad;
      cli.set |= SET_TIME;
    } else if (lmc_flag_is(&a, "--threads")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_int64("--threads", v, 1, 1024, &iv)) goto bad;
      cli.threads = (int)iv;
    } else if (lmc_flag_is(&a, "--seed")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_int64("--seed", v, 0, INT64_MAX, &iv)) goto bad;
      cli.seed = (uint64_t)iv;
    } else if (lmc_flag_is(&a, "--maxdepth")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_int64("--maxdepth", v, -1, 1000, &iv)) goto bad;
      cli.maxdepth = (int)iv;
      cli.set |= SET_MAXDEPTH;
    } else if (lmc_flag_is(&a, "--rrdepth")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_int64("--rrdepth", v, 1, 1000, &iv)) goto bad;
      cli.rrdepth = (int)iv;
      cli.set |= SET_RRDEPTH;
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
    } else if (lmc_flag_is(&a, "--snapshot")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_double("--snapshot", v, 1e-3, 1e9, &cli.snapshot))
        goto bad;
    } else if (lmc_flag_is(&a, "--exposure")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_exposure(v, &exposure)) goto bad;
    } else if (lmc_flag_is(&a, "--largestep")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_double("--largestep", v, 0, 1, &cli.largestep))
        goto bad;
      cli.set |= SET_LARGESTEP;
    } else if (lmc_flag_is(&a, "--small-step")) {
      int gauss;
      if (!(v = lmc_flag_value(&a)) ||
          !lmc_parse_choice("--small-step", v, "kelemen", "gauss", &gauss))
        goto bad;
      cli.small_gauss = gauss;
      cli.set |= SET_SMALL_STEP;
    } else if (lmc_flag_is(&a, "--chains")) {
      int64_t n;
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_int64("--chains", v, 1, 1 << 20, &n)) goto bad;
      cli.chains = (int)n;
      cli.set |= SET_CHAINS;
    } else if (lmc_flag_is(&a, "--roughness-threshold")) {
      if (!(v = lmc_flag_value(&a)) ||
          !lmc_parse_double("--roughness-threshold", v, 0, 1e6, &cli.rough_min))
        goto bad;
      cli.set |= SET_ROUGH;
    } else if (lmc_flag_is(&a, "--largestep-scale")) {
      if (!(v = lmc_flag_value(&a)) ||
          !lmc_parse_double("--largestep-scale", v, 0, 1e6, &cli.largestep_scale))
        goto bad;
      cli.set |= SET_LARGESTEP_SCALE;
    } else if (lmc_flag_is(&a, "--sigma")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_double("--sigma", v, 1e-9, 1, &cli.sigma))
        goto bad;
      cli.set |= SET_SIGMA;
    } else if (lmc_flag_is(&a, "--bootstrap-error")) {
      if (!(v = lmc_flag_value(&a)) ||
          !lmc_parse_double("--bootstrap-error", v, 1e-4, 1, &cli.bootstrap_error))
        goto bad;
    } else if (lmc_flag_is(&a, "--bootstrap")) {
      if (!(v = lmc_flag_value(&a)) ||
          !lmc_parse_int64("--bootstrap", v, 1, INT64_MAX / 2, &cli.bootstrap))
        goto bad;
      cli.set |= SET_BOOTSTRAP;
    } else if (lmc_flag_is(&a, "--sampler")) {
      int sobol;
      if (!(v = lmc_flag_value(&a)) ||
          !lmc_parse_choice("--sampler", v, "independent", "sobol", &sobol))
        goto bad;
      cli.sampler = sobol ? LMC_SAMPLER_SOBOL : LMC_SAMPLER_INDEPENDENT;
      cli.set |= SET_SAMPLER;
    } else if (lmc_flag_is(&a, "--direct")) {
      int mcmc;
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_choice("--direct", v, "separate", "mcmc", &mcmc))
        goto bad;
      cli.direct_separate = !mcmc;
      cli.set |= SET_DIRECT;
    } else if (lmc_flag_is(&a, "--allocate")) {
      if (!(v = lmc_flag_value(&a)) ||
          !lmc_parse_choice("--allocate", v, "b", "even", &cli.mcmc_even))
        goto bad;
    } else if (lmc_flag_is(&a, "--adapt")) {
      if (!(v = lmc_flag_value(&a))) goto bad;
      if (!lmc_parse_adapt(v, &cli.adapt)) {
        fprintf(stderr, "lmc: flag --adapt: '%s' is not one of none, adam, diminish, cache\n", v);
        goto bad;
      }
      cli.set |= SET_ADAPT;
    } else if (lmc_flag_is(&a, "--step")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_double("--step", v, 1e-12, 1, &cli.lmc_step))
        goto bad;
    } else if (lmc_flag_is(&a, "--step-range")) {
      if (!(v = lmc_flag_value(&a)) ||
          !lmc_parse_double("--step-range", v, 1, 1e6, &cli.step_range))
        goto bad;
    } else if (lmc_flag_is(&a, "--adam-eps")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_double("--adam-eps", v, 0, 1e6, &cli.adam_eps))
        goto bad;
    } else if (lmc_flag_is(&a, "--precond-clamp")) {
      if (!(v = lmc_flag_value(&a))) goto bad;
      char tail;
      if (sscanf(v, "%lf,%lf%c", &cli.precond_lo, &cli.precond_hi, &tail) != 2 ||
          !(cli.precond_lo > 0) || !(cli.precond_hi >= cli.precond_lo) ||
          !isfinite(cli.precond_hi)) {
        fprintf(stderr, "lmc: flag --precond-clamp: '%s' is not LO,HI with 0 < LO <= HI\n", v);
        goto bad;
      }
    } else if (lmc_flag_is(&a, "--grad-bound")) {
      if (!(v = lmc_flag_value(&a)) ||
          !lmc_parse_double("--grad-bound", v, 1e-9, 1e300, &cli.grad_bound))
        goto bad;
    } else if (lmc_flag_is(&a, "--cache-fraction")) {
      if (!(v = lmc_flag_value(&a)) ||
          !lmc_parse_double("--cache-fraction", v, 0, 0.99, &cli.cache_fraction))
        goto bad;
    } else if (lmc_flag_is(&a, "--cache-gradient")) {
      int off;
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_choice("--cache-gradient", v, "on", "off", &off))
        goto bad;
      cli.cache_gradient = !off;
    } else if (lmc_flag_is(&a, "--cache-drift")) {
      int off;
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_choice("--cache-drift", v, "on", "off", &off))
        goto bad;
      cli.cache_no_drift = off;
    } else if (lmc_flag_is(&a, "--cache-step")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_double("--cache-step", v, 1e-9, 0.5, &cli.cache_step))
        goto bad;
    } else if (lmc_flag_is(&a, "--cache-prior")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_double("--cache-prior", v, 1e-9, 0.5, &cli.cache_prior))
        goto bad;
    } else if (lmc_flag_is(&a, "--cache-radius")) {
      if (!(v = lmc_flag_value(&a)) ||
          !lmc_parse_double("--cache-radius", v, 1e-9, 1.0, &cli.cache_radius))
        goto bad;
    } else if (lmc_flag_is(&a, "--cache-k")) {
      int64_t n;
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_int64("--cache-k", v, 1, 32, &n)) goto bad;
      cli.cache_k = (int)n;
    } else if (lmc_flag_is(&a, "--h2mc-sigma")) {
      if (!(v = lmc_flag_value(&a)) ||
          !lmc_parse_double("--h2mc-sigma", v, 1e-6, 0.5, &cli.h2mc_sigma))
        goto bad;
    } else if (lmc_flag_is(&a, "--iso-prob")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_double("--iso-prob", v, 0, 1, &cli.iso_prob))
        goto bad;
    } else if (lmc_flag_is(&a, "--delayed")) {
      int off;
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_choice("--delayed", v, "on", "off", &off))
        goto bad;
      cli.delayed = !off;
    } else if (lmc_flag_is(&a, "--states")) {
      if (!(v = lmc_flag_value(&a))) goto bad;
      if (!strcmp(v, "pt")) cli.mcmc_states = MCMC_STATES_PT;
      else if (!strcmp(v, "mmlt")) cli.mcmc_states = MCMC_STATES_MMLT;
      else if (!strcmp(v, "bdpt")) cli.mcmc_states = MCMC_STATES_BDPT;
      else {
        fprintf(stderr, "lmc: flag --states: '%s' is not pt, mmlt or bdpt\n", v);
        goto bad;
      }
      cli.set |= SET_STATES;
    } else if (lmc_flag_is(&a, "--lmc-states")) { /* the name --states had for lmc alone */
      if (!(v = lmc_flag_value(&a))) goto bad;
      if (!strcmp(v, "mmlt")) cli.mcmc_states = MCMC_STATES_MMLT;
      else if (!strcmp(v, "pt")) cli.mcmc_states = MCMC_STATES_PT;
      else if (!strcmp(v, "bdpt")) cli.mcmc_states = MCMC_STATES_BDPT;
      else {
        fprintf(stderr, "lmc: flag --lmc-states: '%s' is not one of mmlt, pt, bdpt\n", v);
        goto bad;
      }
      cli.set |= SET_STATES;
    } else if (lmc_flag_is(&a, "-q") || lmc_flag_is(&a, "--quiet")) {
      cli.quiet = 1;
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
    fprintf(stderr, "lmc render: no scene given\n%s%s", lmc_render_usage, lmc_render_usage_mcmc);
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
    free(defines);
    return EXIT_BADINPUT;
  }
  free(defines);
  t_load = omp_get_wtime() - t_load;
  if (res_w > 0) {
    camera_set_resolution(&s->cam, res_w, res_h);
  }

  /* The scene's settings, overridden by the command line. */
  render_settings rs = s->settings;
  if (!(rs.set & SET_INTEGRATOR)) snprintf(rs.integrator, sizeof rs.integrator, "pt");
  if (cli.set & SET_INTEGRATOR) memcpy(rs.integrator, cli.integrator, sizeof rs.integrator);
  if (cli.set & SET_SPP) rs.spp = cli.spp;
  if (cli.set & SET_TIME) rs.time_limit = cli.time_limit;
  if (cli.set & SET_MAXDEPTH) rs.maxdepth = cli.maxdepth;
  if (cli.set & SET_RRDEPTH) rs.rrdepth = cli.rrdepth;
  if ((cli.set & SET_TIME) && !(cli.set & SET_SPP)) rs.set &= ~(unsigned)SET_SPP;
  if (cli.set & SET_LARGESTEP) rs.largestep = cli.largestep;
  if (cli.set & SET_SIGMA) rs.sigma = cli.sigma;
  if (cli.set & SET_SMALL_STEP) rs.small_gauss = cli.small_gauss;
  if (cli.set & SET_LARGESTEP_SCALE) rs.largestep_scale = cli.largestep_scale;
  if (cli.set & SET_ROUGH) rs.rough_min = cli.rough_min;
  if (cli.set & SET_CHAINS) rs.chains = cli.chains;
  if (cli.set & SET_BOOTSTRAP) rs.bootstrap = cli.bootstrap;
  rs.bootstrap_error = cli.bootstrap_error;
  if (cli.set & SET_DIRECT) rs.direct_separate = cli.direct_separate;
  if (cli.set & SET_SAMPLER) rs.sampler = cli.sampler;
  /* The scene's directSamples is a sample count for its own spp: --spp
   * given here sets both passes. */
  if (cli.set & SET_SPP) rs.direct_spp = 0;
  rs.mcmc_even = cli.mcmc_even;
  if (cli.set & SET_STATES) rs.mcmc_states = cli.mcmc_states;
  if (cli.set & SET_ADAPT) rs.adapt = cli.adapt;
  rs.snapshot = cli.snapshot;
  rs.lmc_step = cli.lmc_step;
  rs.step_range = cli.step_range;
  rs.adam_eps = cli.adam_eps;
  rs.precond_lo = cli.precond_lo;
  rs.precond_hi = cli.precond_hi;
  rs.grad_bound = cli.grad_bound;
  rs.cache_fraction = cli.cache_fraction;
  rs.iso_prob = cli.iso_prob;
  rs.h2mc_sigma = cli.h2mc_sigma;
  rs.cache_gradient = cli.cache_gradient;
  rs.cache_step = cli.cache_step;
  rs.cache_prior = cli.cache_prior;
  rs.cache_radius = cli.cache_radius;
  rs.cache_k = cli.cache_k;
  rs.cache_no_drift = cli.cache_no_drift;
  rs.delayed = cli.delayed;
  rs.set |= cli.set;
  rs.threads = cli.threads;
  rs.seed = cli.seed;
  rs.quiet = cli.quiet;
  if (!lmc_integrator_known(rs.integrator)) {
    lmc_warn(scene_path, 0,
             "the scene asks for integrator '%s', which lmc does not have; "
             "rendering with bdpt (choose with --integrator)",
             rs.integrator);
    snprintf(rs.integrator, sizeof rs.integrator, "bdpt");
  }
  if ((cli.set & SET_ADAPT) && strcmp(rs.integrator, "lmc"))
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
  free(defines);
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
