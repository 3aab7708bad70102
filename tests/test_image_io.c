/*
 * test_image_io.c: image readers and writers (PNG, JPEG, OpenEXR), format
 * dispatch by magic bytes, the sRGB curve, the size limits every reader
 * checks in the header, PNG chunks that claim more memory than the file
 * holds, EXR chunks that ZIP does not shrink (stored raw, read back bit for
 * bit; OpenEXRCore's own encoder finds one whose deflate stream is exactly
 * as long as the raw data), and the writers' promise never to leave a
 * partial file behind.
 *
 * Test images are generated into /tmp: PNGs of every colour type and depth
 * with libpng directly, two small JPEGs embedded below (made with libjpeg
 * at quality 100 from flat colours), EXRs with our own writer. The torus
 * scene's checker.png and sunsky.exr (../shared) are read when present.
 */
#define _POSIX_C_SOURCE 200809L

#include <dirent.h>
#include <math.h>
#include <openexr.h>
#include <png.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <cmocka.h>

#include "test_util.h"

#include "render/image.h"

/* 16x8 RGB (200, 100, 50) and 8x8 grey 128, libjpeg quality 100. */
static const unsigned char rgb_jpg[635] = {
    255, 216, 255, 224, 0, 16, 74, 70, 73, 70, 0, 1, 1, 0, 0, 1, 0, 1, 0, 0,
    255, 219, 0, 67, 0, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1,
    1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1,
    1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1,
    1, 1, 1, 1, 1, 1, 1, 1, 1, 255, 219, 0, 67, 1, 1, 1, 1, 1, 1, 1,
    1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1,
    1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1,
    1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 255, 192,
    0, 17, 8, 0, 8, 0, 16, 3, 1, 34, 0, 2, 17, 1, 3, 17, 1, 255, 196, 0,
    31, 0, 0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 1,
    2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 255, 196, 0, 181, 16, 0, 2, 1, 3, 3,
    2, 4, 3, 5, 5, 4, 4, 0, 0, 1, 125, 1, 2, 3, 0, 4, 17, 5, 18, 33,
    49, 65, 6, 19, 81, 97, 7, 34, 113, 20, 50, 129, 145, 161, 8, 35, 66, 177, 193, 21,
    82, 209, 240, 36, 51, 98, 114, 130, 9, 10, 22, 23, 24, 25, 26, 37, 38, 39, 40, 41,
    42, 52, 53, 54, 55, 56, 57, 58, 67, 68, 69, 70, 71, 72, 73, 74, 83, 84, 85, 86,
    87, 88, 89, 90, 99, 100, 101, 102, 103, 104, 105, 106, 115, 116, 117, 118, 119, 120, 121, 122,
    131, 132, 133, 134, 135, 136, 137, 138, 146, 147, 148, 149, 150, 151, 152, 153, 154, 162, 163, 164,
    165, 166, 167, 168, 169, 170, 178, 179, 180, 181, 182, 183, 184, 185, 186, 194, 195, 196, 197, 198,
    199, 200, 201, 202, 210, 211, 212, 213, 214, 215, 216, 217, 218, 225, 226, 227, 228, 229, 230, 231,
    232, 233, 234, 241, 242, 243, 244, 245, 246, 247, 248, 249, 250, 255, 196, 0, 31, 1, 0, 3,
    1, 1, 1, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 1, 2, 3, 4, 5,
    6, 7, 8, 9, 10, 11, 255, 196, 0, 181, 17, 0, 2, 1, 2, 4, 4, 3, 4, 7,
    5, 4, 4, 0, 1, 2, 119, 0, 1, 2, 3, 17, 4, 5, 33, 49, 6, 18, 65, 81,
    7, 97, 113, 19, 34, 50, 129, 8, 20, 66, 145, 161, 177, 193, 9, 35, 51, 82, 240, 21,
    98, 114, 209, 10, 22, 36, 52, 225, 37, 241, 23, 24, 25, 26, 38, 39, 40, 41, 42, 53,
    54, 55, 56, 57, 58, 67, 68, 69, 70, 71, 72, 73, 74, 83, 84, 85, 86, 87, 88, 89,
    90, 99, 100, 101, 102, 103, 104, 105, 106, 115, 116, 117, 118, 119, 120, 121, 122, 130, 131, 132,
    133, 134, 135, 136, 137, 138, 146, 147, 148, 149, 150, 151, 152, 153, 154, 162, 163, 164, 165, 166,
    167, 168, 169, 170, 178, 179, 180, 181, 182, 183, 184, 185, 186, 194, 195, 196, 197, 198, 199, 200,
    201, 202, 210, 211, 212, 213, 214, 215, 216, 217, 218, 226, 227, 228, 229, 230, 231, 232, 233, 234,
    242, 243, 244, 245, 246, 247, 248, 249, 250, 255, 218, 0, 12, 3, 1, 0, 2, 17, 3, 17,
    0, 63, 0, 231, 232, 162, 138, 255, 0, 43, 207, 246, 192, 255, 217,
};
static const unsigned char grey_jpg[331] = {
    255, 216, 255, 224, 0, 16, 74, 70, 73, 70, 0, 1, 1, 0, 0, 1, 0, 1, 0, 0,
    255, 219, 0, 67, 0, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1,
    1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1,
    1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1,
    1, 1, 1, 1, 1, 1, 1, 1, 1, 255, 192, 0, 11, 8, 0, 8, 0, 8, 1, 1,
    17, 0, 255, 196, 0, 31, 0, 0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0,
    0, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 255, 196, 0, 181, 16,
    0, 2, 1, 3, 3, 2, 4, 3, 5, 5, 4, 4, 0, 0, 1, 125, 1, 2, 3, 0,
    4, 17, 5, 18, 33, 49, 65, 6, 19, 81, 97, 7, 34, 113, 20, 50, 129, 145, 161, 8,
    35, 66, 177, 193, 21, 82, 209, 240, 36, 51, 98, 114, 130, 9, 10, 22, 23, 24, 25, 26,
    37, 38, 39, 40, 41, 42, 52, 53, 54, 55, 56, 57, 58, 67, 68, 69, 70, 71, 72, 73,
    74, 83, 84, 85, 86, 87, 88, 89, 90, 99, 100, 101, 102, 103, 104, 105, 106, 115, 116, 117,
    118, 119, 120, 121, 122, 131, 132, 133, 134, 135, 136, 137, 138, 146, 147, 148, 149, 150, 151, 152,
    153, 154, 162, 163, 164, 165, 166, 167, 168, 169, 170, 178, 179, 180, 181, 182, 183, 184, 185, 186,
    194, 195, 196, 197, 198, 199, 200, 201, 202, 210, 211, 212, 213, 214, 215, 216, 217, 218, 225, 226,
    227, 228, 229, 230, 231, 232, 233, 234, 241, 242, 243, 244, 245, 246, 247, 248, 249, 250, 255, 218,
    0, 8, 1, 1, 0, 0, 63, 0, 43, 255, 217,
};

