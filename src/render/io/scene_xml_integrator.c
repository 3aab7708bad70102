/*
 * scene_xml_integrator.c: the scene loader's integrators (Mitsuba's
 * <integrator> and the LMC reference implementation's <dpt> block), for
 * scene_xml_internal.h: each sets the defaults that flags override (the
 * integrator, depths, and parameters passed on to the option tables by
 * their flag names).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/io/scene_xml_internal.h"

/* ---- Integrators. ------------------------------------------------------- */

static void xml__set_integrator(render_settings *r, const char *name) {
  snprintf(r->integrator, sizeof r->integrator, "%.*s", (int)sizeof r->integrator - 1, name);
  r->set |= SET_INTEGRATOR;
}

/* Reads maxDepth / rrDepth of an integrator unless already set by an outer
 * one. */
static lmc_status xml__depths(builder *B, pset *o) {
  render_settings *r = &B->s->settings;
  lmc_status st;
  long long v;
  int found;
  if ((st = xml__int(B, o, "maxDepth", -1, &v, &found)) != LMC_OK) return st;
  if (found && !(r->set & SET_MAXDEPTH)) {
    r->maxdepth = (int)v;
    r->set |= SET_MAXDEPTH;
  }
  if ((st = xml__int(B, o, "rrDepth", 5, &v, &found)) != LMC_OK) return st;
  if (found && !(r->set & SET_RRDEPTH)) {
    r->rrdepth = (int)v;
    r->set |= SET_RRDEPTH;
  }
  return LMC_OK;
}

/* Mitsuba's direct integrator's sample counts and hideEmitters, passed
 * on to direct's flags (render/integrators/integrator_direct.c):
 * emitterSamples and bsdfSamples (each by default shadingSamples, itself
 * by default 1), neither negative and not both 0. */
static lmc_status xml__direct(builder *B, pset *o) {
  static const char *const names[3] = {"shadingSamples", "emitterSamples", "bsdfSamples"};
  static const char *const flags[3] = {NULL, "emitter-samples", "bsdf-samples"};
  long long n[3];
  int found[3];
  lmc_status st;
  for (int i = 0; i < 3; i++) {
    if ((st = xml__int(B, o, names[i], i ? n[0] : 1, &n[i], &found[i])) != LMC_OK) return st;
    if (n[i] < 0) {
      prop *p = xml__find(o, names[i]);
      return xml__fail(B, LMC_EPARSE, p->file, p->line,
                       "integrator \"direct\": %s %lld is negative", names[i], n[i]);
    }
  }
  if (n[1] == 0 && n[2] == 0)
    return xml__fail(B, LMC_EPARSE, o->file, o->line,
                     "integrator \"direct\": emitterSamples and bsdfSamples are both 0 (no "
                     "strategy left to sample the light)");
  /* Each count given (or set through shadingSamples), at its place. */
  for (int i = 1; i < 3; i++) {
    if (!found[i] && !found[0]) continue;
    char v[32];
    snprintf(v, sizeof v, "%lld", n[i]);
    if ((st = xml__pass(B, xml__find(o, found[i] ? names[i] : names[0]), flags[i], v)) != LMC_OK)
      return st;
  }
  int hide, found_hide;
  if ((st = xml__bool(B, o, "hideEmitters", 0, &hide, &found_hide)) != LMC_OK) return st;
  if (found_hide &&
      (st = xml__pass(B, xml__find(o, "hideEmitters"), "hide-emitters", hide ? "on" : "off")))
    return st;
  return LMC_OK;
}

