/*
 * gcache.c: the frozen gradient cache (see gcache.h for the model).
 *
 * Stage 1 appends entries to one flat record buffer, each record laid out
 * as [dim, f, u[dim], m1[dim], m2[dim]]. gcache_freeze gathers each
 * dimension's records into its own arrays (structure of arrays), builds a
 * k-d tree over them (split on the widest axis at the median, leaves of at
 * most GCACHE_LEAF entries; the entries are reordered so that each leaf is
 * a contiguous range) and picks the independence anchors.
 */
#include "lmc/kernels/gcache.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/kernels/mala.h"

#define GCACHE_LEAF 8

typedef struct gcache_node {
  int axis;          /* split axis, -1 for a leaf */
  double split;      /* left: u[axis] <= split */
  int64_t left, right; /* child nodes */
  int64_t begin, end;  /* entry range (leaves) */
} gcache_node;

/* The entries and tree of one dimension. */
typedef struct gcache_tree {
  int64_t n;
  double *u, *m1, *m2, *f; /* n x dim each (f: n) */
  gcache_node *nodes;
  int64_t n_nodes;
} gcache_tree;

/* An independence anchor: entry idx of dimension dim. */
typedef struct gcache_anchor {
  int dim;
  int64_t idx;
} gcache_anchor;

struct gcache {
  int max_dim;
  int *len;          /* vector length of each key 1 .. max_dim (keyed caches; else len[d] = d) */
  int frozen;
  double *rec;       /* stage 1 records */
  int64_t rec_top, rec_cap;
  int64_t *count;    /* entries per dimension (index 0 .. max_dim) */
  int64_t total;
  gcache_tree *trees; /* index 1 .. max_dim, after freeze */
  gcache_anchor *anchors;
  int n_anchors;
};

lmc_status gcache_create(gcache **OUT_c, int max_dim, int64_t capacity, lmc_error *err) {
  *OUT_c = NULL;
  if (max_dim < 1 || capacity < 0)
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "gcache: bad size (%d dims)", max_dim);
  gcache *c = calloc(1, sizeof *c);
  if (!c) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "gcache: out of memory");
  c->max_dim = max_dim;
  c->rec_cap = capacity;
  c->rec = capacity > 0 ? malloc((size_t)capacity * sizeof(double)) : NULL;
  c->count = calloc((size_t)max_dim + 1, sizeof(int64_t));
  c->len = calloc((size_t)max_dim + 1, sizeof(int));
  if ((capacity > 0 && !c->rec) || !c->count || !c->len) {
    gcache_destroy(c);
    return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "gcache: out of memory");
  }
  for (int d = 0; d <= max_dim; d++) c->len[d] = d;
  *OUT_c = c;
  return LMC_OK;
}

lmc_status gcache_create_keyed(gcache **OUT_c, int n_keys, const int *len, int64_t capacity,
                               lmc_error *err) {
  lmc_status st = gcache_create(OUT_c, n_keys, capacity, err);
  if (st) return st;
  for (int d = 1; d <= n_keys; d++) {
    if (len[d - 1] < 1) {
      gcache_destroy(*OUT_c);
      *OUT_c = NULL;
      return lmc_error_set(err, LMC_EINVAL, NULL, 0, "gcache: key %d has length %d", d, len[d - 1]);
    }
    (*OUT_c)->len[d] = len[d - 1];
  }
  return LMC_OK;
}

int gcache_len(const gcache *c, int key) { return key >= 1 && key <= c->max_dim ? c->len[key] : 0; }

static void gcache__free_trees(gcache *c) {
  if (!c->trees) return;
  for (int d = 0; d <= c->max_dim; d++) {
    gcache_tree *t = &c->trees[d];
    free(t->u), free(t->m1), free(t->m2), free(t->f), free(t->nodes);
  }
  free(c->trees);
  c->trees = NULL;
  free(c->anchors);
  c->anchors = NULL;
  c->n_anchors = 0;
}

void gcache_destroy(gcache *c) {
  if (!c) return;
  gcache__free_trees(c);
  free(c->rec);
  free(c->count);
  free(c->len);
  free(c);
}

