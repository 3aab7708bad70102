/*
 * mmlt_moves.c: the moves of the mmlt and the bdpt states (space.h's
 * mc_space_moves): the reversible jump and the fused path mutation of
 * mmlt_jump.h, one of each per chain, added by the driver to the kernels
 * of any integrator on these states (pssmlt, mmlt, lmc, h2mc) when
 * --technique-jump or --path-mutations asks, with their statistics lines.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/driver/method.h"
#include "lmc/states/mmlt_jump.h"

typedef struct mmm__run {
  const mc_space *space; /* borrowed */
  double jump, path;     /* the shares of the mutations that are not large steps */
  int n;
  int *family;           /* per chain */
  mc_mmlt_jump *jumps;   /* per chain: the strategy jumps (NULL: none) */
  mc_mmlt_jump *paths;   /* per chain: the fused path mutations (NULL: none) */
} mmm__run;

static void mmm__destroy(void *r) {
  mmm__run *run = r;
  if (!run) return;
  for (int i = 0; i < run->n; i++) {
    if (run->jumps) mc_mmlt_jump_free(&run->jumps[i]);
    if (run->paths) mc_mmlt_jump_free(&run->paths[i]);
  }
  free(run->jumps);
  free(run->paths);
  free(run->family);
  free(run);
}

static lmc_status mmm__create(void **OUT_run, const mc_space *sp, int n, const int *family,
                              double jump, double path, lmc_error *err) {
  *OUT_run = NULL;
  mmm__run *run = calloc(1, sizeof *run);
  if (run) run->family = malloc((size_t)(n > 0 ? n : 1) * sizeof *run->family);
  if (run && jump > 0.0) run->jumps = calloc((size_t)(n > 0 ? n : 1), sizeof *run->jumps);
  if (run && path > 0.0) run->paths = calloc((size_t)(n > 0 ? n : 1), sizeof *run->paths);
  if (!run || !run->family || (jump > 0.0 && !run->jumps) || (path > 0.0 && !run->paths)) {
    mmm__destroy(run);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the mmlt states' moves");
  }
  run->space = sp, run->jump = jump, run->path = path;
  for (int i = 0; i < n; i++) {
    const mc_target *T = &sp->fam[family[i]].target;
    run->family[i] = family[i];
    lmc_status st = run->jumps ? mc_mmlt_jump_init(&run->jumps[i], T, 0, err) : LMC_OK;
    if (!st && run->paths) st = mc_mmlt_jump_init(&run->paths[i], T, 1, err);
    run->n = i + 1;
    if (st) {
      mmm__destroy(run);
      return st;
    }
  }
  *OUT_run = run;
  return LMC_OK;
}

/* The moves take their shares of the mutations that are not large steps
 * (k[0]) from every other kernel in proportion; a jump only where the
 * family has a strategy to change. */
static int mmm__add_kernels(void *r, int i, mc_kernel *k, double *p, int n) {
  mmm__run *run = r;
  const mc_space_family *F = &run->space->fam[run->family[i]];
  int jump = run->jumps && (F->technique >= 0 || F->target.n_labels > 0);
  double share = (jump ? run->jump : 0.0) + (run->paths ? run->path : 0.0);
  if (!(share > 0.0) || n < 1 || n + 2 > MC_MAX_KERNELS) return n;
  double rest = k[0].kind == MC_KERNEL_LARGE ? 1.0 - p[0] : 1.0;
  for (int q = k[0].kind == MC_KERNEL_LARGE ? 1 : 0; q < n; q++) p[q] *= 1.0 - share;
  if (jump) k[n] = mc_mmlt_jump_kernel(&run->jumps[i]), p[n++] = run->jump * rest;
  if (run->paths) k[n] = mc_mmlt_jump_kernel(&run->paths[i]), p[n++] = run->path * rest;
  return n;
}

static void mmm__share_stats(void *r) {
  mmm__run *run = r;
  _Static_assert(sizeof(mc_mmlt_jump_stats) % sizeof(int64_t) == 0, "int64_t counters only");
  if (!run || run->n == 0) return;
  if (run->jumps)
    mc_share_counters(&run->jumps[0].st, run->n, sizeof *run->jumps, sizeof(mc_mmlt_jump_stats));
  if (run->paths)
    mc_share_counters(&run->paths[0].st, run->n, sizeof *run->paths, sizeof(mc_mmlt_jump_stats));
}

/* One kind of move's statistics line. */
static void mmm__report_moves(const mmm__run *run, const mc_mmlt_jump *mv, const char *kname,
                              const char *what, mc_chain *const *chains, int n,
                              double chain_seconds) {
  mc_mmlt_jump_stats t = {0};
  for (int i = 0; i < run->n; i++) {
    t.proposed += mv[i].st.proposed, t.lone += mv[i].st.lone;
    t.refused += mv[i].st.refused, t.mismatch += mv[i].st.mismatch;
    t.inversions += mv[i].st.inversions, t.reused += mv[i].st.reused;
    for (int q = 0; q < MC_PATH_MOVE_FUSED; q++) t.kinds[q] += mv[i].st.kinds[q];
  }
  int64_t acc = 0;
  for (int c = 0; c < n; c++)
    for (int q = 0; q < chains[c]->n_kernels; q++)
      if (chains[c]->kernels[q].name && !strcmp(chains[c]->kernels[q].name, kname))
        acc += chains[c]->stats[q].accepted;
  double pr = t.proposed > 0 ? (double)t.proposed : 1.0;
  fprintf(stderr,
          "lmc: %s: %lld proposed, %.1f%% accepted, %.2f%% with no move to make, "
          "%.3f%% refused (a path its walks cannot reach), %.3f%% walked elsewhere; "
          "%lld subpaths inverted (%.4g/s); %.1f%% from a state whose path was kept\n",
          what, (long long)t.proposed, 100.0 * (double)acc / pr, 100.0 * (double)t.lone / pr,
          100.0 * (double)t.refused / pr, 100.0 * (double)t.mismatch / pr,
          (long long)t.inversions,
          (double)t.inversions / (chain_seconds > 1e-9 ? chain_seconds : 1e-9),
          100.0 * (double)t.reused / pr);
  if (mv[0].perturb)
    fprintf(stderr,
            "lmc: %s drawn: %lld bidirectional, %lld lens, %lld multi-chain, %lld caustic, "
            "%lld lens subpath\n",
            what, (long long)t.kinds[MC_PATH_MOVE_BIDIR], (long long)t.kinds[MC_PATH_MOVE_LENS],
            (long long)t.kinds[MC_PATH_MOVE_MULTICHAIN], (long long)t.kinds[MC_PATH_MOVE_CAUSTIC],
            (long long)t.kinds[MC_PATH_MOVE_LENSSUB]);
}

static void mmm__report(void *r, mc_chain *const *chains, int n, double chain_seconds) {
  mmm__run *run = r;
  if (!run || run->n == 0) return;
  if (run->jumps)
    mmm__report_moves(run, run->jumps, "jump", "technique jumps", chains, n, chain_seconds);
  if (run->paths)
    mmm__report_moves(run, run->paths, "path", "path mutations (fused)", chains, n,
                      chain_seconds);
}

const mc_space_moves mc_strategy_moves = {
    .create = mmm__create,
    .destroy = mmm__destroy,
    .add_kernels = mmm__add_kernels,
    .share_stats = mmm__share_stats,
    .report = mmm__report,
};
