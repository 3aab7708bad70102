/*
 * tev.c: the tev viewer's client (tev.h): a one-slot mailbox the render
 * thread fills, and a sender thread that empties it over TCP.
 *
 * Invariants. The mutex guards the mailbox (slot, fresh) and the end
 * (closing, deadline, done, orphaned); everything else belongs to the
 * sender thread alone. The render thread holds the mutex only to copy an
 * image in; the sender only to swap that image with its own buffer, so
 * neither ever waits for the other's work, and the network is the
 * sender's alone. Every socket call is non-blocking and every wait is a
 * poll of at most TEV_SLICE_MS, after which the sender looks again at the
 * deadline tev_destroy may have set.
 *
 * A connection is dropped (and the warning given, once) when the viewer
 * refuses or closes it, an error occurs, or a connection or a whole image
 * takes longer than TEV_CONNECT_SECONDS or TEV_FRAME_SECONDS (a viewer too
 * slow to read: the render's images would pile up in the kernel's
 * buffers). Images posted while disconnected are dropped until the
 * back-off has passed; the next connection creates the image again.
 */
#define _POSIX_C_SOURCE 200809L
#include "render/io/tev.h"

#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <poll.h>
#include <pthread.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>

#include "render/options.h"

#define TEV_BACKOFF_MIN 1.0      /* seconds before the first retry */
#define TEV_BACKOFF_MAX 30.0     /* the longest wait between retries */
#define TEV_CONNECT_SECONDS 2.0  /* for a connection to be made */
#define TEV_FRAME_SECONDS 5.0    /* for a whole image to be sent */
#define TEV_SLICE_MS 50          /* the longest single wait in poll */
#define TEV_NAME_MAX 256         /* the image name's room, NUL included */
#define TEV_MAX_CHANNELS 6
/* A packet's bytes besides the pixels: length, type, focus, name, the
 * channels' count and names, the tile, offsets and strides. */
#define TEV_HEADER_MAX (4 + 1 + 1 + TEV_NAME_MAX + 4 + TEV_MAX_CHANNELS * 8 + 16 + \
                        2 * TEV_MAX_CHANNELS * 8)

/* The channels' names: the image's, then its standard error's. */
static const char *const tev__names[TEV_MAX_CHANNELS] = {"R", "G", "B",
                                                         "error.R", "error.G", "error.B"};

#ifndef MSG_NOSIGNAL
#define MSG_NOSIGNAL 0 /* (systems without it have SO_NOSIGPIPE, set on the socket) */
#endif

struct lmc_tev {
  char host[LMC_ADDRESS_MAX], port[8];
  char where[LMC_ADDRESS_MAX + 8]; /* "host:port", for the warning */
  char base[TEV_NAME_MAX]; /* the name given to tev_create */
  int width, height;
  int nch;              /* channels: 3, or 6 with the error */
  /* The mailbox and the end, under mu. */
  pthread_mutex_t mu;
  pthread_cond_t wake;  /* to the sender: an image, or the end */
  pthread_cond_t ended; /* to tev_destroy: the sender returned */
  float *slot;          /* width * height * nch, interleaved: the image posted last */
  char slot_label[TEV_NAME_MAX / 2]; /* ... and its label */
  int fresh;            /* slot holds an image not taken yet */
  int closing;          /* tev_destroy was called */
  double deadline;      /* closing: the monotonic time the sender stops by */
  int done;             /* the sender returned */
  int orphaned;         /* tev_destroy stopped waiting: the sender frees t */
  /* The sender's own. */
  pthread_t thread;
  float *frame;           /* the image being sent */
  char name[TEV_NAME_MAX];  /* ... under this name: the base and its label */
  char shown[TEV_NAME_MAX]; /* the name of the image created on this connection */
  unsigned char *packet;  /* one packet's bytes */
  int fd;                 /* the connection, -1 when none */
  int created;            /* CreateImage sent on this connection */
  double next_try;        /* no connection attempt before this (monotonic seconds) */
  double backoff;         /* the wait after the next failure */
  int warned;             /* the one warning was given */
};

