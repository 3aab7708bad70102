/*
 * mcmc_report.c: the MCMC driver's statistics lines (stderr, rank 0, at
 * the end of a render that is not --quiet): per kernel its proposals,
 * acceptance and the inverse path sampler's tally; the rays a mutation
 * traced per kernel and, on a labelled space, the chains' time at each
 * path length; per family of a per-length space its b and acceptance;
 * the mutations per second and b; then the integrator's own lines and
 * the space's moves'. The counters are every rank's (mcmc_dist.c shares
 * them first).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lmc/driver/mcmc_internal.h"
#include "render/dist.h"

/* The rays a mutation traced, per kernel (the large step's with the share
 * of its roulette's F(u)); on a labelled space whose families say their
 * labels' lengths, the chains' time at each path length and the rays a
 * step of a kernel other than the large step traced from there. */
static void mcmc__report_rays(const mcmc_render *R, const mc_kernel_stats *tot,
                              const char *const *names, int nk) {
  int64_t rays = 0, steps = 0, sum_rays = 0, sum_evals = 0;
  for (int q = 0; q < nk; q++) rays += tot[q].rays, steps += tot[q].proposed;
  if (steps == 0 || rays == 0) return;
  char line[512];
  int o = snprintf(line, sizeof line, "lmc: rays       %.3g per mutation:", (double)rays / (double)steps);
  for (int q = 0; q < nk && o < (int)sizeof line; q++)
    o += snprintf(line + o, sizeof line - (size_t)o, "%s %s %.3g", q ? "," : "", names[q],
                  (double)tot[q].rays / fmax(1.0, (double)tot[q].proposed));
  for (int i = 0; i < R->n_slots; i++)
    sum_rays += R->slots[i].chain->sum_rays, sum_evals += R->slots[i].chain->sum_evals;
  if (sum_evals > 0 && o < (int)sizeof line)
    snprintf(line + o, sizeof line - (size_t)o, " (%lld roulette F(u) evaluations, %.3g rays each)",
             (long long)sum_evals, (double)sum_rays / (double)sum_evals);
  fprintf(stderr, "%s\n", line);

  /* The labels' tallies by path length (MCMC_MAX_DEPTH bounds a length). */
  enum { LEN_MAX = 64 };
  int64_t at[LEN_MAX][3];
  memset(at, 0, sizeof at);
  int64_t total = 0;
  for (int i = 0; i < R->n_slots; i++) {
    const mc_chain *c = R->slots[i].chain;
    const mcmc_family *F = &R->fam[R->slots[i].family];
    if (!c->lab || !F->sf->length_of) continue;
    for (int l = 0; l < c->target->n_labels; l++) {
      int len = F->sf->length_of(F->sf, l, -1);
      if (len < 0 || len >= LEN_MAX) continue;
      for (int k = 0; k < 3; k++) at[len][k] += c->lab[3 * l + k];
      total += c->lab[3 * l];
    }
  }
  if (total == 0) return;
  o = snprintf(line, sizeof line, "lmc: states     by length (share of steps, rays a step but the large):");
  for (int len = 0; len < LEN_MAX && o < (int)sizeof line; len++)
    if (at[len][0] > 0)
      o += snprintf(line + o, sizeof line - (size_t)o, " %d %.1f%% %.3g", len,
                    100.0 * (double)at[len][0] / (double)total,
                    (double)at[len][2] / fmax(1.0, (double)at[len][1]));
  fprintf(stderr, "%s\n", line);
}

/* Statistics (stderr): per kernel, per family of a per-length space,
 * mutations per second, b; then the integrator's. */
