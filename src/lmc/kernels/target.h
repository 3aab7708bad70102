/*
 * target.h: what a Markov chain samples, as an interface.
 *
 * The kernels of src/lmc (large step, Kelemen's small step, MALA/LMC with
 * its preconditioners) never see a scene: they see an mc_target, a function
 * that maps a primary sample vector u in [0,1)^dim to a non-negative target
 * value f(u) and, on request, its gradient. A scene target (the path
 * sampler of src/render behind it) also reports what the state adds to the
 * image: an RGB value at a raster position. Tests drive the same kernels
 * with toy densities in a few dimensions.
 *
 * Coordinates. A state has `dim` coordinates, split into consecutive blocks,
 * one per sampler stream (LMC_STREAM_CAMERA, _LIGHT, _CONNECT of
 * render/sampler.h); stream_dim[k] is the size of block k and the blocks
 * sum to dim. The target draws its numbers from an lmc_sampler: the j-th
 * number it draws from stream k is coordinate stream_offset(k) + j. A toy
 * target puts everything in stream 0. Drawing from the sampler (rather than
 * reading an array) lets a chain create coordinates lazily, as Kelemen et
 * al. 2002 do, and tells the chain how many coordinates a path used.
 *
 * Gradient. When `grad` is not NULL, eval also writes grad[i] = df/du_i
 * for every coordinate i < dim (0 where f does not depend on u_i), and sets
 * *OUT_grad_ok to 1; it sets 0 when no gradient exists at this state
 * (f = 0, or the derivative capacity overflowed), in which case the chain
 * falls back to a gradient-free proposal. The gradient of log f is grad / f.
 *
 * Thread safety: eval is called concurrently from several threads, each
 * with its own scratch (from scratch_create), its own sampler and its own
 * grad buffer; the target itself is read-only.
 */
#ifndef LMC_MCMC_TARGET_H
#define LMC_MCMC_TARGET_H

#include <stdint.h>

#include "render/sampler.h"
#include "render/vec3.h"

/* What one evaluation of a state gives. */
typedef struct mc_value {
  double f;      /* the target value (>= 0, finite); scenes: luminance of `value` */
  rgb value;     /* what the state adds to the image (scenes; toy targets: f, f, f) */
  double rx, ry; /* raster position of that contribution (scenes) */
  double f_large; /* labelled targets: f in the large step's coordinates (f without the
                     Jacobian of relabel, below); the chain keeps it, targets need not */
} mc_value;

/* What a scratch of a scene target has counted (scratch_counts). */
typedef struct mc_counts {
  int64_t grad_evals;  /* evaluations with the gradient */
  int64_t hess_evals;  /* ... of which also with the Hessian (eval_hess) */
  int64_t nan_samples; /* non-finite contributions dropped (set to 0) */
} mc_counts;

/* One label's part of an evaluation of every label at once (eval_all). */
typedef struct mc_contrib {
  int label;
  mc_value v;
} mc_contrib;

