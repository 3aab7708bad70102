/*
 * h2mc.c: the H2MC proposal (h2mc.h).
 */
#include "lmc/kernels/h2mc.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/kernels/mala.h"

/* LAPACK's symmetric eigensolver (Fortran calling convention). */
extern void dsyev_(const char *jobz, const char *uplo, const int *n, double *a, const int *lda,
                   double *w, double *work, const int *lwork, int *info);

#define H2MC_TINY 1e-10 /* |eigenvalue| below this: no curvature */

h2mc_params h2mc_params_default(void) {
  h2mc_params p = {0.01, 1.57079632679489661923, 0};
  return p;
}

int h2mc_lwork(int n) { return n < 1 ? 1 : 3 * n; }

static void h2mc__isotropic(int n, double sigma, h2mc_gauss *G) {
  G->n = n;
  G->isotropic = 1;
  G->log_norm = -n * (log(sigma) + MALA_LOG_SQRT_TWO_PI);
}

int h2mc_gauss_build(const h2mc_params *p, int n, const double *g, double *H, double *work,
                     int lwork, h2mc_gauss *G) {
  double frob2 = 0.0;
  for (int i = 0; i < n * n; i++) frob2 += H[i] * H[i];
  double prior_prec = 1.0 / (p->sigma * p->sigma);
  if (n == 0 || !(sqrt(frob2) >= 0.5 * prior_prec)) {
    h2mc__isotropic(n, p->sigma, G);
    return 0;
  }
  /* H = V diag(l) V^T; dsyev leaves V in H (column i: eigenvector i). */
  int info = 0;
  dsyev_("V", "U", &n, H, &n, G->P, work, &lwork, &info);
  if (info != 0) {
    h2mc__isotropic(n, p->sigma, G);
    return -1;
  }
  memcpy(G->V, H, (size_t)n * (size_t)n * sizeof(double));
  double L = p->L;
  double sn2 = sin(L) * sin(L), cn = 1.0 - cos(L);
  double sh2 = sinh(L) * sinh(L), ch = cosh(L) - 1.0;
  double log_norm = -n * MALA_LOG_SQRT_TWO_PI;
  for (int i = 0; i < n; i++) {
    const double *v = G->V + (size_t)i * n;
    double b = 0.0;
    for (int j = 0; j < n; j++) b += v[j] * g[j];
    double l = G->P[i], o, s, coef; /* the offset's mean o = coef b, its variance s */
    if (l < -H2MC_TINY) {
      o = cn * b / -l;
      coef = cn / -l;
      s = sn2 / -l;
    } else if (l > H2MC_TINY) {
      o = ch * b / l;
      coef = ch / l;
      s = sh2 / l;
    } else {
      o = 0.5 * b * L * L;
      coef = 0.5 * L * L;
      s = L * L;
    }
    double P = 1.0 / s + prior_prec;
    G->P[i] = P;
    G->m[i] = o / (s * P);
    G->k[i] = coef / (s * P);
    G->l[i] = l;
    log_norm += 0.5 * log(P);
  }
  G->n = n;
  G->isotropic = 0;
  G->log_norm = log_norm;
  return 0;
}

double h2mc_gauss_log_density(const h2mc_gauss *G, const double *d, double sigma) {
  int n = G->n;
  double q = 0.0;
  if (G->isotropic) {
    for (int j = 0; j < n; j++) q += d[j] * d[j];
    return G->log_norm - 0.5 * q / (sigma * sigma);
  }
  for (int i = 0; i < n; i++) {
    const double *v = G->V + (size_t)i * n;
    double e = -G->m[i];
    for (int j = 0; j < n; j++) e += v[j] * d[j];
    q += G->P[i] * e * e;
  }
  return G->log_norm - 0.5 * q;
}

double h2mc_gauss_log_screen(const h2mc_gauss *G, const double *d, double log_f_ratio) {
  if (G->isotropic) return log_f_ratio;
  int n = G->n;
  double qf = 0.0, qr = 0.0;
  for (int i = 0; i < n; i++) {
    const double *v = G->V + (size_t)i * n;
    double e = 0.0;
    for (int j = 0; j < n; j++) e += v[j] * d[j];
    double ef = e - G->m[i], er = -e - (G->m[i] + G->k[i] * G->l[i] * e);
    qf += G->P[i] * ef * ef;
    qr += G->P[i] * er * er;
  }
  return log_f_ratio - 0.5 * (qr - qf);
}

