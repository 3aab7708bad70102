/*
 * mmlt_jump.h: the reversible jump between the strategies of the mmlt
 * and the bdpt states (Bitterli, Jakob, Novak and Jarosz 2017, "Reversible
 * Jump Metropolis Light Transport using Inverse Mappings"): a move that
 * keeps the state's path and changes the strategy (s, t) that makes it;
 * and the fused path mutation.
 *
 * The move. From a state of strategy t (its path x = x_0 .. x_k, walked
 * again from its numbers), the MIS weights w_t'(x) of every strategy of
 * length k are computed (bdpt_resplit, bdpt_path_pdfs, bdpt_mis_weight;
 * zero where a strategy cannot make x: a connection at a delta vertex, a
 * camera walk ending on a point light). A strategy t' != t is drawn with
 * probability w_t' / (W - w_t), W = sum of the weights, and x is mapped
 * into t''s numbers by the inverse of BDPT's subpaths (integrator.h,
 * bdpt_invert_*): the technique coordinate uniform in t''s interval, the
 * film, camera, light and connect numbers that make x, and every number
 * x does not fix a fresh uniform, so that the new numbers are distributed
 * as a uniform sample given that it makes x.
 *
 * Why the ratio is (W - w_t) / (W - w_t'). The states' f is n_k times a
 * strategy's MIS-weighted estimate, f_t(u) = n_k w_t(x) C(x) / p_t(x)
 * with p_t the density with which t's numbers make x (the states'
 * estimate is unbiased, so p_t is the true density of that map). In the
 * coordinates (t, x, numbers not fixed by x) the target is proportional
 * to w_t(x) C(x) times the conditional density of the free numbers, which
 * the inverse draws from; the move is then a Metropolised Gibbs step on t
 * given x (Liu 1996), whose acceptance is min(1, (W - w_t) / (W - w_t')).
 * The chain's formula f(y) q(x|y) / (f(x) q(y|x)) is made to give that:
 * propose returns log q(y|x) = -log f(x) - log(W - w_t), log_density
 * -log f(y) - log(W - w_t') (the same x: cached by propose).
 *
 * The fused move (perturb = 1; Otsu, Kaplanyan, Hanika, Dachsbacher and
 * Hachisuka 2017's fusion of the two spaces). The state's path x is moved
 * in path space by one of path-space MLT's moves, drawn uniformly among
 * those that apply to x (as the mlt integrator draws them): Veach's
 * bidirectional mutation (mut_bidir.h), the lens, multi-chain and caustic
 * perturbations (mut_perturb.h) and the lens subpath mutation
 * (mut_lenssub.h), into y; the selection's ratio n(x) / n(y), n the number
 * of moves that apply, joins the move's own. The moves' path space has the family's length alone, so a
 * bidirectional mutation adds as many edges as it deletes (P(ka | kd) is
 * then 1 at ka = kd, and kd = 1 makes no move) and a lens subpath mutation
 * whose new subpath has another length makes no proposal. y's strategy t'
 * is drawn with probability w_t'(y) (the full conditional) and its numbers
 * found as above. In the coordinates above the target is w_t(x) C(x) times
 * the free numbers' density, the strategy's draw is its conditional, so
 * the ratio is the path move's own, C(y) T(y -> x) / (C(x) T(x -> y))
 * n(x) / n(y) (with C the path's measurement contribution, pathspace.h):
 * propose returns log q(y|x) = -log f(x) - log that ratio, log_density
 * -log f(y).
 * A state whose path has no contribution in path space (its camera ray in
 * the film's margin, which the states sample) stays.
 *
 * On the bdpt states (bdpt_states.h; a labelled target) the same moves
 * change the state's label: the strategy is the label's (s, t), a new
 * strategy's numbers are written in its label's coordinates (its rough
 * vertices' absolute directions, the s = 1 connect triple of its t), and
 * the kernel reports the new label (chain.h's mc_kernel.label). The
 * target of (u, l) is the strategy's MIS-weighted contribution in l's
 * coordinates, w_l(x) C(x) / p_l(x) up to the film's constant, with p_l
 * the density of x in those coordinates, which the inverse's Jacobian is:
 * the same two ratios follow. One family holds every length in [kmin,
 * kmax], so the path moves keep that range alone: Veach's bidirectional
 * mutation changes the path's length, as in mlt, and the chain's marginal
 * over paths is C(x) over all of them.
 *
 * Cost. Each move walks the state's path again from its numbers; a
 * kernel keeps the last path it walked with those numbers (and, for the
 * fused move, that path in path space) and skips the walk when the state
 * has not moved since (a rejected proposal of any kernel leaves it), a
 * function of the numbers alone, so the chain is the same, image for
 * image. propose also walks its proposal from the new numbers and
 * evaluates it with the target's own function (mc_bdpt_states_value, the
 * mmlt states' mc_mmlt_connect), which the chain takes in place of
 * evaluating y (mc_kernel.value); once y is accepted, that walk is the
 * state's.
 *
 * Refusals. A re-split whose numbers a walk cannot reach (a direction
 * deep in a sampler's clamped tail, bsdf_invert) is refused: the state
 * stays, as a proposal of zero density. A proposal whose walk does not
 * land on the same raster point (a ray that grazed an edge) is rejected
 * too. Both are counted; they should be near zero.
 */
