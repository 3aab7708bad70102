/*
 * integrator_mlt.c: `--integrator mlt`, path-space Metropolis light
 * transport (Veach and Guibas 1997; Veach 1997, chapter 11), on the MCMC
 * driver (method.h) and the path states (path_states.c): chains of whole
 * light paths moved by Veach's bidirectional mutation (lmc/path/mut_bidir.h),
 * which deletes a subpath (possibly the whole path) and regenerates it from
 * both ends, by the lens, multi-chain and caustic perturbations
 * (lmc/path/mut_perturb.h), which move a path a little keeping its form,
 * and by the lens subpath mutation (lmc/path/mut_lenssub.h), which moves
 * it to a fresh image point, by the manifold perturbation
 * (lmc/path/mut_manifold.h), which walks a specular chain pinned at both
 * ends, and by HSLT's half-vector perturbation (the same file), which
 * steps every half vector between the camera's first non-specular vertex
 * and the light and walks the path to them. Each move is on or off (Mitsuba's flags; the
 * lens subpath mutation, which Mitsuba lacks, has none), all on by default; a step
 * selects among those that apply to the current path with equal weights,
 * as Mitsuba does, but for the primary-sample step's own (--pss-weight;
 * path_states.c puts the selection into the ratio). As
 * Veach's, direct light is rendered apart by default (--direct separate).
 */
#include <stddef.h>
#include <stdlib.h>

#include "lmc/driver/method.h"
#include "lmc/states/path_states.h"

typedef struct mlt_settings {
  int move[MC_PATH_MOVE_COUNT]; /* on (1) or off, by mc_path_move */
  double pss_weight;            /* the primary-sample step's selection weight (the others 1) */
  double hslt_weight;           /* HSLT's likewise */
} mlt_settings;

static const mlt_settings mlt__defaults = {{1, 1, 1, 1, 1, 0, 0, 0}, 1.0, 1.0};
static const char *const mlt__names[MC_PATH_MOVE_COUNT] = {
    "bidir", "lens", "multichain", "caustic", "lenssub", "pss", "manifold", "hslt"};

static const lmc_opt mlt__opts[] = {
    {"bidir-mutation", LMC_OPT_CHOICE, offsetof(mlt_settings, move[MC_PATH_MOVE_BIDIR]), 0, 0, 0,
     lmc_opt_off_on, NULL, 0, NULL, "on",
     "Veach's bidirectional mutation: a subpath (up to the whole path) deleted and regenerated",
     "bidirectionalMutation"},
    {"lens-perturbation", LMC_OPT_CHOICE, offsetof(mlt_settings, move[MC_PATH_MOVE_LENS]), 0, 0, 0,
     lmc_opt_off_on, NULL, 0, NULL, "on",
     "the image point moved, the camera's specular chain retraced (paths E S* D (D|L))",
     "lensPerturbation"},
    {"multichain-perturbation", LMC_OPT_CHOICE,
     offsetof(mlt_settings, move[MC_PATH_MOVE_MULTICHAIN]), 0, 0, 0, lmc_opt_off_on, NULL, 0, NULL,
     "on", "the lens perturbation, then each further specular chain's start turned a little",
     "multiChainPerturbation"},
    {"caustic-perturbation", LMC_OPT_CHOICE, offsetof(mlt_settings, move[MC_PATH_MOVE_CAUSTIC]), 0,
     0, 0, lmc_opt_off_on, NULL, 0, NULL, "on",
     "the direction leaving the light side turned, the specular chain retraced to the camera "
     "(paths E D S* (D|L))",
     "causticPerturbation"},
    {"lens-subpath-mutation", LMC_OPT_CHOICE, offsetof(mlt_settings, move[MC_PATH_MOVE_LENSSUB]),
     0, 0, 0, lmc_opt_off_on, NULL, 0, NULL, "on",
     "the camera's subpath E S* D replaced by a fresh one through a uniform image point (Veach; "
     "not in Mitsuba)",
     NULL},
    {"manifold-perturbation", LMC_OPT_CHOICE, offsetof(mlt_settings, move[MC_PATH_MOVE_MANIFOLD]),
     0, 0, 0, lmc_opt_off_on, NULL, 0, NULL, "off",
     "Jakob and Marschner's manifold perturbation: the image point moved, the camera's chain "
     "retraced, the chain behind its first diffuse vertex walked on its manifold, glossy "
     "vertices' half vectors held (paths E (S|G)* D (S|G)+ (D|L))",
     "manifoldPerturbation"},
    {"hslt", LMC_OPT_CHOICE, offsetof(mlt_settings, move[MC_PATH_MOVE_HSLT]), 0, 0, 0,
     lmc_opt_off_on, NULL, 0, NULL, "off",
     "Kaplanyan et al.'s half-vector perturbation (HSLT): the image point moved and every half "
     "vector between the camera's first non-specular vertex and the light stepped by its "
     "roughness (--hslt-step), the path walked to them on its manifold (paths E S* D (S|G|D)+ L)",
     NULL},
    {"hslt-weight", LMC_OPT_DOUBLE, offsetof(mlt_settings, hslt_weight), 0, 1e-3, 1e3, NULL, NULL,
     0, "W", "1",
     "--hslt on: the move's weight in the choice of a move, each other move's being 1 (as "
     "--pss-weight)",
     NULL},
    {"pss-mutation", LMC_OPT_CHOICE, offsetof(mlt_settings, move[MC_PATH_MOVE_PSS]), 0, 0, 0,
     lmc_opt_off_on, NULL, 0, NULL, "off",
     "a primary-sample small step: the path's numbers for a strategy drawn by its MIS weights, "
     "found by inverting its subpaths, moved by Kelemen's step and walked again (exact)",
     NULL},
    {"pss-weight", LMC_OPT_DOUBLE, offsetof(mlt_settings, pss_weight), 0, 1e-3, 1e3, NULL, NULL, 0,
     "W", "1",
     "--pss-mutation on: the step's weight in the choice of a move, each other move's being 1 "
     "(the choice is among the moves that apply to the path, and enters the ratio)",
     NULL},
};