int gcache_add(gcache *c, int dim, const double *u, const double *m1, const double *m2, double f) {
  if (c->frozen || dim < 1 || dim > c->max_dim) return 0;
  int L = c->len[dim];
  int64_t need = 3 * (int64_t)L + 2;
  if (c->rec_top + need > c->rec_cap) return 0;
  double *r = c->rec + c->rec_top;
  r[0] = (double)dim;
  r[1] = f;
  memcpy(r + 2, u, (size_t)L * sizeof(double));
  memcpy(r + 2 + L, m1, (size_t)L * sizeof(double));
  memcpy(r + 2 + 2 * L, m2, (size_t)L * sizeof(double));
  c->rec_top += need;
  c->count[dim]++;
  c->total++;
  return 1;
}

int gcache_add_records(gcache *c, const double *rec, int64_t n) {
  for (int64_t at = 0; at < n;) {
    const double *r = rec + at;
    int dim = (int)r[0];
    if (dim < 1 || dim > c->max_dim) return 0;
    int64_t L = c->len[dim];
    if (at + 3 * L + 2 > n || !gcache_add(c, dim, r + 2, r + 2 + L, r + 2 + 2 * L, r[1])) return 0;
    at += 3 * L + 2;
  }
  return 1;
}

const double *gcache_records(const gcache *c, int64_t *OUT_n) {
  *OUT_n = c->rec_top;
  return c->rec;
}

void gcache_merge(gcache *dst, const gcache *src) {
  if (src->frozen) return;
  gcache_add_records(dst, src->rec, src->rec_top);
}

int gcache_frozen(const gcache *c) { return c->frozen; }
int gcache_max_dim(const gcache *c) { return c->max_dim; }
int64_t gcache_size(const gcache *c) { return c->total; }
int64_t gcache_size_dim(const gcache *c, int dim) {
  return dim >= 1 && dim <= c->max_dim ? c->count[dim] : 0;
}

int64_t gcache_bytes(const gcache *c) {
  int64_t b = c->rec_top * (int64_t)sizeof(double);
  if (c->trees)
    for (int d = 1; d <= c->max_dim; d++) {
      const gcache_tree *t = &c->trees[d];
      b += t->n * (3 * c->len[d] + 1) * (int64_t)sizeof(double) + t->n_nodes * (int64_t)sizeof(gcache_node);
    }
  return b;
}

/* ---- Building the tree ------------------------------------------------- */

/* Swaps entries i and j of tree t (dimension d). */
static void gcache__swap(gcache_tree *t, int d, int64_t i, int64_t j) {
  if (i == j) return;
  double *arr[3] = {t->u, t->m1, t->m2};
  for (int a = 0; a < 3; a++)
    for (int k = 0; k < d; k++) {
      double tmp = arr[a][i * d + k];
      arr[a][i * d + k] = arr[a][j * d + k];
      arr[a][j * d + k] = tmp;
    }
  double tf = t->f[i];
  t->f[i] = t->f[j];
  t->f[j] = tf;
}

/* Quickselect: reorders [lo, hi) so that entry `nth` has the nth smallest
 * u[axis], smaller or equal ones before, larger or equal after. */
static void gcache__select(gcache_tree *t, int d, int axis, int64_t lo, int64_t hi, int64_t nth) {
  while (hi - lo > 1) {
    /* Median of three as the pivot, moved to the end. */
    int64_t mid = lo + (hi - lo) / 2;
    double a = t->u[lo * d + axis], b = t->u[mid * d + axis], cc = t->u[(hi - 1) * d + axis];
    int64_t piv = (a < b) ? ((b < cc) ? mid : (a < cc ? hi - 1 : lo))
                          : ((a < cc) ? lo : (b < cc ? hi - 1 : mid));
    gcache__swap(t, d, piv, hi - 1);
    double pv = t->u[(hi - 1) * d + axis];
    int64_t store = lo;
    for (int64_t i = lo; i < hi - 1; i++)
      if (t->u[i * d + axis] < pv) gcache__swap(t, d, i, store++);
    gcache__swap(t, d, store, hi - 1);
    if (store == nth) return;
    if (nth < store)
      hi = store;
    else
      lo = store + 1;
  }
}

