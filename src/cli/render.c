/*
 * render.c: `lmc render SCENE.xml [flags]`: loads the scene, takes its
 * settings and the flags (the option tables of render/options.h), renders
 * with pt, bdpt, direct or an MCMC integrator and writes OUT.exr (linear) and
 * OUT.png (preview), also when interrupted (Ctrl-C, SIGTERM, --time).
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli/cli.h"
#include "render/dist.h"
#include "render/io/tev.h"

/* Seconds between --reference's figures without --snapshot or --display-server. */
#define LMC_REFERENCE_EVERY 5.0

/* Seconds the end of a render waits at most for its last image to reach
 * the viewer of --display-server. */
#define LMC_DISPLAY_LAST_WAIT 1.5

static const char *lmc_render_usage =
    "usage: lmc render SCENE.xml [flags]   (every flag also as --flag=value)\n"
    "\n"
    "  -o, --output OUT.exr     output; OUT.png (sRGB preview) is written beside it\n"
    "                           (-o OUT.png: the same two files)\n"
    "                           (default: the scene's name in the current folder)\n"
    "  --integrator NAME        pt | bdpt | direct | pssmlt | mmlt | lmc | h2mc | mlt\n"
    "                           (default: the scene's <integrator>/<dpt>, else pt)\n"
    "  --resolution WxH         film size (keeps the field of view)\n"
    "  -D name=value            override a <default> of the scene (repeatable)\n"
    "  --exposure STOPS|auto    the PNG preview: radiance times 2^STOPS, clamped, sRGB\n"
    "                           (default 0, as Mitsuba and tev show the EXR); auto: the\n"
    "                           99th percentile of luminance maps to white\n"
    "  --reference REF.exr      print the relative MSE against REF (lmc compare's\n"
    "                           relmse) at each snapshot (--snapshot, else every\n"
    "                           --display-interval with --display-server, else every\n"
    "                           5 s) and of the final image\n"
    "  -q, --quiet              no progress bar\n"
    "  --spectra linear|mitsuba-0.6.0\n"
    "                           how sampled spectra are read: linear (default, as Mitsuba\n"
    "                           0.6 since 2020), or as the Mitsuba 0.6.0 release did, for\n"
    "                           comparing with images made by it\n"
    "  --strict                 exit 2 instead of rendering when the scene loads with a\n"
    "                           warning (a plugin lmc lacks, no emitter, ...) or an MCMC\n"
    "                           bootstrap finds no light; exit 2 after a black image\n"
    "  -h, --help               this text\n"
    "  --help-markdown          the flags below as Markdown tables (docs/flags.md)\n"
    "\n";

/* Every table of flags: the renderer's, then direct's, the MCMC
 * driver's, its state spaces' and integrators' (mcmc.h). */
#define LMC_MAX_TABLES 32
static int lmc_option_tables(const lmc_opt_table **OUT) {
  OUT[0] = &lmc_render_options;
  return 1 + mcmc_option_tables(OUT + 1, LMC_MAX_TABLES - 1);
}

/* lmc render --help-markdown: the tables below as docs/flags.md shows them. */
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

/* --- lmc render --------------------------------------------------------------- */

static void lmc_on_signal(int sig) { render_request_stop(sig); }

