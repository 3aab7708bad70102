/*
 * scene_xml_medium.c: Mitsuba 0.6's <medium type="homogeneous"> and its
 * <phase> into the scene (render/media/). The medium reads its own
 * parameters (medium_read); the phase function is found by name among the
 * phase models (phase.h) and reads its own. Other medium types warn and
 * stand for no medium.
 */
#include <stdio.h>
#include <string.h>

#include "render/io/scene_xml_internal.h"
#include "render/media/medium.h"

/* The medium's phase function: its one nested <phase> (or a <ref> to
 * one), isotropic without. */
static lmc_status xml__phase(builder *B, pset *o, phase_fn *OUT) {
  phase_init(OUT, "isotropic");
  pset *found;
  prop *next;
  lmc_status st = xml__nested(B, o, "phase", &found, &next);
  if (st != LMC_OK) return st;
  if (next) {
    lmc_warn(next->file, next->line, "a medium has one phase function: using the first");
    next->used = 1;
  }
  if (!found) return LMC_OK;
  if (!phase_init(OUT, found->type)) {
    lmc_warn(found->file, found->line, "phase function \"%s\" is not supported: using isotropic",
             found->type);
    for (int k = 0; k < found->n_props; k++) found->props[k].used = 1;
    return LMC_OK;
  }
  plugin_props pp = {B, found, NULL, NULL};
  st = OUT->model->read ? OUT->model->read(OUT, &pp) : LMC_OK;
  if (st == LMC_OK) xml__warn_unused(found);
  return st;
}

lmc_status xml__medium(builder *B, pset *o, int *out_index) {
  if (o->built) {
    *out_index = o->index;
    return LMC_OK;
  }
  if (o->building)
    return xml__fail(B, LMC_EPARSE, o->file, o->line,
                     "the medium contains itself (through a <ref>)");
  if (strcmp(o->type, "homogeneous") != 0) {
    lmc_warn(o->file, o->line, "medium type \"%s\" is not supported: ignored", o->type);
    for (int k = 0; k < o->n_props; k++) o->props[k].used = 1;
    o->built = 1;
    o->index = *out_index = -1;
    return LMC_OK;
  }
  medium m;
  plugin_props pp = {B, o, NULL, NULL};
  o->building = 1;
  lmc_status st = medium_read(&m, &pp);
  if (st == LMC_OK) st = xml__phase(B, o, &m.ph);
  o->building = 0;
  if (st != LMC_OK) return st;
  /* Mitsuba's sampling strategy: the balance heuristic (its default) is
   * lmc's; the others are accepted with a warning. */
  const char *strategy;
  prop *sp = xml__find(o, "strategy");
  if ((st = xml__string(B, o, "strategy", "balance", &strategy, NULL)) != LMC_OK) return st;
  if (strcmp(strategy, "balance") != 0)
    lmc_warn(sp->file, sp->line, "medium strategy \"%s\": sampled by the balance heuristic",
             strategy);
  xml__warn_unused(o);
  if (o->id[0]) snprintf(m.id, sizeof m.id, "%.63s", o->id);
  snprintf(m.file, sizeof m.file, "%s", o->file);
  m.line = o->line;
  int idx = scene_add_medium(B->s, &m, B->err);
  if (idx < 0) return (lmc_status)idx;
  o->built = 1;
  o->index = *out_index = idx;
  return LMC_OK;
}