/* Monotonic seconds. */
static double tev__now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The time a wait that would end at `until` must end by: earlier when
 * tev_destroy has set its deadline. */
static double tev__limit(lmc_tev *t, double until) {
  pthread_mutex_lock(&t->mu);
  if (t->closing && t->deadline < until) until = t->deadline;
  pthread_mutex_unlock(&t->mu);
  return until;
}

/* Drops the connection after `why` went wrong: the warning (the first
 * time only), and the next attempt after the back-off, which doubles. */
static void tev__fail(lmc_tev *t, const char *why) {
  if (t->fd >= 0) close(t->fd);
  t->fd = -1;
  if (!t->warned)
    fprintf(stderr,
            "lmc: warning: display server %s: %s; the render goes on, and lmc retries in the "
            "background\n",
            t->where, why);
  t->warned = 1;
  t->next_try = tev__now() + t->backoff;
  t->backoff = t->backoff * 2.0 < TEV_BACKOFF_MAX ? t->backoff * 2.0 : TEV_BACKOFF_MAX;
}

/* The text of errno value e (strerror is not thread-safe). */
static const char *tev__strerror(int e, char *buf, size_t n) {
  if (strerror_r(e, buf, n)) snprintf(buf, n, "error %d", e);
  return buf;
}

/* Waits until fd has one of `events`: 1, or 0 when the time (until, or
 * tev_destroy's deadline) is up or poll fails. */
static int tev__wait(lmc_tev *t, int fd, short events, double until) {
  for (;;) {
    double left = tev__limit(t, until) - tev__now();
    if (left <= 0.0) return 0;
    int ms = left * 1e3 < TEV_SLICE_MS ? (int)(left * 1e3) + 1 : TEV_SLICE_MS;
    struct pollfd p = {fd, events, 0};
    int r = poll(&p, 1, ms);
    if (r > 0) return 1; /* (an error or hang-up shows in the call that follows) */
    if (r < 0 && errno != EINTR) return 0;
  }
}

/* --- the connection ------------------------------------------------------------- */

/* Connects to the viewer by `until`: 1, or 0 after tev__fail. */
static int tev__connect(lmc_tev *t, double until) {
  struct addrinfo hints, *res = NULL;
  memset(&hints, 0, sizeof hints);
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_NUMERICSERV;
  int rc = getaddrinfo(t->host, t->port, &hints, &res);
  if (rc) {
    tev__fail(t, gai_strerror(rc));
    return 0;
  }
  char why[160] = "no address";
  for (const struct addrinfo *ai = res; ai && t->fd < 0; ai = ai->ai_next) {
    int fd = socket(ai->ai_family, ai->ai_socktype, ai->ai_protocol);
    if (fd < 0) {
      tev__strerror(errno, why, sizeof why);
      continue;
    }
    fcntl(fd, F_SETFD, FD_CLOEXEC);
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
#ifdef SO_NOSIGPIPE
    int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_NOSIGPIPE, &one, sizeof one);
#endif
    /* Connect, waiting for the handshake without blocking. */
    int err = 0;
    if (connect(fd, ai->ai_addr, ai->ai_addrlen) < 0) {
      err = errno;
      if (err == EINPROGRESS || err == EINTR) {
        socklen_t len = sizeof err;
        err = ETIMEDOUT;
        if (tev__wait(t, fd, POLLOUT, until) &&
            getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) < 0)
          err = errno;
      }
    }
    if (err) {
      tev__strerror(err, why, sizeof why);
      close(fd);
      continue;
    }
    t->fd = fd;
  }
  freeaddrinfo(res);
  if (t->fd < 0) {
    tev__fail(t, why);
    return 0;
  }
  t->created = 0;
  return 1;
}

/* Whether the viewer closed its end (tev never writes: anything it sent
 * is read and dropped). */
static int tev__peer_closed(int fd) {
  char sink[256];
  for (;;) {
    ssize_t n = recv(fd, sink, sizeof sink, 0);
    if (n > 0) continue;
    if (n == 0) return 1;
    return errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR;
  }
}