void h2mc_gauss_sample(const h2mc_gauss *G, const double *z, double sigma, double *OUT_d) {
  int n = G->n;
  if (G->isotropic) {
    for (int j = 0; j < n; j++) OUT_d[j] = sigma * z[j];
    return;
  }
  for (int j = 0; j < n; j++) OUT_d[j] = 0.0;
  for (int i = 0; i < n; i++) {
    const double *v = G->V + (size_t)i * n;
    double a = G->m[i] + z[i] / sqrt(G->P[i]);
    for (int j = 0; j < n; j++) OUT_d[j] += a * v[j];
  }
}

/* ---- The kernel ------------------------------------------------------------ */

/* Carves a Gaussian's arrays out of *blk (n x n, then n and n doubles). */
static void h2mc__carve_gauss(h2mc_gauss *G, double **blk, size_t n) {
  G->V = *blk;
  G->P = G->V + n * n;
  G->m = G->P + n;
  G->l = G->m + n;
  G->k = G->l + n;
  *blk = G->k + n;
}

lmc_status h2mc_kernel_init(h2mc_kernel *k, const mc_target *target, const h2mc_params *p,
                            lmc_error *err) {
  memset(k, 0, sizeof *k);
  k->p = *p;
  k->target = target;
  k->dim = target->dim;
  k->subset = !target->local_coords && target->n_labels > 0 && target->label_coords;
  if (!(p->sigma > 0.0) || !(p->L > 0.0))
    return lmc_error_set(err, LMC_EINVAL, NULL, 0, "h2mc: sigma and L must be positive");
  int n = MC_HESS_MAX > target->dim ? target->dim : MC_HESS_MAX;
  if (n < 1) n = 1;
  k->lwork = h2mc_lwork(n);
  /* One block: g, H, work, z, d, the two slots' Gaussians and values
   * (doubles), then idx and the slots' idx. */
  size_t m = (size_t)n, dim = (size_t)(target->dim > 0 ? target->dim : 1);
  size_t doubles = m + m * m + (size_t)k->lwork + 2 * m + 2 * (m * m + 4 * m) + 2 * dim;
  double *blk = malloc(doubles * sizeof(double) + (dim + 2 * m) * sizeof(int));
  if (!blk) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory for the h2mc kernel");
  k->g = blk;
  k->H = k->g + m;
  k->work = k->H + m * m;
  k->z = k->work + k->lwork;
  k->d = k->z + m;
  double *rest = k->d + m;
  for (int q = 0; q < 2; q++) {
    h2mc__carve_gauss(&k->slot[q].G, &rest, m);
    k->slot[q].u = rest;
    rest += dim;
  }
  k->idx = (int *)rest;
  k->slot[0].idx = k->idx + dim;
  k->slot[1].idx = k->slot[0].idx + m;
  return LMC_OK;
}

void h2mc_kernel_free(h2mc_kernel *k) {
  if (!k) return;
  free(k->g); /* the block */
  memset(k, 0, sizeof *k);
}

/* The coordinates the kernel moves at a state: the target's local_coords,
 * else its label's (labelled targets with label_coords), else all, without
 * those of step scale 0 (left to large steps), at most MC_HESS_MAX. A
 * function of what the kernel does not move, so both directions of a step
 * move the same ones. */
static int h2mc__coords(const h2mc_kernel *k, const mc_state *x, int *OUT_idx) {
  const mc_target *T = k->target;
  int label = x->label;
  int n;
  if (T->local_coords) {
    n = T->local_coords(T, x->u, label, OUT_idx);
  } else if (T->n_labels > 0 && T->label_coords) {
    n = T->label_coords(T, label, OUT_idx);
  } else {
    n = T->dim;
    for (int i = 0; i < n; i++) OUT_idx[i] = i;
  }
  int m = 0;
  for (int a = 0; a < n && m < MC_HESS_MAX; a++)
    if (!T->step_scale || T->step_scale[OUT_idx[a]] > 0.0) OUT_idx[m++] = OUT_idx[a];
  return m;
}

