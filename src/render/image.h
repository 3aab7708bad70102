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

#include <stddef.h>

#include "render/error.h"

typedef struct lmc_image {
  int width, height, channels;
  float *data; /* owned: width * height * channels floats */
} lmc_image;

/* Allocates a zeroed image (img is caller-owned storage). */
lmc_status image_init(lmc_image *img, int width, int height, int channels, lmc_error *err);
/* Frees the pixels; accepts NULL and an image that was never initialised to zero. */
void image_free(lmc_image *img);
/* The error of an image against a reference of its size (both 3
 * channels): mse over pixels and channels, relmse the mean of (I - R)^2 /
 * (R^2 + 0.01), relmse_trimmed the same without the 0.1% of pixels of
 * largest error (one firefly of a short render can outweigh the rest),
 * mean_ratio the mean luminance of img over ref's. */
typedef struct lmc_image_error {
  double mse, relmse, relmse_trimmed, mean_ratio;
} lmc_image_error;
/* Each pixel's relative squared error (I - R)^2 / (R^2 + 0.01), the mean
 * over its channels, into OUT_rel (width * height); img and ref 3-channel
 * images of one size. */
void image_rel_error(const lmc_image *img, const lmc_image *ref, double *OUT_rel);
/* Fails on a size or channel mismatch (LMC_EINVAL) or no memory. */
lmc_status image_error(const lmc_image *img, const lmc_image *ref, lmc_image_error *OUT,
                       lmc_error *err);

/* Converts in place to 3 channels (grey is replicated, alpha dropped). */
lmc_status image_to_rgb(lmc_image *img, lmc_error *err);
/* Replaces img by channel `channel` (0 r, 1 g, 2 b, 3 alpha) repeated in 3
 * channels; a grey image's colour channels are its grey. An alpha asked of
 * an image without one is an error (LMC_EUNSUPPORTED). */
lmc_status image_select_channel(lmc_image *img, int channel, lmc_error *err);

/* The largest image the readers accept: IMAGE_MAX_SIDE pixels a side (16K,
 * the texture limit of current GPUs) and IMAGE_MAX_PIXELS in all (2^27: a
 * 16K x 8K environment map loads, 2 GiB as float RGBA; 16K x 16K does
 * not). Each reader checks the size its header claims before it allocates
 * or decodes any pixel, so a hostile header cannot exhaust memory or time.
 * Fuzz builds (LMC_FUZZ) stop at 2^20 pixels, as libjpeg-turbo's own fuzz
 * targets do: under ASan a valid 2 KB PNG of 4096 x 4096 pixels takes
 * 3 s and 600 MB, which libFuzzer's limits count against the fuzzer. */
#define IMAGE_MAX_SIDE 16384
#ifndef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
#define IMAGE_MAX_PIXELS (1L << 27)
#else
#define IMAGE_MAX_PIXELS (1L << 20)
#endif

/* Checks a header's claimed size against the limits above: LMC_OK, or
 * LMC_EUNSUPPORTED with an error that names the file, the format ("PNG")
 * and the size. Non-positive sizes are the reader's to reject. */
lmc_status image_check_size(const char *path, const char *format, long long width,
                            long long height, lmc_error *err);

/* Reads PNG, JPEG or EXR, chosen by the file's magic bytes (not its name).
 * `srgb_to_linear`: for 8-bit formats, decode sRGB (1) or take values as
 * linear (0). Errors name the file. */
lmc_status image_read(const char *path, int srgb_to_linear, lmc_image *out, lmc_error *err);
lmc_status image_read_png(const char *path, int srgb_to_linear, lmc_image *out, lmc_error *err);
lmc_status image_read_jpeg(const char *path, int srgb_to_linear, lmc_image *out, lmc_error *err);
lmc_status image_read_exr(const char *path, lmc_image *out, lmc_error *err);
/* The channels layer.R, layer.G, layer.B (or layer.Y) of an EXR
 * (layer NULL: image_read_exr); LMC_EUNSUPPORTED naming the layer when
 * the file has none. */
lmc_status image_read_exr_layer(const char *path, const char *layer, lmc_image *out,
                                lmc_error *err);

/* Writes a 3-channel image as a linear float (FP32) RGB EXR. */
lmc_status image_write_exr(const char *path, const lmc_image *img, lmc_error *err);
/* The same with a second 3-channel image of the same size (limg) as the
 * channels layer.R, layer.G, layer.B (layer NULL: none). */
lmc_status image_write_exr_layer(const char *path, const lmc_image *img, const char *layer,
                                 const lmc_image *limg, lmc_error *err);
/* Writes an 8-bit sRGB PNG of a 3-channel linear image, multiplying by
 * `scale` first (an exposure). */
lmc_status image_write_png(const char *path, const lmc_image *img, double scale, lmc_error *err);

/* sRGB transfer functions. */
double srgb_to_linear(double v);
double linear_to_srgb(double v);

/* A temporary file name beside path, "<path>.tmp-<pid>-<n>", unique per
 * process and call: the writers write there and rename it over path. */
void image_temp_name(const char *path, char *buf, size_t size);

#endif