/* Builds the subtree over entries [begin, end); returns its node index. */
static int64_t gcache__build(gcache_tree *t, int d, int64_t begin, int64_t end) {
  int64_t id = t->n_nodes++;
  gcache_node *nd = &t->nodes[id];
  nd->begin = begin, nd->end = end, nd->axis = -1, nd->left = nd->right = -1, nd->split = 0.0;
  if (end - begin <= GCACHE_LEAF) return id;
  /* Split the widest axis at the median. */
  int axis = 0;
  double widest = -1.0;
  for (int k = 0; k < d; k++) {
    double lo = INFINITY, hi = -INFINITY;
    for (int64_t i = begin; i < end; i++) {
      double v = t->u[i * d + k];
      lo = v < lo ? v : lo;
      hi = v > hi ? v : hi;
    }
    if (hi - lo > widest) widest = hi - lo, axis = k;
  }
  if (!(widest > 0.0)) return id; /* all entries coincide: one leaf */
  int64_t mid = begin + (end - begin) / 2;
  gcache__select(t, d, axis, begin, end, mid);
  double split = t->u[mid * d + axis];
  int64_t left = gcache__build(t, d, begin, mid);
  int64_t right = gcache__build(t, d, mid, end);
  nd = &t->nodes[id]; /* (the array does not move, but keep the habit) */
  nd->axis = axis, nd->split = split, nd->left = left, nd->right = right;
  return id;
}

/* Chooses up to `want` anchors evenly over all entries (in dimension
 * order, then entry order), at the midpoints of `want` equal strides. */
static int gcache__anchors(gcache *c, int want) {
  if (want <= 0 || c->total == 0) return 0;
  if (want > c->total) want = (int)c->total;
  c->anchors = malloc((size_t)want * sizeof(gcache_anchor));
  if (!c->anchors) return -1;
  double stride = (double)c->total / want;
  int k = 0, d = 1;
  int64_t before = 0; /* entries of dimensions below d */
  for (; k < want; k++) {
    int64_t g = (int64_t)((k + 0.5) * stride);
    while (g >= before + c->trees[d].n) before += c->trees[d++].n;
    c->anchors[k].dim = d;
    c->anchors[k].idx = g - before;
  }
  c->n_anchors = k;
  return 0;
}

lmc_status gcache_freeze(gcache *c, int anchors, int64_t max_per_dim, lmc_error *err) {
  if (c->frozen) return LMC_OK;
  c->trees = calloc((size_t)c->max_dim + 1, sizeof(gcache_tree));
  if (!c->trees) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "gcache: out of memory");
  /* Gather each dimension's records: entry j of dimension d is kept when
   * floor(j keep / count) advances (every entry when nothing is capped). */
  int64_t *keep = calloc((size_t)c->max_dim + 1, sizeof(int64_t));
  int64_t *seen = calloc((size_t)c->max_dim + 1, sizeof(int64_t));
  if (!keep || !seen) {
    free(keep), free(seen);
    goto oom;
  }
  for (int d = 1; d <= c->max_dim; d++)
    keep[d] = max_per_dim > 0 && c->count[d] > max_per_dim ? max_per_dim : c->count[d];
  for (int d = 1; d <= c->max_dim; d++) {
    gcache_tree *t = &c->trees[d];
    int64_t n = keep[d];
    if (n == 0) continue;
    size_t nd = (size_t)n * (size_t)c->len[d];
    t->u = malloc(nd * sizeof(double));
    t->m1 = malloc(nd * sizeof(double));
    t->m2 = malloc(nd * sizeof(double));
    t->f = malloc((size_t)n * sizeof(double));
    t->nodes = malloc((size_t)(2 * (n / GCACHE_LEAF + 1) * 2 + 1) * sizeof(gcache_node));
    if (!t->u || !t->m1 || !t->m2 || !t->f || !t->nodes) {
      free(keep), free(seen);
      goto oom;
    }
  }
  for (int64_t at = 0; at < c->rec_top;) {
    const double *r = c->rec + at;
    int d = (int)r[0], L = c->len[d];
    at += 3 * (int64_t)L + 2;
    int64_t j = seen[d]++;
    if (keep[d] < c->count[d] && (j * keep[d]) / c->count[d] == ((j + 1) * keep[d]) / c->count[d])
      continue;
    gcache_tree *t = &c->trees[d];
    int64_t i = t->n++;
    memcpy(t->u + i * L, r + 2, (size_t)L * sizeof(double));
    memcpy(t->m1 + i * L, r + 2 + L, (size_t)L * sizeof(double));
    memcpy(t->m2 + i * L, r + 2 + 2 * L, (size_t)L * sizeof(double));
    t->f[i] = r[1];
  }
  free(keep), free(seen);
  c->total = 0;
  for (int d = 1; d <= c->max_dim; d++) c->count[d] = c->trees[d].n, c->total += c->trees[d].n;
  /* Build the trees and anchors. */
  for (int d = 1; d <= c->max_dim; d++) {
    gcache_tree *t = &c->trees[d];
    if (t->n == 0) continue;
    gcache__build(t, c->len[d], 0, t->n);
  }
  if (gcache__anchors(c, anchors) < 0) goto oom;
  free(c->rec);
  c->rec = NULL;
  c->rec_top = c->rec_cap = 0;
  c->frozen = 1;
  return LMC_OK;