static const lmc_opt_table mlt__options = {"Path-space MLT (--integrator mlt)", mlt__opts,
                                           (int)(sizeof mlt__opts / sizeof mlt__opts[0]),
                                           &mlt__defaults, sizeof(mlt_settings)};

static lmc_status mlt__create(void **OUT_run, const mc_method_setup *setup, lmc_error *err) {
  mlt_settings *ms = malloc(sizeof *ms);
  if (!ms) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for mlt's settings");
  *OUT_run = ms;
  lmc_status st = lmc_opt_read(&mlt__options, setup->rs, ms, err);
  if (st) return st;
  int on = 0;
  for (int j = 0; j < MC_PATH_MOVE_COUNT; j++) on += ms->move[j];
  if (!on)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                         "--integrator mlt: every mutation is off (--bidir-mutation, "
                         "--lens-perturbation, --multichain-perturbation, --caustic-perturbation, "
                         "--lens-subpath-mutation, --manifold-perturbation, --hslt, "
                         "--pss-mutation)");
  if (ms->pss_weight != 1.0 && !ms->move[MC_PATH_MOVE_PSS])
    return lmc_error_set(err, LMC_EINVAL, NULL, 0,
                         "--pss-weight: the primary-sample step is off (--pss-mutation on)");
  if (ms->hslt_weight != 1.0 && !ms->move[MC_PATH_MOVE_HSLT])
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "--hslt-weight: HSLT is off (--hslt on)");
  if (!ms->move[MC_PATH_MOVE_BIDIR] && !setup->rs->quiet)
    lmc_warn(NULL, 0,
             "mlt without the bidirectional mutation: the perturbations alone keep each path's "
             "form and length, and a path none applies to never moves");
  return LMC_OK;
}

static void mlt__destroy(void *run) { free(run); }

static int mlt__chain_kernels(void *run, const mc_method_setup *setup, int i,
                              const mc_space_family *F, mc_kernel *k, double *p) {
  (void)setup, (void)i, (void)F;
  const mlt_settings *ms = run ? run : &mlt__defaults;
  int n = 0;
  for (int j = 0; j < MC_PATH_MOVE_COUNT; j++) {
    if (!ms->move[j]) continue;
    k[n] = (mc_kernel){.name = mlt__names[j], .kind = MC_KERNEL_OWN, .coord = j};
    p[n++] = j == MC_PATH_MOVE_PSS    ? ms->pss_weight
             : j == MC_PATH_MOVE_HSLT ? ms->hslt_weight
                                      : 1.0;
  }
  return n;
}

const mc_method mc_method_mlt = {
    .name = "mlt",
    .default_states = MCMC_STATES_PATH,
    .opts = &mlt__options,
    .create = mlt__create,
    .destroy = mlt__destroy,
    .chain_kernels = mlt__chain_kernels,
};
