/*
 * mesh_obj.c: the Wavefront OBJ reader.
 *
 * Supported statements: `v x y z [w]`, `vt u [v [w]]`, `vn x y z` and
 * `f` with corners written v, v/vt, v//vn or v/vt/vn. Indices are 1-based;
 * a negative index counts back from the most recent element (-1 is the last
 * one read so far). Polygons with more than three corners are triangulated
 * as fans around their first corner. Grouping and material statements (o, g,
 * s, usemtl, mtllib) and everything else are ignored: the XML scene assigns
 * materials. A line ending in a backslash continues on the next line.
 *
 * Every distinct (v, vt, vn) triple used by a face becomes one output
 * vertex, found through an open-addressing hash table, so a vertex shared by
 * faces with the same attributes is stored once.
 *
 * Texture coordinates: Mitsuba 0.5/0.6's OBJ plugin has a `flipTexCoords`
 * option that defaults to true and stores (u, 1 - v), since most OBJ
 * exporters put v = 0 at the bottom of the image while Mitsuba's bitmap
 * lookups put it at the top. We follow that default: uv = (u, 1 - v).
 *
 * When only some corners have a normal, the others get a zero normal, which
 * mesh_validate later recomputes from the adjacent faces. Errors carry the
 * OBJ file name and the line number.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/io/io.h"

/* A growable array of doubles. */
typedef struct obj__darr {
  double *v;
  int64_t n, cap;
} obj__darr;

static int obj__push(obj__darr *a, double x) {
  if (a->n == a->cap) {
    int64_t cap = a->cap ? 2 * a->cap : 1024;
    double *v = realloc(a->v, (size_t)cap * sizeof(double));
    if (!v) return 0;
    a->v = v;
    a->cap = cap;
  }
  a->v[a->n++] = x;
  return 1;
}

/* One face corner: 0-based indices into the v, vt, vn arrays (-1: absent). */
typedef struct obj__key {
  int64_t v, vt, vn;
} obj__key;

typedef struct obj__reader {
  const char *path;
  obj__darr pos, tex, nrm;
  /* Output vertices (their keys) and triangles. */
  obj__key *verts;
  int64_t n_verts, cap_verts;
  uint32_t *tris;
  int64_t n_tris, cap_tris;
  /* Hash table from key to output vertex (+1; 0 = empty). */
  int64_t *table;
  int64_t table_size;
  int any_vt, any_vn;
} obj__reader;

static uint64_t obj__hash(obj__key k) {
  uint64_t h = (uint64_t)k.v * 0x9E3779B97F4A7C15ull;
  h ^= (uint64_t)(k.vt + 1) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
  h ^= (uint64_t)(k.vn + 1) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
  return h ^ (h >> 29);
}

static int obj__table_grow(obj__reader *r) {
  int64_t size = r->table_size ? 2 * r->table_size : 4096;
  int64_t *t = calloc((size_t)size, sizeof(int64_t));
  if (!t) return 0;
  for (int64_t i = 0; i < r->n_verts; i++) {
    uint64_t h = obj__hash(r->verts[i]) & (uint64_t)(size - 1);
    while (t[h]) h = (h + 1) & (uint64_t)(size - 1);
    t[h] = i + 1;
  }
  free(r->table);
  r->table = t;
  r->table_size = size;
  return 1;
}

/* Output vertex of a corner, created when first seen; -1 on out of memory. */
static int64_t obj__vertex(obj__reader *r, obj__key k) {
  if (2 * (r->n_verts + 1) > r->table_size && !obj__table_grow(r)) return -1;
  uint64_t mask = (uint64_t)(r->table_size - 1);
  uint64_t h = obj__hash(k) & mask;
  while (r->table[h]) {
    obj__key o = r->verts[r->table[h] - 1];
    if (o.v == k.v && o.vt == k.vt && o.vn == k.vn) return r->table[h] - 1;
    h = (h + 1) & mask;
  }
  if (r->n_verts == r->cap_verts) {
    int64_t cap = r->cap_verts ? 2 * r->cap_verts : 1024;
    obj__key *v = realloc(r->verts, (size_t)cap * sizeof(obj__key));
    if (!v) return -1;
    r->verts = v;
    r->cap_verts = cap;
  }
  r->verts[r->n_verts] = k;
  r->table[h] = r->n_verts + 1;
  return r->n_verts++;
}

