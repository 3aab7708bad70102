/*
 * mut_manifold.h: the manifold perturbation of manifold exploration
 * (Jakob and Marschner 2012, section 5; Jakob's thesis, chapter 4) on
 * pathspace.h's states, for paths whose specular chains are smooth (delta)
 * surfaces: the image point moves as the lens perturbation moves it, the
 * camera's specular chain is retraced to a new first non-specular vertex,
 * and the specular chain behind that vertex, which no ray from it can
 * retrace (its far end is pinned), follows by the manifold walk
 * (lmc/path/manifold.h).
 *
 * Form. x_1 .. x_{b-1} are S (delta surfaces; none when b = 1), x_b is a
 * non-delta surface, x_{b+1} .. x_{c-1} are S (at least one: with none the
 * lens perturbation applies), and x_c is fixed: a non-delta surface, or
 * the emitter end x_k (a point, spot or area light's point, or a
 * direction at infinity). This is the form no other perturbation moves
 * when x_c is the emitter end at infinity (a caustic of an environment
 * seen on a diffuse surface, E D S+ L) and the form that the lens and
 * multi-chain perturbations can only move apart when both sides of x_b
 * are specular (E S+ D S+ L). Glossy vertices (ps_glossy) are not
 * followed yet: a path with one in x_1 .. x_{c-1} makes no proposal.
 *
 * The move. The raster point moves by the lens perturbation's offset
 * (mut_perturb.h: length with density proportional to 1/r on [r1, r2],
 * uniform angle); the camera ray through it is retraced through x_1 ..
 * x_{b-1}, each S vertex keeping its lobe, to a new y_b on a surface of
 * x_b's kind. The chain x_c, x_{c-1}, .., x_{b+1}, x_b (x_c its fixed
 * start) then walks (mf_walk) until its end reaches y_b; its vertices are
 * y's y_{c-1} .. y_{b+1}, and y_b joins y_{b+1} (a shadow ray). The walk
 * is deterministic, so the move is reversible only if the walk from y's
 * chain back to x_b returns to x's chain: it is computed, and a y whose
 * reverse walk fails or lands elsewhere (by more than 1e-6 of the scene's
 * radius at any vertex) is refused (T(y -> x) = 0).
 *
 * Transition density, in the path measure of the changed vertices
 * y_1 .. y_{c-1} (pathspace.h's: area, delta vertices' Diracs reduced):
 *   T(x -> y) = p_r(|dr|) / (2 pi |dr|) * W H * pdf_cam(y_1)
 *               * prod_{i=2..b} |cos y_i| / |y_i - y_{i-1}|^2      (the lens part)
 *               * Phi(y) / J(y)                                    (the chain)
 * where Phi is the density the chain's vertices would have if it were
 * traced from x_c with a solid-angle density of one (after a direction
 * start: a density of one on the plane perpendicular to it), each vertex
 * reached through the S vertex before it by ps_forced_density from the
 * light side:
 *   Phi = |cos y_{c-1}| / |y_{c-1} - x_c|^2 (a direction start: |cos y_{c-1}|)
 *         * prod_{j=b..c-2} ps_forced_density(y, j + 1, j + 2, j, light side),
 * and J = d omega_c / dA_b (a direction start: dA_perp / dA_b) is the
 * generalized geometry term of the chain without x_c's cosine
 * (mf_geometry_term): y_b is drawn with the lens part's area density, and
 * the chain is a function of y_b, so its direction at x_c has the density
 * of y_b divided by J. For a chain without S vertices Phi / J = 1. The
 * acceptance is f(y) T(y -> x) / (f(x) T(x -> y)), the offsets' densities
 * cancelling as in the lens perturbation.
 */
#ifndef LMC_PATH_MUT_MANIFOLD_H
#define LMC_PATH_MUT_MANIFOLD_H

#include "lmc/path/manifold.h"
#include "lmc/path/mut_perturb.h"

typedef struct mut_manifold {
  const ps_context *ctx;  /* borrowed */
  const mut_perturb *mp;  /* borrowed: the raster offset's range (r1, r2) */
  mf_options walk;        /* the walks' settings (mf_options_default) */
  double back_tol;        /* the reverse walk's chain against x's: 1e-6 scene radius */
  double test_jac_power;  /* tests only: J raised to this wrong power (1: right) */
} mut_manifold;

/* What one proposal did (for the statistics line; may be summed). */
typedef struct mut_manifold_tally {
  int64_t walks;      /* walks begun (forward and reverse) */
  int64_t walked;     /* walks that reached their target */
  int64_t traces;     /* the walks' projections (rays through the chain) */
  int64_t irreversible; /* proposals refused because the reverse walk failed or went elsewhere */
} mut_manifold_tally;

void mut_manifold_init(mut_manifold *mm, const ps_context *ctx, const mut_perturb *mp);

/* The form's indices of x (the opening comment): b and c, 1 when it
 * applies, else 0. */
int mut_manifold_form(const mut_manifold *mm, const ps_path *x, int *OUT_b, int *OUT_c);
static inline int mut_manifold_applies(const mut_manifold *mm, const ps_path *x) {
  int b, c;
  return mut_manifold_form(mm, x, &b, &c);
}

/* y from x through the image point (rx, ry): the retrace and the walk
 * (the opening comment), without the reverse walk. Returns 1 with y
 * evaluated (f(y) may be 0: the join blocked), 0 when there is no y. rays
 * (may be NULL) adds the rays traced, tally (may be NULL) the walks. */
int mut_manifold_generate(const mut_manifold *mm, const ps_path *x, double rx, double ry,
                          ps_path *OUT_y, int64_t *rays, mut_manifold_tally *tally);

/* Whether the walk from y's chain to x's x_b returns to x's chain. */
int mut_manifold_reversible(const mut_manifold *mm, const ps_path *x, const ps_path *y,
                            int64_t *rays, mut_manifold_tally *tally);

/* T(x -> y) (the opening comment), 0 when y cannot come from x. */
double mut_manifold_density(const mut_manifold *mm, const ps_path *x, const ps_path *y);

/* Proposes y from x (to which the move must apply): draws the offset,
 * generates y, checks the reverse walk and writes f(y) T(y -> x) / (f(x)
 * T(x -> y)) to *OUT_ratio (0 for a refused y). Returns 0 when there is no
 * proposal. */
int mut_manifold_propose(const mut_manifold *mm, rng *r, const ps_path *x, ps_path *OUT_y,
                         double *OUT_ratio, int64_t *rays, mut_manifold_tally *tally);

#endif
