/*
 * mesh_ply.c: the Stanford PLY reader (ascii, binary_little_endian,
 * binary_big_endian).
 *
 * A PLY file is a text header that declares elements (a name and a count)
 * and their properties (a scalar type, or a list with a count type and an
 * item type), followed by the element data in declaration order. We read:
 *   vertex: x y z, optional nx ny nz, optional texture coordinates named
 *           u v, s t, texture_u texture_v or texture_s texture_t;
 *   face:   the list vertex_indices (or vertex_index); polygons with more
 *           than three corners become fans around the first corner.
 * Every other element and property is skipped (in binary files by its
 * size, list by list). Texture coordinates are taken as they are (Mitsuba's
 * PLY plugin does not flip v, unlike its OBJ plugin).
 *
 * The whole file is read into memory and every read is bounds-checked, so a
 * truncated or lying file gives an error, never a crash. Errors name the
 * file, and for the header and ascii bodies the line.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/io/io.h"

typedef enum ply__type {
  PLY_NONE = 0,
  PLY_I8, PLY_U8, PLY_I16, PLY_U16, PLY_I32, PLY_U32, PLY_F32, PLY_F64
} ply__type;

typedef struct ply__prop {
  char name[64];
  ply__type type;       /* scalar type, or item type of a list */
  ply__type count_type; /* PLY_NONE for scalars */
} ply__prop;

typedef struct ply__elem {
  char name[64];
  int64_t count;
  ply__prop *props;
  int n_props;
} ply__elem;

enum { PLY_ASCII, PLY_LE, PLY_BE };

/* The body cursor. */
typedef struct ply__in {
  const char *path;
  const unsigned char *p, *end;
  int format;
  int line; /* ascii only */
} ply__in;

static int ply__type_size(ply__type t) {
  static const int size[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};
  return size[t];
}

static ply__type ply__parse_type(const char *s) {
  static const struct {
    const char *name;
    ply__type type;
  } names[] = {{"char", PLY_I8},     {"int8", PLY_I8},     {"uchar", PLY_U8},   {"uint8", PLY_U8},
               {"short", PLY_I16},   {"int16", PLY_I16},   {"ushort", PLY_U16}, {"uint16", PLY_U16},
               {"int", PLY_I32},     {"int32", PLY_I32},   {"uint", PLY_U32},   {"uint32", PLY_U32},
               {"float", PLY_F32},   {"float32", PLY_F32}, {"double", PLY_F64}, {"float64", PLY_F64}};
  for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
    if (strcmp(s, names[i].name) == 0) return names[i].type;
  return PLY_NONE;
}

/* Reads one value of type t as a double; returns 0 at end of data or on a
 * malformed ascii token. */
static int ply__read(ply__in *in, ply__type t, double *out) {
  if (in->format == PLY_ASCII) {
    /* Skip whitespace, counting lines. */
    while (in->p < in->end && (*in->p == ' ' || *in->p == '\t' || *in->p == '\n' || *in->p == '\r')) {
      if (*in->p == '\n') in->line++;
      in->p++;
    }
    if (in->p >= in->end) return 0;
    char tok[128];
    size_t n = 0;
    while (in->p < in->end && !(*in->p == ' ' || *in->p == '\t' || *in->p == '\n' || *in->p == '\r')) {
      if (n + 1 < sizeof tok) tok[n++] = (char)*in->p;
      in->p++;
    }
    tok[n] = '\0';
    char *e;
    *out = strtod(tok, &e);
    return e != tok && *e == '\0';
  }
  int size = ply__type_size(t);
  if (in->end - in->p < size) return 0;
  unsigned char b[8];
  /* Bring the bytes into little-endian order, then assemble. */
  for (int i = 0; i < size; i++) b[i] = in->format == PLY_LE ? in->p[i] : in->p[size - 1 - i];
  in->p += size;
  uint64_t u = 0;
  for (int i = size - 1; i >= 0; i--) u = (u << 8) | b[i];
  switch (t) {
    case PLY_I8: *out = (double)(int8_t)(uint8_t)u; break;
    case PLY_U8: *out = (double)(uint8_t)u; break;
    case PLY_I16: *out = (double)(int16_t)(uint16_t)u; break;
    case PLY_U16: *out = (double)(uint16_t)u; break;
    case PLY_I32: *out = (double)(int32_t)(uint32_t)u; break;
    case PLY_U32: *out = (double)(uint32_t)u; break;
    case PLY_F32: {
      uint32_t w = (uint32_t)u;
      float f;
      memcpy(&f, &w, 4);
      *out = f;
      break;
    }
    case PLY_F64: {
      double d;
      memcpy(&d, &u, 8);
      *out = d;
      break;
    }
    default: return 0;
  }
  return 1;
}