static int obj__triangle(obj__reader *r, int64_t a, int64_t b, int64_t c) {
  if (r->n_tris == r->cap_tris) {
    int64_t cap = r->cap_tris ? 2 * r->cap_tris : 1024;
    uint32_t *t = realloc(r->tris, (size_t)cap * 3 * sizeof(uint32_t));
    if (!t) return 0;
    r->tris = t;
    r->cap_tris = cap;
  }
  r->tris[3 * r->n_tris] = (uint32_t)a;
  r->tris[3 * r->n_tris + 1] = (uint32_t)b;
  r->tris[3 * r->n_tris + 2] = (uint32_t)c;
  r->n_tris++;
  return 1;
}

static void obj__reader_free(obj__reader *r) {
  free(r->pos.v);
  free(r->tex.v);
  free(r->nrm.v);
  free(r->verts);
  free(r->tris);
  free(r->table);
}

/* Reads a whole file into a NUL-terminated buffer. */
static lmc_status obj__slurp(const char *path, char **out, size_t *out_len, lmc_error *err) {
  FILE *f = fopen(path, "rb");
  if (!f) return lmc_error_set(err, LMC_EIO, path, 0, "cannot open: %s", strerror(errno));
  size_t cap = 1 << 16, len = 0;
  char *buf = malloc(cap);
  while (buf) {
    if (len + 1 >= cap) {
      char *b = realloc(buf, cap * 2);
      if (!b) {
        free(buf);
        buf = NULL;
        break;
      }
      buf = b;
      cap *= 2;
    }
    size_t n = fread(buf + len, 1, cap - 1 - len, f);
    len += n;
    if (n == 0) break;
  }
  int failed = ferror(f);
  fclose(f);
  if (!buf) return lmc_error_set(err, LMC_ENOMEM, path, 0, "out of memory reading the file");
  if (failed) {
    free(buf);
    return lmc_error_set(err, LMC_EIO, path, 0, "read error");
  }
  buf[len] = '\0';
  *out = buf;
  *out_len = len;
  return LMC_OK;
}

/* Parses up to `max` numbers from s; returns how many were found, or -1
 * when a token is not a number. */
static int obj__numbers(const char *s, double *x, int max) {
  int n = 0;
  for (;;) {
    while (*s == ' ' || *s == '\t') s++;
    if (!*s) return n;
    char *end;
    double v = strtod(s, &end);
    if (end == s) return -1;
    if (n < max) x[n] = v;
    n++;
    s = end;
    if (*s && *s != ' ' && *s != '\t') return -1;
  }
}

/* Resolves an OBJ index (1-based, or negative = relative) against `count`
 * elements; returns the 0-based index or -1 when invalid. */
static int64_t obj__resolve(long long i, int64_t count) {
  if (i > 0 && i <= count) return i - 1;
  if (i < 0 && i >= -count) return count + i; /* never negates i: -LLONG_MIN overflows */
  return -1;
}