/* 5x3 tiled (2x2 tiles, uncompressed) half-float RGBA written with
 * OpenEXRCore: pixel i has R, G, B, A = 1, 2, 3, 4 plus i / 16. */
static const unsigned char tiled_exr[673] = {
    118, 47, 49, 1, 2, 2, 0, 0, 116, 121, 112, 101, 0, 115, 116, 114, 105, 110, 103, 0,
    10, 0, 0, 0, 116, 105, 108, 101, 100, 105, 109, 97, 103, 101, 99, 111, 109, 112, 114, 101,
    115, 115, 105, 111, 110, 0, 99, 111, 109, 112, 114, 101, 115, 115, 105, 111, 110, 0, 1, 0,
    0, 0, 0, 100, 97, 116, 97, 87, 105, 110, 100, 111, 119, 0, 98, 111, 120, 50, 105, 0,
    16, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 4, 0, 0, 0, 2, 0, 0, 0,
    100, 105, 115, 112, 108, 97, 121, 87, 105, 110, 100, 111, 119, 0, 98, 111, 120, 50, 105, 0,
    16, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 4, 0, 0, 0, 2, 0, 0, 0,
    108, 105, 110, 101, 79, 114, 100, 101, 114, 0, 108, 105, 110, 101, 79, 114, 100, 101, 114, 0,
    1, 0, 0, 0, 0, 112, 105, 120, 101, 108, 65, 115, 112, 101, 99, 116, 82, 97, 116, 105,
    111, 0, 102, 108, 111, 97, 116, 0, 4, 0, 0, 0, 0, 0, 128, 63, 115, 99, 114, 101,
    101, 110, 87, 105, 110, 100, 111, 119, 67, 101, 110, 116, 101, 114, 0, 118, 50, 102, 0, 8,
    0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 115, 99, 114, 101, 101, 110, 87, 105, 110,
    100, 111, 119, 87, 105, 100, 116, 104, 0, 102, 108, 111, 97, 116, 0, 4, 0, 0, 0, 0,
    0, 128, 63, 116, 105, 108, 101, 115, 0, 116, 105, 108, 101, 100, 101, 115, 99, 0, 9, 0,
    0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 0, 99, 104, 97, 110, 110, 101, 108, 115, 0,
    99, 104, 108, 105, 115, 116, 0, 73, 0, 0, 0, 65, 0, 1, 0, 0, 0, 0, 0, 0,
    0, 1, 0, 0, 0, 1, 0, 0, 0, 66, 0, 1, 0, 0, 0, 0, 0, 0, 0, 1,
    0, 0, 0, 1, 0, 0, 0, 71, 0, 1, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0,
    0, 1, 0, 0, 0, 82, 0, 1, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1,
    0, 0, 0, 0, 0, 177, 1, 0, 0, 0, 0, 0, 0, 229, 1, 0, 0, 0, 0, 0,
    0, 25, 2, 0, 0, 0, 0, 0, 0, 61, 2, 0, 0, 0, 0, 0, 0, 97, 2, 0,
    0, 0, 0, 0, 0, 133, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
    0, 0, 0, 0, 0, 0, 0, 0, 0, 32, 0, 0, 0, 0, 68, 16, 68, 0, 66, 32,
    66, 0, 64, 32, 64, 0, 60, 64, 60, 80, 68, 96, 68, 160, 66, 192, 66, 160, 64, 192,
    64, 64, 61, 128, 61, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
    0, 32, 0, 0, 0, 32, 68, 48, 68, 64, 66, 96, 66, 64, 64, 96, 64, 128, 60, 192,
    60, 112, 68, 128, 68, 224, 66, 0, 67, 224, 64, 0, 65, 192, 61, 0, 62, 2, 0, 0,
    0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 16, 0, 0, 0, 64, 68, 128,
    66, 128, 64, 0, 61, 144, 68, 32, 67, 32, 65, 64, 62, 0, 0, 0, 0, 1, 0, 0,
    0, 0, 0, 0, 0, 0, 0, 0, 0, 16, 0, 0, 0, 160, 68, 176, 68, 64, 67, 96,
    67, 64, 65, 96, 65, 128, 62, 192, 62, 1, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0,
    0, 0, 0, 0, 0, 16, 0, 0, 0, 192, 68, 208, 68, 128, 67, 160, 67, 128, 65, 160,
    65, 0, 63, 64, 63, 2, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
    0, 8, 0, 0, 0, 224, 68, 192, 67, 192, 65, 128, 63,
};

static void check_ok(lmc_status st, const lmc_error *err) {
  if (st != LMC_OK) {
    char buf[2048];
    lmc_error_format(err, buf, sizeof buf);
    fail_msg("unexpected error: %s", buf);
  }
}

static int write_file(const char *path, const void *data, size_t n) {
  FILE *f = fopen(path, "wb");
  if (!f) return 0;
  size_t w = fwrite(data, 1, n, f);
  fclose(f);
  return w == n;
}

static unsigned char *read_all(const char *path, size_t *n) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  unsigned char *buf = malloc(1 << 24);
  *n = fread(buf, 1, 1 << 24, f);
  fclose(f);
  return buf;
}

/* Counts directory entries whose name starts with prefix. */
static int count_files(const char *dir, const char *prefix) {
  DIR *d = opendir(dir);
  if (!d) return -1;
  int n = 0;
  struct dirent *e;
  while ((e = readdir(d)))
    if (strncmp(e->d_name, prefix, strlen(prefix)) == 0) n++;
  closedir(d);
  return n;
}