oom:
  gcache__free_trees(c);
  return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "gcache: out of memory");
}

/* ---- Queries ------------------------------------------------------------- */

typedef struct gcache_knn_state {
  const gcache_tree *t;
  int d, k, found;
  double max_d2; /* entries at or beyond this squared distance are not wanted */
  const double *q;
  int64_t *idx;
  double *d2; /* sorted ascending, `found` valid */
} gcache_knn_state;

static void gcache__knn_visit(gcache_knn_state *s, int64_t node) {
  const gcache_node *nd = &s->t->nodes[node];
  if (nd->axis < 0) {
    for (int64_t i = nd->begin; i < nd->end; i++) {
      const double *p = s->t->u + i * s->d;
      /* The partial sum only grows: stop as soon as it reaches the bound
       * (in 20-60 dimensions most entries are out after a few terms). */
      double bound = s->found == s->k ? fmin(s->max_d2, s->d2[s->k - 1]) : s->max_d2;
      double dist = 0.0;
      int j = 0;
      for (; j < s->d && dist < bound; j++) {
        double e = p[j] - s->q[j];
        dist += e * e;
      }
      if (dist >= bound) continue;
      /* Insert into the sorted list of the best k. */
      int at = s->found < s->k ? s->found++ : s->k - 1;
      while (at > 0 && s->d2[at - 1] > dist) {
        s->d2[at] = s->d2[at - 1];
        s->idx[at] = s->idx[at - 1];
        at--;
      }
      s->d2[at] = dist;
      s->idx[at] = i;
    }
    return;
  }
  double diff = s->q[nd->axis] - nd->split;
  int64_t nearer = diff <= 0.0 ? nd->left : nd->right;
  int64_t farther = diff <= 0.0 ? nd->right : nd->left;
  gcache__knn_visit(s, nearer);
  double bound = s->found < s->k ? s->max_d2 : fmin(s->max_d2, s->d2[s->k - 1]);
  if (diff * diff < bound) gcache__knn_visit(s, farther);
}

/* The k nearest within squared distance max_d2 (INFINITY: all). */
static int gcache__knn(const gcache *c, int dim, const double *u, int k, double max_d2,
                       int64_t *OUT_idx, double *OUT_d2) {
  if (!c->frozen || dim < 1 || dim > c->max_dim || k < 1) return 0;
  if (k > GCACHE_MAX_K) k = GCACHE_MAX_K;
  const gcache_tree *t = &c->trees[dim];
  if (t->n == 0) return 0;
  gcache_knn_state s = {t, c->len[dim], k, 0, max_d2, u, OUT_idx, OUT_d2};
  gcache__knn_visit(&s, 0);
  return s.found;
}

int gcache_knn(const gcache *c, int dim, const double *u, int k, int64_t *OUT_idx,
               double *OUT_d2) {
  return gcache__knn(c, dim, u, k, INFINITY, OUT_idx, OUT_d2);
}

int gcache_knn_within(const gcache *c, int dim, const double *u, int k, double max_d2,
                      int64_t *OUT_idx, double *OUT_d2) {
  int found = gcache__knn(c, dim, u, k, max_d2 * (1.0 + 1e-12), OUT_idx, OUT_d2);
  while (found > 0 && OUT_d2[found - 1] > max_d2) found--;
  return found;
}