/* Parses one face corner "v[/vt][/vn]" at *s (advancing it). */
static lmc_status obj__corner(obj__reader *r, const char **s, int line, obj__key *k,
                              lmc_error *err) {
  const char *p = *s;
  char *end;
  k->vt = k->vn = -1;
  errno = 0;
  long long iv = strtoll(p, &end, 10);
  if (end == p) return lmc_error_set(err, LMC_EPARSE, r->path, line, "malformed face corner");
  k->v = obj__resolve(iv, r->pos.n / 3);
  if (k->v < 0)
    return lmc_error_set(err, LMC_EPARSE, r->path, line,
                         "vertex index %lld out of range (%lld vertices so far)", iv,
                         (long long)(r->pos.n / 3));
  p = end;
  if (*p == '/') {
    p++;
    if (*p != '/') {
      long long it = strtoll(p, &end, 10);
      if (end == p) return lmc_error_set(err, LMC_EPARSE, r->path, line, "malformed face corner");
      k->vt = obj__resolve(it, r->tex.n / 2);
      if (k->vt < 0)
        return lmc_error_set(err, LMC_EPARSE, r->path, line,
                             "texture coordinate index %lld out of range (%lld so far)", it,
                             (long long)(r->tex.n / 2));
      p = end;
    }
    if (*p == '/') {
      p++;
      long long in = strtoll(p, &end, 10);
      if (end == p) return lmc_error_set(err, LMC_EPARSE, r->path, line, "malformed face corner");
      k->vn = obj__resolve(in, r->nrm.n / 3);
      if (k->vn < 0)
        return lmc_error_set(err, LMC_EPARSE, r->path, line,
                             "normal index %lld out of range (%lld so far)", in,
                             (long long)(r->nrm.n / 3));
      p = end;
    }
  }
  if (*p && *p != ' ' && *p != '\t')
    return lmc_error_set(err, LMC_EPARSE, r->path, line, "malformed face corner");
  *s = p;
  return LMC_OK;
}

/* Handles one logical line (NUL-terminated, continuation already joined). */
static lmc_status obj__line(obj__reader *r, const char *s, int line, lmc_error *err) {
  while (*s == ' ' || *s == '\t') s++;
  double x[4] = {0.0, 0.0, 0.0, 0.0};
  if (s[0] == 'v' && (s[1] == ' ' || s[1] == '\t')) {
    /* v x y z [w] (extra colour values some exporters add are ignored) */
    int n = obj__numbers(s + 2, x, 3);
    if (n < 3) return lmc_error_set(err, LMC_EPARSE, r->path, line, "expected 'v x y z'");
    if (!obj__push(&r->pos, x[0]) || !obj__push(&r->pos, x[1]) || !obj__push(&r->pos, x[2]))
      return lmc_error_set(err, LMC_ENOMEM, r->path, line, "out of memory");
  } else if (s[0] == 'v' && s[1] == 't' && (s[2] == ' ' || s[2] == '\t')) {
    int n = obj__numbers(s + 3, x, 2);
    if (n < 1) return lmc_error_set(err, LMC_EPARSE, r->path, line, "expected 'vt u [v [w]]'");
    /* Mitsuba's flipTexCoords default: v -> 1 - v. */
    if (!obj__push(&r->tex, x[0]) || !obj__push(&r->tex, 1.0 - x[1]))
      return lmc_error_set(err, LMC_ENOMEM, r->path, line, "out of memory");
  } else if (s[0] == 'v' && s[1] == 'n' && (s[2] == ' ' || s[2] == '\t')) {
    int n = obj__numbers(s + 3, x, 3);
    if (n < 3) return lmc_error_set(err, LMC_EPARSE, r->path, line, "expected 'vn x y z'");
    if (!obj__push(&r->nrm, x[0]) || !obj__push(&r->nrm, x[1]) || !obj__push(&r->nrm, x[2]))
      return lmc_error_set(err, LMC_ENOMEM, r->path, line, "out of memory");
  } else if (s[0] == 'f' && (s[1] == ' ' || s[1] == '\t')) {
    /* Triangulate the polygon as a fan around its first corner. */
    const char *p = s + 2;
    int64_t first = -1, prev = -1;
    int corners = 0;
    for (;;) {
      while (*p == ' ' || *p == '\t') p++;
      if (!*p) break;
      obj__key k = {-1, -1, -1};
      lmc_status st = obj__corner(r, &p, line, &k, err);
      if (st != LMC_OK) return st;
      if (k.vt >= 0) r->any_vt = 1;
      if (k.vn >= 0) r->any_vn = 1;
      int64_t v = obj__vertex(r, k);
      if (v < 0) return lmc_error_set(err, LMC_ENOMEM, r->path, line, "out of memory");
      if (corners == 0) first = v;
      if (corners >= 2 && !obj__triangle(r, first, prev, v))
        return lmc_error_set(err, LMC_ENOMEM, r->path, line, "out of memory");
      prev = v;
      corners++;
    }
    if (corners < 3)
      return lmc_error_set(err, LMC_EPARSE, r->path, line, "face with %d corner(s)", corners);
  }
  /* Everything else (comments, o, g, s, usemtl, mtllib, l, p, ...) is ignored. */
  return LMC_OK;
}

