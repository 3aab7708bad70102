/*
 * image.h: float images in memory, and their readers and writers.
 *
 * Pixels are row-major with the top row first and channels interleaved.
 * Readers return linear values: 8-bit PNG and JPEG files are taken to be
 * sRGB-encoded (as Mitsuba's bitmap texture does by default) and converted,
 * EXR files are linear already. Grey images are returned with 1 channel,
 * RGB with 3 and RGBA with 4; image_to_rgb drops alpha and expands grey.
 *
 * Writers never leave a truncated file: they write to a temporary file in
 * the target's folder and rename it over the target when complete.
 * Only io/image_exr.c includes OpenEXR.
 */
#ifndef LMC_RENDER_IMAGE_H
#define LMC_RENDER_IMAGE_H

#include "render/error.h"

typedef struct lmc_image {
  int width, height, channels;
  float *data; /* owned: width * height * channels floats */
} lmc_image;

/* Allocates a zeroed image (img is caller-owned storage). */
lmc_status image_init(lmc_image *img, int width, int height, int channels, lmc_error *err);
/* Frees the pixels; accepts NULL and an image that was never initialised to zero. */
void image_free(lmc_image *img);
/* Converts in place to 3 channels (grey is replicated, alpha dropped). */
lmc_status image_to_rgb(lmc_image *img, lmc_error *err);

/* Reads PNG, JPEG or EXR, chosen by the file's magic bytes (not its name).
 * `srgb_to_linear`: for 8-bit formats, decode sRGB (1) or take values as
 * linear (0). Errors name the file. */
lmc_status image_read(const char *path, int srgb_to_linear, lmc_image *out, lmc_error *err);
lmc_status image_read_png(const char *path, int srgb_to_linear, lmc_image *out, lmc_error *err);
lmc_status image_read_jpeg(const char *path, int srgb_to_linear, lmc_image *out, lmc_error *err);
lmc_status image_read_exr(const char *path, lmc_image *out, lmc_error *err);

/* Writes a 3-channel image as a linear float (FP32) RGB EXR. */
lmc_status image_write_exr(const char *path, const lmc_image *img, lmc_error *err);
/* Writes an 8-bit sRGB PNG of a 3-channel linear image, multiplying by
 * `scale` first (an exposure). */
lmc_status image_write_png(const char *path, const lmc_image *img, double scale, lmc_error *err);

/* sRGB transfer functions. */
double srgb_to_linear(double v);
double linear_to_srgb(double v);

#endif
