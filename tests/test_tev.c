/*
 * test_tev.c: `lmc render --display-server` (render/io/tev.h) against
 * receivers written here, on 127.0.0.1 at an ephemeral port, in a thread
 * of this process while the binary renders:
 *
 *  - a parsing receiver reads every byte and checks it against tev's
 *    protocol: each connection opens with CreateImage (the output's file
 *    name, the film's size, channels R, G, B), then only UpdateImageV3
 *    packets (the name, R, G, B, a tile inside the image of at most
 *    TEV_TILE a side, offsets 0 1 2 and strides 3, exactly the tile's
 *    floats after the header as the length field says); the tiles of each
 *    image cover it exactly once; the last image equals the EXR written,
 *    bit for bit. Once with pt under --time (several images), once with
 *    pssmlt under --spp, whose EXR must also be the one the same seed
 *    gives without the flag; with --reference the images are named
 *    "OUT relmse X", each new name after a CloseImage of the old, the
 *    last with the final line's relmse; with --error on (pssmlt, pt) the
 *    channels are R, G, B, error.R, error.G, error.B (offsets 0 .. 5,
 *    strides 6), the last image equals the EXR's image and error layers,
 *    and --snapshot's files carry the error layer;
 *  - a receiver that accepts and never reads (a small receive buffer), one
 *    that closes at once, and none at all (a closed port): the render
 *    exits 0 with the image the same seed gives without the flag, in the
 *    time of a render without it plus DISPLAY_MARGIN seconds, and warns
 *    once naming the address; under --time it ends within the limit plus
 *    DISPLAY_MARGIN;
 *  - bad addresses exit 2 with a message naming the flag.
 * The counts of packets, images, pixels and runs checked are asserted.
 */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <arpa/inet.h>
#include <dirent.h>
#include <math.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "render/image.h"
#include "render/io/tev.h"
#include "test_util.h"

#define SCENE "data/analytic/diffuse_sphere.xml"
#define CBOX "../scenes/cornell-box/scene.xml" /* (the MCMC runs: light on long paths) */
#define TMP LMC_TEST_TMP "/lmc_test_tev"
/* Seconds a render with a display may take beyond one without. */
#define DISPLAY_MARGIN 3.0

static char err_text[1 << 16];

static double now_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Runs `lmc render SCENE ARGS -q -o TMP/OUT` (under timeout; the scene
 * CBOX for the MCMC integrators, else SCENE); its exit status, its wall
 * time in *OUT_seconds, its stderr in err_text. */
static int render(const char *args, const char *out, double *OUT_seconds) {
  char cmd[4096];
  snprintf(cmd, sizeof cmd,
           "timeout 60 '%s' render '%s' %s -q -o '" TMP "/%s' > " TMP "/out.txt 2> " TMP
           "/err.txt",
           LMC_BINARY, strstr(args, "pssmlt") ? CBOX : SCENE, args, out);
  double t0 = now_seconds();
  int rc = system(cmd);
  *OUT_seconds = now_seconds() - t0;
  slurp_text(TMP "/err.txt", err_text, sizeof err_text);
  if (rc == -1 || !WIFEXITED(rc)) return -1;
  return WEXITSTATUS(rc);
}

static lmc_image read_exr(const char *name) {
  char path[1024];
  snprintf(path, sizeof path, TMP "/%s", name);
  lmc_image img = {0};
  lmc_error err;
  if (image_read_exr(path, &img, &err)) fail_msg("%s: %s", path, err.msg);
  assert_int_equal(img.channels, 3);
  return img;
}

/* The number of float bits that differ between two EXRs of the same size. */
static long exr_differences(const char *a, const char *b) {
  lmc_image x = read_exr(a), y = read_exr(b);
  assert_int_equal(x.width, y.width);
  assert_int_equal(x.height, y.height);
  long diff = 0;
  for (size_t i = 0; i < 3 * (size_t)x.width * (size_t)x.height; i++)
    diff += memcmp(&x.data[i], &y.data[i], sizeof(float)) != 0;
  image_free(&x);
  image_free(&y);
  return diff;
}