/* Copies the basename of path into name. */
static void obj__basename(const char *path, char *name, size_t size) {
  const char *b = strrchr(path, '/');
  snprintf(name, size, "%s", b ? b + 1 : path);
}

lmc_status mesh_read_obj(const char *path, mesh *OUT_mesh, lmc_error *err) {
  memset(OUT_mesh, 0, sizeof *OUT_mesh);
  OUT_mesh->light = -1;
  char *buf = NULL;
  size_t len = 0;
  lmc_status st = obj__slurp(path, &buf, &len, err);
  if (st != LMC_OK) return st;

  /* Parse line by line, joining backslash continuations in place. */
  obj__reader r;
  memset(&r, 0, sizeof r);
  r.path = path;
  int line = 1;
  char *s = buf;
  while (st == LMC_OK && *s) {
    int start_line = line;
    char *w = s, *rd = s;
    for (;;) {
      char c = *rd;
      if (c == '\0') break;
      if (c == '\n' || c == '\r') {
        /* A backslash right before the line break continues the line. */
        char *q = w;
        while (q > s && (q[-1] == ' ' || q[-1] == '\t')) q--;
        if (q > s && q[-1] == '\\') {
          w = q - 1;
          if (c == '\r' && rd[1] == '\n') rd++;
          rd++;
          line++;
          continue;
        }
        break;
      }
      if (c == '#') { /* comment: skip to the end of the line */
        while (*rd && *rd != '\n' && *rd != '\r') rd++;
        continue;
      }
      *w++ = c;
      rd++;
    }
    char *next = rd;
    if (*next == '\r' && next[1] == '\n') next += 2;
    else if (*next) next++;
    if (*rd) line++;
    *w = '\0';
    st = obj__line(&r, s, start_line, err);
    s = next;
  }
  free(buf);
  if (st != LMC_OK) {
    obj__reader_free(&r);
    return st;
  }

  /* Build the mesh from the de-duplicated vertices. */
  st = mesh_alloc(OUT_mesh, r.n_verts, r.n_tris, r.any_vn, r.any_vt, err);
  if (st != LMC_OK) {
    obj__reader_free(&r);
    if (err) snprintf(err->file, sizeof err->file, "%s", path);
    return st;
  }
  for (int64_t i = 0; i < r.n_verts; i++) {
    obj__key k = r.verts[i];
    for (int c = 0; c < 3; c++) OUT_mesh->p[3 * i + c] = (float)r.pos.v[3 * k.v + c];
    if (OUT_mesh->n && k.vn >= 0)
      for (int c = 0; c < 3; c++) OUT_mesh->n[3 * i + c] = (float)r.nrm.v[3 * k.vn + c];
    if (OUT_mesh->uv && k.vt >= 0)
      for (int c = 0; c < 2; c++) OUT_mesh->uv[2 * i + c] = (float)r.tex.v[2 * k.vt + c];
  }
  if (r.n_tris > 0) memcpy(OUT_mesh->idx, r.tris, (size_t)r.n_tris * 3 * sizeof(uint32_t));
  obj__basename(path, OUT_mesh->name, sizeof OUT_mesh->name);
  obj__reader_free(&r);
  return LMC_OK;
}
