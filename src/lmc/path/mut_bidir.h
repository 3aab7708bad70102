/*
 * mut_bidir.h: Veach's bidirectional mutation of path-space MLT (Veach
 * 1997, section 11.4.2; Veach and Guibas 1997) on pathspace.h's states,
 * with its exact transition density and acceptance ratio.
 *
 * A mutation of x = x_0 .. x_k (x_0 the pinhole, x_k on an emitter):
 *  1. deletion: kd = m - l edges, the vertices strictly between x_l and x_m
 *     go, -1 <= l < m <= k + 1 (l = -1: the pinhole goes too; m = k + 1:
 *     the emitter vertex; (-1, k + 1): the whole path). kd has
 *     P(1) = 1/4, P(2) = 1/2, P(j) = 2^-j (j >= 3), normalised over
 *     1 .. k + 2; the range uniformly among the kd-ranges, which are every
 *     (l, l + kd) but (-1, 0) and (k, k + 1) (a pinhole or emitter cannot
 *     become an inner vertex);
 *  2. addition: ka edges, P(ka) proportional to 2^-|ka - kd| over the ka
 *     that keep the new length k' = k - kd + ka within [kmin, kmax],
 *     (kd, ka) = (1, 1) (the identity) excluded (no proposal when no ka
 *     is left: kd = 1 at k = kmax); the ka - 1 new vertices
 *     split as lc from the camera side (extending x_l by camera or BSDF
 *     sampling; the pinhole first when l = -1) and mc = ka - 1 - lc from
 *     the light side (extending x_m by emission or BSDF sampling; a fresh
 *     light endpoint when m = k + 1), lc uniform over its legal values:
 *     lc >= 1 when l = -1 (no walk hits the pinhole), mc >= 1 when
 *     m = k + 1 and no emitter can be hit, ka >= 2 when l = -1 or
 *     m = k + 1;
 *  3. the two ends joined by a connecting edge (visibility, BSDFs), or,
 *     when m = k + 1 and mc = 0, the camera walk ending on an emitter.
 * The proposal y has its range (l, l + ka); the reverse move deletes it and
 * adds kd edges.
 *
 * Transition density. For a given range and ka,
 *   T(x -> y) = P(kd) P(range | kd) P(ka | kd) (1 / n_splits)
 *               sum_lc prod_{new camera-side j} pdf_cam(y_j)
 *                      prod_{new light-side j} pdf_light(y_j),
 * the sum over every split lc that could have made y (Veach's sum over the
 * ways of generating the same path), each split counting only when both
 * ends of its connecting edge are connectible (no delta lobe there) and its
 * densities are positive. The range and ka are the move's auxiliary choice
 * (the reverse move's is (range (l, l + ka), kd)); the acceptance
 *   a(x -> y) = min(1, f(y) T(y -> x) / (f(x) T(x -> y)))
 * (f's luminance) then satisfies detailed balance. A generated y whose own
 * split has density zero under this rule (a delta lobe at a connection) is
 * not proposed: the chain stays, as on any failed generation. A kept
 * vertex a walk scatters from anew takes the lobe the walk sampled, and the
 * ends of the connection their smooth lobes (pathspace.h's flags).
 *
 * The densities come from y's caches (pathspace.h), so that T is O(ka) per
 * split sum; mut_bidir_density with scratch = 1 recomputes them instead
 * with bdpt's bdpt_path_pdfs on the re-split path (the tests compare both).
 */
#ifndef LMC_PATH_MUT_BIDIR_H
#define LMC_PATH_MUT_BIDIR_H

#include "lmc/path/pathspace.h"
#include "render/rng.h"

/* Why a mutation made no proposal. */
typedef enum mut_bidir_status {
  MUT_BIDIR_OK = 0,       /* a proposal (its ratio may be 0: f(y) = 0) */
  MUT_BIDIR_NO_SPLIT,     /* the chosen range and ka allow no split */
  MUT_BIDIR_WALK_FAILED,  /* a walk ended early or left the path space */
  MUT_BIDIR_ZERO_DENSITY  /* the split that made y has density 0 (the rules above) */
} mut_bidir_status;

/* One mutation's choices. */
typedef struct mut_bidir_record {
  int l, m;                /* the deleted range of x (vertices strictly between) */
  int kd, ka;              /* edges deleted and added */
  int lc, mc;              /* the split that made y: new vertices from the camera, the light */
  mut_bidir_status status; /* MUT_BIDIR_OK, or why no proposal */
} mut_bidir_record;