/* --- the receivers -------------------------------------------------------------- */

typedef enum { RECV_PARSE, RECV_NOREAD, RECV_CLOSE } recv_mode;

typedef struct receiver {
  recv_mode mode;
  int listen_fd, port;
  volatile int stop;
  pthread_t thread;
  pthread_mutex_t mu;
  /* PARSE: every connection's bytes, one after the other. */
  unsigned char *bytes;
  size_t n_bytes, cap;
  size_t conn_start[64];
  int connections;
  /* NOREAD: the connections held open. */
  int held[64];
  int n_held;
} receiver;

static void append(receiver *r, const unsigned char *p, size_t n) {
  if (r->n_bytes + n > r->cap) {
    r->cap = 2 * (r->n_bytes + n);
    r->bytes = realloc(r->bytes, r->cap);
    assert_non_null(r->bytes);
  }
  memcpy(r->bytes + r->n_bytes, p, n);
  r->n_bytes += n;
}

/* Serves one accepted connection as the mode says. */
static void serve(receiver *r, int fd) {
  if (r->mode == RECV_CLOSE) {
    close(fd);
    r->connections++;
    return;
  }
  if (r->mode == RECV_NOREAD) {
    if (r->n_held < 64) r->held[r->n_held++] = fd;
    else close(fd);
    r->connections++;
    return;
  }
  if (r->connections < 64) r->conn_start[r->connections] = r->n_bytes;
  r->connections++;
  unsigned char buf[1 << 16];
  for (;;) {
    ssize_t k = recv(fd, buf, sizeof buf, 0);
    if (k <= 0) break;
    append(r, buf, (size_t)k);
  }
  close(fd);
}

static void *receiver_main(void *arg) {
  receiver *r = arg;
  for (;;) {
    struct pollfd p = {r->listen_fd, POLLIN, 0};
    int ready = poll(&p, 1, 20);
    if (ready > 0) {
      int fd = accept(r->listen_fd, NULL, NULL);
      if (fd >= 0) serve(r, fd);
    } else if (r->stop) {
      break; /* (nothing pending: the render has exited) */
    }
  }
  return NULL;
}

/* Listens on 127.0.0.1 at an ephemeral port; NOREAD with a small receive
 * buffer (set before listen, so accepted sockets inherit it). */
