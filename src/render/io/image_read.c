/*
 * image_read.c: image_read (image.h) looks at the first bytes of the file,
 * not its name, and hands it to its format's reader:
 *   89 50 4E 47 0D 0A 1A 0A  PNG,   FF D8 FF  JPEG,   76 2F 31 01  OpenEXR.
 */
#include "render/image.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

lmc_status image_read(const char *path, int srgb_to_linear_flag, lmc_image *out, lmc_error *err) {
  memset(out, 0, sizeof *out);
  FILE *f = fopen(path, "rb");
  if (!f) return lmc_error_set(err, LMC_EIO, path, 0, "cannot open: %s", strerror(errno));
  unsigned char magic[8] = {0};
  size_t n = fread(magic, 1, sizeof magic, f);
  fclose(f);
  static const unsigned char png_magic[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (n >= 8 && memcmp(magic, png_magic, 8) == 0)
    return image_read_png(path, srgb_to_linear_flag, out, err);
  if (n >= 3 && magic[0] == 0xFF && magic[1] == 0xD8 && magic[2] == 0xFF)
    return image_read_jpeg(path, srgb_to_linear_flag, out, err);
  if (n >= 4 && magic[0] == 0x76 && magic[1] == 0x2F && magic[2] == 0x31 && magic[3] == 0x01)
    return image_read_exr(path, out, err);
  return lmc_error_set(err, LMC_EUNSUPPORTED, path, 0,
                       "unknown image format (not PNG, JPEG or OpenEXR)");
}