/* Sends n bytes by `until`: 1, or 0 after tev__fail. */
static int tev__send_all(lmc_tev *t, const unsigned char *p, size_t n, double until) {
  while (n > 0) {
    ssize_t k = send(t->fd, p, n, MSG_NOSIGNAL);
    if (k > 0) {
      p += k, n -= (size_t)k;
      continue;
    }
    int e = errno;
    if (k < 0 && (e == EAGAIN || e == EWOULDBLOCK || e == EINTR)) {
      if (tev__wait(t, t->fd, POLLOUT, until)) continue;
      tev__fail(t, "the viewer does not take the image in time");
      return 0;
    }
    char buf[128];
    tev__fail(t, k < 0 ? tev__strerror(e, buf, sizeof buf) : "the connection was closed");
    return 0;
  }
  return 1;
}

/* --- the packets ------------------------------------------------------------------ */

/* Little-endian writers: each returns the byte after what it wrote. */
static unsigned char *tev__u32(unsigned char *p, uint32_t v) {
  for (int i = 0; i < 4; i++) *p++ = (unsigned char)(v >> (8 * i));
  return p;
}

static unsigned char *tev__i64(unsigned char *p, int64_t v) {
  uint64_t u = (uint64_t)v;
  for (int i = 0; i < 8; i++) *p++ = (unsigned char)(u >> (8 * i));
  return p;
}

static unsigned char *tev__str(unsigned char *p, const char *s) {
  size_t n = strlen(s) + 1;
  memcpy(p, s, n);
  return p + n;
}

/* The start of every packet lmc sends but CloseImage: room for its
 * length, its type, grabFocus and the image's name. */
static unsigned char *tev__head(lmc_tev *t, int type, int grab_focus) {
  unsigned char *p = t->packet + 4;
  *p++ = (unsigned char)type;
  *p++ = (unsigned char)(grab_focus != 0);
  return tev__str(p, t->name);
}

/* Writes the length into the packet ending at `end`; its size. */
static size_t tev__seal(lmc_tev *t, const unsigned char *end) {
  size_t n = (size_t)(end - t->packet);
  tev__u32(t->packet, (uint32_t)n);
  return n;
}

/* The channels' count and names. */
static unsigned char *tev__channels(const lmc_tev *t, unsigned char *p) {
  p = tev__u32(p, (uint32_t)t->nch);
  for (int c = 0; c < t->nch; c++) p = tev__str(p, tev__names[c]);
  return p;
}

/* CloseImage of the image shown so far: its name alone. */
static size_t tev__close_packet(lmc_tev *t) {
  unsigned char *p = t->packet + 4;
  *p++ = (unsigned char)TEV_CLOSE_IMAGE;
  return tev__seal(t, tev__str(p, t->shown));
}

/* CreateImage: the image, its size and channels (and the viewer's focus). */
static size_t tev__create_packet(lmc_tev *t) {
  unsigned char *p = tev__head(t, TEV_CREATE_IMAGE, 1);
  p = tev__u32(p, (uint32_t)t->width);
  p = tev__u32(p, (uint32_t)t->height);
  return tev__seal(t, tev__channels(t, p));
}

/* UpdateImageV3 of the tile (x, y, w, h) of t->frame: its channels
 * interleaved. */
static size_t tev__tile_packet(lmc_tev *t, int x, int y, int w, int h) {
  const int nch = t->nch;
  unsigned char *p = tev__head(t, TEV_UPDATE_IMAGE_V3, 0);
  p = tev__channels(t, p);
  p = tev__u32(p, (uint32_t)x);
  p = tev__u32(p, (uint32_t)y);
  p = tev__u32(p, (uint32_t)w);
  p = tev__u32(p, (uint32_t)h);
  for (int c = 0; c < nch; c++) p = tev__i64(p, c);
  for (int c = 0; c < nch; c++) p = tev__i64(p, nch);
  for (int j = 0; j < h; j++) {
    const float *row = t->frame + (size_t)nch * ((size_t)(y + j) * (size_t)t->width + (size_t)x);
    for (int i = 0; i < nch * w; i++) {
      uint32_t bits;
      memcpy(&bits, &row[i], sizeof bits);
      p = tev__u32(p, bits);
    }
  }
  return tev__seal(t, p);
}