/* A deterministic generator for test values (xorshift64*). */
static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static double rnd(void) {
  rng_state ^= rng_state >> 12;
  rng_state ^= rng_state << 25;
  rng_state ^= rng_state >> 27;
  return (double)((rng_state * 0x2545F4914F6CDD1Dull) >> 11) / 9007199254740992.0;
}

/* ---- sRGB ------------------------------------------------------------------ */

static void test_srgb_curve(void **state) {
  (void)state;
  int n = 0;
  for (int i = 0; i <= 1000; i++) {
    double v = i / 1000.0;
    assert_near(linear_to_srgb(srgb_to_linear(v)), v, 1e-12);
    n++;
  }
  assert_int_equal(n, 1001);
  assert_near(srgb_to_linear(1.0), 1.0, 1e-15);
  assert_near(srgb_to_linear(0.5), 0.21404114048223255, 1e-12);
  assert_near(linear_to_srgb(0.001), 0.01292, 1e-12);
}

/* ---- EXR ------------------------------------------------------------------- */

static void test_exr_roundtrip(void **state) {
  (void)state;
  lmc_image img, back;
  lmc_error err;
  /* 37 x 23: neither a multiple of the 16-line ZIP chunk nor square. */
  check_ok(image_init(&img, 37, 23, 3, &err), &err);
  for (int i = 0; i < 37 * 23 * 3; i++) img.data[i] = (float)((rnd() - 0.2) * pow(10.0, 8 * rnd() - 4));
  img.data[0] = 0.0f;
  img.data[1] = -0.0f;
  img.data[2] = 1e-40f; /* denormal */
  img.data[3] = 3.0e38f;
  const char *path = "/tmp/lmc_test_imageio.exr";
  check_ok(image_write_exr(path, &img, &err), &err);
  check_ok(image_read(path, 1, &back, &err), &err);
  assert_int_equal(back.width, 37);
  assert_int_equal(back.height, 23);
  assert_int_equal(back.channels, 3);
  assert_memory_equal(back.data, img.data, sizeof(float) * 37 * 23 * 3);
  image_free(&back);
  /* Overwriting an existing file works and leaves no temporary behind. */
  img.data[5] = 42.0f;
  check_ok(image_write_exr(path, &img, &err), &err);
  check_ok(image_read_exr(path, &back, &err), &err);
  assert_near(back.data[5], 42.0, 0.0);
  image_free(&back);
  assert_int_equal(count_files("/tmp", "lmc_test_imageio.exr.tmp"), 0);

  /* Truncations of the file are errors, not crashes. */
  size_t n = 0;
  unsigned char *bytes = read_all(path, &n);
  assert_non_null(bytes);
  int n_err = 0, n_cut = 0;
  for (size_t cut = 0; cut < n; cut += n / 13 + 1) {
    const char *tpath = "/tmp/lmc_test_imageio_cut.exr";
    assert_true(write_file(tpath, bytes, cut));
    n_cut++;
    if (image_read(tpath, 0, &back, &err) != LMC_OK) n_err++;
    else image_free(&back);
    remove(tpath);
  }
  assert_int_equal(n_err, n_cut);
  free(bytes);
  image_free(&img);
  remove(path);
}

/* ---- EXR chunks stored raw ------------------------------------------------ */

/* The chunk image_write_exr stores as ZIP: 64 x 16 RGB floats, 12288 bytes. */
enum { RAW_W = 64, RAW_LINES = 16, RAW_FLOATS = RAW_W * RAW_LINES * 3 };

/* Compresses the first chunk of img (RAW_W wide) with OpenEXRCore's own ZIP
 * compressor, as image_write_exr hands it the pixels, without writing it:
 * OUT_packed is the raw size, the return the deflate size (0 on error). */
static uint64_t zip_size(exr_context_t ctxt, const float *rgb, uint64_t *OUT_packed) {
  exr_chunk_info_t cinfo;
  exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
  if (exr_write_scanline_chunk_info(ctxt, 0, 0, &cinfo) != EXR_ERR_SUCCESS ||
      exr_encoding_initialize(ctxt, 0, &cinfo, &enc) != EXR_ERR_SUCCESS)
    return 0;
  for (int c = 0; c < enc.channel_count; c++) {
    exr_coding_channel_info_t *ci = &enc.channels[c];
    int k = ci->channel_name[0] == 'R' ? 0 : ci->channel_name[0] == 'G' ? 1 : 2;
    ci->encode_from_ptr = (const uint8_t *)(rgb + k);
    ci->user_pixel_stride = 3 * (int32_t)sizeof(float);
    ci->user_line_stride = 3 * (int32_t)sizeof(float) * RAW_W;
    ci->user_bytes_per_element = 4;
    ci->user_data_type = EXR_PIXEL_FLOAT;
  }
  uint64_t size = 0;
  if (exr_encoding_choose_default_routines(ctxt, 0, &enc) == EXR_ERR_SUCCESS) {
    enc.write_fn = NULL;
    if (exr_encoding_run(ctxt, 0, &enc) == EXR_ERR_SUCCESS) size = enc.compressed_bytes;
  }
  *OUT_packed = enc.packed_bytes;
  exr_encoding_destroy(ctxt, &enc);
  return size;
}

/* Fills chunk (RAW_FLOATS floats) with k floats of noise (31 random bits,
 * always finite), then one float with `bits` random low mantissa bits, then
 * the constant 0.5: the deflate size grows with k by about 4 bytes and with
 * bits by fractions of a byte. */
static void fill_noise(float *chunk, const uint32_t *noise, int k, int bits) {
  for (int i = 0; i < RAW_FLOATS; i++) {
    uint32_t u = 0x3F000000u;
    if (i < k) u = noise[i] & 0xBFFFFFFFu;
    else if (i == k) u |= noise[i] & (uint32_t)((1ull << bits) - 1);
    memcpy(&chunk[i], &u, sizeof u);
  }
}

/* Searches for a chunk whose deflate stream is exactly as long as its raw
 * data, the case where a ZIP chunk must be stored raw although compression
 * did not make it longer. Returns 1 if found (chunk filled), else 0. */