void mcmc__report(mcmc_render *R, const mc_counts *counts) {
  const char *names[MC_MAX_KERNELS] = {0};
  mc_kernel_stats tot[MC_MAX_KERNELS];
  memset(tot, 0, sizeof tot);
  int nk = 0;
  int64_t overflow = 0;
  for (int i = 0; i < R->n_slots; i++) {
    mc_chain *c = R->slots[i].chain;
    overflow += c->overflow;
    for (int q = 0; q < c->n_kernels; q++) {
      if (q >= nk) names[nk++] = c->kernels[q].name;
      tot[q].proposed += c->stats[q].proposed;
      tot[q].accepted += c->stats[q].accepted;
      tot[q].inverted += c->stats[q].inverted;
      tot[q].refused += c->stats[q].refused, tot[q].elsewhere += c->stats[q].elsewhere;
      tot[q].walks += c->stats[q].walks, tot[q].walked += c->stats[q].walked;
      tot[q].irreversible += c->stats[q].irreversible;
      tot[q].rays += c->stats[q].rays;
    }
  }
  for (int q = 0; q < nk; q++) {
    double pr = fmax(1.0, (double)tot[q].proposed);
    fprintf(stderr, "lmc: %-10s proposed %lld, accepted %lld (%.1f%%)\n", names[q],
            (long long)tot[q].proposed, (long long)tot[q].accepted,
            100.0 * (double)tot[q].accepted / pr);
    if (tot[q].inverted > 0)
      fprintf(stderr,
              "lmc: %-10s %lld subpaths inverted (%.4g/s), %.3f%% refused (a path its walks "
              "cannot reach), %.3f%% walked elsewhere\n",
              names[q], (long long)tot[q].inverted,
              (double)tot[q].inverted / fmax(1e-9, R->chain_seconds),
              100.0 * (double)tot[q].refused / pr, 100.0 * (double)tot[q].elsewhere / pr);
    if (tot[q].walks > 0)
      fprintf(stderr,
              "lmc: %-10s %lld manifold walks (%.4g/s), %.1f%% reached their target; %.3f%% of "
              "proposals refused (the reverse walk did not return)\n",
              names[q], (long long)tot[q].walks,
              (double)tot[q].walks / fmax(1e-9, R->chain_seconds),
              100.0 * (double)tot[q].walked / (double)tot[q].walks,
              100.0 * (double)tot[q].irreversible / pr);
  }
  mcmc__report_rays(R, tot, names, nk);
  for (int g = 0; g < R->n_fam; g++) {
    const mcmc_family *F = &R->fam[g];
    if (F->sf->length <= 0) continue;
    int64_t pr = 0, ac = 0;
    for (int i = 0; i < F->n_chains; i++) {
      const mc_chain *c = R->slots[F->first_chain + i].chain;
      for (int q = 0; q < c->n_kernels; q++) pr += c->stats[q].proposed, ac += c->stats[q].accepted;
    }
    fprintf(stderr,
            "lmc: length %-3d b %.5g (%.1f%%, %lld paths), %d chains, proposed %lld, accepted %.1f%%\n",
            F->sf->length, F->b_ref, 100.0 * sqrt(F->b_ref_var) / fmax(F->b_ref, 1e-300),
            (long long)(F->bt.n_est + F->n_large), F->n_chains, (long long)pr,
            100.0 * (double)ac / fmax(1.0, (double)pr));
  }
  int64_t n_boot = 0, n_plan = 0;
  for (int g = 0; g < R->n_fam; g++) {
    n_boot += R->fam[g].bt.n_est;
    n_plan += R->fam[g].bt.n - R->fam[g].bt.n_est;
  }
  char note[96] = "";
  if (R->sp.estimate_b) {
    /* b from the space's estimator; the families' own samples picked the starts */
    n_boot = R->shared_paths;
    n_plan = 0;
    for (int g = 0; g < R->n_fam; g++) n_plan += R->fam[g].bt.n;
    snprintf(note, sizeof note, " (%s)", R->sp.b_note ? R->sp.b_note : "the states' own");
  }
  fprintf(stderr,
          "lmc: %d chains, %.4g mutations/s; b = %.6g +- %.2g (%.2f%%, %lld bootstrap paths%s; "
          "%lld more for planning and starting states)\n",
          R->n_slots, (double)R->st->samples / fmax(R->chain_seconds, 1e-9), R->b_total,
          sqrt(R->b_var), 100.0 * sqrt(R->b_var) / fmax(R->b_total, 1e-300), (long long)n_boot,
          note, (long long)n_plan);
  double b_ref = 0.0, b_ref_var = 0.0;
  int64_t n_large = 0;
  for (int g = 0; g < R->n_fam; g++)
    b_ref += R->fam[g].b_ref, b_ref_var += R->fam[g].b_ref_var, n_large += R->fam[g].n_large;
  if (R->norm != MCMC_NORM_BOOT && n_large > 0)
    fprintf(stderr, "lmc: b with large steps = %.6g +- %.2g (%.2f%%, %lld large steps more)\n",
            b_ref, sqrt(b_ref_var), 100.0 * sqrt(b_ref_var) / fmax(b_ref, 1e-300),
            (long long)n_large);
  if (R->n_snapshots > 0)
    fprintf(stderr, "lmc: %d snapshots, %.3g ms each to gather (b, counters, splats%s)\n",
            R->n_snapshots, 1e3 * R->snapshot_seconds / R->n_snapshots,
            dist_active() ? " of every rank" : "");
  if (overflow > 0)
    fprintf(stderr, "lmc: %lld coordinates drawn past the state's blocks\n", (long long)overflow);
  if (R->M->report || R->moves) {
    mc_chain **chains = malloc((size_t)R->n_slots * sizeof *chains);
    if (chains) {
      for (int i = 0; i < R->n_slots; i++) chains[i] = R->slots[i].chain;
      if (R->M->report) R->M->report(R->mrun, chains, R->n_slots, R->chain_seconds, counts);
      if (R->moves) R->sp.moves->report(R->moves, chains, R->n_slots, R->chain_seconds);
      free(chains);
    }
  }
}