static lmc_status ply__eof(ply__in *in, const char *what, lmc_error *err) {
  if (in->format == PLY_ASCII)
    return lmc_error_set(err, LMC_EPARSE, in->path, in->line, "malformed or missing value in %s",
                         what);
  return lmc_error_set(err, LMC_EPARSE, in->path, 0, "unexpected end of data in %s", what);
}

/* Reads a whole file into memory. */
static lmc_status ply__slurp(const char *path, unsigned char **out, size_t *out_len,
                             lmc_error *err) {
  FILE *f = fopen(path, "rb");
  if (!f) return lmc_error_set(err, LMC_EIO, path, 0, "cannot open: %s", strerror(errno));
  size_t cap = 1 << 16, len = 0;
  unsigned char *buf = malloc(cap);
  while (buf) {
    if (len == cap) {
      unsigned char *b = realloc(buf, cap * 2);
      if (!b) {
        free(buf);
        buf = NULL;
        break;
      }
      buf = b;
      cap *= 2;
    }
    size_t n = fread(buf + len, 1, cap - len, f);
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
  *out = buf;
  *out_len = len;
  return LMC_OK;
}

static void ply__free_elems(ply__elem *e, int n) {
  for (int i = 0; i < n; i++) free(e[i].props);
  free(e);
}

/* Parses the header; *body points after "end_header\n". */
static lmc_status ply__header(const char *path, const unsigned char *buf, size_t len,
                              ply__elem **OUT_elems, int *OUT_n, int *OUT_format,
                              size_t *OUT_body, int *OUT_line, lmc_error *err) {
  ply__elem *elems = NULL;
  int n = 0, format = -1, line = 0;
  size_t pos = 0;
  lmc_status st = LMC_OK;
  *OUT_elems = NULL;
  for (;;) {
    /* Next header line. */
    if (pos >= len) {
      st = lmc_error_set(err, LMC_EPARSE, path, line, "missing end_header");
      break;
    }
    line++;
    char text[512];
    size_t k = 0;
    while (pos < len && buf[pos] != '\n') {
      if (k + 1 < sizeof text && buf[pos] != '\r') text[k++] = (char)buf[pos];
      pos++;
    }
    pos++; /* the '\n' */
    text[k] = '\0';
    char w0[64] = "", w1[64] = "", w2[64] = "", w3[64] = "", w4[64] = "";
    int nw = sscanf(text, "%63s %63s %63s %63s %63s", w0, w1, w2, w3, w4);
    if (line == 1) {
      if (strcmp(w0, "ply") != 0) {
        st = lmc_error_set(err, LMC_EPARSE, path, 1, "not a PLY file (no 'ply' magic)");
        break;
      }
      continue;
    }
    if (nw <= 0 || strcmp(w0, "comment") == 0 || strcmp(w0, "obj_info") == 0) continue;
    if (strcmp(w0, "format") == 0) {
      if (strcmp(w1, "ascii") == 0) format = PLY_ASCII;
      else if (strcmp(w1, "binary_little_endian") == 0) format = PLY_LE;
      else if (strcmp(w1, "binary_big_endian") == 0) format = PLY_BE;
      else {
        st = lmc_error_set(err, LMC_EUNSUPPORTED, path, line, "unknown PLY format '%s'", w1);
        break;
      }
    } else if (strcmp(w0, "element") == 0) {
      char *e;
      long long count = strtoll(w2, &e, 10);
      if (nw < 3 || e == w2 || *e || count < 0) {
        st = lmc_error_set(err, LMC_EPARSE, path, line, "malformed element line");
        break;
      }
      ply__elem *g = realloc(elems, (size_t)(n + 1) * sizeof *elems);
      if (!g) {
        st = lmc_error_set(err, LMC_ENOMEM, path, line, "out of memory");
        break;
      }
      elems = g;
      memset(&elems[n], 0, sizeof elems[n]);
      snprintf(elems[n].name, sizeof elems[n].name, "%s", w1);
      elems[n].count = count;
      n++;
    } else if (strcmp(w0, "property") == 0) {
      if (n == 0) {
        st = lmc_error_set(err, LMC_EPARSE, path, line, "property before any element");
        break;
      }
      ply__prop pr;
      memset(&pr, 0, sizeof pr);
      if (strcmp(w1, "list") == 0) {
        pr.count_type = ply__parse_type(w2);
        pr.type = ply__parse_type(w3);
        snprintf(pr.name, sizeof pr.name, "%s", w4);
        if (nw < 5 || !pr.count_type || !pr.type || pr.count_type == PLY_F32 ||
            pr.count_type == PLY_F64) {
          st = lmc_error_set(err, LMC_EPARSE, path, line, "malformed list property");
          break;
        }
      } else {
        pr.type = ply__parse_type(w1);
        snprintf(pr.name, sizeof pr.name, "%s", w2);
        if (nw < 3 || !pr.type) {
          st = lmc_error_set(err, LMC_EPARSE, path, line, "malformed property (type '%s')", w1);
          break;
        }
      }
      ply__elem *el = &elems[n - 1];
      ply__prop *g = realloc(el->props, (size_t)(el->n_props + 1) * sizeof *g);
      if (!g) {
        st = lmc_error_set(err, LMC_ENOMEM, path, line, "out of memory");
        break;
      }
      el->props = g;
      el->props[el->n_props++] = pr;
    } else if (strcmp(w0, "end_header") == 0) {
      if (format < 0) st = lmc_error_set(err, LMC_EPARSE, path, line, "missing format line");
      break;
    } else {
      st = lmc_error_set(err, LMC_EPARSE, path, line, "unknown header keyword '%s'", w0);
      break;
    }
  }
  if (st != LMC_OK) {
    ply__free_elems(elems, n);
    return st;
  }
  *OUT_elems = elems;
  *OUT_n = n;
  *OUT_format = format;
  *OUT_body = pos;
  *OUT_line = line + 1;
  return LMC_OK;
}

/* Index of the property called one of names[], or -1. */
static int ply__find(const ply__elem *e, const char *const *names, int n_names) {
  for (int j = 0; j < n_names; j++)
    for (int i = 0; i < e->n_props; i++)
      if (strcmp(e->props[i].name, names[j]) == 0) return i;
  return -1;
}

/* Where the data mesh_read_ply uses sits: the vertex and face elements,
 * each vertex property's slot (0..7 = x y z nx ny nz u v, -1 unused) and
 * the face element's index list. */
typedef struct ply__layout {
  int iv, iface, list_prop, has_n, has_uv;
  int slot_of[64];
} ply__layout;

static lmc_status ply__locate(const char *path, const ply__elem *elems, int n_elems,
                              ply__layout *L, lmc_error *err) {
  L->iv = L->iface = L->list_prop = -1;
  L->has_n = L->has_uv = 0;
  for (int i = 0; i < n_elems; i++) {
    if (strcmp(elems[i].name, "vertex") == 0 && L->iv < 0) L->iv = i;
    if (strcmp(elems[i].name, "face") == 0 && L->iface < 0) L->iface = i;
  }
  if (L->iv < 0) return lmc_error_set(err, LMC_EPARSE, path, 0, "no vertex element");
  const ply__elem *ev = &elems[L->iv];
  if (ev->n_props > 64)
    return lmc_error_set(err, LMC_EUNSUPPORTED, path, 0, "too many vertex properties");
  static const char *const names[8][4] = {
      {"x"}, {"y"}, {"z"}, {"nx"}, {"ny"}, {"nz"},
      {"u", "s", "texture_u", "texture_s"}, {"v", "t", "texture_v", "texture_t"}};
  for (int i = 0; i < 64; i++) L->slot_of[i] = -1;
  int found[8];
  for (int s = 0; s < 8; s++) {
    found[s] = ply__find(ev, names[s], s >= 6 ? 4 : 1);
    if (found[s] >= 0) {
      if (ev->props[found[s]].count_type != PLY_NONE) found[s] = -1;
      else L->slot_of[found[s]] = s;
    }
  }
  if (found[0] < 0 || found[1] < 0 || found[2] < 0)
    return lmc_error_set(err, LMC_EPARSE, path, 0, "vertex element lacks x, y or z");
  L->has_n = found[3] >= 0 && found[4] >= 0 && found[5] >= 0;
  L->has_uv = found[6] >= 0 && found[7] >= 0;
  if (L->iface >= 0) {
    static const char *const lnames[] = {"vertex_indices", "vertex_index"};
    L->list_prop = ply__find(&elems[L->iface], lnames, 2);
    if (L->list_prop < 0 || elems[L->iface].props[L->list_prop].count_type == PLY_NONE)
      return lmc_error_set(err, LMC_EPARSE, path, 0, "face element lacks a vertex_indices list");
  }
  return LMC_OK;
}

/* The vertex rows' storage: 8 doubles per vertex. Each row takes at least a
 * few bytes of the body (the sizes of its scalars and list counts, or in
 * ASCII one character and one separator per property); bounding the count
 * by the data keeps the allocation proportional to the file, whatever the
 * header claims. */
static lmc_status ply__alloc_vertices(const char *path, const ply__elem *ev, int format,
                                      size_t body_len, double **OUT_vdata, lmc_error *err) {
  int64_t n_verts = ev->count, row_min = 0;
  for (int k = 0; k < ev->n_props; k++) {
    const ply__prop *pr = &ev->props[k];
    row_min += format == PLY_ASCII
                   ? 2
                   : ply__type_size(pr->count_type != PLY_NONE ? pr->count_type : pr->type);
  }
  if (row_min < 1) row_min = 1;
  if (n_verts > (int64_t)UINT32_MAX || n_verts > ((int64_t)body_len + 1) / row_min)
    return lmc_error_set(err, LMC_EPARSE, path, 0, "vertex count %lld exceeds the file's data",
                         (long long)n_verts);
  if (!(*OUT_vdata = calloc((size_t)n_verts * 8 + 1, sizeof(double))))
    return lmc_error_set(err, LMC_ENOMEM, path, 0, "out of memory");
  return LMC_OK;
}

/* The triangles of the faces, fanned out. */
typedef struct ply__tris {
  uint32_t *idx; /* owned: 3 per triangle */
  int64_t n, cap;
} ply__tris;

static lmc_status ply__add_tri(ply__tris *T, const char *path, double a, double b, double c,
                               lmc_error *err) {
  if (T->n == T->cap) {
    int64_t cap = T->cap ? 2 * T->cap : 1024;
    uint32_t *t = realloc(T->idx, (size_t)cap * 3 * sizeof(uint32_t));
    if (!t) return lmc_error_set(err, LMC_ENOMEM, path, 0, "out of memory");
    T->idx = t;
    T->cap = cap;
  }
  T->idx[3 * T->n] = (uint32_t)a;
  T->idx[3 * T->n + 1] = (uint32_t)b;
  T->idx[3 * T->n + 2] = (uint32_t)c;
  T->n++;
  return LMC_OK;
}

/* One list property of row r of element el: its count, then the items,
 * fanned into triangles when it is the face list (is_face), else skipped. */
static lmc_status ply__read_list(ply__in *in, const ply__elem *el, const ply__prop *pr, int64_t r,
                                 int is_face, int64_t n_verts, ply__tris *T, lmc_error *err) {
  double cnt, x;
  /* Range before the cast: converting a double beyond int64 (or NaN, which
   * ASCII files may spell) is undefined behaviour. */
  if (!ply__read(in, pr->count_type, &cnt) || !(cnt >= 0.0 && cnt <= 1e15) || cnt != floor(cnt))
    return ply__eof(in, el->name, err);
  int64_t c = (int64_t)cnt;
  int ascii = in->format == PLY_ASCII;
  if (is_face && c < 3)
    return lmc_error_set(err, LMC_EPARSE, in->path, ascii ? in->line : 0,
                         "face %lld has %lld corner(s)", (long long)r, (long long)c);
  if (!ascii && !is_face) {
    /* Skip by size. */
    int64_t bytes = c * ply__type_size(pr->type);
    if (in->end - in->p < bytes) return ply__eof(in, el->name, err);
    in->p += bytes;
    return LMC_OK;
  }
  double first = 0, prev = 0;
  for (int64_t k = 0; k < c; k++) {
    if (!ply__read(in, pr->type, &x)) return ply__eof(in, el->name, err);
    if (!is_face) continue;
    if (!(x >= 0.0 && x < (double)n_verts) || x != floor(x))
      return lmc_error_set(err, LMC_EPARSE, in->path, ascii ? in->line : 0,
                           "face %lld: vertex index %g out of range (%lld vertices)",
                           (long long)r, x, (long long)n_verts);
    if (k == 0) first = x;
    if (k >= 2) {
      lmc_status st = ply__add_tri(T, in->path, first, prev, x, err); /* fan (first, prev, x) */
      if (st != LMC_OK) return st;
    }
    prev = x;
  }
  return LMC_OK;
}

/* The body, element by element: the vertex slots into vdata, the faces
 * into T, everything else read past. */
static lmc_status ply__body(ply__in *in, const ply__elem *elems, int n_elems, const ply__layout *L,
                            double *vdata, ply__tris *T, lmc_error *err) {
  int64_t n_verts = elems[L->iv].count;
  for (int e = 0; e < n_elems; e++) {
    const ply__elem *el = &elems[e];
    /* An element without properties has no data: its rows take no bytes, so
     * its count (up to 2^63 in a header) bounds nothing and is not walked. */
    if (el->n_props == 0) continue;
    for (int64_t r = 0; r < el->count; r++) {
      if (in->p >= in->end) return ply__eof(in, el->name, err);
      for (int pi = 0; pi < el->n_props; pi++) {
        const ply__prop *pr = &el->props[pi];
        if (pr->count_type != PLY_NONE) {
          int is_face = e == L->iface && pi == L->list_prop;
          lmc_status st = ply__read_list(in, el, pr, r, is_face, n_verts, T, err);
          if (st != LMC_OK) return st;
          continue;
        }
        double x;
        if (!ply__read(in, pr->type, &x)) return ply__eof(in, el->name, err);
        if (e == L->iv && L->slot_of[pi] >= 0) vdata[8 * r + L->slot_of[pi]] = x;
      }
    }
  }
  return LMC_OK;
}

/* The mesh from the vertex rows and the triangles. */
static lmc_status ply__build(const char *path, const ply__layout *L, int64_t n_verts,
                             const double *vdata, const ply__tris *T, mesh *OUT_mesh,
                             lmc_error *err) {
  lmc_status st = mesh_alloc(OUT_mesh, n_verts, T->n, L->has_n, L->has_uv, err);
  if (st != LMC_OK) return st;
  for (int64_t i = 0; i < n_verts; i++) {
    for (int c = 0; c < 3; c++) OUT_mesh->p[3 * i + c] = (float)vdata[8 * i + c];
    if (L->has_n)
      for (int c = 0; c < 3; c++) OUT_mesh->n[3 * i + c] = (float)vdata[8 * i + 3 + c];
    if (L->has_uv)
      for (int c = 0; c < 2; c++) OUT_mesh->uv[2 * i + c] = (float)vdata[8 * i + 6 + c];
  }
  if (T->n) memcpy(OUT_mesh->idx, T->idx, (size_t)T->n * 3 * sizeof(uint32_t));
  const char *b = strrchr(path, '/');
  snprintf(OUT_mesh->name, sizeof OUT_mesh->name, "%s", b ? b + 1 : path);
  return LMC_OK;
}

lmc_status mesh_read_ply(const char *path, mesh *OUT_mesh, lmc_error *err) {
  memset(OUT_mesh, 0, sizeof *OUT_mesh);
  OUT_mesh->light = -1;
  unsigned char *buf = NULL;
  size_t len = 0;
  lmc_status st = ply__slurp(path, &buf, &len, err);
  if (st != LMC_OK) return st;

  ply__elem *elems = NULL;
  int n_elems = 0, format = 0, line = 0;
  size_t body = 0;
  st = ply__header(path, buf, len, &elems, &n_elems, &format, &body, &line, err);
  if (st != LMC_OK) {
    free(buf);
    return st;
  }
  ply__layout L;
  double *vdata = NULL;
  ply__tris T = {NULL, 0, 0};
  ply__in in = {path, buf + body, buf + len, format, line};
  st = ply__locate(path, elems, n_elems, &L, err);
  if (st == LMC_OK) st = ply__alloc_vertices(path, &elems[L.iv], format, len - body, &vdata, err);
  if (st == LMC_OK) st = ply__body(&in, elems, n_elems, &L, vdata, &T, err);
  if (st == LMC_OK) st = ply__build(path, &L, elems[L.iv].count, vdata, &T, OUT_mesh, err);
  if (st != LMC_OK && err && !err->file[0]) snprintf(err->file, sizeof err->file, "%s", path);
  free(vdata);
  free(T.idx);
  ply__free_elems(elems, n_elems);
  free(buf);
  return st;
}