static int find_exact_zip_chunk(float *chunk) {
  const char *path = "/tmp/lmc_test_imageio_probe.exr";
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  exr_context_t ctxt = NULL;
  int part = 0, found = 0;
  static const char *const names[3] = {"R", "G", "B"};
  exr_result_t rv = exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, &init);
  if (rv == EXR_ERR_SUCCESS) rv = exr_add_part(ctxt, "", EXR_STORAGE_SCANLINE, &part);
  if (rv == EXR_ERR_SUCCESS)
    rv = exr_initialize_required_attr_simple(ctxt, part, RAW_W, RAW_LINES, EXR_COMPRESSION_ZIP);
  for (int c = 0; c < 3 && rv == EXR_ERR_SUCCESS; c++)
    rv = exr_add_channel(ctxt, part, names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR, 1, 1);
  if (rv == EXR_ERR_SUCCESS) rv = exr_write_header(ctxt);
  uint32_t *noise = malloc(sizeof(uint32_t) * RAW_FLOATS);
  for (int seed = 0; rv == EXR_ERR_SUCCESS && !found && seed < 64; seed++) {
    for (int i = 0; i < RAW_FLOATS; i++) noise[i] = (uint32_t)(rnd() * 4294967296.0);
    /* The last k, from the top, at which the chunk still compresses... */
    uint64_t packed = 0, size = 0;
    int k = RAW_FLOATS;
    do {
      fill_noise(chunk, noise, --k, 0);
      size = zip_size(ctxt, chunk, &packed);
    } while (k > 0 && size >= packed);
    /* ...and one more noisy float, bit by bit, around it. */
    for (int kk = k - 1; !found && kk <= k + 1; kk++)
      for (int bits = 0; !found && bits < 32; bits++) {
        fill_noise(chunk, noise, kk, bits);
        found = zip_size(ctxt, chunk, &packed) == packed && packed == sizeof(float) * RAW_FLOATS;
        if (found)
          printf("  exact-size ZIP chunk: seed %d, %d noisy floats + %d bits\n", seed, kk, bits);
      }
  }
  free(noise);
  exr_finish(&ctxt);
  remove(path);
  return found;
}

/* ZIP chunks that deflate does not shrink are stored raw (packed size ==
 * unpacked size), which readers take as "not compressed". Three chunks: a
 * smooth one (compressed), noise that deflate makes longer, and one whose
 * deflate stream has exactly the raw size: OpenEXRCore before 3.4.8 stores
 * that stream, which every reader then takes for raw floats. */
static void test_exr_raw_chunks(void **state) {
  (void)state;
  lmc_image img, back;
  lmc_error err;
  check_ok(image_init(&img, RAW_W, 3 * RAW_LINES, 3, &err), &err);
  for (int i = 0; i < RAW_FLOATS; i++) img.data[i] = (float)(i % (3 * RAW_W)) / 256.0f;
  for (int i = 0; i < RAW_FLOATS; i++) {
    uint32_t u = (uint32_t)(rnd() * 4294967296.0) & 0xBFFFFFFFu;
    memcpy(&img.data[RAW_FLOATS + i], &u, sizeof u);
  }
  assert_true(find_exact_zip_chunk(img.data + 2 * RAW_FLOATS));

  const char *path = "/tmp/lmc_test_imageio_raw.exr";
  check_ok(image_write_exr(path, &img, &err), &err);
  /* How each chunk was stored: compressed, raw, raw. */
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  exr_context_t ctxt = NULL;
  assert_int_equal(exr_start_read(&ctxt, path, &init), EXR_ERR_SUCCESS);
  int n_raw = 0;
  for (int c = 0; c < 3; c++) {
    exr_chunk_info_t cinfo;
    assert_int_equal(exr_read_scanline_chunk_info(ctxt, 0, c * RAW_LINES, &cinfo), EXR_ERR_SUCCESS);
    assert_int_equal(cinfo.unpacked_size, sizeof(float) * RAW_FLOATS);
    if (c == 0) assert_true(cinfo.packed_size < cinfo.unpacked_size);
    else if (cinfo.packed_size == cinfo.unpacked_size) n_raw++;
  }
  exr_finish(&ctxt);
  assert_int_equal(n_raw, 2);

  /* Bit for bit back. */
  check_ok(image_read_exr(path, &back, &err), &err);
  assert_int_equal(back.width, RAW_W);
  assert_int_equal(back.height, 3 * RAW_LINES);
  int n_same[3] = {0, 0, 0};
  for (int i = 0; i < 3 * RAW_FLOATS; i++)
    if (memcmp(&back.data[i], &img.data[i], sizeof(float)) == 0) n_same[i / RAW_FLOATS]++;
  printf("  floats back bit for bit per chunk: %d %d %d of %d\n", n_same[0], n_same[1], n_same[2],
         RAW_FLOATS);
  for (int c = 0; c < 3; c++) assert_int_equal(n_same[c], RAW_FLOATS);
  image_free(&back);
  image_free(&img);
  remove(path);
}

static void test_exr_sunsky(void **state) {
  (void)state;
  char path[1024];
  snprintf(path, sizeof path, "%s/scenes/torus/data/sunsky.exr", LMC_SHARED_DIR);
  FILE *f = fopen(path, "rb");
  if (!f) skip();
  fclose(f);
  lmc_image img;
  lmc_error err;
  check_ok(image_read(path, 1, &img, &err), &err);
  assert_int_equal(img.width, 512);
  assert_int_equal(img.height, 256);
  assert_true(img.channels == 3 || img.channels == 4);
  size_t n = (size_t)img.width * img.height * img.channels, bad = 0;
  double sum = 0.0;
  for (size_t i = 0; i < n; i++) {
    if (!isfinite(img.data[i]) || img.data[i] < 0.0f) bad++;
    sum += img.data[i];
  }
  assert_int_equal(bad, 0);
  assert_true(sum > 0.0);
  printf("  sunsky.exr: %d x %d x %d, mean %g\n", img.width, img.height, img.channels, sum / n);
  image_free(&img);
}

