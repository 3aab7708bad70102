/*
 * fuzz_ply.c: libFuzzer target for the PLY reader, ASCII and binary (io/mesh_ply.c).
 *
 * The input is written to a file and read with mesh_read_ply; a mesh that reads
 * is then checked with mesh_validate, as the scene loader does, so the
 * validation of indices and values is fuzzed too. Errors are expected
 * results; only crashes, hangs, leaks and undefined behaviour are findings.
 */
#include <string.h>

#include "fuzz_util.h"
#include "render/io/io.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  lmc_warn_set_quiet(1);
  const char *path = fuzz_write("input.ply", data, size);
  mesh m;
  memset(&m, 0, sizeof m);
  lmc_error err;
  lmc_error_clear(&err);
  if (mesh_read_ply(path, &m, &err) == LMC_OK) mesh_validate(&m, path, 0, &err);
  mesh_free(&m);
  return 0;
}
