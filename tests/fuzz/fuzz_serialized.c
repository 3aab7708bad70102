/*
 * fuzz_serialized.c: libFuzzer target for Mitsuba's .serialized mesh reader
 * (io/mesh_serialized.c).
 *
 * The input is written to a file and shapes 0 and 1 are read from it (the
 * shape index selects an offset from the file's trailing table, which is
 * where a corrupt file is most dangerous); a mesh that reads is checked
 * with mesh_validate, as the scene loader does. Errors are expected
 * results; only crashes, hangs, leaks and undefined behaviour are findings.
 */
#include <string.h>

#include "fuzz_util.h"
#include "render/io/io.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  lmc_warn_set_quiet(1);
  const char *path = fuzz_write("input.serialized", data, size);
  for (int shape = 0; shape < 2; shape++) {
    mesh m;
    memset(&m, 0, sizeof m);
    lmc_error err;
    lmc_error_clear(&err);
    if (mesh_read_serialized(path, shape, &m, &err) == LMC_OK) mesh_validate(&m, path, 0, &err);
    mesh_free(&m);
  }
  return 0;
}