static void test_exr_tiled_half_rgba(void **state) {
  (void)state;
  const char *path = "/tmp/lmc_test_imageio_tiled.exr";
  assert_true(write_file(path, tiled_exr, sizeof tiled_exr));
  lmc_image img;
  lmc_error err;
  check_ok(image_read(path, 1, &img, &err), &err);
  assert_int_equal(img.width, 5);
  assert_int_equal(img.height, 3);
  assert_int_equal(img.channels, 4);
  /* Exact in half precision; checks tile placement and channel order. */
  int n_ok = 0;
  for (int i = 0; i < 5 * 3 * 4; i++)
    if (img.data[i] == (float)(i % 4 + 1) + (float)(i / 4) / 16.0f) n_ok++;
  assert_int_equal(n_ok, 60);
  check_ok(image_to_rgb(&img, &err), &err);
  assert_int_equal(img.channels, 3);
  assert_near(img.data[3 * 7 + 2], 3.0 + 7.0 / 16.0, 0.0);
  image_free(&img);
  remove(path);
}

/* ---- PNG ------------------------------------------------------------------- */

static void test_png_roundtrip(void **state) {
  (void)state;
  lmc_image img, back;
  lmc_error err;
  check_ok(image_init(&img, 29, 17, 3, &err), &err);
  for (int i = 0; i < 29 * 17 * 3; i++) img.data[i] = (float)rnd();
  img.data[0] = -1.0f;  /* clamps to 0 */
  img.data[1] = 7.0f;   /* clamps to 1 */
  img.data[2] = NAN;    /* becomes 0 */
  const char *path = "/tmp/lmc_test_imageio.png";
  check_ok(image_write_png(path, &img, 1.0, &err), &err);
  check_ok(image_read(path, 1, &back, &err), &err);
  assert_int_equal(back.width, 29);
  assert_int_equal(back.height, 17);
  assert_int_equal(back.channels, 3);
  /* Quantisation to 8 bits after the curve: |srgb(read) - srgb(orig)| <= 0.5/255. */
  int n_ok = 0;
  for (int i = 3; i < 29 * 17 * 3; i++) {
    double d = fabs(linear_to_srgb(back.data[i]) - linear_to_srgb(img.data[i]));
    if (d <= 0.5 / 255 + 1e-6) n_ok++;
  }
  assert_int_equal(n_ok, 29 * 17 * 3 - 3);
  assert_near(back.data[0], 0.0, 0.0);
  assert_near(back.data[1], 1.0, 1e-7);
  assert_near(back.data[2], 0.0, 0.0);
  image_free(&back);

  /* The scale multiplies first: 0.25 * 2 reads back as ~0.5. */
  for (int i = 0; i < 29 * 17 * 3; i++) img.data[i] = 0.25f;
  check_ok(image_write_png(path, &img, 2.0, &err), &err);
  check_ok(image_read_png(path, 1, &back, &err), &err);
  assert_near(linear_to_srgb(back.data[7]), linear_to_srgb(0.5), 0.5 / 255 + 1e-6);
  image_free(&back);
  /* Read without decoding: the stored sRGB code value. */
  check_ok(image_read_png(path, 0, &back, &err), &err);
  assert_near(back.data[7], round(linear_to_srgb(0.5) * 255) / 255, 1e-6);
  image_free(&back);
  assert_int_equal(count_files("/tmp", "lmc_test_imageio.png.tmp"), 0);

  /* Truncations are errors. */
  size_t n = 0;
  unsigned char *bytes = read_all(path, &n);
  int n_err = 0, n_cut = 0;
  for (size_t cut = 0; cut < n; cut += n / 11 + 1) {
    const char *tpath = "/tmp/lmc_test_imageio_cut.png";
    assert_true(write_file(tpath, bytes, cut));
    n_cut++;
    if (image_read(tpath, 1, &back, &err) != LMC_OK) n_err++;
    else image_free(&back);
    remove(tpath);
  }
  assert_int_equal(n_err, n_cut);
  free(bytes);
  image_free(&img);
  remove(path);
}

/* Writes a 4x3 PNG of any type with libpng; samples s(x, y, c). */
static unsigned png_sample(int x, int y, int c, int depth) {
  unsigned max = depth == 16 ? 65535u : (1u << depth) - 1;
  return (unsigned)((x * 7 + y * 13 + c * 5) % 11) * max / 10;
}

static void write_test_png(const char *path, int color, int depth) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) fail_msg("libpng failed writing a test image");
  png_init_io(png, f);
  png_set_IHDR(png, info, 4, 3, depth, color, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  if (color == PNG_COLOR_TYPE_PALETTE) {
    png_color pal[11];
    for (int i = 0; i < 11; i++) pal[i].red = pal[i].green = pal[i].blue = (png_byte)(i * 25);
    png_set_PLTE(png, info, pal, 11);
  }
  png_write_info(png, info);
  int ch = color == PNG_COLOR_TYPE_GRAY || color == PNG_COLOR_TYPE_PALETTE ? 1
           : color == PNG_COLOR_TYPE_GRAY_ALPHA                         ? 2
           : color == PNG_COLOR_TYPE_RGB                                ? 3
                                                                        : 4;
  for (int y = 0; y < 3; y++) {
    unsigned char row[4 * 4 * 2] = {0};
    for (int x = 0; x < 4; x++)
      for (int c = 0; c < ch; c++) {
        unsigned v = color == PNG_COLOR_TYPE_PALETTE ? png_sample(x, y, 0, 8) * 10 / 255
                                                     : png_sample(x, y, c, depth);
        if (depth == 16) {
          row[2 * (x * ch + c)] = (unsigned char)(v >> 8);
          row[2 * (x * ch + c) + 1] = (unsigned char)(v & 255);
        } else {
          row[x * ch + c] = (unsigned char)v;
        }
      }
    png_write_row(png, row);
  }
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  fclose(f);
}

