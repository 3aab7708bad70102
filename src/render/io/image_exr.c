/*
 * image_exr.c: OpenEXR reading and writing through the OpenEXRCore C API.
 *
 * This is the only file that includes OpenEXR. Reading accepts the first
 * part of scanline and tiled files (level 0 of tiled mip/rip maps), any
 * compression the library decodes, and half, float or uint channels, which
 * the library converts to float while unpacking. Channels R, G, B (and A if
 * present) give a 3- or 4-channel image; otherwise a Y channel gives a
 * 1-channel image. Subsampled channels (luminance/chroma files) are not
 * supported. The image covers the data window, whose size is checked
 * against image.h's limits before any pixel is allocated. EXR values are
 * linear.
 *
 * Writing produces a single-part scanline file with FP32 R, G, B channels
 * and ZIP compression (16 lines per chunk); a chunk that deflate does not
 * shrink is stored raw, as the format requires. As every writer in lmc, it
 * writes "<path>.tmp-<pid>-<n>" next to the target and renames it over the
 * target only when complete, removing the temporary on failure.
 *
 * OpenEXRCore reports errors through a per-context callback: we route it
 * into a buffer owned by the call, so messages are thread safe.
 */
#define _POSIX_C_SOURCE 200809L

#include <openexr.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "render/image.h"

/* The last message the library reported for one context. */
typedef struct exr__msg {
  char text[512];
} exr__msg;

static void exr__on_error(exr_const_context_t ctxt, exr_result_t code, const char *msg) {
  void *ud = NULL;
  if (exr_get_user_data(ctxt, &ud) == EXR_ERR_SUCCESS && ud) {
    exr__msg *m = ud;
    snprintf(m->text, sizeof m->text, "%s", msg ? msg : exr_get_default_error_message(code));
  }
}

static lmc_status exr__fail(lmc_error *err, const char *path, exr_result_t rv, const exr__msg *m,
                            lmc_status code, const char *what) {
  return lmc_error_set(err, code, path, 0, "%s: %s", what,
                       m->text[0] ? m->text : exr_get_default_error_message(rv));
}

/* Indices of the channels we read in the order we store them, or -1. */
typedef struct exr__layout {
  char names[4][72];
  int count;
} exr__layout;

/* The channels to read: R, G, B (and A), else Y; with a layer (NULL: the
 * image itself) the layer's, "layer.R" and so on. */
static int exr__choose(const exr_attr_chlist_t *ch, const char *layer, exr__layout *lay) {
  int has[5] = {0, 0, 0, 0, 0};
  static const char *const base[5] = {"R", "G", "B", "A", "Y"};
  char want[5][72];
  for (int k = 0; k < 5; k++)
    snprintf(want[k], sizeof want[k], "%.63s%s%s", layer ? layer : "", layer ? "." : "", base[k]);
  for (int i = 0; i < ch->num_channels; i++)
    for (int k = 0; k < 5; k++)
      if (strcmp(ch->entries[i].name.str, want[k]) == 0) has[k] = 1;
  lay->count = 0;
  if (has[0] && has[1] && has[2]) {
    for (int k = 0; k < (has[3] ? 4 : 3); k++) memcpy(lay->names[lay->count++], want[k], 72);
    return 1;
  }
  if (has[4]) {
    memcpy(lay->names[lay->count++], want[4], 72);
    return 1;
  }
  return 0;
}

/* Decodes one chunk into the image; (ox, oy) is the chunk's first pixel
 * relative to the data window. Every channel of the chunk is decoded, each
 * into its own plane of a scratch buffer, and the wanted ones are then
 * interleaved into the image. Two OpenEXRCore 3.1 behaviours force this:
 * with interleaved destination pointers it picks specialised half-to-float
 * unpackers that assume a channel order (we saw RGBA come back as ABGR),
 * and its specialised planar unpackers write every channel even when a
 * channel's decode_to_ptr is NULL (fuzzing found the NULL write with a file
 * of channels B, G, R and one more, as in an RGB + Z render). */