static int h2mc__coords_cb(void *self, const mc_state *x, int *OUT_idx) {
  return h2mc__coords(self, x, OUT_idx);
}

/* The Gaussian at state s over the n coordinates idx, in the step-scaled
 * coordinates z = u / c: g and H of log f from the state's derivatives of f. */
static void h2mc__gauss_at(h2mc_kernel *k, const mc_state *s, const int *idx, int n,
                           h2mc_gauss *G) {
  const double *c = k->target->step_scale;
  if (!(s->v.f > 0.0) || !s->grad_ok || !s->hess_ok) {
    h2mc__isotropic(n, k->p.sigma, G);
    return;
  }
  double f = s->v.f, inv = 1.0 / f;
  for (int a = 0; a < n; a++) k->g[a] = s->grad[idx[a]] * inv * (c ? c[idx[a]] : 1.0);
  /* Positions of the Hessian's coordinates among idx (-1: not moved). */
  memset(k->H, 0, (size_t)n * (size_t)n * sizeof(double));
  int hn = s->hn;
  int pos[MC_HESS_MAX];
  for (int a = 0; a < hn; a++) {
    pos[a] = -1;
    for (int b = 0; b < n; b++)
      if (idx[b] == s->hidx[a]) {
        pos[a] = b;
        break;
      }
  }
  /* hess log f = hess f / f - g g^T with g = grad log f. */
  for (int a = 0; a < hn; a++) {
    if (pos[a] < 0) continue;
    const double *row = s->hess + (size_t)a * hn - (size_t)a * (size_t)(a - 1) / 2 - (size_t)a;
    for (int b = a; b < hn; b++) {
      if (pos[b] < 0) continue;
      double ca = c ? c[s->hidx[a]] : 1.0, cb = c ? c[s->hidx[b]] : 1.0;
      double h = row[b] * inv * ca * cb;
      k->H[pos[a] * n + pos[b]] = h;
      k->H[pos[b] * n + pos[a]] = h;
    }
  }
  for (int a = 0; a < n; a++)
    for (int b = 0; b < n; b++) k->H[a * n + b] -= k->g[a] * k->g[b];
  if (h2mc_gauss_build(&k->p, n, k->g, k->H, k->work, k->lwork, G) != 0) k->st.eig_fail++;
}

/* Whether slot S was built at state s (moving idx[0 .. n-1]). */
static int h2mc__slot_holds(const h2mc_kernel *k, const h2mc_slot *S, const mc_state *s,
                            const int *idx, int n) {
  if (!S->valid || S->label != s->label || S->n != n || S->ok != (s->grad_ok && s->hess_ok) ||
      memcmp(&S->f, &s->v.f, sizeof S->f) != 0 || memcmp(S->idx, idx, (size_t)n * sizeof *idx))
    return 0;
  if (!k->subset) return memcmp(S->u, s->u, (size_t)k->dim * sizeof *s->u) == 0;
  for (int a = 0; a < n; a++)
    if (memcmp(&S->u[a], &s->u[idx[a]], sizeof *s->u) != 0) return 0;
  return 1;
}

/* The Gaussian at state s over the n coordinates idx: a slot that holds it
 * already, else built into slot `into` (the other one is kept). Returns
 * the slot. */
static int h2mc__gauss_of(h2mc_kernel *k, const mc_state *s, const int *idx, int n, int into) {
  for (int q = 0; q < 2; q++)
    if (h2mc__slot_holds(k, &k->slot[q], s, idx, n)) return q;
  h2mc_slot *S = &k->slot[into];
  h2mc__gauss_at(k, s, idx, n, &S->G);
  k->st.built++;
  S->valid = 1, S->label = s->label, S->n = n, S->ok = s->grad_ok && s->hess_ok, S->f = s->v.f;
  memcpy(S->idx, idx, (size_t)n * sizeof *idx);
  if (!k->subset) memcpy(S->u, s->u, (size_t)k->dim * sizeof *s->u);
  else
    for (int a = 0; a < n; a++) S->u[a] = s->u[idx[a]];
  return into;
}