lmc_status xml__integrator(builder *B, pset *o, int nested) {
  render_settings *r = &B->s->settings;
  lmc_status st;
  const char *t = o->type;
  int choose = !nested || !(r->set & SET_INTEGRATOR);
  static const char *const silent[] = {"strictNormals", "hideEmitters", "twoStage",
                                       "directSamples", "luminanceSamples", "separateDirect",
                                       "lightImage", "sampleDirect", "granularity", NULL};
  if (strcmp(t, "path") == 0 || strcmp(t, "volpath") == 0 || strcmp(t, "volpath_simple") == 0) {
    /* (volpath: lmc's pt renders media; so does it for Mitsuba's path,
     * which would cross them unattenuated: docs/mitsuba-scenes.md) */
    if (choose) xml__set_integrator(r, "pt");
  } else if (strcmp(t, "bdpt") == 0) {
    if (choose) xml__set_integrator(r, "bdpt");
  } else if (strcmp(t, "pssmlt") == 0 || strcmp(t, "mlt") == 0 || strcmp(t, "erpt") == 0) {
    if (t[0] == 'e') lmc_warn(o->file, o->line, "integrator \"erpt\" maps to pssmlt");
    if (choose) xml__set_integrator(r, t[0] == 'm' ? "mlt" : "pssmlt");
    int found;
    /* Direct light: Mitsuba's directSamples (default 16, pt's samples per
     * pixel for paths of <= 2 segments; -1: MLT renders them too) and
     * separateDirect. Our default is separate as well. */
    long long ds;
    int sep, found_sep;
    if ((st = xml__int(B, o, "directSamples", 16, &ds, &found)) != LMC_OK) return st;
    if (found) {
      prop *p = xml__find(o, "directSamples");
      char n[32];
      snprintf(n, sizeof n, "%lld", ds > 0 ? ds : 0);
      if ((st = xml__pass(B, p, "direct", ds >= 0 ? "separate" : "mcmc")) != LMC_OK) return st;
      if (ds >= 0 && (st = xml__pass(B, p, "direct-spp", n)) != LMC_OK) return st;
      if (ds == 0)
        lmc_warn(p->file, p->line,
                 "directSamples 0 (direct light hidden) is not supported: direct light is "
                 "rendered separately with the scene's samples per pixel");
    }
    if ((st = xml__bool(B, o, "separateDirect", 1, &sep, &found_sep)) != LMC_OK) return st;
    if (found_sep && !(found && ds < 0) &&
        (st = xml__pass(B, xml__find(o, "separateDirect"), "direct", sep ? "separate" : "mcmc")))
      return st;
    /* Mitsuba's bidirectional (default true): pssmlt on a BDPT sample, our
     * bdpt states; false: on a path tracer's samples. */
    int bidir, found_bidir;
    if ((st = xml__bool(B, o, "bidirectional", 1, &bidir, &found_bidir)) != LMC_OK) return st;
    if (found_bidir && !bidir && (st = xml__pass(B, xml__find(o, "bidirectional"), "states", "pt")))
      return st;
    /* Path-space MLT's mutation flags (bidirectionalMutation,
     * lensPerturbation, ...) pass on to mlt's own flags; pssmlt has none. */
    static const char *const mlt_silent[] = {"lambda", "chainLength", "numChains", "maxChains",
                                             NULL};
    static const char *const pss_silent[] = {"bidirectionalMutation", "lensPerturbation",
                                             "multiChainPerturbation", "causticPerturbation",
                                             "manifoldPerturbation", NULL};
    xml__accept(o, mlt_silent);
    if (t[0] != 'm') xml__accept(o, pss_silent);
  } else if (strcmp(t, "direct") == 0) {
    if (choose) xml__set_integrator(r, "direct");
    if ((st = xml__direct(B, o)) != LMC_OK) return st;
  } else if (strcmp(t, "mmlt") == 0 || strcmp(t, "lmc") == 0 || strcmp(t, "h2mc") == 0) {
    /* lmc's own MCMC integrators; their parameters are their flags. */
    if (choose) xml__set_integrator(r, t);
  } else {
    int has_inner = 0;
    for (int i = 0; i < o->n_props; i++)
      if (o->props[i].kind == PROP_OBJECT && strcmp(o->props[i].obj->tag, "integrator") == 0)
        has_inner = 1;
    if (has_inner)
      lmc_warn(o->file, o->line, "integrator \"%s\" is not supported: using the nested one", t);
    else
      lmc_warn(o->file, o->line, "integrator \"%s\" is not supported: ignored", t);
    for (int i = 0; i < o->n_props; i++)
      if (o->props[i].kind != PROP_OBJECT) o->props[i].used = 1;
  }
  if ((st = xml__depths(B, o)) != LMC_OK) return st;
  xml__accept(o, silent);
  /* Nested integrators (pssmlt wrapping a path tracer, adaptive, ...). */
  for (int i = 0; i < o->n_props; i++) {
    prop *p = &o->props[i];
    if (p->kind == PROP_OBJECT && strcmp(p->obj->tag, "integrator") == 0) {
      p->used = 1;
      if ((st = xml__integrator(B, p->obj, 1)) != LMC_OK) return st;
    }
  }
  if ((st = xml__keep_params(B, o)) != LMC_OK) return st;
  xml__warn_unused(o);
  return LMC_OK;
}

