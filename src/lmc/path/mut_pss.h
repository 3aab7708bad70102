/*
 * mut_pss.h: a primary-sample small step of a path, from path space (the
 * fusion of the two spaces of Otsu, Kaplanyan, Hanika, Dachsbacher and
 * Hachisuka 2017, seen from the path-space chain): the path x of length k
 * is mapped to the numbers of one of BDPT's strategies by the inverse
 * path sampler, the numbers take Kelemen's small step, and are walked
 * into a path y of the same length.
 *
 * The move. A strategy (s, t) of length k is drawn with probability
 * w_t(x), its MIS weight for x (bdpt_mis_weights; length 1 has (0, 2)
 * alone, none to a light no ray hits); x is re-split at it and inverted into numbers u (the film
 * position u0 = rx / W, u1 = ry / H for t >= 2, the camera subpath's, the
 * light subpath's, or for s = 1 the light sample's), every number x does
 * not fix drawn uniformly (integrator.h's bdpt_invert_*). Every number
 * moves by Kelemen's offset (log-uniform in (s1, s2], either sign, wrapped
 * into [0, 1); the light-position number that picks an area light's
 * triangle by a fixed factor) into u', which is walked with the same
 * strategy into y.
 *
 * Why it is exact. Extend the chain's state with the strategy t and the
 * numbers z that x does not fix: pi(x, t, z) = C(x) w_t(x) q_t(z | x),
 * q_t the inverse's density, whose marginal is the chain's target C(x).
 * Drawing t and z is a Gibbs step on (t, z) given x. In the numbers of
 * strategy t that extended target is w_t(x) C(x) / p_t(x) (p_t the
 * density with which t's numbers make x, the inverse's Jacobian), BDPT's
 * MIS-weighted contribution of t, up to a factor of t alone. The small
 * step is symmetric, so the Metropolis-Hastings ratio of the step in
 * those numbers is c_t(u') / c_t(u), both from bdpt_connect on the walks
 * of u and u' (x walked again from its numbers). A y outside the path
 * space (C(y) = 0: another length, an escaped ray) has ratio 0. Both
 * steps leave pi invariant, so the move leaves C(x) invariant, and mixes
 * with the chain's path moves (path_states.c).
 */
#ifndef LMC_PATH_MUT_PSS_H
#define LMC_PATH_MUT_PSS_H

#include <stdint.h>

#include "lmc/path/pathspace.h"
#include "render/rng.h"

typedef struct mut_pss {
  const ps_context *ctx; /* borrowed */
  double s1, s2;         /* Kelemen's offsets: log-uniform in (s1, s2] (1/1024, 1/64) */
  double u1_scale;       /* the factor on the light-position number (1: none) */
  double test_power;     /* tests only: the ratio raised to this power (1; 0 accepts all) */
} mut_pss;

/* What the proposals met, for the statistics line: subpaths inverted,
 * paths the inverses could not take back to numbers (or with no strategy
 * of weight), and numbers that walked to another path than x (a failed
 * round trip, to rounding). */
typedef struct mut_pss_tally {
  int64_t inverted, refused, elsewhere;
} mut_pss_tally;

/* The vertices of scratch a proposal needs. */
#define MUT_PSS_SCRATCH (5 * (BDPT_MAX_VERTICES + 1))

/* u1_scale: mc_light_u1_scale's factor. */
void mut_pss_init(mut_pss *m, const ps_context *ctx, double u1_scale);

/* Proposes y from x with the ratio c_t(u') / c_t(u) in *OUT_ratio, 0 for
 * a y outside the path space (scratch: MUT_PSS_SCRATCH vertices). Returns
 * 0 when there is no proposal (x cannot be inverted, or its numbers walk
 * elsewhere). rays (may be NULL) adds the rays traced, tally (may be
 * NULL) what the proposal met. */
int mut_pss_propose(const mut_pss *m, rng *r, const ps_path *x, ps_path *OUT_y,
                    double *OUT_ratio, bdpt_vertex *scratch, int64_t *rays,
                    mut_pss_tally *tally);

#endif