/* --- the sender ------------------------------------------------------------------- */

/* Sends t->frame: connects first when there is no connection (not before
 * the back-off has passed, unless it is the last image), creates the
 * image on a new connection, then sends its tiles. */
static void tev__send_frame(lmc_tev *t, int last) {
  double now = tev__now();
  if (tev__limit(t, now + 1.0) <= now) return; /* (tev_destroy's deadline has passed) */
  if (t->fd >= 0 && tev__peer_closed(t->fd)) tev__fail(t, "the viewer closed the connection");
  if (t->fd < 0) {
    if (!last && now < t->next_try) return;
    if (!tev__connect(t, now + TEV_CONNECT_SECONDS)) return;
  }
  double until = tev__now() + TEV_FRAME_SECONDS;
  if (t->created && strcmp(t->shown, t->name) != 0) {
    /* A new name (its label changed): tev cannot rename an image, so the
     * old one is closed and the image created again under the new name. */
    size_t n = tev__close_packet(t);
    if (!tev__send_all(t, t->packet, n, until)) return;
    t->created = 0;
  }
  if (!t->created) {
    size_t n = tev__create_packet(t);
    if (!tev__send_all(t, t->packet, n, until)) return;
    t->created = 1;
    snprintf(t->shown, sizeof t->shown, "%s", t->name);
  }
  for (int y = 0; y < t->height; y += TEV_TILE)
    for (int x = 0; x < t->width; x += TEV_TILE) {
      int w = t->width - x < TEV_TILE ? t->width - x : TEV_TILE;
      int h = t->height - y < TEV_TILE ? t->height - y : TEV_TILE;
      size_t n = tev__tile_packet(t, x, y, w, h);
      if (!tev__send_all(t, t->packet, n, until)) return;
    }
  t->backoff = TEV_BACKOFF_MIN; /* (a whole image went through) */
}

static void tev__free(lmc_tev *t) {
  pthread_mutex_destroy(&t->mu);
  pthread_cond_destroy(&t->wake);
  pthread_cond_destroy(&t->ended);
  free(t->slot);
  free(t->frame);
  free(t->packet);
  free(t);
}

/* The sender thread: takes the newest image from the mailbox and sends
 * it, until tev_destroy asks it to end and no image is left. */
static void *tev__main(void *arg) {
  lmc_tev *t = arg;
  pthread_mutex_lock(&t->mu);
  for (;;) {
    while (!t->fresh && !t->closing) pthread_cond_wait(&t->wake, &t->mu);
    if (!t->fresh) break;
    float *swap = t->frame;
    t->frame = t->slot, t->slot = swap;
    if (t->slot_label[0])
      snprintf(t->name, sizeof t->name, "%.126s %.126s", t->base, t->slot_label);
    else
      snprintf(t->name, sizeof t->name, "%s", t->base);
    t->fresh = 0;
    int last = t->closing;
    pthread_mutex_unlock(&t->mu);
    tev__send_frame(t, last);
    pthread_mutex_lock(&t->mu);
  }
  if (t->fd >= 0) close(t->fd);
  t->fd = -1;
  t->done = 1;
  int orphaned = t->orphaned;
  pthread_cond_broadcast(&t->ended);
  pthread_mutex_unlock(&t->mu);
  if (orphaned) tev__free(t);
  return NULL;
}

/* --- the API -------------------------------------------------------------------------- */