static void test_png_types(void **state) {
  (void)state;
  static const struct {
    int color, depth, channels;
  } cases[] = {
      {PNG_COLOR_TYPE_GRAY, 8, 1},       {PNG_COLOR_TYPE_GRAY, 16, 1},
      {PNG_COLOR_TYPE_GRAY_ALPHA, 8, 4}, {PNG_COLOR_TYPE_RGB, 8, 3},
      {PNG_COLOR_TYPE_RGB, 16, 3},       {PNG_COLOR_TYPE_RGB_ALPHA, 8, 4},
      {PNG_COLOR_TYPE_RGB_ALPHA, 16, 4}, {PNG_COLOR_TYPE_PALETTE, 8, 3},
  };
  const char *path = "/tmp/lmc_test_imageio_types.png";
  int n_checked = 0;
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
    write_test_png(path, cases[k].color, cases[k].depth);
    lmc_image img;
    lmc_error err;
    check_ok(image_read(path, 0, &img, &err), &err);
    assert_int_equal(img.width, 4);
    assert_int_equal(img.height, 3);
    assert_int_equal(img.channels, cases[k].channels);
    double max = cases[k].depth == 16 ? 65535.0 : 255.0;
    for (int y = 0; y < 3; y++)
      for (int x = 0; x < 4; x++)
        for (int c = 0; c < img.channels; c++) {
          double expect;
          if (cases[k].color == PNG_COLOR_TYPE_PALETTE) {
            expect = (png_sample(x, y, 0, 8) * 10 / 255) * 25 / 255.0;
          } else if (cases[k].color == PNG_COLOR_TYPE_GRAY_ALPHA) {
            expect = png_sample(x, y, c == 3 ? 1 : 0, 8) / max;
          } else {
            expect = png_sample(x, y, c, cases[k].depth) / max;
          }
          assert_near(img.data[(y * 4 + x) * img.channels + c], expect, 1e-6);
          n_checked++;
        }
    image_free(&img);
    /* With decoding, colour goes through the curve and alpha does not. */
    check_ok(image_read(path, 1, &img, &err), &err);
    int x = 3, y = 2, c = img.channels - 1;
    double raw = cases[k].color == PNG_COLOR_TYPE_PALETTE
                     ? (png_sample(x, y, 0, 8) * 10 / 255) * 25 / 255.0
                     : png_sample(x, y, cases[k].color == PNG_COLOR_TYPE_GRAY_ALPHA ? 1 : c,
                                  cases[k].depth) / max;
    double expect = img.channels == 4 ? raw : srgb_to_linear(raw);
    assert_near(img.data[(y * 4 + x) * img.channels + c], expect, 1e-6);
    image_free(&img);
  }
  assert_int_equal(n_checked, 12 * (1 + 1 + 4 + 3 + 3 + 4 + 4 + 3));
  remove(path);
}

static void test_png_checker(void **state) {
  (void)state;
  char path[1024];
  snprintf(path, sizeof path, "%s/scenes/torus/data/checker.png", LMC_SHARED_DIR);
  FILE *f = fopen(path, "rb");
  if (!f) skip();
  fclose(f);
  lmc_image img;
  lmc_error err;
  check_ok(image_read(path, 1, &img, &err), &err);
  assert_int_equal(img.width, 256);
  assert_int_equal(img.height, 256);
  assert_int_equal(img.channels, 3);
  float lo = 1.0f, hi = 0.0f;
  size_t bad = 0;
  for (size_t i = 0; i < 256u * 256u * 3u; i++) {
    if (!(img.data[i] >= 0.0f && img.data[i] <= 1.0f)) bad++;
    lo = fminf(lo, img.data[i]);
    hi = fmaxf(hi, img.data[i]);
  }
  assert_int_equal(bad, 0);
  assert_true(hi - lo > 0.1f); /* a checkerboard has two distinct colours */
  printf("  checker.png: values in [%g, %g]\n", lo, hi);
  image_free(&img);
}

/* ---- JPEG ------------------------------------------------------------------ */

static void test_jpeg(void **state) {
  (void)state;
  const char *path = "/tmp/lmc_test_imageio.jpg";
  lmc_image img;
  lmc_error err;
  /* RGB: flat (200, 100, 50); quality 100 keeps it within a code value or two. */
  assert_true(write_file(path, rgb_jpg, sizeof rgb_jpg));
  check_ok(image_read(path, 0, &img, &err), &err);
  assert_int_equal(img.width, 16);
  assert_int_equal(img.height, 8);
  assert_int_equal(img.channels, 3);
  static const double want[3] = {200, 100, 50};
  int n_ok = 0;
  for (int i = 0; i < 16 * 8 * 3; i++)
    if (fabs(img.data[i] * 255.0 - want[i % 3]) <= 2.0) n_ok++;
  assert_int_equal(n_ok, 16 * 8 * 3);
  image_free(&img);
  check_ok(image_read_jpeg(path, 1, &img, &err), &err);
  assert_near(img.data[0], srgb_to_linear(200 / 255.0), 0.01);
  image_free(&img);
  /* Grey. */
  assert_true(write_file(path, grey_jpg, sizeof grey_jpg));
  check_ok(image_read(path, 0, &img, &err), &err);
  assert_int_equal(img.channels, 1);
  assert_near(img.data[10] * 255.0, 128.0, 2.0);
  check_ok(image_to_rgb(&img, &err), &err);
  assert_int_equal(img.channels, 3);
  assert_near(img.data[3 * 10 + 2] * 255.0, 128.0, 2.0);
  image_free(&img);
  /* Truncated: an error (libjpeg only warns; we do not accept it). */
  int n_err = 0, n_cut = 0;
  for (size_t cut = 0; cut < sizeof rgb_jpg - 2; cut += 41) {
    assert_true(write_file(path, rgb_jpg, cut));
    n_cut++;
    if (image_read(path, 0, &img, &err) != LMC_OK) n_err++;
    else image_free(&img);
  }
  assert_int_equal(n_err, n_cut);
  /* Scan data cut short but closed by EOI: libjpeg only warns ("premature
   * end of data segment") and pads with grey; for us an error. */
  size_t sos = 0;
  while (!(rgb_jpg[sos] == 0xFF && rgb_jpg[sos + 1] == 0xDA)) sos++;
  size_t data = sos + 2 + ((size_t)rgb_jpg[sos + 2] << 8 | rgb_jpg[sos + 3]);
  n_err = n_cut = 0;
  for (size_t cut = data; cut < sizeof rgb_jpg - 2; cut++) {
    unsigned char bytes[sizeof rgb_jpg];
    memcpy(bytes, rgb_jpg, cut);
    bytes[cut] = 0xFF;
    bytes[cut + 1] = 0xD9;
    assert_true(write_file(path, bytes, cut + 2));
    n_cut++;
    if (image_read(path, 0, &img, &err) != LMC_OK) n_err++;
    else image_free(&img);
  }
  assert_int_equal(n_cut, 10);
  assert_int_equal(n_err, n_cut);
  remove(path);
}

/* ---- size limits ----------------------------------------------------------- */