void lmc_render_catch_signals(void) {
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

/* --reference: the error of img against it, one line on stderr (when is
 * the time, or NULL for the final image), and the label the viewer shows
 * after the image's name, "relmse X" (label: LMC_LABEL_MAX chars). */
#define LMC_LABEL_MAX 64
static void lmc_report_error(const lmc_image *img, const lmc_image *ref, const char *ref_path,
                             const double *when, char *label) {
  lmc_image_error e;
  lmc_error err;
  lmc_error_clear(&err);
  if (image_error(img, ref, &e, &err)) return;
  char at[64] = "final image";
  if (when) snprintf(at, sizeof at, "%.1f s", *when);
  fprintf(stderr, "lmc: %s: relmse %.6g (trimmed %.6g, mean ratio %.5f) against %s\n", at,
          e.relmse, e.relmse_trimmed, e.mean_ratio, ref_path);
  snprintf(label, LMC_LABEL_MAX, "relmse %.6g", e.relmse);
}

/* Writes the EXR and its PNG preview, and posts the image to the viewer
 * (display; NULL: none); *OUT_black tells whether every pixel is 0 (with
 * warn_black, also said as a warning naming the scene). */
static int lmc_write_outputs(const film *f, const char *exr_path, char *png_path, size_t png_size,
                             const lmc_exposure *exposure, const char *scene_path,
                             int warn_black, lmc_tev *display, const lmc_image *ref,
                             const char *ref_path, int *OUT_black) {
  lmc_error err;
  lmc_error_clear(&err);
  lmc_image img = {0};
  char msg[2048];
  if (film_develop(f, &img, &err)) {
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
    image_free(&img);
    return 0;
  }
  /* --error: each pixel's standard error beside it, as channels error.R, G, B. */
  lmc_image eimg = {0};
  if (film_has_error(f) && image_init(&eimg, f->width, f->height, 3, &err) == LMC_OK)
    film_error_develop_to(f, eimg.data);
  /* The final image to the viewer first (with its error against the
   * reference in its name): it goes out while the files are written. */
  char label[LMC_LABEL_MAX] = "";
  if (ref) lmc_report_error(&img, ref, ref_path, NULL, label);
  tev_post(display, &img, eimg.data ? &eimg : NULL, label);
  lmc_status wst = eimg.data ? image_write_exr_layer(exr_path, &img, "error", &eimg, &err)
                             : image_write_exr(exr_path, &img, &err);
  image_free(&eimg);
  if (wst) {
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
  size_t n = (size_t)img.width * img.height * img.channels, nonzero = 0;
  for (size_t i = 0; i < n; i++) nonzero += img.data[i] != 0.0f;
  *OUT_black = n > 0 && nonzero == 0;
  if (*OUT_black && warn_black) lmc_warn(scene_path, 0, "the image is black: nothing lit was seen");
  image_free(&img);
  return 1;
}

/* The drivers' snapshot hook (settings.h), shared by --snapshot, which
 * writes OUTSTEM-<seconds>s.exr (safe write: temporary file and rename, as
 * the final output), and --display-server, which sends the image to tev;
 * each at its own interval, the film developed once for both. */
typedef struct lmc_snapshot_ctx {
  const char *out_exr;
  double file_every, next_file; /* --snapshot (0: none) */
  lmc_tev *display;             /* --display-server (NULL: none) */
  double display_every, next_display;
  lmc_image img;                /* owned: the developed film, kept from one call to the next */
  lmc_image eimg;               /* owned: its standard error (--error on; else empty) */
  const lmc_image *ref;         /* --reference (NULL: none) */
  const char *ref_path;
  double ref_every, next_ref;
  char label[LMC_LABEL_MAX];    /* the last error against it, for the viewer */
} lmc_snapshot_ctx;

static void lmc_write_snapshot(const lmc_snapshot_ctx *sc, const lmc_image *img,
                               const lmc_image *eimg, double seconds) {
  char path[1100], stem[1024];
  snprintf(stem, sizeof stem, "%s", sc->out_exr);
  size_t len = strlen(stem);
  if (len > 4 && strcmp(stem + len - 4, ".exr") == 0) stem[len - 4] = '\0';
  snprintf(path, sizeof path, "%s-%.1fs.exr", stem, seconds);
  lmc_error err;
  lmc_error_clear(&err);
  if (eimg->data ? image_write_exr_layer(path, img, "error", eimg, &err)
                 : image_write_exr(path, img, &err)) {
    char msg[2048];
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: snapshot: %s\n", msg);
  }
}

static void lmc_on_snapshot(void *ctx, const struct film *f, double seconds) {
  lmc_snapshot_ctx *sc = ctx;
  int file = sc->file_every > 0.0 && seconds >= sc->next_file;
  int display = sc->display && seconds >= sc->next_display;
  int refd = sc->ref && seconds >= sc->next_ref;
  if (!file && !display && !refd) return;
  lmc_error err;
  lmc_error_clear(&err);
  if (!sc->img.data && image_init(&sc->img, f->width, f->height, 3, &err)) {
    char msg[2048];
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: snapshot: %s\n", msg);
  } else {
    film_develop_to(f, sc->img.data);
    /* (the error too, when the film has one: the files' and the viewer's
     * channels; an error without memory for it is left out) */
    if (film_has_error(f) && !sc->eimg.data &&
        image_init(&sc->eimg, f->width, f->height, 3, &err))
      image_free(&sc->eimg);
    if (film_has_error(f) && sc->eimg.data) film_error_develop_to(f, sc->eimg.data);
    if (file) lmc_write_snapshot(sc, &sc->img, &sc->eimg, seconds);
    if (refd) lmc_report_error(&sc->img, sc->ref, sc->ref_path, &seconds, sc->label);
    if (display) tev_post(sc->display, &sc->img, sc->eimg.data ? &sc->eimg : NULL, sc->label);
  }
  while (file && sc->next_file <= seconds) sc->next_file += sc->file_every;
  while (display && sc->next_display <= seconds) sc->next_display += sc->display_every;
  while (refd && sc->next_ref <= seconds) sc->next_ref += sc->ref_every;
}

/* --display-server: the client, showing the image under the output's
 * file name (NULL, after a message, when it cannot start: the render
 * goes on without it). Rank 0 alone shows the image. */
static lmc_tev *lmc_display_start(const render_settings *rs, const scene *s, const char *out_exr) {
  if (!rs->display_server[0] || dist_rank() != 0) return NULL;
  const char *slash = strrchr(out_exr, '/');
  lmc_tev *t = NULL;
  lmc_error err;
  lmc_error_clear(&err);
  if (tev_create(&t, rs->display_server, slash ? slash + 1 : out_exr, s->cam.width,
                 s->cam.height, rs->error, &err)) {
    char msg[2048];
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: flag --display-server: %s (rendering without it)\n", msg);
    return NULL;
  }
  return t;
}

/* Rank 0's end of a render: writes the image and prints the summary
 * (per_rank: every rank's rays and samples, NULL in one process); the
 * exit status. */
static int render__finish(const scene *s, const render_settings *rs, const film *f,
                          const render_stats *st, const int64_t *per_rank, const char *out_exr,
                          char *out_png, size_t png_size, const lmc_exposure *exposure,
                          const char *scene_path, double t_load, const lmc_snapshot_ctx *snap) {
  int black = 0;
  int ok = lmc_write_outputs(f, out_exr, out_png, png_size, exposure, scene_path,
                             s->n_lights > 0, snap->display, snap->ref, snap->ref_path, &black);
  if (dist_active()) {
    fprintf(stderr, "lmc: %d processes (MPI ranks), the image and counts of all of them\n",
            dist_size());
    for (int r = 0; r < dist_size(); r++)
      fprintf(stderr, "lmc: rank %d: %.4g rays, %lld %s\n", r, (double)per_rank[2 * r],
              (long long)per_rank[2 * r + 1],
              mcmc_is_integrator(rs->integrator) ? "mutations" : "camera samples");
  }
  fprintf(stderr,
          "lmc: %s %dx%d, %lld spp (%lld samples) in %.2f s (load %.2f s), %.3g rays, "
          "%.3g Mrays/s%s%s\n",
          rs->integrator, f->width, f->height, (long long)st->passes, (long long)st->samples,
          st->seconds, t_load, (double)st->rays, st->rays / fmax(st->seconds, 1e-9) / 1e6,
          st->interrupted ? ", interrupted" : "", st->timed_out ? ", time limit reached" : "");
  if (st->nan_samples > 0)
    fprintf(stderr, "lmc: dropped %lld non-finite samples\n", (long long)st->nan_samples);
  if (ok) printf("wrote %s\nwrote %s\n", out_exr, out_png);
  if (!ok) return EXIT_FAIL;
  if (st->interrupted) return render_stop_signal() == SIGTERM ? EXIT_SIGTERM : EXIT_SIGINT;
  if (black && rs->strict) {
    fprintf(stderr, "lmc: --strict: the image is black\n");
    return EXIT_BADINPUT;
  }
  return EXIT_OK;
}

/* Renders s with rs, then writes what there is even when interrupted;
 * the exit status. */
static int render__run(scene *s, render_settings *rs, const char *output, const char *scene_path,
                       const lmc_exposure *exposure, double t_load, const lmc_image *ref,
                       const char *ref_path) {
  char out_exr[1024], out_png[1100];
  if (output)
    snprintf(out_exr, sizeof out_exr, "%s", output);
  else
    lmc_default_output(scene_path, out_exr, sizeof out_exr);
  /* -o OUT.png names the preview: the EXR is OUT.exr beside it. */
  size_t len = strlen(out_exr);
  if (len > 4 && strcasecmp(out_exr + len - 4, ".png") == 0) memcpy(out_exr + len - 4, ".exr", 4);
  /* The snapshot hook: the files of --snapshot and the viewer of
   * --display-server, the drivers calling at the shorter interval. */
  lmc_snapshot_ctx snap = {out_exr, rs->snapshot, rs->snapshot, NULL, rs->display_interval,
                           rs->display_interval, {0, 0, 0, NULL}, {0, 0, 0, NULL}, NULL, NULL,
                           0.0, 0.0, ""};
  snap.display = lmc_display_start(rs, s, out_exr);
  /* --reference: at each snapshot, else with the viewer, else every 5 s. */
  if (ref && dist_rank() == 0) {
    snap.ref = ref, snap.ref_path = ref_path;
    snap.ref_every = rs->snapshot > 0.0         ? rs->snapshot
                     : rs->display_server[0] ? rs->display_interval
                                             : LMC_REFERENCE_EVERY;
    snap.next_ref = snap.ref_every;
  }
  /* (On every rank alike: the snapshots are collective.) */
  if (rs->display_server[0] && (rs->snapshot <= 0.0 || rs->display_interval < rs->snapshot))
    rs->snapshot = rs->display_interval;
  if (ref && rs->snapshot <= 0.0) rs->snapshot = LMC_REFERENCE_EVERY;
  if (rs->snapshot > 0.0) {
    rs->snapshot_fn = lmc_on_snapshot;
    rs->snapshot_ctx = &snap;
  }
  film f;
  render_stats st;
  lmc_error err;
  lmc_error_clear(&err);
  lmc_status rst = mcmc_is_integrator(rs->integrator) ? mcmc_render_run(s, rs, &f, &st, &err)
                                                        : render_run(s, rs, &f, &st, &err);
  if (rst) {
    char msg[2048];
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
    tev_destroy(snap.display, 0.0);
    image_free(&snap.img);
    image_free(&snap.eimg);
    /* Settings the render refused (a combination of flags no table can
     * check alone: --pss-weight without --pss-mutation, ...) are bad
     * input, as a bad flag is. */
    return rst == LMC_ESTRICT || rst == LMC_EINVAL || rst == LMC_EUNSUPPORTED ? EXIT_BADINPUT
                                                                              : EXIT_FAIL;
  }
  image_free(&snap.img); /* (the snapshots are over) */
  image_free(&snap.eimg);
  /* Every rank's own rays and samples, for rank 0's summary. */
  int64_t *per_rank = dist_active() ? calloc(2 * (size_t)dist_size(), sizeof *per_rank) : NULL;
  if (dist_active() && !per_rank) dist_abort(EXIT_FAIL);
  if (per_rank) {
    per_rank[2 * dist_rank()] = st.rank_rays, per_rank[2 * dist_rank() + 1] = st.rank_samples;
    dist_allsum_i64(per_rank, 2 * (size_t)dist_size());
  }
  if (dist_rank() != 0) {
    free(per_rank);
    film_free(&f);
    /* Rank 0 holds the image of every rank (dist.h) and writes it; the
     * others wait for it and exit with its status (a launcher ends the
     * whole job when a rank exits with a failure, even Ctrl-C's 130). */
    double c = EXIT_FAIL;
    dist_broadcast(&c, 1);
    return (int)c;
  }
  int code = render__finish(s, rs, &f, &st, per_rank, out_exr, out_png, sizeof out_png, exposure,
                            scene_path, t_load, &snap);
  /* The last image to the viewer: a short wait at most. */
  tev_destroy(snap.display, LMC_DISPLAY_LAST_WAIT);
  free(per_rank);
  film_free(&f);
  if (dist_active()) {
    double c = code;
    dist_broadcast(&c, 1);
  }
  return code;
}

/* What the command line gives the render besides the flag tables. */
typedef struct lmc_render_input {
  const char *scene_path, *output;
  const char **defines; /* owned: freed by render__load_and_run */
  int n_defines;
  int res_w, res_h; /* --resolution (0: the scene's) */
  const scene_load_options *lopts;
  const lmc_exposure *exposure;
  const char *reference; /* --reference (NULL: none) */
} lmc_render_input;

/* Loads the scene, merges its settings with the flags (given[] is owned
 * and freed here), refuses under --strict when anything was warned about,
 * renders and writes; the exit status. */
static int render__load_and_run(const lmc_render_input *in, const render_settings *cli,
                                lmc_given *given, int n_given) {
  lmc_error err;
  lmc_error_clear(&err);
  scene *s = NULL;
  double t_load = omp_get_wtime();
  lmc_status lst =
      scene_load_xml_opts(in->scene_path, in->defines, in->n_defines, in->lopts, &s, &err);
  free(in->defines);
  if (lst) {
    char msg[2048];
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
    free(given);
    return EXIT_BADINPUT;
  }
  t_load = omp_get_wtime() - t_load;
  if (in->res_w > 0) camera_set_resolution(&s->cam, in->res_w, in->res_h);

  /* Its settings and the flags, then the render. */
  render_settings rs;
  lmc_status sst = lmc_render_settings(s, in->scene_path, cli, given, n_given, &rs, &err);
  free(given);
  if (sst) {
    char msg[2048];
    lmc_error_format(&err, msg, sizeof msg);
    fprintf(stderr, "lmc: %s\n", msg);
    scene_destroy(s);
    return EXIT_BADINPUT;
  }
  render_media_note(s, rs.integrator,
                    render_integrator_media(rs.integrator) || mcmc_renders_media(&rs));
  /* --strict: every warning so far (a plugin lmc lacks or replaced, a
   * scene without light, media the integrator does not render, ...)
   * means the image would not be the scene's. */
  if (rs.strict && lmc_warning_count() > 0) {
    fprintf(stderr, "lmc: --strict: %s loaded with %d warning%s (above): not rendering\n",
            in->scene_path, lmc_warning_count(), lmc_warning_count() == 1 ? "" : "s");
    scene_destroy(s);
    return EXIT_BADINPUT;
  }
  /* --reference: an image of the film's size. */
  lmc_image ref = {0};
  if (in->reference) {
    char msg[2048];
    if (image_read(in->reference, 0, &ref, &err) || image_to_rgb(&ref, &err)) {
      lmc_error_format(&err, msg, sizeof msg);
      fprintf(stderr, "lmc: flag --reference: %s\n", msg);
      image_free(&ref);
      scene_destroy(s);
      return EXIT_BADINPUT;
    }
    if (ref.width != s->cam.width || ref.height != s->cam.height) {
      fprintf(stderr, "lmc: flag --reference: %s is %dx%d but the render is %dx%d\n",
              in->reference, ref.width, ref.height, s->cam.width, s->cam.height);
      image_free(&ref);
      scene_destroy(s);
      return EXIT_BADINPUT;
    }
  }
  int status = render__run(s, &rs, in->output, in->scene_path, in->exposure, t_load,
                           in->reference ? &ref : NULL, in->reference);
  image_free(&ref);
  scene_destroy(s);
  return status;
}

int lmc_cmd_render(int argc, char **argv) {
  const char *scene_path = NULL, *output = NULL, *reference = NULL;
  const char **defines = calloc((size_t)argc + 1, sizeof(char *));
  int n_defines = 0;
  render_settings cli = render_settings_default();
  cli.set = 0;
  int res_w = 0, res_h = 0;
  scene_load_options lopts = {SPECTRUM_INTERP_LINEAR};
  lmc_exposure exposure = {0, 0.0};
  lmc_args a = {argc, 2, argv, NULL};
  if (!defines) return EXIT_FAIL;
  /* Ctrl-C while the scene loads: the render then ends at once and
   * writes what it has (main installed the handlers before MPI too). */
  lmc_render_catch_signals();

  /* Parse the flags; the scene's own settings are merged below. The flags
   * of the tables are checked into cli now and applied to the scene's
   * settings after loading (given[]). */
  const lmc_opt_table *tables[LMC_MAX_TABLES];
  int n_tables = lmc_option_tables(tables);
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
        fprintf(stderr, "lmc: flag --integrator: unknown integrator '%s' (valid: pt, bdpt, direct",
                v);
        for (int i = 0; i < n; i++) fprintf(stderr, ", %s", names[i]);
        fprintf(stderr, ")\n");
        goto bad;
      }
      snprintf(cli.integrator, sizeof cli.integrator, "%s", v);
      cli.set |= SET_INTEGRATOR;
    } else if (lmc_flag_is(&a, "--spectra")) {
      if (!(v = lmc_flag_value(&a))) goto bad;
      if (strcmp(v, "linear") == 0) lopts.spectra = SPECTRUM_INTERP_LINEAR;
      else if (strcmp(v, "mitsuba-0.6.0") == 0) lopts.spectra = SPECTRUM_INTERP_MITSUBA_060;
      else {
        fprintf(stderr, "lmc: flag --spectra: unknown value '%s' (linear or mitsuba-0.6.0)\n", v);
        goto bad;
      }
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
    } else if (lmc_flag_is(&a, "--reference")) {
      if (!(reference = lmc_flag_value(&a))) goto bad;
    } else if (lmc_flag_is(&a, "--exposure")) {
      if (!(v = lmc_flag_value(&a)) || !lmc_parse_exposure(v, &exposure)) goto bad;
    } else if (lmc_flag_is(&a, "-q") || lmc_flag_is(&a, "--quiet")) {
      cli.quiet = 1;
    } else if (lmc_flag_is(&a, "--strict")) {
      cli.strict = 1;
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

  lmc_render_input in = {scene_path, output,  defines,   n_defines, res_w,
                         res_h,      &lopts,  &exposure, reference};
  return render__load_and_run(&in, &cli, given, n_given);
bad:
  free(defines), free(given);
  return EXIT_BADINPUT;
}