typedef struct mc_target mc_target;
struct mc_chain_kind;
struct mc_target {
  int dim;                           /* coordinates of a state */
  int stream_dim[LMC_STREAM_COUNT];  /* block sizes per stream, summing to dim */
  void *ctx;                         /* borrowed: the target's own data */
  /* Evaluates the state drawn from smp (see above). Returns 0 on success. */
  int (*eval)(const mc_target *t, void *scratch, lmc_sampler *smp, mc_value *OUT_value,
              double *OUT_grad, int *OUT_grad_ok);
  /* Per-chain scratch (may be NULL functions: no scratch). */
  void *(*scratch_create)(const mc_target *t);
  void (*scratch_destroy)(void *scratch);
  /* Optional (NULL: none): a workspace that every chain one thread drives
   * may share for the temporaries of an evaluation (the derivative passes'
   * arenas), so that they stay in that thread's cache instead of one copy
   * per chain. scratch_bind(scratch, ws) makes `scratch` use ws (borrowed;
   * NULL: its own, made on first use) until bound again; what an
   * evaluation leaves in ws is not read by the next. */
  void *(*workspace_create)(const mc_target *t);
  void (*workspace_destroy)(void *ws);
  void (*scratch_bind)(void *scratch, void *ws);
  /* Optional counter of rays traced in `scratch` since it was created (NULL: none). */
  int64_t (*scratch_rays)(const void *scratch);
  /* Optional (NULL: none): the other counters of `scratch` since it was
   * created, added to *OUT. */
  void (*scratch_counts)(const void *scratch, mc_counts *OUT);
  /* Optional (NULL: all 1), borrowed: per-coordinate factor on the offsets of
   * Kelemen's small step, in [0, 1]. A target sets it below 1 for a
   * coordinate whose mapping has a huge derivative (e.g. the triangle
   * choice of a finely tessellated area light, which a step of 1/1024
   * throws to the far side of the light); 0 leaves the coordinate to large
   * steps. Each factor is a constant, so the step stays symmetric. */
  const double *step_scale;
  /* Optional (NULL: none): an unbiased estimate of b = E[f] with less
   * variance than f itself, from the numbers of smp: E[f | every coordinate
   * but the target's own discrete choice] (mmlt: the sum over the length's
   * strategies of their MIS-weighted contributions, i.e. the expectation
   * over the technique coordinate). Used for the normalisation only. */
  double (*eval_expect)(const mc_target *t, void *scratch, lmc_sampler *smp);
  /* Optional (n_labels 0: none): labelled states. A state is then a
   * coordinate vector u and a label l in 0 .. n_labels-1 (the multiplexed
   * bidirectional states of mcmc.c: l is a BDPT strategy (s, t)), with the
   * target f(u, l); the chain samples u and l jointly. eval_label evaluates
   * f(u, l) (eval is not used). eval_all evaluates every label for the same
   * numbers at once, writing the labels with f > 0 to OUT (room for
   * n_labels entries) and returning their count; their sum
   * F(u) = sum_l f(u, l) is what the bootstrap averages (b = E[F]), and the
   * chain's large step proposes a fresh u with a label chosen in
   * proportion to f(u, l) (chain.h). f(u, l) from eval_label must equal
   * the label's entry of eval_all for the same numbers.
   *
   * A labelled target may give each label its own coordinates (relabel,
   * may be NULL). The numbers a large step draws are then the "large-step
   * coordinates" u; once the chain has picked label l for them,
   * relabel(t, scratch, l, u, r) rewrites u in place into l's coordinates
   * v (scratch still holding that eval_all's work; r: a generator for the
   * numbers v leaves free) and returns the Jacobian |du/dv| >= 0 of the
   * change, so that the state's density in v is f |du/dv|: eval_label
   * reads v and reports OUT_value->f and value in v's measure, and
   * f_large, the same state's f in u's measure (f / |du/dv|). eval_all
   * with from_label >= 0 reads numbers that are in label from_label's
   * coordinates and reports every label's f in u's measure (the current
   * state's F); with from_label -1 the numbers are large-step coordinates.
   * A target without relabel ignores from_label. */
  int n_labels;
  int (*eval_label)(const mc_target *t, void *scratch, lmc_sampler *smp, int label,
                    mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok);
  int (*eval_all)(const mc_target *t, void *scratch, lmc_sampler *smp, int from_label,
                  mc_contrib *OUT);
  double (*relabel)(const mc_target *t, void *scratch, int label, double *u, rng *r);
  /* Optional (labelled targets): the coordinates a label's value varies
   * with smoothly (its continuous numbers, not its discrete choices),
   * written to OUT_idx (room for dim) in a fixed order; returns their
   * count. LMC's cache keys its entries by label and these coordinates
   * (gcache.h). */
  int (*label_coords)(const mc_target *t, int label, int *OUT_idx);
  /* Optional (NULL: no Hessians; kernels with needs_grad 2 then see none):
   * eval or eval_label (label ignored without labels) with, besides the
   * gradient, the Hessian of f over the coordinates f varies with
   * smoothly: their indices to OUT_hidx (*OUT_hn of them, at most
   * MC_HESS_MAX) and d^2 f / du_i du_j for i <= j over them to OUT_hess,
   * the upper triangle row by row (entry (a, b), a <= b, at
   * a hn - a (a - 1) / 2 + b - a). *OUT_hess_ok is 1 when they are valid
   * (f > 0, a gradient, no overflow), else 0. */
  int (*eval_hess)(const mc_target *t, void *scratch, lmc_sampler *smp, int label,
                   mc_value *OUT_value, double *OUT_grad, int *OUT_grad_ok, int *OUT_hn,
                   int *OUT_hidx, double *OUT_hess, int *OUT_hess_ok);
  /* Optional (NULL: every coordinate, or label_coords for labelled
   * targets): the coordinates a local kernel that moves a subset (H2MC's)
   * moves at the state (u, label), written to OUT_idx (room for dim);
   * returns their count. It must depend only on the label and on
   * coordinates outside the set it returns, so that a step and its
   * reverse move the same ones (mmlt's states: the numbers the state's
   * strategy reads, a function of the technique coordinate). */
  int (*local_coords)(const mc_target *t, const double *u, int label, int *OUT_idx);
  /* Optional (NULL: the chain's state is the primary sample vector u,
   * chain.h): a chain over states of the target's own (path space,
   * lmc/path), which the chain framework starts, steps and counts through
   * these hooks (chain.h's mc_chain_kind). eval then draws a starting
   * state from the sampler's numbers (the bootstrap's samples). */
  const struct mc_chain_kind *chain_kind;
};

/* The most coordinates a target's Hessian spans (AD_H_CAPACITY of src/ad). */
#define MC_HESS_MAX 96

/* The smallest of t's step scales (1 without them). */
static inline double mc_step_scale_min(const mc_target *t) {
  double m = 1.0;
  for (int i = 0; t->step_scale && i < t->dim; i++)
    if (t->step_scale[i] < m) m = t->step_scale[i];
  return m;
}

/* First coordinate of stream k. */
static inline int mc_target_stream_offset(const mc_target *t, int k) {
  int off = 0;
  for (int i = 0; i < k; i++) off += t->stream_dim[i];
  return off;
}

#endif
