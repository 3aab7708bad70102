/*
 * path_lights.c: the emitters for the path evaluators (path_internal.h):
 * light_ad.h's dual sampling routines and densities (one source with the
 * plain ones of light.h, light_generic.h), the discrete choices they make
 * noted in the dual path's topology, and the flags the evaluators record.
 */
#include "render/integrators/path_internal.h"
#include "render/lights/light_ad.h"

void path__light_topo(path__ctx *c, int64_t tri, const int64_t cell[2]) {
  if (tri >= 0) path__topo(c, tri);
  if (cell[0] >= 0) {
    path__topo(c, cell[0]);
    path__topo(c, cell[1]);
  }
}

ad path__pdf_li(path__ctx *c, const light *l, adv3 ref, adv3 w, adv3 p, vec3 n) {
  return light_pdf_li_ad(c->A, l, c->sc, ref, w, p, n);
}

int path__sample_li(path__ctx *c, const light *l, adv3 ref, ad u1, ad u2, path__li *out) {
  int ok = light_sample_li_ad(c->A, l, c->sc, ref, u1, u2, out);
  path__light_topo(c, out->tri, out->cell);
  return ok;
}

unsigned path__emit_flag(const light *l) {
  switch (l->type) {
  case LIGHT_AREA:
    return PATH_EMIT_AREA;
  case LIGHT_CONSTANT:
    return PATH_EMIT_INFINITE;
  case LIGHT_ENVMAP:
    return PATH_EMIT_INFINITE | PATH_EMIT_ENVMAP;
  default:
    return PATH_EMIT_DELTA;
  }
}

unsigned path__lobe_flag(int bsdf_flags) {
  unsigned f = 0;
  if (bsdf_flags & BSDF_DIFFUSE_LOBE) f |= PATH_LOBE_DIFFUSE;
  if (bsdf_flags & BSDF_GLOSSY) f |= PATH_LOBE_GLOSSY;
  if (bsdf_flags & BSDF_DELTA) f |= PATH_LOBE_DELTA;
  if (bsdf_flags & BSDF_TRANSMISSION) f |= PATH_LOBE_TRANSMISSION;
  return f;
}
