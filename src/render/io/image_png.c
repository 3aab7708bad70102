/*
 * image_png.c: PNG reading and writing (libpng) for image.h.
 *
 * PNG reading (libpng) expands palettes, low bit depths and tRNS
 * transparency, and keeps 16-bit samples. Grey gives 1 channel, RGB 3 and
 * RGBA 4; grey+alpha (also grey with a tRNS key) is returned as RGBA, since
 * image.h only knows 1, 3 and 4 channels. Colour samples are divided by
 * their maximum (255 or 65535) and, when asked, decoded with the sRGB curve
 * (16-bit files too: PNG samples are sRGB-encoded); alpha stays linear.
 * The size in the header is checked against image.h's limits first.
 * Ancillary chunks (text, gAMA, iCCP, sPLT, ...) are skipped unread: the
 * reader needs only IHDR, PLTE, tRNS and IDAT, and libpng 1.6.39 allocates
 * (and zeroes) a text, sPLT, pCAL or sCAL chunk's claimed length, up to
 * 2 GiB, before it finds that the file is 400 bytes long. Skipped chunks are
 * read through a small fixed buffer, so the reader's memory is bounded by
 * the pixel limit whatever the file claims.
 *
 * PNG writing: 8-bit RGB, v -> round(255 * clamp(srgb(scale * v), 0, 1)),
 * NaN -> 0. Like every writer it writes a temporary file beside the target
 * and renames it over the target when complete.
 *
 * libpng reports errors by longjmp; everything the jump could clobber is
 * volatile or allocated before setjmp.
 */
#define _POSIX_C_SOURCE 200809L

#include "render/image.h"

#include <errno.h>
#include <math.h>
#include <png.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* libpng error and warning handlers: keep the message, jump back. */
typedef struct png__ctx {
  char msg[256];
} png__ctx;

static void png__error(png_structp png, png_const_charp msg) {
  png__ctx *ctx = png_get_error_ptr(png);
  if (ctx) snprintf(ctx->msg, sizeof ctx->msg, "%s", msg);
  png_longjmp(png, 1);
}

static void png__warning(png_structp png, png_const_charp msg) {
  (void)png;
  (void)msg;
}

lmc_status image_read_png(const char *path, int srgb_to_linear_flag, lmc_image *out,
                          lmc_error *err) {
  memset(out, 0, sizeof *out);
  FILE *f = fopen(path, "rb");
  if (!f) return lmc_error_set(err, LMC_EIO, path, 0, "cannot open: %s", strerror(errno));
  png__ctx ctx = {""};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &ctx, png__error, png__warning);
  png_infop info = png ? png_create_info_struct(png) : NULL;
  if (!png || !info) {
    png_destroy_read_struct(png ? &png : NULL, NULL, NULL);
    fclose(f);
    return lmc_error_set(err, LMC_ENOMEM, path, 0, "out of memory (libpng)");
  }
  unsigned char *volatile pixels = NULL;
  png_bytep *volatile rows = NULL;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, NULL);
    fclose(f);
    free(pixels);
    free(rows);
    image_free(out);
    return lmc_error_set(err, LMC_EPARSE, path, 0, "bad PNG: %s", ctx.msg[0] ? ctx.msg : "error");
  }
  png_init_io(png, f);
  /* Sizes beyond libpng's own limit (10^6) then get our message too. */
  png_set_user_limits(png, 0x7fffffff, 0x7fffffff);
  /* Skip every chunk but IHDR, PLTE, tRNS, IDAT and IEND without storing
   * it (num_chunks -1 selects libpng's list of all ancillary chunks it
   * knows; unknown ones are skipped by default). A chunk longer than the
   * malloc limit below only draws a warning in libpng 1.6.39 (a benign
   * error) and is then read into a buffer of its claimed size, so the limit
   * alone does not bound memory; it still caps what libpng would inflate
   * from a compressed chunk (iCCP, zTXt, iTXt) if one were ever kept. */
  png_set_keep_unknown_chunks(png, PNG_HANDLE_CHUNK_NEVER, NULL, -1);
  png_set_chunk_malloc_max(png, (png_alloc_size_t)1 << 20);
  png_read_info(png, info);
  lmc_status st = image_check_size(path, "PNG", png_get_image_width(png, info),
                                   png_get_image_height(png, info), err);
  if (st != LMC_OK) {
    png_destroy_read_struct(&png, &info, NULL);
    fclose(f);
    return st;
  }

  /* Expand palettes, grey < 8 bits and tRNS; 16-bit samples in host order. */
  png_set_expand(png);
  if (png_get_bit_depth(png, info) == 16) {
    const uint16_t one = 1;
    if (*(const unsigned char *)&one == 1) png_set_swap(png);
  }
  int color = png_get_color_type(png, info);
  if (color == PNG_COLOR_TYPE_GRAY_ALPHA ||
      (color == PNG_COLOR_TYPE_GRAY && png_get_valid(png, info, PNG_INFO_tRNS)))
    png_set_gray_to_rgb(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);

  int w = (int)png_get_image_width(png, info), h = (int)png_get_image_height(png, info);
  int ch = png_get_channels(png, info), depth = png_get_bit_depth(png, info);
  size_t rowbytes = png_get_rowbytes(png, info);
  if (w <= 0 || h <= 0 || (ch != 1 && ch != 3 && ch != 4) || (depth != 8 && depth != 16) ||
      rowbytes != (size_t)w * (size_t)ch * (size_t)(depth / 8))
    png_error(png, "unsupported PNG layout");
  /* The header can claim any size; the file's size bounds what it holds.
   * Deflate packs at most about 1032:1, so more than 1100 decoded bytes per
   * file byte (beyond 64 MiB) is a lie that would only exhaust memory. */
  struct stat sb;
  if (fstat(fileno(f), &sb) == 0 && (double)rowbytes * h > 64.0 * 1024 * 1024 &&
      (double)rowbytes * h > 1100.0 * (double)sb.st_size)
    png_error(png, "the header claims more pixels than the file can hold");
  pixels = malloc(rowbytes * (size_t)h);
  rows = malloc(sizeof(png_bytep) * (size_t)h);
  if (!pixels || !rows) png_error(png, "out of memory");
  for (int y = 0; y < h; y++) rows[y] = pixels + rowbytes * (size_t)y;
  png_read_image(png, rows);
  png_read_end(png, NULL);

  /* Convert to float: colour through the sRGB curve when asked, alpha linear. */
  st = image_init(out, w, h, ch, err);
  if (st == LMC_OK) {
    float lut[256];
    for (int i = 0; i < 256; i++)
      lut[i] = (float)(srgb_to_linear_flag ? srgb_to_linear(i / 255.0) : i / 255.0);
    size_t n = (size_t)w * (size_t)h * (size_t)ch;
    for (size_t i = 0; i < n; i++) {
      int is_alpha = ch == 4 && (i % 4) == 3;
      if (depth == 8) {
        unsigned v = pixels[i];
        out->data[i] = is_alpha ? (float)(v / 255.0) : lut[v];
      } else {
        uint16_t v;
        memcpy(&v, pixels + 2 * i, 2);
        double x = v / 65535.0;
        out->data[i] = (float)(is_alpha || !srgb_to_linear_flag ? x : srgb_to_linear(x));
      }
    }
  } else if (err) {
    snprintf(err->file, sizeof err->file, "%s", path);
  }
  png_destroy_read_struct(&png, &info, NULL);
  fclose(f);
  free(pixels);
  free(rows);
  return st;
}