static exr_result_t exr__decode_chunk(exr_context_t ctxt, const exr_chunk_info_t *cinfo,
                                      const exr__layout *lay, lmc_image *img, int64_t ox,
                                      int64_t oy) {
  int64_t cw = cinfo->width, chh = cinfo->height;
  if (ox < 0 || oy < 0 || cw <= 0 || chh <= 0 || ox + cw > img->width || oy + chh > img->height)
    return EXR_ERR_CORRUPT_CHUNK;
  size_t plane = (size_t)cw * (size_t)chh;
  exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
  exr_result_t rv = exr_decoding_initialize(ctxt, 0, cinfo, &dec);
  if (rv != EXR_ERR_SUCCESS) return rv;
  float *scratch = dec.channel_count > 0 ? calloc(plane * (size_t)dec.channel_count, sizeof(float))
                                         : NULL;
  if (!scratch) {
    exr_decoding_destroy(ctxt, &dec);
    return dec.channel_count > 0 ? EXR_ERR_OUT_OF_MEMORY : EXR_ERR_CORRUPT_CHUNK;
  }

  /* Every channel gets its plane; find where each wanted channel went. */
  int src[4] = {-1, -1, -1, -1};
  for (int c = 0; c < dec.channel_count; c++) {
    exr_coding_channel_info_t *ci = &dec.channels[c];
    ci->decode_to_ptr = (uint8_t *)(scratch + plane * (size_t)c);
    ci->user_pixel_stride = (int32_t)sizeof(float);
    ci->user_line_stride = (int32_t)(sizeof(float) * (size_t)cw);
    ci->user_bytes_per_element = 4;
    ci->user_data_type = EXR_PIXEL_FLOAT;
    for (int k = 0; k < lay->count; k++)
      if (src[k] < 0 && strcmp(ci->channel_name, lay->names[k]) == 0) src[k] = c;
  }
  for (int k = 0; k < lay->count; k++)
    if (src[k] < 0) rv = EXR_ERR_CORRUPT_CHUNK;
  if (rv == EXR_ERR_SUCCESS) rv = exr_decoding_choose_default_routines(ctxt, 0, &dec);
  if (rv == EXR_ERR_SUCCESS) rv = exr_decoding_run(ctxt, 0, &dec);
  exr_decoding_destroy(ctxt, &dec);

  /* Interleave the wanted planes into the image. */
  if (rv == EXR_ERR_SUCCESS) {
    for (int64_t y = 0; y < chh; y++)
      for (int64_t x = 0; x < cw; x++) {
        float *dst = img->data + ((size_t)(oy + y) * (size_t)img->width + (size_t)(ox + x)) *
                                     (size_t)img->channels;
        for (int k = 0; k < lay->count; k++)
          dst[k] = scratch[plane * (size_t)src[k] + (size_t)(y * cw + x)];
      }
  }
  free(scratch);
  return rv;
}

lmc_status image_read_exr(const char *path, lmc_image *out, lmc_error *err) {
  return image_read_exr_layer(path, NULL, out, err);
}