lmc_status tev_create(lmc_tev **OUT, const char *address, const char *name, int width,
                      int height, int with_error, lmc_error *err) {
  *OUT = NULL;
  char host[LMC_ADDRESS_MAX];
  int port;
  if (!lmc_address_parse(address, 1, 65535, host, sizeof host, &port))
    return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                         "display server '%s' is not HOST or HOST:PORT", address);
  if (width <= 0 || height <= 0)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "display: an image of %dx%d", width, height);
  lmc_tev *t = calloc(1, sizeof *t);
  if (!t) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory");
  snprintf(t->host, sizeof t->host, "%s", host);
  snprintf(t->port, sizeof t->port, "%d", port ? port : TEV_DEFAULT_PORT);
  snprintf(t->where, sizeof t->where, "%s:%s", t->host, t->port);
  snprintf(t->base, sizeof t->base, "%s", name);
  snprintf(t->name, sizeof t->name, "%s", name);
  t->width = width, t->height = height;
  t->nch = with_error ? 6 : 3;
  t->fd = -1;
  t->backoff = TEV_BACKOFF_MIN;
  size_t n = (size_t)t->nch * (size_t)width * (size_t)height;
  t->slot = malloc(n * sizeof(float));
  t->frame = malloc(n * sizeof(float));
  t->packet = malloc(TEV_HEADER_MAX + (size_t)t->nch * sizeof(float) * TEV_TILE * TEV_TILE);
  if (!t->slot || !t->frame || !t->packet) {
    free(t->slot), free(t->frame), free(t->packet), free(t);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory");
  }
  /* The condition tev_destroy waits on with a deadline runs on the
   * monotonic clock, as every time here. */
  pthread_condattr_t ca;
  pthread_condattr_init(&ca);
  pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
  pthread_mutex_init(&t->mu, NULL);
  pthread_cond_init(&t->wake, NULL);
  pthread_cond_init(&t->ended, &ca);
  pthread_condattr_destroy(&ca);
  int rc = pthread_create(&t->thread, NULL, tev__main, t);
  if (rc) {
    tev__free(t);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "display: no thread for the sender (%d)", rc);
  }
  *OUT = t;
  return LMC_OK;
}

void tev_post(lmc_tev *t, const lmc_image *img, const lmc_image *error, const char *label) {
  if (!t || !img || !img->data || img->width != t->width || img->height != t->height ||
      img->channels != 3)
    return;
  if (error && (!error->data || error->width != t->width || error->height != t->height ||
                error->channels != 3))
    return;
  size_t np = (size_t)t->width * (size_t)t->height;
  pthread_mutex_lock(&t->mu);
  if (t->nch == 3) {
    memcpy(t->slot, img->data, 3 * np * sizeof(float));
  } else {
    for (size_t i = 0; i < np; i++)
      for (int c = 0; c < 3; c++) {
        t->slot[6 * i + (size_t)c] = img->data[3 * i + (size_t)c];
        t->slot[6 * i + 3 + (size_t)c] = error ? error->data[3 * i + (size_t)c] : INFINITY;
      }
  }
  snprintf(t->slot_label, sizeof t->slot_label, "%s", label ? label : "");
  t->fresh = 1;
  pthread_cond_signal(&t->wake);
  pthread_mutex_unlock(&t->mu);
}

void tev_destroy(lmc_tev *t, double wait_seconds) {
  if (!t) return;
  pthread_mutex_lock(&t->mu);
  t->closing = 1;
  t->deadline = tev__now() + (wait_seconds > 0.0 ? wait_seconds : 0.0);
  pthread_cond_signal(&t->wake);
  /* The sender stops by the deadline unless it is inside a call that
   * cannot be interrupted (a name lookup): a short grace, then it is
   * left to finish and free t on its own. */
  double give_up = t->deadline + 0.25;
  struct timespec ts;
  ts.tv_sec = (time_t)give_up;
  ts.tv_nsec = (long)((give_up - (double)ts.tv_sec) * 1e9);
  while (!t->done)
    if (pthread_cond_timedwait(&t->ended, &t->mu, &ts) == ETIMEDOUT) break;
  if (!t->done) {
    t->orphaned = 1;
    pthread_mutex_unlock(&t->mu);
    pthread_detach(t->thread);
    return;
  }
  pthread_mutex_unlock(&t->mu);
  pthread_join(t->thread, NULL);
  tev__free(t);
}