const double *gcache_entry_u(const gcache *c, int dim, int64_t i) {
  return c->trees[dim].u + i * c->len[dim];
}
const double *gcache_entry_m1(const gcache *c, int dim, int64_t i) {
  return c->trees[dim].m1 + i * c->len[dim];
}
const double *gcache_entry_m2(const gcache *c, int dim, int64_t i) {
  return c->trees[dim].m2 + i * c->len[dim];
}
double gcache_entry_f(const gcache *c, int dim, int64_t i) { return c->trees[dim].f[i]; }

int gcache_precond(const gcache *c, int dim, const double *u, const gcache_params *p,
                   double *OUT_M) {
  int64_t idx[GCACHE_MAX_K];
  double d2[GCACHE_MAX_K];
  /* Only neighbours within the radius count (the search prunes beyond it). */
  int L = gcache_len(c, dim);
  double r2 = p->radius * p->radius * (double)L;
  int found = gcache__knn(c, dim, u, p->k, r2 * (1.0 + 1e-12), idx, d2);
  while (found > 0 && d2[found - 1] > r2) found--;
  if (found == 0) {
    double one = 1.0 < p->lo ? p->lo : (1.0 > p->hi ? p->hi : 1.0);
    for (int i = 0; i < L; i++) OUT_M[i] = one;
    return 0;
  }
  /* Inverse-distance weights, h = 1e-6 keeps a coincident entry finite. */
  double wsum = 0.0, w[GCACHE_MAX_K];
  for (int j = 0; j < found; j++) {
    w[j] = 1.0 / (sqrt(d2[j]) + 1e-6);
    wsum += w[j];
  }
  const gcache_tree *t = &c->trees[dim];
  for (int i = 0; i < L; i++) {
    double v = 0.0;
    for (int j = 0; j < found; j++) v += w[j] * t->m2[idx[j] * L + i];
    /* A coordinate whose gradient was exactly 0 at every neighbour (a
     * discrete choice) gets 1, as adam_precond gives it. */
    OUT_M[i] = v == 0.0 ? 1.0 : 1.0 / (p->eps + sqrt(v / wsum));
    OUT_M[i] = OUT_M[i] < p->lo ? p->lo : (OUT_M[i] > p->hi ? p->hi : OUT_M[i]);
  }
  return found;
}

int gcache_anchor_count(const gcache *c) { return c->frozen ? c->n_anchors : 0; }

void gcache_indep_sample(const gcache *c, int D, double sigma, rng *r, double *OUT_u) {
  const gcache_anchor *a = &c->anchors[rng_uniform_u32(r, (uint32_t)c->n_anchors)];
  int L = c->len[a->dim];
  const double *p = c->trees[a->dim].u + a->idx * L;
  int d = L < D ? L : D;
  for (int i = 0; i < d; i++) OUT_u[i] = mala_wrap(p[i] + sigma * mala_std_normal(r));
  for (int i = d; i < D; i++) OUT_u[i] = rng_uniform(r);
}

double gcache_indep_log_density(const gcache *c, int D, double sigma, const double *u) {
  int K = gcache_anchor_count(c);
  if (K == 0) return -INFINITY;
  /* Per coordinate, the wrapped normal is the nearest image alone when
   * sigma is small against the distance to the next one (the test of
   * mala_log_wrapped_normal): then its log is -d^2 / (2 sigma^2) + lnorm,
   * summed cheaply; other coordinates take the full function. */
  double inv = 0.5 / (sigma * sigma), lnorm = -log(sigma) - MALA_LOG_SQRT_TWO_PI;
  /* log (1/K sum_k exp(l_k)) with the log-sum-exp shift by the largest l_k. */
  double lmax = -INFINITY, sum = 0.0;
  for (int k = 0; k < K; k++) {
    const gcache_anchor *a = &c->anchors[k];
    int L = c->len[a->dim];
    const double *p = c->trees[a->dim].u + a->idx * L;
    int d = L < D ? L : D;
    double q = 0.0, l = 0.0;
    for (int i = 0; i < d; i++) {
      double e = mala_torus_diff(u[i], p[i]);
      if (mala_nearest_image_exact(e, inv))
        q += e * e;
      else
        l += mala_log_wrapped_normal(u[i], p[i], sigma) - lnorm;
    }
    l += -q * inv + d * lnorm;
    if (l > lmax) {
      sum = sum * exp(lmax - l) + 1.0;
      lmax = l;
    } else {
      sum += exp(l - lmax);
    }
  }
  return lmax + log(sum) - log((double)K);
}