lmc_status image_read_exr_layer(const char *path, const char *layer, lmc_image *out,
                                lmc_error *err) {
  memset(out, 0, sizeof *out);
  exr__msg m = {""};
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.error_handler_fn = exr__on_error;
  init.user_data = &m;
  exr_context_t ctxt = NULL;
  exr_result_t rv = exr_start_read(&ctxt, path, &init);
  if (rv != EXR_ERR_SUCCESS) {
    lmc_status st = exr__fail(err, path, rv, &m, rv == EXR_ERR_FILE_ACCESS ? LMC_EIO : LMC_EPARSE,
                              "cannot read EXR");
    exr_finish(&ctxt);
    return st;
  }

  /* Header: storage, data window, channels. */
  lmc_status st = LMC_OK;
  exr_storage_t storage;
  exr_attr_box2i_t dw;
  const exr_attr_chlist_t *ch = NULL;
  exr__layout lay;
  if ((rv = exr_get_storage(ctxt, 0, &storage)) != EXR_ERR_SUCCESS ||
      (rv = exr_get_data_window(ctxt, 0, &dw)) != EXR_ERR_SUCCESS ||
      (rv = exr_get_channels(ctxt, 0, &ch)) != EXR_ERR_SUCCESS) {
    st = exr__fail(err, path, rv, &m, LMC_EPARSE, "bad EXR header");
  } else if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED) {
    st = lmc_error_set(err, LMC_EUNSUPPORTED, path, 0, "deep EXR files are not supported");
  } else if (!exr__choose(ch, layer, &lay)) {
    if (layer)
      st = lmc_error_set(err, LMC_EUNSUPPORTED, path, 0, "EXR has no %s.R,G,B channels", layer);
    else
      st = lmc_error_set(err, LMC_EUNSUPPORTED, path, 0, "EXR has neither R,G,B nor Y channels");
  } else {
    for (int i = 0; i < ch->num_channels; i++)
      if (ch->entries[i].x_sampling != 1 || ch->entries[i].y_sampling != 1)
        st = lmc_error_set(err, LMC_EUNSUPPORTED, path, 0, "subsampled EXR channel '%s'",
                           ch->entries[i].name.str);
  }
  int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
  if (st == LMC_OK && (w <= 0 || h <= 0))
    st = lmc_error_set(err, LMC_EPARSE, path, 0, "empty EXR data window %lld x %lld", (long long)w,
                       (long long)h);
  if (st == LMC_OK) st = image_check_size(path, "EXR", w, h, err);
  /* A header can claim any size; the file's own size bounds what it can
   * really hold. No EXR compression packs more than about 1000:1 (ZIP, as
   * deflate), times 2 for half data decoded to float: beyond 4096 image
   * bytes per file byte (and 64 MiB) the header is lying, and the
   * allocation would only serve to run out of memory (found by fuzzing). */
  struct stat sb;
  if (st == LMC_OK && stat(path, &sb) == 0) {
    double bytes = (double)w * (double)h * lay.count * sizeof(float);
    if (bytes > 64.0 * 1024 * 1024 && bytes > 4096.0 * (double)sb.st_size)
      st = lmc_error_set(err, LMC_EPARSE, path, 0,
                         "EXR claims %lld x %lld pixels, more than its %lld bytes can hold",
                         (long long)w, (long long)h, (long long)sb.st_size);
  }
  if (st == LMC_OK) st = image_init(out, (int)w, (int)h, lay.count, err);

  /* Decode every chunk of level 0. */
  if (st == LMC_OK && storage == EXR_STORAGE_SCANLINE) {
    int32_t lines = 1;
    rv = exr_get_scanlines_per_chunk(ctxt, 0, &lines);
    if (rv != EXR_ERR_SUCCESS || lines <= 0) st = exr__fail(err, path, rv, &m, LMC_EPARSE, "bad EXR");
    for (int64_t y = dw.min.y; st == LMC_OK && y <= dw.max.y; y += lines) {
      exr_chunk_info_t cinfo;
      rv = exr_read_scanline_chunk_info(ctxt, 0, (int)y, &cinfo);
      if (rv == EXR_ERR_SUCCESS) rv = exr__decode_chunk(ctxt, &cinfo, &lay, out, 0, y - dw.min.y);
      if (rv != EXR_ERR_SUCCESS) st = exr__fail(err, path, rv, &m, LMC_EPARSE, "cannot decode EXR");
    }
  } else if (st == LMC_OK) {
    int32_t tw = 0, th = 0, lw = 0, lh = 0, nx = 0, ny = 0;
    rv = exr_get_tile_sizes(ctxt, 0, 0, 0, &tw, &th);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_level_sizes(ctxt, 0, 0, 0, &lw, &lh);
    if (rv != EXR_ERR_SUCCESS || tw <= 0 || th <= 0)
      st = exr__fail(err, path, rv, &m, LMC_EPARSE, "bad tiled EXR");
    else {
      nx = (lw + tw - 1) / tw;
      ny = (lh + th - 1) / th;
    }
    for (int ty = 0; st == LMC_OK && ty < ny; ty++) {
      for (int tx = 0; st == LMC_OK && tx < nx; tx++) {
        exr_chunk_info_t cinfo;
        rv = exr_read_tile_chunk_info(ctxt, 0, tx, ty, 0, 0, &cinfo);
        /* Tiles are addressed by tile index: pixel origin = index * tile size. */
        if (rv == EXR_ERR_SUCCESS)
          rv = exr__decode_chunk(ctxt, &cinfo, &lay, out, (int64_t)tx * tw, (int64_t)ty * th);
        if (rv != EXR_ERR_SUCCESS)
          st = exr__fail(err, path, rv, &m, LMC_EPARSE, "cannot decode EXR tile");
      }
    }
  }
  exr_finish(&ctxt);
  if (st != LMC_OK) image_free(out);
  return st;
}

lmc_status image_write_exr(const char *path, const lmc_image *img, lmc_error *err) {
  return image_write_exr_layer(path, img, NULL, NULL, err);
}