static void receiver_start(receiver *r, recv_mode mode) {
  memset(r, 0, sizeof *r);
  r->mode = mode;
  r->listen_fd = socket(AF_INET, SOCK_STREAM, 0);
  assert_true(r->listen_fd >= 0);
  if (mode == RECV_NOREAD) {
    int small = 4096;
    setsockopt(r->listen_fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
  }
  struct sockaddr_in a;
  memset(&a, 0, sizeof a);
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  assert_int_equal(bind(r->listen_fd, (struct sockaddr *)&a, sizeof a), 0);
  assert_int_equal(listen(r->listen_fd, 16), 0);
  socklen_t len = sizeof a;
  assert_int_equal(getsockname(r->listen_fd, (struct sockaddr *)&a, &len), 0);
  r->port = ntohs(a.sin_port);
  assert_int_equal(pthread_create(&r->thread, NULL, receiver_main, r), 0);
}

static void receiver_stop(receiver *r) {
  r->stop = 1;
  pthread_join(r->thread, NULL);
  close(r->listen_fd);
  for (int i = 0; i < r->n_held; i++) close(r->held[i]);
}

/* A port of 127.0.0.1 nobody listens on: bound, then closed. */
static int closed_port(void) {
  int fd = socket(AF_INET, SOCK_STREAM, 0);
  struct sockaddr_in a;
  memset(&a, 0, sizeof a);
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  assert_int_equal(bind(fd, (struct sockaddr *)&a, sizeof a), 0);
  socklen_t len = sizeof a;
  assert_int_equal(getsockname(fd, (struct sockaddr *)&a, &len), 0);
  close(fd);
  return ntohs(a.sin_port);
}

/* --- the protocol ------------------------------------------------------------------ */

/* A reader of one packet's bytes: each read fails the test past the end. */
typedef struct rd {
  const unsigned char *p;
  size_t at, n;
} rd;

static uint64_t rd_le(rd *r, int bytes) {
  if (r->at + (size_t)bytes > r->n) fail_msg("packet ends inside a field at byte %zu", r->at);
  uint64_t v = 0;
  for (int i = 0; i < bytes; i++) v |= (uint64_t)r->p[r->at + (size_t)i] << (8 * i);
  r->at += (size_t)bytes;
  return v;
}

static int32_t rd_i32(rd *r) { return (int32_t)(uint32_t)rd_le(r, 4); }

static const char *rd_str(rd *r) {
  const char *s = (const char *)r->p + r->at;
  const void *nul = memchr(s, 0, r->n - r->at);
  if (!nul) fail_msg("string without its NUL at byte %zu", r->at);
  r->at += strlen(s) + 1;
  return s;
}

/* The channels a run's packets must carry: 3, or 6 with --error on. */
static int g_nch = 3;

static void rd_channels(rd *r) {
  static const char *names[6] = {"R", "G", "B", "error.R", "error.G", "error.B"};
  assert_int_equal(rd_i32(r), g_nch);
  for (int c = 0; c < g_nch; c++) assert_string_equal(rd_str(r), names[c]);
}

/* What the parse of one run found. */
typedef struct tally {
  int creates, updates, full_images, closes;
  int last_full;   /* the last image's tiles covered it */
  float *canvas;   /* the image as the viewer would show it */
  char last_name[256]; /* the name of the last image */
} tally;

/* An image's name: the output's file name, or it and a label "relmse X"
 * (--reference). */
static void check_name(const char *got, const char *name) {
  size_t n = strlen(name);
  if (strncmp(got, name, n) != 0) fail_msg("image name '%s', expected '%s...'", got, name);
  if (got[n] == 0) return;
  double x;
  char rest[8];
  if (sscanf(got + n, " relmse %lf%7s", &x, rest) != 1 || !(x >= 0.0))
    fail_msg("image name '%s': not '%s relmse X'", got, name);
}

/* Checks one connection's packets (bytes [0, n)), painting the tiles. */
static void parse_connection(const unsigned char *b, size_t n, const char *name, int W, int H,
                             tally *t, int *stamp, int *image_id) {
  size_t off = 0;
  long area = 0;
  int first = 1;
  char shown[256] = "";
  while (off < n) {
    if (n - off < 5) fail_msg("%zu bytes left: no packet header", n - off);
    rd r = {b + off, 0, n - off};
    uint32_t len = (uint32_t)rd_le(&r, 4);
    if (len < 6 || len > n - off) fail_msg("length %u with %zu bytes left", len, n - off);
    r.n = len; /* (reads past the length fail) */
    int type = (int)rd_le(&r, 1);
    if (type == TEV_CLOSE_IMAGE && !first) {
      /* CloseImage of the image shown (its name changes): its name alone,
       * and CreateImage next. */
      assert_string_equal(rd_str(&r), shown);
      assert_int_equal(r.at, len);
      t->closes++;
      first = 1;
      off += len;
      continue;
    }
    int focus = (int)rd_le(&r, 1);
    assert_true(focus == 0 || focus == 1);
    const char *got = rd_str(&r);
    if (first) {
      check_name(got, name);
      snprintf(shown, sizeof shown, "%s", got);
      snprintf(t->last_name, sizeof t->last_name, "%s", got);
    } else {
      assert_string_equal(got, shown);
    }
    if (first) {
      /* CreateImage: the size and channels, nothing more. */
      assert_int_equal(type, TEV_CREATE_IMAGE);
      assert_int_equal(rd_i32(&r), W);
      assert_int_equal(rd_i32(&r), H);
      rd_channels(&r);
      assert_int_equal(r.at, len);
      t->creates++;
      first = 0;
      off += len;
      continue;
    }
    /* UpdateImageV3: a tile inside the image, its channels interleaved. */
    assert_int_equal(type, TEV_UPDATE_IMAGE_V3);
    rd_channels(&r);
    int x = rd_i32(&r), y = rd_i32(&r), w = rd_i32(&r), h = rd_i32(&r);
    if (x < 0 || y < 0 || w <= 0 || h <= 0 || w > TEV_TILE || h > TEV_TILE || x + w > W ||
        y + h > H)
      fail_msg("tile %d,%d %dx%d in an image of %dx%d", x, y, w, h, W, H);
    const size_t nch = (size_t)g_nch;
    for (size_t c = 0; c < nch; c++) assert_int_equal((int64_t)rd_le(&r, 8), (int64_t)c);
    for (size_t c = 0; c < nch; c++) assert_int_equal((int64_t)rd_le(&r, 8), (int64_t)nch);
    if (len - r.at != 4 * nch * (size_t)w * (size_t)h)
      fail_msg("tile %dx%d: %zu bytes of values, expected %zu", w, h, len - r.at,
               4 * nch * (size_t)w * (size_t)h);
    /* A tile at the origin begins an image; each pixel once per image. */
    if (x == 0 && y == 0) ++*image_id, area = 0;
    for (int j = 0; j < h; j++)
      for (int i = 0; i < w; i++) {
        size_t px = (size_t)(y + j) * (size_t)W + (size_t)(x + i);
        if (stamp[px] == *image_id) fail_msg("pixel %d,%d sent twice in one image", x + i, y + j);
        stamp[px] = *image_id;
        for (size_t c = 0; c < nch; c++) {
          uint32_t bits = (uint32_t)rd_le(&r, 4);
          memcpy(&t->canvas[nch * px + c], &bits, sizeof bits);
        }
      }
    area += (long)w * h;
    t->last_full = area == (long)W * H;
    t->full_images += t->last_full;
    t->updates++;
    off += len;
  }
}

/* Checks everything the parsing receiver got. */
static void parse_all(const receiver *rv, const char *name, int W, int H, tally *t) {
  memset(t, 0, sizeof *t);
  t->canvas = calloc((size_t)g_nch * (size_t)W * (size_t)H, sizeof(float));
  int *stamp = calloc((size_t)W * (size_t)H, sizeof(int));
  assert_non_null(t->canvas);
  assert_non_null(stamp);
  int image_id = 0;
  assert_true(rv->connections >= 1 && rv->connections <= 64);
  for (int c = 0; c < rv->connections; c++) {
    size_t end = c + 1 < rv->connections ? rv->conn_start[c + 1] : rv->n_bytes;
    parse_connection(rv->bytes + rv->conn_start[c], end - rv->conn_start[c], name, W, H, t,
                     stamp, &image_id);
  }
  free(stamp);
}

/* The viewer's last image against the EXR: the pixel values compared
 * (and with g_nch 6 the error channels against the EXR's). */
static long canvas_equals_exr(const tally *t, const char *exr) {
  lmc_image img = read_exr(exr), eimg = {0};
  if (g_nch == 6) {
    char path[1024];
    snprintf(path, sizeof path, TMP "/%s", exr);
    lmc_error err;
    if (image_read_exr_layer(path, "error", &eimg, &err)) fail_msg("%s: %s", path, err.msg);
  }
  long n = 3L * img.width * img.height, same = 0;
  for (long i = 0; i < n; i++) {
    long px = i / 3, c = i % 3;
    same += !memcmp(&t->canvas[g_nch * px + c], &img.data[i], sizeof(float));
    if (g_nch == 6) same += !memcmp(&t->canvas[6 * px + 3 + c], &eimg.data[i], sizeof(float));
  }
  long want = n * (g_nch / 3);
  if (same != want)
    fail_msg("%s: %ld of %ld values differ from the viewer's image", exr, want - same, want);
  image_free(&img);
  image_free(&eimg);
  return same;
}

/* --- the tests ------------------------------------------------------------------------- */

static int setup(void **state) {
  (void)state;
  mkdir(TMP, 0755);
  return 0;
}

/* One render against the parsing receiver, checked; the packets' tally. */
static void parsed_render(const char *args, const char *out, int W, int H, tally *t) {
  receiver rv;
  receiver_start(&rv, RECV_PARSE);
  char full[2048];
  snprintf(full, sizeof full, "%s --resolution %dx%d --display-server 127.0.0.1:%d", args, W, H,
           rv.port);
  double secs;
  int rc = render(full, out, &secs);
  receiver_stop(&rv);
  if (rc != 0) fail_msg("lmc render %s: exit %d: %s", full, rc, err_text);
  if (strstr(err_text, "display server")) fail_msg("a warning with a viewer present: %s", err_text);
  parse_all(&rv, out, W, H, t);
  free(rv.bytes);
  fprintf(stderr, "  %s: %d connection(s), %d CreateImage, %d tiles, %d whole images, %.2f s\n",
          out, rv.connections, t->creates, t->updates, t->full_images, secs);
  assert_int_equal(t->creates, rv.connections + t->closes);
  assert_true(t->last_full);
}

static void test_protocol_pt(void **state) {
  (void)state;
  /* 300x170: tiles of 128 and the edge tiles of 44 and 42. */
  tally t;
  /* --snapshot's files at their interval beside the display at its own. */
  system("rm -f " TMP "/tev_pt-*.exr");
  parsed_render("--integrator pt --time 1.5 --threads 2 --display-interval 0.2 --snapshot 0.5",
                "tev_pt.exr", 300, 170, &t);
  assert_true(t.full_images >= 4); /* images during the render, and the last */
  /* (named by the second they were taken at: the first display tick
   * after each multiple of 0.5 s) */
  int files = 0;
  DIR *d = opendir(TMP);
  assert_non_null(d);
  for (struct dirent *e; (e = readdir(d));)
    files += !strncmp(e->d_name, "tev_pt-", 7) && strstr(e->d_name, "s.exr");
  closedir(d);
  fprintf(stderr, "  %d snapshot files beside the display\n", files);
  assert_true(files >= 2 && files <= 3);
  assert_int_equal(t.updates % 6, 0);
  assert_int_equal(canvas_equals_exr(&t, "tev_pt.exr"), 3L * 300 * 170);
  free(t.canvas);
}

static void test_protocol_pssmlt(void **state) {
  (void)state;
  tally t;
  const char *args = "--integrator pssmlt --spp 6 --bootstrap 16384 --seed 5 --threads 2 "
                     "--display-interval 0.05";
  parsed_render(args, "tev_pssmlt.exr", 160, 120, &t);
  assert_true(t.full_images >= 3); /* images of the chains' snapshots, and the last */
  assert_int_equal(canvas_equals_exr(&t, "tev_pssmlt.exr"), 3L * 160 * 120);
  free(t.canvas);
  /* The same image without the display: snapshots change nothing. */
  double secs;
  char plain[512];
  snprintf(plain, sizeof plain, "%s --resolution 160x120", args);
  assert_int_equal(render(plain, "tev_pssmlt_plain.exr", &secs), 0);
  assert_int_equal(exr_differences("tev_pssmlt.exr", "tev_pssmlt_plain.exr"), 0);
}

/* --error on: the viewer's images carry the error as channels error.R,
 * G, B, and the last equals the EXR's image and error layers; pssmlt (the
 * chains' groups at each snapshot) and pt under --time (its passes), each
 * of whose --snapshot files carries the error layer too, finite once two
 * passes are done. */
static void test_protocol_error(void **state) {
  (void)state;
  g_nch = 6;
  tally t;
  parsed_render("--integrator pssmlt --spp 6 --bootstrap 16384 --seed 5 --threads 2 "
                "--display-interval 0.05 --error on",
                "tev_err_pssmlt.exr", 160, 120, &t);
  assert_true(t.full_images >= 3);
  assert_int_equal(canvas_equals_exr(&t, "tev_err_pssmlt.exr"), 6L * 160 * 120);
  free(t.canvas);
  system("rm -f " TMP "/tev_err_pt-*.exr");
  parsed_render("--integrator pt --time 1.5 --threads 2 --display-interval 0.2 --snapshot 0.5 "
                "--error on",
                "tev_err_pt.exr", 300, 170, &t);
  assert_true(t.full_images >= 4);
  assert_int_equal(canvas_equals_exr(&t, "tev_err_pt.exr"), 6L * 300 * 170);
  free(t.canvas);
  g_nch = 3;
  int files = 0;
  DIR *d = opendir(TMP);
  assert_non_null(d);
  for (struct dirent *e; (e = readdir(d));) {
    if (strncmp(e->d_name, "tev_err_pt-", 11) || !strstr(e->d_name, "s.exr")) continue;
    char path[1024];
    snprintf(path, sizeof path, TMP "/%s", e->d_name);
    lmc_image eimg = {0};
    lmc_error err;
    if (image_read_exr_layer(path, "error", &eimg, &err)) fail_msg("%s: %s", path, err.msg);
    long finite = 0, n = 3L * eimg.width * eimg.height;
    for (long i = 0; i < n; i++) finite += isfinite(eimg.data[i]);
    assert_int_equal(finite, n);
    image_free(&eimg);
    files++;
  }
  closedir(d);
  assert_true(files >= 2 && files <= 3);
}

/* --reference: the viewer's image is named "OUT relmse X" after the error
 * of the image it shows; a new name closes the old image and creates it
 * again; the last name carries the final line's relmse. */
static void test_reference_name(void **state) {
  (void)state;
  double secs;
  assert_int_equal(render("--integrator pssmlt --spp 24 --bootstrap 16384 --seed 9 --threads 2 "
                          "--resolution 160x120",
                          "tev_ref.exr", &secs),
                   0);
  tally t;
  parsed_render("--integrator pssmlt --spp 6 --bootstrap 16384 --seed 5 --threads 2 "
                "--display-interval 0.05 --reference " TMP "/tev_ref.exr",
                "tev_named.exr", 160, 120, &t);
  const char *fin = strstr(err_text, "final image: relmse ");
  assert_non_null(fin);
  char want[128];
  double x;
  assert_int_equal(sscanf(fin, "final image: relmse %lf", &x), 1);
  snprintf(want, sizeof want, "tev_named.exr relmse %.6g", x);
  fprintf(stderr, "  last name '%s', %d CloseImage, %d CreateImage\n", t.last_name, t.closes,
          t.creates);
  assert_string_equal(t.last_name, want);
  assert_true(t.closes >= 1); /* the error changed as the chains ran */
  assert_int_equal(canvas_equals_exr(&t, "tev_named.exr"), 3L * 160 * 120);
  free(t.canvas);
}

/* The viewers that fail, each against the same render without one. */
static void test_robust(void **state) {
  (void)state;
  /* (images of 0.9 MB every 0.05 s: more than the kernel's buffers hold
   * for a viewer that never reads) */
  const char *args = "--integrator pt --spp 10 --seed 7 --threads 2 --resolution 320x240";
  double t_plain;
  assert_int_equal(render(args, "tev_plain.exr", &t_plain), 0);
  static const char *what[] = {"never reads", "closes at once", "absent"};
  int runs = 0;
  for (int mode = 0; mode < 3; mode++) {
    receiver rv;
    memset(&rv, 0, sizeof rv);
    int port = 0;
    if (mode < 2) {
      receiver_start(&rv, mode == 0 ? RECV_NOREAD : RECV_CLOSE);
      port = rv.port;
    } else {
      port = closed_port();
    }
    char full[1024], out[64];
    snprintf(full, sizeof full, "%s --display-server 127.0.0.1:%d --display-interval 0.05", args,
             port);
    snprintf(out, sizeof out, "tev_robust%d.exr", mode);
    double secs;
    int rc = render(full, out, &secs);
    if (mode < 2) receiver_stop(&rv);
    fprintf(stderr, "  viewer %s: exit %d in %.2f s (%.2f s without), %d connection(s)\n",
            what[mode], rc, secs, t_plain, mode < 2 ? rv.connections : 0);
    if (rc != 0) fail_msg("viewer %s: exit %d: %s", what[mode], rc, err_text);
    assert_le(secs, t_plain + DISPLAY_MARGIN);
    assert_int_equal(exr_differences(out, "tev_plain.exr"), 0);
    char where[64];
    snprintf(where, sizeof where, "display server 127.0.0.1:%d", port);
    const char *warn = strstr(err_text, where);
    if (!warn) fail_msg("viewer %s: no warning naming it: %s", what[mode], err_text);
    if (strstr(warn + 1, "display server"))
      fail_msg("viewer %s: warned more than once: %s", what[mode], err_text);
    if (mode < 2) assert_true(rv.connections >= 1);
    runs++;
  }
  assert_int_equal(runs, 3);
}

/* Under --time, a viewer that never reads: the limit plus the margin. */
static void test_time_limit_noread(void **state) {
  (void)state;
  receiver rv;
  receiver_start(&rv, RECV_NOREAD);
  char full[512];
  snprintf(full, sizeof full,
           "--integrator pssmlt --time 1.5 --threads 2 --resolution 300x200 "
           "--display-server 127.0.0.1:%d --display-interval 0.05",
           rv.port);
  double secs;
  int rc = render(full, "tev_time.exr", &secs);
  receiver_stop(&rv);
  fprintf(stderr, "  --time 1.5, a viewer that never reads: exit %d in %.2f s\n", rc, secs);
  if (rc != 0) fail_msg("exit %d: %s", rc, err_text);
  assert_le(secs, 1.5 + DISPLAY_MARGIN);
  assert_true(secs >= 1.5); /* (the chains ran: a render, not an early stop) */
  assert_true(rv.connections >= 1);
}

static void test_bad_addresses(void **state) {
  (void)state;
  static const char *bad[] = {"", ":14158", "host:0", "host:65536", "host:12ab", "a b",
                              "a..b", "host:"};
  int n = 0;
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char args[256];
    snprintf(args, sizeof args, "--spp 1 --resolution 4x4 '--display-server=%s'", bad[i]);
    double secs;
    int rc = render(args, "tev_bad.exr", &secs);
    if (rc != 2) fail_msg("--display-server '%s': exit %d, expected 2", bad[i], rc);
    if (!strstr(err_text, "--display-server"))
      fail_msg("--display-server '%s': the message does not name the flag: %s", bad[i], err_text);
    n++;
  }
  assert_int_equal(n, 8);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup(test_bad_addresses, setup),
      cmocka_unit_test_setup(test_protocol_pt, setup),
      cmocka_unit_test_setup(test_protocol_pssmlt, setup),
      cmocka_unit_test_setup(test_protocol_error, setup),
      cmocka_unit_test_setup(test_reference_name, setup),
      cmocka_unit_test_setup(test_robust, setup),
      cmocka_unit_test_setup(test_time_limit_noread, setup),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