/* Writes the PNG to an open file; returns 0 on success. */
static int image__png_to_file(FILE *f, const unsigned char *rgb, int w, int h, png__ctx *ctx) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, ctx, png__error, png__warning);
  png_infop info = png ? png_create_info_struct(png) : NULL;
  if (!png || !info) {
    png_destroy_write_struct(png ? &png : NULL, NULL);
    snprintf(ctx->msg, sizeof ctx->msg, "out of memory (libpng)");
    return 1;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return 1;
  }
  png_init_io(png, f);
  png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_write_info(png, info);
  for (int y = 0; y < h; y++) png_write_row(png, rgb + (size_t)y * (size_t)w * 3);
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return 0;
}

lmc_status image_write_png(const char *path, const lmc_image *img, double scale, lmc_error *err) {
  if (!img || !img->data || img->channels != 3 || img->width <= 0 || img->height <= 0)
    return lmc_error_set(err, LMC_EINVAL, path, 0, "image_write_png needs a 3-channel image");

  /* Quantise: 8-bit sRGB of scale * v, clamped; NaN -> 0. */
  size_t n = (size_t)img->width * (size_t)img->height * 3;
  unsigned char *rgb = malloc(n);
  if (!rgb) return lmc_error_set(err, LMC_ENOMEM, path, 0, "out of memory");
  for (size_t i = 0; i < n; i++) {
    double v = scale * img->data[i];
    if (!(v > 0.0)) v = 0.0;
    double s = v >= 1.0 ? 1.0 : linear_to_srgb(v);
    rgb[i] = (unsigned char)(s * 255.0 + 0.5);
  }

  char tmp[4096];
  image_temp_name(path, tmp, sizeof tmp);
  FILE *f = fopen(tmp, "wb");
  if (!f) {
    free(rgb);
    return lmc_error_set(err, LMC_EIO, path, 0, "cannot create the file: %s", strerror(errno));
  }
  png__ctx ctx = {""};
  int bad = image__png_to_file(f, rgb, img->width, img->height, &ctx);
  free(rgb);
  if (fclose(f) != 0 && !bad) {
    bad = 1;
    snprintf(ctx.msg, sizeof ctx.msg, "write error");
  }
  if (!bad && rename(tmp, path) != 0) {
    bad = 1;
    snprintf(ctx.msg, sizeof ctx.msg, "cannot rename the temporary file: %s", strerror(errno));
  }
  if (bad) {
    remove(tmp);
    return lmc_error_set(err, LMC_EIO, path, 0, "cannot write PNG: %s", ctx.msg);
  }
  return LMC_OK;
}