/* Writes a PNG header claiming w x h 8-bit grey pixels and an empty IDAT:
 * enough for a reader to learn the size, no pixels to decode. */
static void write_png_header(const char *path, png_uint_32 w, png_uint_32 h) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) fail_msg("libpng failed writing a test header");
  png_set_user_limits(png, 0x7fffffff, 0x7fffffff);
  png_init_io(png, f);
  png_set_IHDR(png, info, w, h, 8, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_write_chunk(png, (png_const_bytep) "IDAT", NULL, 0);
  png_destroy_write_struct(&png, &info);
  fclose(f);
}

/* Reading path fails with LMC_EUNSUPPORTED and a message naming w x h. */
static void check_too_large(const char *path, long long w, long long h) {
  lmc_image img;
  lmc_error err;
  lmc_error_clear(&err);
  lmc_status st = image_read(path, 1, &img, &err);
  if (st == LMC_OK) image_free(&img);
  if (st != LMC_EUNSUPPORTED)
    fail_msg("%s (%lld x %lld): status %d, want %d; message '%s'", path, w, h, (int)st,
             (int)LMC_EUNSUPPORTED, err.msg);
  char want[64];
  snprintf(want, sizeof want, "%lld x %lld pixels", w, h);
  if (!strstr(err.msg, want)) fail_msg("message '%s' does not name '%s'", err.msg, want);
  assert_string_equal(err.file, path);
  assert_null(img.data);
}

static void test_size_limits(void **state) {
  (void)state;
  const long long side = IMAGE_MAX_SIDE, rows = IMAGE_MAX_PIXELS / IMAGE_MAX_SIDE;
  lmc_image img;
  lmc_error err;

  /* PNG: a side too long, too many pixels, and beyond libpng's own 10^6. */
  const char *path = "/tmp/lmc_test_imageio_huge.png";
  write_png_header(path, (png_uint_32)side + 1, 1);
  check_too_large(path, side + 1, 1);
  write_png_header(path, (png_uint_32)side, (png_uint_32)rows + 1);
  check_too_large(path, side, rows + 1);
  write_png_header(path, 1, 2000000);
  check_too_large(path, 1, 2000000);
  /* At the limits the size passes; the header-only file is then malformed. */
  write_png_header(path, (png_uint_32)side, (png_uint_32)rows);
  assert_int_equal(image_read(path, 1, &img, &err), LMC_EPARSE);
  remove(path);
#ifndef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
  /* A 16K x 8K environment map is within the limits. */
  check_ok(image_check_size("env.exr", "EXR", 16384, 8192, &err), &err);
#endif

  /* JPEG: the 16 x 8 test image with its SOF0 claiming side + 1 columns. */
  unsigned char jpg[sizeof rgb_jpg];
  memcpy(jpg, rgb_jpg, sizeof jpg);
  size_t sof = 0;
  while (!(jpg[sof] == 0xFF && jpg[sof + 1] == 0xC0)) sof++;
  /* FF C0, length (2 bytes), precision (1), height (2), width (2). */
  jpg[sof + 7] = (unsigned char)((side + 1) >> 8);
  jpg[sof + 8] = (unsigned char)((side + 1) & 255);
  const char *jpath = "/tmp/lmc_test_imageio_huge.jpg";
  assert_true(write_file(jpath, jpg, sizeof jpg));
  check_too_large(jpath, side + 1, 8);
  remove(jpath);

  /* EXR: one row a pixel too wide, written by our writer (200 KB). */
  const char *epath = "/tmp/lmc_test_imageio_huge.exr";
  check_ok(image_init(&img, (int)side + 1, 1, 3, &err), &err);
  check_ok(image_write_exr(epath, &img, &err), &err);
  image_free(&img);
  check_too_large(epath, side + 1, 1);
  remove(epath);
}

/* ---- ancillary chunks ------------------------------------------------------ */

/* The process's peak resident memory so far, in KiB (Linux units). */
static long peak_rss_kib(void) {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss;
}

static void put_u32(unsigned char *p, uint32_t v) {
  p[0] = (unsigned char)(v >> 24);
  p[1] = (unsigned char)(v >> 16);
  p[2] = (unsigned char)(v >> 8);
  p[3] = (unsigned char)v;
}

/* Text chunks far beyond libpng's 8 MB chunk limit, plain and compressed,
 * before and after the image data: a valid file, read with the pixels
 * intact and the text skipped. */
static void test_png_text_chunks(void **state) {
  (void)state;
  const size_t big = 16u << 20;
  char *text = malloc(big + 1);
  assert_non_null(text);
  memset(text, 'a', big);
  text[big] = '\0';
  const char *path = "/tmp/lmc_test_imageio_text.png";
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) fail_msg("libpng failed writing a test image");
  png_init_io(png, f);
  png_set_IHDR(png, info, 4, 3, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  /* Before IDAT: 9 MiB of tEXt and a zTXt that inflates to 16 MiB. */
  png_text before[2];
  memset(before, 0, sizeof before);
  before[0].compression = PNG_TEXT_COMPRESSION_NONE;
  before[0].key = "Comment";
  before[0].text = text + big - (9u << 20);
  before[1].compression = PNG_TEXT_COMPRESSION_zTXt;
  before[1].key = "Bomb";
  before[1].text = text;
  png_set_text(png, info, before, 2);
  png_write_info(png, info);
  for (int y = 0; y < 3; y++) {
    png_byte row[12];
    for (int i = 0; i < 12; i++) row[i] = (png_byte)(20 * y + i);
    png_write_row(png, row);
  }
  /* After IDAT (png_write_end writes the text not yet written): an iTXt
   * that inflates to 16 MiB. */
  png_text after;
  memset(&after, 0, sizeof after);
  after.compression = PNG_ITXT_COMPRESSION_zTXt;
  after.key = "Bomb2";
  after.text = text;
  png_set_text(png, info, &after, 1);
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  fclose(f);
  free(text);

  lmc_image img;
  lmc_error err;
  long rss0 = peak_rss_kib();
  check_ok(image_read_png(path, 0, &img, &err), &err);
  long grown = peak_rss_kib() - rss0;
  assert_int_equal(img.width, 4);
  assert_int_equal(img.height, 3);
  assert_int_equal(img.channels, 3);
  for (int y = 0; y < 3; y++)
    for (int i = 0; i < 12; i++) assert_near(img.data[12 * y + i], (20 * y + i) / 255.0, 1e-6);
  image_free(&img);
  if (grown > 32 << 10) fail_msg("reading %s raised the peak RSS by %ld KiB", path, grown);
  remove(path);
}