lmc_status image_write_exr_layer(const char *path, const lmc_image *img, const char *layer,
                                 const lmc_image *limg, lmc_error *err) {
  if (!img || !img->data || img->channels != 3 || img->width <= 0 || img->height <= 0)
    return lmc_error_set(err, LMC_EINVAL, path, 0, "image_write_exr needs a 3-channel image");
  if (layer && (!limg || !limg->data || limg->channels != 3 || limg->width != img->width ||
                limg->height != img->height || strlen(layer) > 60))
    return lmc_error_set(err, LMC_EINVAL, path, 0,
                         "image_write_exr: the layer needs a 3-channel image of the same size");
  char tmp[4096];
  image_temp_name(path, tmp, sizeof tmp);
  exr__msg m = {""};
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.error_handler_fn = exr__on_error;
  init.user_data = &m;
  exr_context_t ctxt = NULL;
  exr_result_t rv = exr_start_write(&ctxt, tmp, EXR_WRITE_FILE_DIRECTLY, &init);
  if (rv != EXR_ERR_SUCCESS) {
    lmc_status st = exr__fail(err, path, rv, &m, LMC_EIO, "cannot create EXR");
    exr_finish(&ctxt);
    remove(tmp);
    return st;
  }

  /* Header: one scanline part, FP32 R, G, B, ZIP. */
  int part = 0;
  lmc_status st = LMC_OK;
  rv = exr_add_part(ctxt, "", EXR_STORAGE_SCANLINE, &part);
  if (rv == EXR_ERR_SUCCESS)
    rv = exr_initialize_required_attr_simple(ctxt, part, img->width, img->height,
                                             EXR_COMPRESSION_ZIP);
  static const char *const names[3] = {"R", "G", "B"};
  for (int c = 0; c < 3 && rv == EXR_ERR_SUCCESS; c++)
    rv = exr_add_channel(ctxt, part, names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR, 1, 1);
  for (int c = 0; layer && c < 3 && rv == EXR_ERR_SUCCESS; c++) {
    char name[72];
    snprintf(name, sizeof name, "%s.%s", layer, names[c]);
    rv = exr_add_channel(ctxt, part, name, EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR, 1, 1);
  }
  if (rv == EXR_ERR_SUCCESS) rv = exr_write_header(ctxt);
  if (rv != EXR_ERR_SUCCESS) st = exr__fail(err, path, rv, &m, LMC_EIO, "cannot write EXR header");

  /* Pixels, chunk by chunk. */
  int32_t lines = 1;
  if (st == LMC_OK && (rv = exr_get_scanlines_per_chunk(ctxt, part, &lines)) != EXR_ERR_SUCCESS)
    st = exr__fail(err, path, rv, &m, LMC_EIO, "cannot write EXR");
  for (int y = 0; st == LMC_OK && y < img->height; y += lines) {
    exr_chunk_info_t cinfo;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    rv = exr_write_scanline_chunk_info(ctxt, part, y, &cinfo);
    if (rv == EXR_ERR_SUCCESS) rv = exr_encoding_initialize(ctxt, part, &cinfo, &enc);
    if (rv == EXR_ERR_SUCCESS) {
      for (int c = 0; c < enc.channel_count; c++) {
        exr_coding_channel_info_t *ci = &enc.channels[c];
        /* R, G, B of the image, or of the layer ("layer.R", ...). */
        const char *dot = strrchr(ci->channel_name, '.');
        const char *cn = dot ? dot + 1 : ci->channel_name;
        const lmc_image *src = dot ? limg : img;
        int k = cn[0] == 'R' ? 0 : cn[0] == 'G' ? 1 : 2;
        ci->encode_from_ptr =
            (const uint8_t *)(src->data + (size_t)cinfo.start_y * (size_t)img->width * 3 + (size_t)k);
        ci->user_pixel_stride = 3 * (int32_t)sizeof(float);
        ci->user_line_stride = 3 * (int32_t)sizeof(float) * img->width;
        ci->user_bytes_per_element = 4;
        ci->user_data_type = EXR_PIXEL_FLOAT;
      }
      rv = exr_encoding_choose_default_routines(ctxt, part, &enc);
      /* We write the chunk ourselves: a chunk whose packed size equals its
       * unpacked size is raw to every reader, but OpenEXRCore before 3.4.8
       * stores a deflate stream exactly as long as the raw data as is. */
      enc.write_fn = NULL;
      if (rv == EXR_ERR_SUCCESS) rv = exr_encoding_run(ctxt, part, &enc);
      if (rv == EXR_ERR_SUCCESS) {
        int raw = enc.compressed_bytes >= enc.packed_bytes;
        rv = exr_write_scanline_chunk(ctxt, part, enc.chunk.start_y,
                                      raw ? enc.packed_buffer : enc.compressed_buffer,
                                      raw ? enc.packed_bytes : enc.compressed_bytes);
      }
      exr_encoding_destroy(ctxt, &enc);
    }
    if (rv != EXR_ERR_SUCCESS) st = exr__fail(err, path, rv, &m, LMC_EIO, "cannot write EXR pixels");
  }
  rv = exr_finish(&ctxt);
  if (st == LMC_OK && rv != EXR_ERR_SUCCESS)
    st = exr__fail(err, path, rv, &m, LMC_EIO, "cannot finish EXR");

  /* Publish the complete file, or leave the target untouched. */
  if (st == LMC_OK && rename(tmp, path) != 0)
    st = lmc_error_set(err, LMC_EIO, path, 0, "cannot rename the temporary file over the target");
  if (st != LMC_OK) remove(tmp);
  return st;
}
