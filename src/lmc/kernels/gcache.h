/*
 * gcache.h: the gradient cache of cache-driven LMC: Adam moments recorded
 * at states of a first stage, frozen into k-d trees, and looked up as a
 * pure function of the state in the second stage.
 *
 * Luan et al. 2020 ("Langevin Monte Carlo Rendering with Gradient-based
 * Adaptation", sec. 5) make the adapted preconditioner unbiased by splitting
 * the render in two stages. Stage 1 runs chains with online Adam and stores
 * (u, adam moments) samples; stage 2 freezes the store. The preconditioner
 * at a state x is then M(x) = lookup(cache, x): it depends on x alone, not
 * on the chain's history, so the proposal q(y | x) = N(x + s/2 M(x) g(x),
 * s M(x)) is a fixed kernel, and with the reverse density built from M(y)
 * the Metropolis-Hastings chain is reversible with respect to pi.
 *
 * Layout. States of different dimension (paths of different length use
 * different numbers of coordinates) live in separate trees, one per
 * dimension d = 1 .. max_dim; a lookup only sees entries of its own
 * dimension. Distances are Euclidean in [0,1)^d (not on the torus: any
 * deterministic function of the state keeps the kernel fixed; Euclidean
 * distance keeps the k-d tree exact).
 *
 * Lookup (gcache_precond): the k nearest entries within radius sqrt(dim), weighted
 * by 1 / (distance + h); the weighted mean of their bias-corrected second
 * moments v gives M = clamp(1 / (eps + sqrt(v)), lo, hi) (v exactly 0, a
 * coordinate with no derivative: 1, clamped). With no entry within the
 * radius, M = I (clamped): isotropic where nothing is near.
 *
 * Global move (beyond the paper): an independence proposal that draws a
 * state near a cached one. At freeze, up to `anchors` entries are chosen
 * evenly over the whole cache (every entry equally likely, deterministic
 * stride): stage-1 chains visit states in proportion to the target, so the
 * anchors follow pi, high-contribution regions first. A draw picks an
 * anchor uniformly, moves its d coordinates by N(0, sigma^2) each (wrapped)
 * and draws the coordinates d .. D-1 of a D-dimensional state uniformly.
 * Its exact density at any y, (1 / K) sum_k prod_{i<d_k}
 * wrapped_normal(y_i; a_k,i, sigma), does not depend on the current state,
 * so the MH ratio is f(y) q(x) / (f(x) q(y)).
 *
 * Threads: building (add, merge, freeze) is single-threaded (each thread
 * fills its own cache, merged afterwards); after gcache_freeze every query
 * is read-only and thread-safe. No query allocates.
 */
#ifndef LMC_MCMC_GCACHE_H
#define LMC_MCMC_GCACHE_H

#include <stdint.h>

#include "render/error.h"
#include "render/rng.h"

#define GCACHE_MAX_K 32 /* largest k of a nearest-neighbour query */

typedef struct gcache gcache;

/* How a frozen cache turns neighbours into a preconditioner. */
typedef struct gcache_params {
  int k;         /* neighbours (1 .. GCACHE_MAX_K) */
  double radius; /* neighbours farther than radius sqrt(dim) are ignored (Euclidean: the
                    RMS distance per coordinate is what radius bounds) */
  double eps, lo, hi; /* M = clamp(1 / (eps + sqrt(v)), lo, hi) */
} gcache_params;

/* An empty cache for states of 1 .. max_dim coordinates, holding at most
 * `capacity` doubles of entries (an entry of dimension d takes 3 d + 2). */
lmc_status gcache_create(gcache **OUT_c, int max_dim, int64_t capacity, lmc_error *err);
/* A keyed cache: entries of key k (1 .. n_keys) are vectors of len[k - 1]
 * coordinates, each key its own tree (a key stands where a dimension
 * stands in the calls below; keys are the labels of a labelled target,
 * target.h, each with its own coordinates). */
lmc_status gcache_create_keyed(gcache **OUT_c, int n_keys, const int *len, int64_t capacity,
                               lmc_error *err);
/* The vector length of key (dimension) k: k itself for gcache_create. */
int gcache_len(const gcache *c, int key);
/* Frees c (NULL allowed). */
void gcache_destroy(gcache *c);

/* Stage 1: records a state u of dimension dim with its bias-corrected Adam
 * moments m1, m2 (dim values each) and its target value f. Returns 1, or 0
 * when the cache is full, frozen, or dim is out of range (nothing stored). */
int gcache_add(gcache *c, int dim, const double *u, const double *m1, const double *m2, double f);
/* Appends src's entries to dst (both not frozen; stops when dst is full). */
void gcache_merge(gcache *dst, const gcache *src);
/* The entries as they are stored, n doubles at the pointer returned (an
 * entry of dimension d: d, f, then u, m1 and m2, 3 d + 2 in all): what
 * gcache_add_records appends to a cache of the same dimensions (another
 * process's copy, render/dist.h). Returns 1, or 0 at the first entry that
 * does not fit or is malformed (those before it stay). */
const double *gcache_records(const gcache *c, int64_t *OUT_n);
int gcache_add_records(gcache *c, const double *rec, int64_t n);

/* Builds the k-d trees and picks up to `anchors` independence anchors;
 * after this the cache is read-only. max_per_dim > 0 keeps at most that
 * many entries per dimension, evenly spaced in the order they were added
 * (a lookup's cost grows with the tree; 0: keep all). */
lmc_status gcache_freeze(gcache *c, int anchors, int64_t max_per_dim, lmc_error *err);
int gcache_frozen(const gcache *c);

int gcache_max_dim(const gcache *c);
/* Entries in the whole cache, or of one dimension (frozen or not). */
int64_t gcache_size(const gcache *c);
int64_t gcache_size_dim(const gcache *c, int dim);
/* Bytes held by the entries and trees. */
int64_t gcache_bytes(const gcache *c);

/* Frozen caches: the k nearest entries of dimension dim to u (k <= GCACHE_MAX_K),
 * nearest first; returns how many were found (fewer when the tree is small).
 * OUT_idx: entry indices within that dimension; OUT_d2: squared distances. */
int gcache_knn(const gcache *c, int dim, const double *u, int k, int64_t *OUT_idx,
               double *OUT_d2);
/* The same for entries within squared distance max_d2 only (a far
 * cheaper search when few are that near). */
int gcache_knn_within(const gcache *c, int dim, const double *u, int k, double max_d2,
                      int64_t *OUT_idx, double *OUT_d2);
/* Entry i of dimension dim (frozen): its state, moments and target value. */
const double *gcache_entry_u(const gcache *c, int dim, int64_t i);
const double *gcache_entry_m1(const gcache *c, int dim, int64_t i);
const double *gcache_entry_m2(const gcache *c, int dim, int64_t i);
double gcache_entry_f(const gcache *c, int dim, int64_t i);

/* The preconditioner at u (dimension dim) into OUT_M[0 .. dim-1]; returns
 * the number of neighbours used (0: isotropic M = clamp(1)). */
int gcache_precond(const gcache *c, int dim, const double *u, const gcache_params *p,
                   double *OUT_M);

/* Independence proposal: number of anchors (0: unavailable). */
int gcache_anchor_count(const gcache *c);
/* Draws a state of D >= max_dim coordinates near a random anchor, std
 * sigma per anchored coordinate, the others uniform. */
void gcache_indep_sample(const gcache *c, int D, double sigma, rng *r, double *OUT_u);
/* log density of gcache_indep_sample at u (exact; -INFINITY without anchors). */
double gcache_indep_log_density(const gcache *c, int D, double sigma, const double *u);

#endif