/* The <dpt> block of the LMC / H2MC reference scenes (Li et al.'s dpt). */
lmc_status xml__dpt(builder *B, pset *o) {
  render_settings *r = &B->s->settings;
  lmc_status st;
  const char *integ;
  prop *ip;
  int bidir, mala, h2mc, found;
  long long v;
  if ((st = xml__string(B, o, "integrator", "mcmc", &integ, &ip)) != LMC_OK) return st;
  if ((st = xml__bool(B, o, "bidirectional", 1, &bidir, NULL)) != LMC_OK) return st;
  if ((st = xml__bool(B, o, "mala", 0, &mala, NULL)) != LMC_OK) return st;
  if ((st = xml__bool(B, o, "h2mc", 0, &h2mc, NULL)) != LMC_OK) return st;
  if (strcmp(integ, "mcmc") == 0) {
    /* dpt's chains live in the bdpt states (bidirectional, the default) or
     * on a path tracer's samples. */
    if (!bidir && (st = xml__pass(B, xml__find(o, "bidirectional"), "states", "pt"))) return st;
    if (mala) {
      xml__set_integrator(r, "lmc");
    } else if (h2mc) {
      xml__set_integrator(r, "h2mc");
    } else {
      xml__set_integrator(r, "pssmlt");
    }
  } else if (strcmp(integ, "pt") == 0 || strcmp(integ, "mc") == 0) {
    xml__set_integrator(r, bidir && integ[1] == 'c' ? "bdpt" : "pt");
  } else if (strcmp(integ, "bdpt") == 0) {
    xml__set_integrator(r, "bdpt");
  } else {
    lmc_warn(ip ? ip->file : o->file, ip ? ip->line : o->line,
             "<dpt> integrator \"%s\" is not supported: ignored", integ);
  }
  if ((st = xml__int(B, o, "mindepth", -1, &v, &found)) != LMC_OK) return st;
  if (found) {
    r->mindepth = (int)v;
    r->set |= SET_MINDEPTH;
  }
  if ((st = xml__int(B, o, "maxdepth", -1, &v, &found)) != LMC_OK) return st;
  if (found) {
    r->maxdepth = (int)v;
    r->set |= SET_MAXDEPTH;
  }
  if ((st = xml__int(B, o, "spp", 16, &v, &found)) != LMC_OK) return st;
  if (found) {
    if (v <= 0) return xml__fail(B, LMC_EPARSE, o->file, o->line, "spp must be positive");
    r->spp = v;
    r->set |= SET_SPP;
    B->spp_from_dpt = 1;
  }
  /* largestepprob, numinitsamples, largestepscale, roughnessthreshold,
   * numchains and every flag's own name pass on to the option tables
   * (scene.params). */
  if ((st = xml__int(B, o, "directspp", 256, &v, &found)) != LMC_OK) return st;
  if (found) {
    if (v < 0) return xml__fail(B, LMC_EPARSE, o->file, o->line, "directspp must be >= 0");
    prop *p = xml__find(o, "directspp");
    char n[32];
    snprintf(n, sizeof n, "%lld", v);
    if ((st = xml__pass(B, p, "direct", v > 0 ? "separate" : "mcmc")) != LMC_OK) return st;
    if (v > 0 && (st = xml__pass(B, p, "direct-spp", n)) != LMC_OK) return st;
  }
  if ((st = xml__keep_params(B, o)) != LMC_OK) return st;
  xml__warn_unused(o);
  return LMC_OK;
}

