/*
 * fuzz_util.h: what the fuzz targets share.
 *
 * lmc's readers take file names, not memory, so every target writes the
 * input bytes to a file in a private temporary folder (made once per
 * process with mkdtemp, removed at exit) and hands that name to the reader.
 * The folder also holds the small auxiliary files the XML target's scenes
 * refer to (fuzz_xml.c writes them).
 *
 * Each target defines LLVMFuzzerTestOneInput. Built with clang and
 * -fsanitize=fuzzer it is a libFuzzer binary; built with any compiler and
 * linked with fuzz_replay.c it replays the committed corpus, which is how
 * the regression cases run in every ctest.
 */
#ifndef LMC_FUZZ_UTIL_H
#define LMC_FUZZ_UTIL_H

#include <stddef.h>
#include <stdint.h>

/* The entry point of every target (libFuzzer's name and signature). */
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The private folder (created on first use; aborts if it cannot be made,
 * which is an environment failure, not a finding). */
const char *fuzz_dir(void);
/* Writes size bytes to fuzz_dir()/name and returns the full path in a
 * static buffer (valid until the next call). */
const char *fuzz_write(const char *name, const void *data, size_t size);

#endif