/* Tests only: which densities of T a deliberately wrong factor scales. */
typedef enum mut_bidir_bias_term {
  MUT_BIDIR_BIAS_NONE = 0,    /* the correct T */
  MUT_BIDIR_BIAS_LIGHT_BSDF,  /* new light-side vertices sampled by a surface's BSDF */
  MUT_BIDIR_BIAS_DELTA        /* new vertices sampled through a delta lobe (either side) */
} mut_bidir_bias_term;

/* The mutation: the path space and a test hook. */
typedef struct mut_bidir {
  const ps_context *ctx;              /* borrowed */
  mut_bidir_bias_term test_bias_term; /* tests only: MUT_BIDIR_BIAS_NONE in use */
  double test_bias;                   /* tests only: the wrong factor on those densities */
} mut_bidir;

void mut_bidir_init(mut_bidir *mb, const ps_context *ctx);

/* P(kd) for a path of length k (0 outside 1 .. k + 2). */
double mut_bidir_pmf_kd(int k, int kd);
/* The number of ranges of kd edges in a path of length k; *OUT_lmin (may
 * be NULL) gets the first range's l. */
int mut_bidir_ranges(int k, int kd, int *OUT_lmin);
/* P(ka | kd) for a path of length k. */
double mut_bidir_pmf_ka(const ps_context *ctx, int k, int kd, int ka);
/* The legal splits lc_lo .. lc_hi of a move with range start l, ka edges
 * added, m_end = 1 when the emitter vertex is in the range. Returns their
 * number (0: none). */
int mut_bidir_splits(const ps_context *ctx, int l, int m_end, int ka, int *OUT_lc_lo,
                     int *OUT_lc_hi);

/* The density of split lc of y's range (l, l + ka): the product of its new
 * vertices' densities, 0 when a connection end is not connectible. From
 * y's caches, or from bdpt_path_pdfs (scratch = 1). */
double mut_bidir_split_density(const mut_bidir *mb, const ps_path *y, int l, int ka, int lc,
                               int scratch);
/* T(x -> y) of the move that deleted x's range (l, l + kd) (x has length
 * k_from) and added ka edges. */
double mut_bidir_density(const mut_bidir *mb, int k_from, const ps_path *y, int l, int kd, int ka,
                         int scratch);

/* Generates y from x with the given choices (x may be NULL for the whole
 * path, l = -1 and m = k + 1 with k = y's length - kd + ka: then pass
 * k_from, else x->k is used). Returns the status; on MUT_BIDIR_OK y's caches
 * are up to date in its changed range and neighbours, and y->f is NOT yet
 * set (mut_bidir_finish). */
mut_bidir_status mut_bidir_generate(const mut_bidir *mb, rng *r, const ps_path *x, int k_from,
                                    int l, int m, int ka, int lc, ps_path *OUT_y);
/* f(y) from f(x) and the factors of the changed range (partial evaluation;
 * from scratch when x is NULL or a factor of x's range is zero), with the
 * connecting edge's visibility. */
void mut_bidir_finish(const mut_bidir *mb, const ps_path *x, const mut_bidir_record *rec,
                      ps_path *y);

/* Proposes y from x: chooses the move, generates y, evaluates f(y) and
 * the Metropolis-Hastings ratio f(y) T(y -> x) / (f(x) T(x -> y)) into
 * *OUT_ratio (0 when there is no proposal). Returns rec->status; accept
 * with probability min(1, ratio) (no forced accepts, no resets). */
mut_bidir_status mut_bidir_propose(const mut_bidir *mb, rng *r, const ps_path *x, ps_path *OUT_y,
                                   mut_bidir_record *OUT_rec, double *OUT_ratio);
/* The ratio of a proposal made by mut_bidir_propose, recomputed (scratch
 * = 1: T from bdpt_path_pdfs and f(y) from scratch). */
double mut_bidir_ratio(const mut_bidir *mb, const ps_path *x, const ps_path *y,
                       const mut_bidir_record *rec, int scratch);

/* An independent path of length k: the whole-path move (l = -1, m = k + 1)
 * from any path; its density mut_bidir_whole_pdf (the split average, without
 * the move's choice probabilities). Returns the status. */
mut_bidir_status mut_bidir_sample_whole(const mut_bidir *mb, rng *r, int k, ps_path *OUT_y);
double mut_bidir_whole_pdf(const mut_bidir *mb, const ps_path *y, int scratch);

#endif
