/*
 * fuzz_xml.c: libFuzzer target for the Mitsuba XML scene loader
 * (io/scene_xml_parse.c and io/scene_xml.c), the whole way from bytes to a
 * finalized scene with its Embree accelerator and light distributions.
 *
 * The input is written as scene.xml into the target's private folder,
 * which also holds small files a scene can name: tri.obj, quad.ply,
 * mesh.serialized (one triangle, version 4), tex.png, env.exr and inc.xml
 * (an <include>able fragment). They are written once per process, the
 * images with lmc's own writers and the serialized mesh with zlib, so the
 * target needs nothing from the source tree. The seed corpus refers to
 * them by these names. Errors are expected results; only crashes, hangs,
 * leaks and undefined behaviour are findings.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "fuzz_util.h"
#include "render/image.h"
#include "render/io/io.h"

static const char fuzz__obj[] =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\n";
static const char fuzz__ply[] =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
static const char fuzz__inc[] =
    "<scene version=\"0.5.0\"><bsdf type=\"diffuse\" id=\"inc\"/>"
    "<texture type=\"checkerboard\" id=\"checks\"/></scene>\n";

/* Appends n little-endian bytes of v. */
static unsigned char *fuzz__le(unsigned char *p, uint64_t v, int n) {
  for (int i = 0; i < n; i++) p[i] = (unsigned char)(v >> (8 * i));
  return p + n;
}

/* One triangle as a version-4 .serialized file, single precision. */
static void fuzz__write_serialized(void) {
  unsigned char raw[256], *p = raw;
  p = fuzz__le(p, 0x1000u, 4); /* flags: single precision */
  *p++ = '\0';                 /* name */
  p = fuzz__le(p, 3, 8);
  p = fuzz__le(p, 1, 8);
  const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  for (int i = 0; i < 9; i++) {
    uint32_t bits;
    memcpy(&bits, &pos[i], 4);
    p = fuzz__le(p, bits, 4);
  }
  for (uint32_t i = 0; i < 3; i++) p = fuzz__le(p, i, 4);
  unsigned char file[512], *q = file;
  q = fuzz__le(q, 0x041C, 2);
  q = fuzz__le(q, 4, 2);
  uLongf zlen = (uLongf)(sizeof file - 32);
  if (compress(q, &zlen, raw, (uLong)(p - raw)) != Z_OK) abort();
  q += zlen;
  q = fuzz__le(q, 0, 8); /* offset of shape 0 */
  q = fuzz__le(q, 1, 4); /* one shape */
  fuzz_write("mesh.serialized", file, (size_t)(q - file));
}

/* Writes the auxiliary files once. */
static void fuzz__setup(void) {
  static int done;
  if (done) return;
  done = 1;
  fuzz_write("tri.obj", fuzz__obj, sizeof fuzz__obj - 1);
  fuzz_write("quad.ply", fuzz__ply, sizeof fuzz__ply - 1);
  fuzz_write("inc.xml", fuzz__inc, sizeof fuzz__inc - 1);
  fuzz__write_serialized();
  lmc_image img;
  lmc_error err;
  if (image_init(&img, 4, 2, 3, &err) != LMC_OK) abort();
  for (int i = 0; i < 4 * 2 * 3; i++) img.data[i] = (float)(i % 7) * 0.25f;
  char path[512];
  snprintf(path, sizeof path, "%s/tex.png", fuzz_dir());
  if (image_write_png(path, &img, 1.0, &err) != LMC_OK) abort();
  snprintf(path, sizeof path, "%s/env.exr", fuzz_dir());
  if (image_write_exr(path, &img, &err) != LMC_OK) abort();
  image_free(&img);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  lmc_warn_set_quiet(1);
  fuzz__setup();
  const char *path = fuzz_write("scene.xml", data, size);
  scene *s = NULL;
  lmc_error err;
  lmc_error_clear(&err);
  static const char *const defines[] = {"fuzzdef=1"};
  if (scene_load_xml(path, defines, 1, &s, &err) == LMC_OK) scene_destroy(s);
  return 0;
}