static double h2mc__propose(void *self, rng *r, const mc_state *x, double *OUT_y) {
  h2mc_kernel *k = self;
  const double *c = k->target->step_scale;
  int n = h2mc__coords(k, x, k->idx);
  k->cur = h2mc__gauss_of(k, x, k->idx, n, k->cur);
  const h2mc_gauss *G = &k->slot[k->cur].G;
  k->st.proposed++;
  k->st.model += !G->isotropic;
  for (int a = 0; a < n; a += 2) {
    double z0, z1;
    mala_std_normal_pair(r, &z0, &z1);
    k->z[a] = z0;
    if (a + 1 < n) k->z[a + 1] = z1;
  }
  h2mc_gauss_sample(G, k->z, k->p.sigma, k->d);
  /* Coordinates not moved keep x's values (the chain reads all of OUT_y
   * from a kernel without a coordinate subset). */
  memcpy(OUT_y, x->u, (size_t)k->dim * sizeof(double));
  double log_c = 0.0;
  for (int a = 0; a < n; a++) {
    int i = k->idx[a];
    double ci = c ? c[i] : 1.0;
    double y = x->u[i] + ci * k->d[a];
    if (!(y >= 0.0 && y < 1.0)) {
      k->st.outside++;
      return -INFINITY;
    }
    OUT_y[i] = y;
    log_c += log(ci);
  }
  return h2mc_gauss_log_density(G, k->d, k->p.sigma) - log_c;
}

static double h2mc__log_density(void *self, const mc_state *from, const double *to_u) {
  h2mc_kernel *k = self;
  const double *c = k->target->step_scale;
  int n = h2mc__coords(k, from, k->idx);
  /* (Built into the slot that is not the current state's.) */
  const h2mc_gauss *G = &k->slot[h2mc__gauss_of(k, from, k->idx, n, 1 - k->cur)].G;
  double log_c = 0.0;
  for (int a = 0; a < n; a++) {
    int i = k->idx[a];
    double ci = c ? c[i] : 1.0;
    k->d[a] = (to_u[i] - from->u[i]) / ci;
    log_c += log(ci);
  }
  return h2mc_gauss_log_density(G, k->d, k->p.sigma) - log_c;
}

/* Delayed acceptance's first test (chain.h), which needs no derivative at
 * `to`: the full ratio with the reverse density predicted by from's
 * quadratic model (h2mc_gauss_log_screen). Any function of the two states
 * keeps the chain exact; this one is the full ratio where log f is
 * quadratic, so the second test, which costs the Hessian at y, rarely
 * rejects. */
static double h2mc__log_screen(void *self, const mc_state *from, const double *to_u, double f_to) {
  h2mc_kernel *k = self;
  double lr = log(f_to) - log(from->v.f);
  const double *c = k->target->step_scale;
  int n = h2mc__coords(k, from, k->idx);
  /* (from is the current state, whose Gaussian the slot cur holds, or the
   * proposal, evaluated with its Hessian just before its reverse test.) */
  const h2mc_gauss *G = &k->slot[h2mc__gauss_of(k, from, k->idx, n, 1 - k->cur)].G;
  for (int a = 0; a < n; a++) {
    int i = k->idx[a];
    k->d[a] = (to_u[i] - from->u[i]) / (c ? c[i] : 1.0);
  }
  return h2mc_gauss_log_screen(G, k->d, lr);
}

mc_kernel h2mc_kernel_make(h2mc_kernel *k) {
  mc_kernel kn;
  memset(&kn, 0, sizeof kn);
  kn.name = "h2mc";
  kn.kind = MC_KERNEL_FULL;
  kn.needs_grad = 2;
  kn.self = k;
  kn.propose = h2mc__propose;
  kn.log_density = h2mc__log_density;
  if (k->p.delayed) kn.log_screen = h2mc__log_screen;
  /* Labelled targets: the chain keeps only the label's coordinates up to
   * date (the others take the lazy small step). local_coords depend on
   * coordinates, which a lazy step would move: there the kernel writes all
   * of y, the coordinates outside the set unchanged. */
  kn.coords = !k->target->local_coords && k->target->n_labels > 0 && k->target->label_coords
                  ? h2mc__coords_cb
                  : NULL;
  return kn;
}