/* Ancillary chunks whose header claims 256 MiB in a file that then ends:
 * each read fails at the end of the file, naming it, without allocating
 * what the chunk claims. libpng 1.6.39 only warns about a chunk beyond its
 * malloc limit, then allocates and zeroes the claimed length for tEXt,
 * zTXt, iTXt, sPLT, pCAL and sCAL (before IDAT): 256 MiB of peak RSS. */
static void test_png_chunk_claims(void **state) {
  (void)state;
  const char *path = "/tmp/lmc_test_imageio_claims.png";
  write_test_png(path, PNG_COLOR_TYPE_RGB, 8);
  size_t n = 0;
  unsigned char *good = read_all(path, &n);
  assert_non_null(good);
  assert_true(n > 33 + 12);
  static const char *const types[] = {"tEXt", "zTXt", "iTXt", "sPLT", "pCAL",
                                      "sCAL", "iCCP", "eXIf", "prVt"};
  const uint32_t claim = 256u << 20;
  long rss0 = peak_rss_kib();
  int n_failed = 0, n_read = 0;
  for (size_t t = 0; t < sizeof types / sizeof types[0]; t++)
    for (int after_idat = 0; after_idat < 2; after_idat++) {
      /* Signature and IHDR (33 bytes), or all but IEND (12 bytes), then the
       * chunk's length, type and 64 bytes of its data. */
      size_t head = after_idat ? n - 12 : 33;
      unsigned char bytes[4096];
      assert_true(head + 8 + 64 <= sizeof bytes);
      memcpy(bytes, good, head);
      put_u32(bytes + head, claim);
      memcpy(bytes + head + 4, types[t], 4);
      for (int i = 0; i < 64; i++) bytes[head + 8 + i] = (unsigned char)('a' + i % 26);
      assert_true(write_file(path, bytes, head + 8 + 64));
      lmc_image img;
      lmc_error err;
      lmc_error_clear(&err);
      lmc_status st = image_read(path, 1, &img, &err);
      n_read++;
      if (st == LMC_OK) {
        image_free(&img);
        continue;
      }
      n_failed++;
      if (st != LMC_EPARSE || strcmp(err.file, path) != 0 || !strstr(err.msg, "bad PNG"))
        fail_msg("%s chunk (after IDAT: %d): status %d, want %d; file '%s'; message '%s'",
                 types[t], after_idat, (int)st, (int)LMC_EPARSE, err.file, err.msg);
    }
  assert_int_equal(n_failed, n_read);
  long grown = peak_rss_kib() - rss0;
  if (grown > 32 << 10)
    fail_msg("%d reads raised the peak RSS by %ld KiB (a chunk claims %u KiB)", n_read, grown,
             (unsigned)(claim >> 10));
  free(good);
  remove(path);
}

/* ---- dispatch and failure paths ------------------------------------------ */

static void test_errors(void **state) {
  (void)state;
  lmc_image img;
  lmc_error err;
  const char *path = "/tmp/lmc_test_imageio.txt";
  assert_true(write_file(path, "hello, not an image\n", 20));
  assert_int_equal(image_read(path, 1, &img, &err), LMC_EUNSUPPORTED);
  assert_string_equal(err.file, path);
  assert_int_not_equal(image_read_png(path, 1, &img, &err), LMC_OK);
  assert_int_not_equal(image_read_jpeg(path, 1, &img, &err), LMC_OK);
  assert_int_not_equal(image_read_exr(path, &img, &err), LMC_OK);
  assert_string_equal(err.file, path);
  remove(path);
  assert_int_equal(image_read("/tmp/lmc_no_such_image.png", 1, &img, &err), LMC_EIO);
  image_free(NULL);

  /* Writing into a folder that does not exist: an error, nothing created. */
  check_ok(image_init(&img, 4, 4, 3, &err), &err);
  const char *dir = "/tmp/lmc_test_imageio_no_such_dir";
  assert_int_not_equal(image_write_png("/tmp/lmc_test_imageio_no_such_dir/a.png", &img, 1.0, &err),
                       LMC_OK);
  assert_string_equal(err.file, "/tmp/lmc_test_imageio_no_such_dir/a.png");
  assert_int_not_equal(image_write_exr("/tmp/lmc_test_imageio_no_such_dir/a.exr", &img, &err),
                       LMC_OK);
  struct stat sb;
  assert_int_not_equal(stat(dir, &sb), 0);
  assert_int_equal(count_files("/tmp", "lmc_test_imageio_no_such_dir"), 0);

  /* A failed write leaves an existing target untouched. */
  const char *target = "/tmp/lmc_test_imageio_keep.png";
  assert_true(write_file(target, "precious", 8));
  lmc_image grey;
  check_ok(image_init(&grey, 4, 4, 1, &err), &err);
  assert_int_equal(image_write_png(target, &grey, 1.0, &err), LMC_EINVAL);
  assert_int_equal(image_write_exr(target, &grey, &err), LMC_EINVAL);
  size_t n = 0;
  unsigned char *bytes = read_all(target, &n);
  assert_int_equal(n, 8);
  assert_memory_equal(bytes, "precious", 8);
  free(bytes);
  assert_int_equal(count_files("/tmp", "lmc_test_imageio_keep.png.tmp"), 0);
  remove(target);
  image_free(&grey);
  image_free(&img);
  assert_int_not_equal(image_init(&img, 0, 4, 3, &err), LMC_OK);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_srgb_curve),    cmocka_unit_test(test_exr_roundtrip),
      cmocka_unit_test(test_exr_raw_chunks), cmocka_unit_test(test_exr_sunsky),
      cmocka_unit_test(test_exr_tiled_half_rgba),    cmocka_unit_test(test_png_roundtrip),
      cmocka_unit_test(test_png_types),     cmocka_unit_test(test_png_checker),
      cmocka_unit_test(test_jpeg),          cmocka_unit_test(test_size_limits),
      cmocka_unit_test(test_png_text_chunks), cmocka_unit_test(test_png_chunk_claims),
      cmocka_unit_test(test_errors),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