#ifndef LMC_MCMC_MMLT_JUMP_H
#define LMC_MCMC_MMLT_JUMP_H

#include <stdint.h>

#include "lmc/kernels/chain.h"
#include "lmc/path/mut_bidir.h"
#include "lmc/path/mut_lenssub.h"
#include "lmc/path/mut_perturb.h"
#include "lmc/states/path_states.h"
#include "render/error.h"
#include "render/integrators/integrator.h"

/* What the jumps of one chain counted (int64_t only: summed over MPI ranks). */
typedef struct mc_mmlt_jump_stats {
  int64_t proposed;    /* jumps tried */
  int64_t lone;        /* the state's strategy is the only one with weight: nothing to jump to */
  int64_t refused;     /* the new strategy's numbers could not be found (a tail, see above) */
  int64_t mismatch;    /* the new numbers walked to another raster point: rejected */
  int64_t inversions;  /* subpaths inverted */
  int64_t reused;      /* proposals from a state whose path was still walked (no walk) */
  int64_t kinds[MC_PATH_MOVE_FUSED]; /* the fused move: path moves drawn, by mc_path_move */
} mc_mmlt_jump_stats;

/* One chain's jump or fused move: its target (an mmlt family's), scratch
 * and counts. */
typedef struct mc_mmlt_jump {
  const mc_target *target; /* borrowed; target->ctx is the family's mc_mmlt_states, or for
                              a labelled target the mc_bdpt_states (bs) */
  const struct mc_bdpt_states *bs; /* the bdpt states, or NULL: the mmlt states */
  int label_to;            /* bdpt states: the label of the last proposal */
  int walked_label;        /* bdpt states: the label of walked_u */
  int perturb;             /* 0: the strategy jump; 1: the fused path perturbation */
  ps_context ctx;          /* perturb: the path space of the family's paths */
  mut_perturb mp;          /* perturb: the perturbations' sizes */
  mut_bidir mb;            /* perturb: the bidirectional mutation */
  mut_lenssub ml;          /* perturb: the lens subpath mutation */
  ps_path *px, *py;        /* perturb: the state's path and the proposal's (owned) */
  bdpt_vertex *v;          /* scratch: 5 arrays of BDPT_MAX_VERTICES + 1 vertices: two
                              for the walks below, the path-space proposal's, cam, lp */
  bdpt_vertex *walked_x;   /* (in v) the path of the state walked last */
  double *walked_u;        /* (in u_block) that state's numbers (target->dim) */
  int walked_ok;           /* walked_x holds walk(walked_u) */
  int px_ok;               /* perturb: px holds walked_x in path space */
  bdpt_vertex *pend_x;     /* (in v) the last proposal's walk, */
  double *pend_u;          /* (in u_block) its numbers */
  int pend_ok, pend_label; /* pend_x holds walk(pend_u) for pend_label */
  double *u_block;         /* owned: walked_u and pend_u */
  mc_value yv;             /* the last proposal's value ... */
  int y_ok;                /* ... when propose evaluated it (mc_kernel.value) */
  double log_rest_to;      /* log(W - w_t') of the last proposal, for log_density */
  double rx, ry;           /* the raster point of its path */
  int test_kind;           /* tests only: the fused move's path move (mc_path_move; -1 in use: drawn) */
  mc_mmlt_jump_stats st;
} mc_mmlt_jump;

lmc_status mc_mmlt_jump_init(mc_mmlt_jump *j, const mc_target *mmlt_target, int perturb,
                             lmc_error *err);
void mc_mmlt_jump_free(mc_mmlt_jump *j);
/* The kernel (MC_KERNEL_FULL, "jump" or "path") over j, which must outlive it. */
mc_kernel mc_mmlt_jump_kernel(mc_mmlt_jump *j);

#endif
