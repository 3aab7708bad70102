/*
 * mesh_serialized.c: Mitsuba's `.serialized` mesh files (versions 3 and 4).
 *
 * Layout (all little-endian), as documented by Mitsuba's serialized plugin:
 * the file is a sequence of shapes, each being
 *   uint16 format id 0x041C, uint16 version (3 or 4),
 *   then a zlib stream holding
 *     uint32 flags (0x0001 vertex normals, 0x0002 texture coordinates,
 *                   0x0008 vertex colours, 0x0010 face normals,
 *                   0x1000 single precision, 0x2000 double precision;
 *                   with neither, single precision, as Mitsuba assumes),
 *     version 4 only: the shape's name, NUL-terminated,
 *     uint64 vertex count, uint64 triangle count,
 *     positions (3 per vertex), normals (3, if 0x0001), texture
 *     coordinates (2, if 0x0002), colours (3, if 0x0008; skipped here),
 *     triangle indices (3 per triangle; uint32, or uint64 when the vertex
 *     count exceeds 2^32 - 1, which we cannot index and reject).
 * The file ends with the byte offset of each shape (uint64 in version 4,
 * uint32 in version 3) followed by a uint32 shape count.
 *
 * We inflate the requested shape's stream into memory (growing the buffer
 * as zlib produces output, never trusting a declared size) and only then
 * check the declared counts against the decompressed length, so a corrupt
 * or truncated file fails cleanly instead of allocating wildly.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "render/io/io.h"

#define SER_FORMAT_ID 0x041C
#define SER_HAS_NORMALS 0x0001u
#define SER_HAS_TEXCOORDS 0x0002u
#define SER_HAS_COLORS 0x0008u
#define SER_FACE_NORMALS 0x0010u
#define SER_SINGLE 0x1000u
#define SER_DOUBLE 0x2000u

static uint64_t ser__le(const unsigned char *b, int n) {
  uint64_t v = 0;
  for (int i = n - 1; i >= 0; i--) v = (v << 8) | b[i];
  return v;
}

/* Inflates the zlib stream that starts at the current position of f into a
 * freshly allocated buffer. */
static lmc_status ser__inflate(FILE *f, const char *path, unsigned char **out, size_t *out_len,
                               lmc_error *err) {
  z_stream zs;
  memset(&zs, 0, sizeof zs);
  if (inflateInit(&zs) != Z_OK) return lmc_error_set(err, LMC_ENOMEM, path, 0, "zlib init failed");
  unsigned char in[32768];
  size_t cap = 1 << 16, len = 0;
  unsigned char *buf = malloc(cap);
  lmc_status st = buf ? LMC_OK : lmc_error_set(err, LMC_ENOMEM, path, 0, "out of memory");
  int ret = Z_OK;
  while (st == LMC_OK && ret != Z_STREAM_END) {
    if (zs.avail_in == 0) {
      size_t n = fread(in, 1, sizeof in, f);
      if (n == 0) {
        st = lmc_error_set(err, LMC_EPARSE, path, 0, "truncated compressed shape data");
        break;
      }
      zs.next_in = in;
      zs.avail_in = (uInt)n;
    }
    if (len == cap) {
      unsigned char *b = cap > ((size_t)1 << 40) ? NULL : realloc(buf, cap * 2);
      if (!b) {
        st = lmc_error_set(err, LMC_ENOMEM, path, 0, "out of memory inflating a shape");
        break;
      }
      buf = b;
      cap *= 2;
    }
    zs.next_out = buf + len;
    zs.avail_out = (uInt)((cap - len) > 0x40000000u ? 0x40000000u : (cap - len));
    uInt before = zs.avail_out;
    ret = inflate(&zs, Z_NO_FLUSH);
    len += before - zs.avail_out;
    if (ret != Z_OK && ret != Z_STREAM_END && ret != Z_BUF_ERROR)
      st = lmc_error_set(err, LMC_EPARSE, path, 0, "corrupt compressed shape data (%s)",
                         zs.msg ? zs.msg : "zlib error");
  }
  inflateEnd(&zs);
  if (st != LMC_OK) {
    free(buf);
    return st;
  }
  *out = buf;
  *out_len = len;
  return LMC_OK;
}

/* Reads n floats (single or double) from the decompressed data into dst
 * (which may be NULL to skip). */
