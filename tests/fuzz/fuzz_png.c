/*
 * fuzz_png.c: libFuzzer target for the PNG reader (libpng, image.c).
 *
 * The input is written to a file and read with image_read_png, then the
 * image is converted to RGB as textures do. Errors are expected results;
 * only crashes, hangs, leaks and undefined behaviour are findings.
 */
#include <string.h>

#include "fuzz_util.h"
#include "render/image.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  lmc_warn_set_quiet(1);
  const char *path = fuzz_write("input.png", data, size);
  lmc_image img;
  memset(&img, 0, sizeof img);
  lmc_error err;
  lmc_error_clear(&err);
  if (image_read_png(path, 1, &img, &err) == LMC_OK) image_to_rgb(&img, &err);
  image_free(&img);
  return 0;
}
