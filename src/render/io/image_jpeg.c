/*
 * image_jpeg.c: JPEG reading with libjpeg.
 *
 * Greyscale files give a 1-channel image, everything else libjpeg can turn
 * into RGB gives 3 channels (CMYK/YCCK files are rejected). Samples are
 * 8-bit and sRGB-encoded: value / 255, then the sRGB curve when asked.
 *
 * libjpeg's default error handler calls exit(); ours records the message
 * and longjmps back. A file that ends early, or whose scan data stops at a
 * marker before the image is complete, only makes libjpeg warn (it pads
 * the image with grey); we treat both warnings as errors, so a truncated
 * JPEG is reported instead of silently read. The size in the header is
 * checked against image.h's limits before anything is decoded.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <jpeglib.h>
#include <jerror.h>

#include "render/image.h"

typedef struct jpeg__err {
  struct jpeg_error_mgr mgr; /* first member: libjpeg sees this */
  jmp_buf jump;
  char msg[JMSG_LENGTH_MAX];
} jpeg__err;

static void jpeg__error_exit(j_common_ptr cinfo) {
  jpeg__err *e = (jpeg__err *)cinfo->err;
  e->mgr.format_message(cinfo, e->msg);
  longjmp(e->jump, 1);
}

/* Warnings: silent, except premature end of the file or of the scan data
 * (libjpeg would invent the missing pixels), which are fatal here. */
static void jpeg__emit_message(j_common_ptr cinfo, int level) {
  jpeg__err *e = (jpeg__err *)cinfo->err;
  if (level < 0 && (e->mgr.msg_code == JWRN_JPEG_EOF || e->mgr.msg_code == JWRN_HIT_MARKER)) {
    e->mgr.format_message(cinfo, e->msg);
    longjmp(e->jump, 1);
  }
}

lmc_status image_read_jpeg(const char *path, int srgb_to_linear_flag, lmc_image *out,
                           lmc_error *err) {
  memset(out, 0, sizeof *out);
  FILE *f = fopen(path, "rb");
  if (!f) return lmc_error_set(err, LMC_EIO, path, 0, "cannot open: %s", strerror(errno));
  struct jpeg_decompress_struct cinfo;
  jpeg__err je;
  unsigned char *volatile row = NULL;
  cinfo.err = jpeg_std_error(&je.mgr);
  je.mgr.error_exit = jpeg__error_exit;
  je.mgr.emit_message = jpeg__emit_message;
  je.msg[0] = '\0';
  if (setjmp(je.jump)) {
    jpeg_destroy_decompress(&cinfo);
    fclose(f);
    free(row);
    image_free(out);
    return lmc_error_set(err, LMC_EPARSE, path, 0, "bad JPEG: %s", je.msg);
  }
  jpeg_create_decompress(&cinfo);
  jpeg_stdio_src(&cinfo, f);
  jpeg_read_header(&cinfo, TRUE);
  lmc_status st = image_check_size(path, "JPEG", cinfo.image_width, cinfo.image_height, err);
  if (st != LMC_OK) {
    jpeg_destroy_decompress(&cinfo);
    fclose(f);
    return st;
  }

  /* The header can claim any size; the file's size bounds what it holds.
   * Every 8x8 block of every component costs at least one bit (its DC
   * code), so a true JPEG decodes to at most 64 * 8 * 4 float bytes per
   * file byte and component: beyond that (and 64 MiB) the header lies,
   * and libjpeg's own buffers would exhaust memory before any error. */
  struct stat sb;
  double claimed = (double)cinfo.image_width * cinfo.image_height * cinfo.num_components * 4.0;
  if (fstat(fileno(f), &sb) == 0 && claimed > 64.0 * 1024 * 1024 &&
      claimed > 2048.0 * cinfo.num_components * (double)sb.st_size) {
    snprintf(je.msg, sizeof je.msg, "the header claims %ux%u pixels, more than the file can hold",
             (unsigned)cinfo.image_width, (unsigned)cinfo.image_height);
    longjmp(je.jump, 1);
  }

  /* Grey stays grey; YCbCr/RGB become RGB; CMYK is not supported. */
  if (cinfo.jpeg_color_space == JCS_GRAYSCALE) {
    cinfo.out_color_space = JCS_GRAYSCALE;
  } else if (cinfo.jpeg_color_space == JCS_CMYK || cinfo.jpeg_color_space == JCS_YCCK) {
    snprintf(je.msg, sizeof je.msg, "CMYK JPEG files are not supported");
    longjmp(je.jump, 1);
  } else {
    cinfo.out_color_space = JCS_RGB;
  }
  jpeg_start_decompress(&cinfo);
  int w = (int)cinfo.output_width, h = (int)cinfo.output_height, ch = cinfo.output_components;
  st = image_init(out, w, h, ch, err);
  if (st != LMC_OK) {
    snprintf(je.msg, sizeof je.msg, "%.150s", err ? err->msg : "cannot allocate the image");
    longjmp(je.jump, 1);
  }
  row = malloc((size_t)w * (size_t)ch);
  if (!row) {
    snprintf(je.msg, sizeof je.msg, "out of memory");
    longjmp(je.jump, 1);
  }
  float lut[256];
  for (int i = 0; i < 256; i++)
    lut[i] = (float)(srgb_to_linear_flag ? srgb_to_linear(i / 255.0) : i / 255.0);
  while (cinfo.output_scanline < cinfo.output_height) {
    size_t y = cinfo.output_scanline;
    JSAMPROW rows[1] = {row};
    if (jpeg_read_scanlines(&cinfo, rows, 1) != 1) {
      snprintf(je.msg, sizeof je.msg, "cannot read scanline %zu", y);
      longjmp(je.jump, 1);
    }
    float *dst = out->data + y * (size_t)w * (size_t)ch;
    for (size_t i = 0; i < (size_t)w * (size_t)ch; i++) dst[i] = lut[row[i]];
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  fclose(f);
  free(row);
  return LMC_OK;
}