static void ser__floats(const unsigned char *src, int64_t n, int dbl, float *dst) {
  if (!dst) return;
  for (int64_t i = 0; i < n; i++) {
    if (dbl) {
      uint64_t u = ser__le(src + 8 * i, 8);
      double d;
      memcpy(&d, &u, 8);
      dst[i] = (float)d;
    } else {
      uint32_t u = (uint32_t)ser__le(src + 4 * i, 4);
      float x;
      memcpy(&x, &u, 4);
      dst[i] = x;
    }
  }
}

lmc_status mesh_read_serialized(const char *path, int shape_index, mesh *OUT_mesh,
                                lmc_error *err) {
  memset(OUT_mesh, 0, sizeof *OUT_mesh);
  OUT_mesh->light = -1;
  if (shape_index < 0)
    return lmc_error_set(err, LMC_EINVAL, path, 0, "negative shape index %d", shape_index);
  FILE *f = fopen(path, "rb");
  if (!f) return lmc_error_set(err, LMC_EIO, path, 0, "cannot open: %s", strerror(errno));

  /* The first header tells the version, hence the offset table's layout. */
  lmc_status st = LMC_OK;
  unsigned char hdr[8];
  long file_size = -1;
  if (fread(hdr, 1, 4, f) != 4 || ser__le(hdr, 2) != SER_FORMAT_ID)
    st = lmc_error_set(err, LMC_EPARSE, path, 0, "not a Mitsuba serialized mesh file");
  unsigned version = (unsigned)ser__le(hdr + 2, 2);
  if (st == LMC_OK && version != 3 && version != 4)
    st = lmc_error_set(err, LMC_EUNSUPPORTED, path, 0, "serialized file version %u (need 3 or 4)",
                       version);
  if (st == LMC_OK && (fseek(f, 0, SEEK_END) != 0 || (file_size = ftell(f)) < 8))
    st = lmc_error_set(err, LMC_EPARSE, path, 0, "file too short");

  /* The shape table at the end: offsets, then the count. */
  uint64_t offset = 0;
  if (st == LMC_OK) {
    uint32_t count = 0;
    if (fseek(f, file_size - 4, SEEK_SET) != 0 || fread(hdr, 1, 4, f) != 4)
      st = lmc_error_set(err, LMC_EIO, path, 0, "cannot read the shape table");
    else
      count = (uint32_t)ser__le(hdr, 4);
    int osize = version == 4 ? 8 : 4;
    if (st == LMC_OK && (count == 0 || (uint64_t)count * (uint64_t)osize + 4 > (uint64_t)file_size))
      st = lmc_error_set(err, LMC_EPARSE, path, 0, "corrupt shape table (count %lu)",
                         (unsigned long)count);
    if (st == LMC_OK && (uint32_t)shape_index >= count)
      st = lmc_error_set(err, LMC_EINVAL, path, 0, "shape index %d out of range (the file has %lu)",
                         shape_index, (unsigned long)count);
    if (st == LMC_OK) {
      long at = file_size - 4 - (long)osize * (long)(count - (uint32_t)shape_index);
      if (fseek(f, at, SEEK_SET) != 0 || fread(hdr, 1, (size_t)osize, f) != (size_t)osize)
        st = lmc_error_set(err, LMC_EIO, path, 0, "cannot read the shape table");
      else
        offset = ser__le(hdr, osize);
      if (st == LMC_OK && offset + 4 >= (uint64_t)file_size)
        st = lmc_error_set(err, LMC_EPARSE, path, 0, "shape %d: offset %llu beyond the file",
                           shape_index, (unsigned long long)offset);
    }
  }

  /* The shape's own header, then its stream. */
  if (st == LMC_OK) {
    if (fseek(f, (long)offset, SEEK_SET) != 0 || fread(hdr, 1, 4, f) != 4 ||
        ser__le(hdr, 2) != SER_FORMAT_ID || ser__le(hdr + 2, 2) != version)
      st = lmc_error_set(err, LMC_EPARSE, path, 0, "shape %d: bad header at offset %llu",
                         shape_index, (unsigned long long)offset);
  }
  unsigned char *d = NULL;
  size_t dlen = 0;
  if (st == LMC_OK) st = ser__inflate(f, path, &d, &dlen, err);
  fclose(f);
  if (st != LMC_OK) return st;

  /* Parse the decompressed data, checking every size against dlen. */
  size_t pos = 0;
  uint32_t flags = 0;
  uint64_t nv = 0, nt = 0;
  char name[128] = "";
  if (dlen < 4) st = lmc_error_set(err, LMC_EPARSE, path, 0, "shape %d: truncated", shape_index);
  else flags = (uint32_t)ser__le(d, 4), pos = 4;
  if (st == LMC_OK && version == 4) {
    size_t k = 0;
    while (pos < dlen && d[pos] != 0) {
      if (k + 1 < sizeof name) name[k++] = (char)d[pos];
      pos++;
    }
    name[k] = '\0';
    if (pos >= dlen) st = lmc_error_set(err, LMC_EPARSE, path, 0, "shape %d: truncated name", shape_index);
    pos++;
  }
  if (st == LMC_OK) {
    if (dlen - pos < 16) {
      st = lmc_error_set(err, LMC_EPARSE, path, 0, "shape %d: truncated", shape_index);
    } else {
      nv = ser__le(d + pos, 8);
      nt = ser__le(d + pos + 8, 8);
      pos += 16;
    }
  }
  int dbl = (flags & SER_DOUBLE) != 0;
  /* Without either precision flag the data is single precision (as Mitsuba reads it). */
  if (st == LMC_OK && (flags & SER_SINGLE) && (flags & SER_DOUBLE))
    st = lmc_error_set(err, LMC_EPARSE, path, 0, "shape %d: both precision flags", shape_index);
  if (st == LMC_OK && nv > (uint64_t)UINT32_MAX)
    st = lmc_error_set(err, LMC_EUNSUPPORTED, path, 0, "shape %d: %llu vertices (64-bit indices)",
                       shape_index, (unsigned long long)nv);
  size_t fsz = dbl ? 8 : 4;
  int per_vertex = 3 + ((flags & SER_HAS_NORMALS) ? 3 : 0) + ((flags & SER_HAS_TEXCOORDS) ? 2 : 0) +
                   ((flags & SER_HAS_COLORS) ? 3 : 0);
  if (st == LMC_OK) {
    /* Both counts are bounded by the data they claim: no overflow below. */
    uint64_t avail = dlen - pos;
    if (nt > avail / 12 || nv > avail / (fsz * (size_t)per_vertex) ||
        nv * fsz * (uint64_t)per_vertex + nt * 12 > avail)
      st = lmc_error_set(err, LMC_EPARSE, path, 0,
                         "shape %d: %llu vertices and %llu triangles do not fit in %llu bytes",
                         shape_index, (unsigned long long)nv, (unsigned long long)nt,
                         (unsigned long long)avail);
  }
  if (st == LMC_OK)
    st = mesh_alloc(OUT_mesh, (int64_t)nv, (int64_t)nt, (flags & SER_HAS_NORMALS) != 0,
                    (flags & SER_HAS_TEXCOORDS) != 0, err);
  if (st == LMC_OK) {
    ser__floats(d + pos, (int64_t)nv * 3, dbl, OUT_mesh->p);
    pos += nv * 3 * fsz;
    if (flags & SER_HAS_NORMALS) {
      ser__floats(d + pos, (int64_t)nv * 3, dbl, OUT_mesh->n);
      pos += nv * 3 * fsz;
    }
    if (flags & SER_HAS_TEXCOORDS) {
      ser__floats(d + pos, (int64_t)nv * 2, dbl, OUT_mesh->uv);
      pos += nv * 2 * fsz;
    }
    if (flags & SER_HAS_COLORS) pos += nv * 3 * fsz; /* colours: skipped */
    for (uint64_t i = 0; i < 3 * nt; i++) {
      uint32_t v = (uint32_t)ser__le(d + pos + 4 * i, 4);
      if (v >= nv) {
        st = lmc_error_set(err, LMC_EPARSE, path, 0,
                           "shape %d: triangle %llu refers to vertex %lu of %llu", shape_index,
                           (unsigned long long)(i / 3), (unsigned long)v, (unsigned long long)nv);
        break;
      }
      OUT_mesh->idx[i] = v;
    }
    OUT_mesh->face_normals = (flags & SER_FACE_NORMALS) != 0;
    const char *b = strrchr(path, '/');
    if (name[0])
      snprintf(OUT_mesh->name, sizeof OUT_mesh->name, "%s", name);
    else
      snprintf(OUT_mesh->name, sizeof OUT_mesh->name, "%.100s@%d", b ? b + 1 : path, shape_index);
  }
  free(d);
  if (st != LMC_OK) mesh_free(OUT_mesh);
  return st;
}
