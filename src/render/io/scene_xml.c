/*
 * scene_xml.c: second pass of the Mitsuba 0.5/0.6 scene loader, property
 * sets to a scene (the first pass, XML to property sets, is
 * scene_xml_parse.c; the sets are described in props.h). Its builder and
 * helpers are in scene_xml_internal.h, the property lookup in
 * scene_xml_props.c, textures and BSDFs in scene_xml_bsdf.c, emitters in
 * scene_xml_emitter.c.
 *
 * scene_load_xml parses the file, registers every object that has an `id`,
 * then walks the children of <scene> in document order:
 *   sensor      perspective pinhole with its film and reconstruction filter;
 *   bsdf        diffuse, phong, conductor, roughconductor, dielectric,
 *               roughdielectric, plastic, twosided, mask, bumpmap
 *               (Mitsuba's names and defaults; see bsdf.h);
 *   texture     bitmap, checkerboard and scale, built when a BSDF refers to
 *               them;
 *   medium      homogeneous with its phase function (scene_xml_medium.c),
 *               in a shape (interior, exterior), the sensor or at the top
 *               level (rendered by pt; the other integrators warn);
 *   shape       obj, ply, serialized, rectangle, cube, sphere, disk,
 *               cylinder, with an optional nested area emitter; without a
 *               BSDF, Mitsuba's default: black when it emits, else diffuse
 *               0.5; a shape that is only a medium boundary (a medium, no
 *               BSDF, no emitter) is Mitsuba's index-matched interface
 *               (mesh.h: bsdf -1), seen only where media are rendered;
 *   emitter     point, spot, directional, constant, envmap; sunsky, sky
 *               and sun, rasterized into an envmap (sunsky.h) as Mitsuba
 *               does (with sunRadiusScale 0 the sun is a directional
 *               light);
 *   integrator  and the <dpt> block of the LMC/H2MC reference scenes, into
 *               scene->settings (Mitsuba's direct with its sample counts
 *               and hideEmitters, passed on to direct's flags);
 * and finally calls scene_finalize, then says (a warning naming the scene)
 * when no emitter gives light: none in the file, every one ignored, or
 * all black.
 *
 * Conventions:
 *   - Relative file names resolve against the folder of the XML file that
 *     names them (an <include>d file has its own folder).
 *   - Every property the builder reads is marked used; what is left unused
 *     on a known plugin, an unknown plugin type and an unsupported element
 *     are warnings (lmc_warn) naming file and line, never silent.
 *   - Fatal errors (wrong property type, missing required property,
 *     dangling ref, missing mesh or image file, ...) return LMC_EPARSE or
 *     LMC_EIO with the XML file and line of the offending element.
 *   - Degenerate input never loads silently: mesh_validate drops zero-area
 *     triangles (warning) and rejects NaN/Inf values and bad indices; a
 *     mesh left empty is skipped with its area emitter (warning); eta = 1
 *     warns; bitmap textures with NaN/Inf texels warn (the render drops
 *     the samples that meet them); envmap texels that are NaN, Inf or
 *     negative are set to 0 with a warning.
 *   - Conductors: cond_eta = eta / extEta and cond_k = k / extEta, where
 *     extEta defaults to 1 (Mitsuba's "air", 1.000277, differs by 0.03%).
 *     Dielectrics and plastic: eta = intIOR / extIOR.
 *   - Texture images live in scene->images, which may move while the scene
 *     grows, so BSDF textures keep an image index while loading and get
 *     their pointers after the last image was added (fix-up list).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/io/scene_xml_internal.h"
#include "render/sampler.h"

/* ---- Shapes. ------------------------------------------------------------ */

/* The mesh of shape o in object space, read from its file or generated;
 * *OUT_label names it when it has no id. Sets *OUT_skip for a type lmc does
 * not have (warned about, its properties marked read). */
static lmc_status xml__shape_mesh(builder *B, pset *o, mesh *m, const char **OUT_label,
                                  int *OUT_skip) {
  lmc_status st;
  const char *t = o->type;
  *OUT_label = t;
  *OUT_skip = 0;
  if (strcmp(t, "obj") == 0 || strcmp(t, "ply") == 0 || strcmp(t, "serialized") == 0) {
    char path[1024];
    prop *fp = NULL;
    if ((st = xml__file(B, o, "filename", "mesh", path, sizeof path, &fp)) != LMC_OK) return st;
    *OUT_label = fp->s;
    if (t[0] == 'o') {
      st = mesh_read_obj(path, m, B->err);
      static const char *const silent[] = {"flipTexCoords", "collapse", NULL};
      xml__accept(o, silent);
    } else if (t[0] == 'p') {
      st = mesh_read_ply(path, m, B->err);
      static const char *const silent[] = {"srgb", NULL};
      xml__accept(o, silent);
    } else {
      long long index;
      if ((st = xml__int(B, o, "shapeIndex", 0, &index, NULL)) != LMC_OK) return st;
      if (index < 0 || index > 1000000000LL)
        return xml__fail(B, LMC_EPARSE, o->file, o->line, "bad shapeIndex %lld", index);
      st = mesh_read_serialized(path, (int)index, m, B->err);
    }
    if (st != LMC_OK) return xml__relabel(B, st, fp, "mesh");
    double angle;
    int has_angle;
    if ((st = xml__float(B, o, "maxSmoothAngle", 0.0, &angle, &has_angle)) != LMC_OK) return st;
    /* Mitsuba's maxSmoothAngle: vertices split where faces meet at a sharper
     * angle, smooth normals made anew (mesh_rebuild_topology). */
    if (has_angle && !(angle >= 0.0 && angle <= 180.0))
      return xml__fail(B, LMC_EPARSE, o->file, o->line, "maxSmoothAngle %g is not in [0, 180]",
                       angle);
    if (has_angle && (st = mesh_rebuild_topology(m, angle, B->err)) != LMC_OK) return st;
    return LMC_OK;
  }
  if (strcmp(t, "rectangle") == 0) return shape_rectangle(m, B->err);
  if (strcmp(t, "cube") == 0) return shape_cube(m, B->err);
  if (strcmp(t, "disk") == 0) return shape_disk(m, B->err);
  if (strcmp(t, "sphere") == 0) {
    vec3 c;
    double r;
    if ((st = xml__vec(B, o, "center", v3(0, 0, 0), &c, NULL)) != LMC_OK) return st;
    if ((st = xml__float(B, o, "radius", 1.0, &r, NULL)) != LMC_OK) return st;
    if (!(r > 0.0)) return xml__fail(B, LMC_EPARSE, o->file, o->line, "sphere radius must be positive");
    return shape_sphere(c, r, m, B->err);
  }
  if (strcmp(t, "cylinder") == 0) {
    vec3 p0, p1;
    double r;
    if ((st = xml__vec(B, o, "p0", v3(0, 0, 0), &p0, NULL)) != LMC_OK) return st;
    if ((st = xml__vec(B, o, "p1", v3(0, 0, 1), &p1, NULL)) != LMC_OK) return st;
    if ((st = xml__float(B, o, "radius", 1.0, &r, NULL)) != LMC_OK) return st;
    if (!(r > 0.0) || v3_len2(v3_sub(p1, p0)) == 0.0)
      return xml__fail(B, LMC_EPARSE, o->file, o->line, "degenerate cylinder");
    return shape_cylinder(p0, p1, r, m, B->err);
  }
  lmc_warn(o->file, o->line, "unsupported shape type \"%s\": ignored", t);
  for (int i = 0; i < o->n_props; i++) {
    o->props[i].used = 1;
    if (o->props[i].kind == PROP_OBJECT && strcmp(o->props[i].obj->tag, "emitter") == 0)
      B->emitters_ignored++;
  }
  *OUT_skip = 1;
  return LMC_OK;
}

/* The shape's BSDF (its first, else Mitsuba's default) into *OUT_bsdf,
 * its area emitter (the first, or NULL) into *OUT_emitter and its media
 * (name="interior", "exterior") into m. A shape that is only a medium
 * boundary (no BSDF, no emitter) is Mitsuba's index-matched interface:
 * *OUT_bsdf -1. *OUT_skip says to leave the shape out. */
static lmc_status xml__shape_children(builder *B, pset *o, mesh *m, int *OUT_bsdf,
                                      pset **OUT_emitter, int *OUT_skip) {
  lmc_status st;
  int bsdf_index = -1;
  pset *emitter = NULL;
  const prop *boundary = NULL;
  *OUT_skip = 0;
  for (int i = 0; i < o->n_props; i++) {
    prop *p = &o->props[i];
    pset *c = NULL;
    if (p->kind == PROP_OBJECT) c = p->obj;
    else if (p->kind == PROP_REF) {
      if ((st = xml__deref(B, p, &c)) != LMC_OK) return st;
    } else {
      continue;
    }
    if (strcmp(c->tag, "bsdf") == 0) {
      p->used = 1;
      if (bsdf_index >= 0) {
        lmc_warn(p->file, p->line, "shape has more than one BSDF: using the first");
        continue;
      }
      if ((st = xml__bsdf(B, c, &bsdf_index)) != LMC_OK) return st;
    } else if (strcmp(c->tag, "emitter") == 0 && p->kind == PROP_OBJECT) {
      p->used = 1;
      if (strcmp(c->type, "area") != 0) {
        lmc_warn(c->file, c->line, "emitter \"%s\" inside a shape is not supported: ignored",
                 c->type);
        for (int k = 0; k < c->n_props; k++) c->props[k].used = 1;
        B->emitters_ignored++;
        continue;
      }
      if (emitter) {
        lmc_warn(c->file, c->line, "shape has more than one area emitter: using the first");
        B->emitters_ignored++;
        continue;
      }
      emitter = c;
    } else if (strcmp(c->tag, "medium") == 0) {
      p->used = 1;
      int mi;
      if ((st = xml__medium(B, c, &mi)) != LMC_OK) return st;
      if (strcmp(p->name, "interior") == 0) m->interior = mi + 1;
      else if (strcmp(p->name, "exterior") == 0) m->exterior = mi + 1;
      else
        return xml__fail(B, LMC_EPARSE, p->file, p->line,
                         "a medium in a shape needs name=\"interior\" or name=\"exterior\"");
      if (!boundary) boundary = p;
    } else if (p->kind == PROP_REF) {
      return xml__fail(B, LMC_EPARSE, p->file, p->line,
                       "<ref id=\"%s\"> inside a shape must name a BSDF or a medium, not a <%s>",
                       p->ref, c->tag);
    }
  }
  if (boundary && bsdf_index < 0 && !emitter) {
    if (!m->interior && !m->exterior) *OUT_skip = 1; /* (media lmc lacks: warned) */
    *OUT_bsdf = -1;
    *OUT_emitter = NULL;
    return LMC_OK;
  }
  if (bsdf_index < 0 && (st = xml__default_bsdf(B, emitter != NULL, &bsdf_index)) != LMC_OK)
    return st;
  *OUT_bsdf = bsdf_index;
  *OUT_emitter = emitter;
  return LMC_OK;
}

/* Places the mesh in the world (toWorld) and reads its flags. */
static lmc_status xml__shape_place(builder *B, pset *o, const char *label, mesh *m) {
  lmc_status st;
  xform to_world;
  if ((st = xml__xform(B, o, "toWorld", &to_world, NULL)) != LMC_OK) return st;
  if (!xform_is_identity(&to_world)) mesh_transform(m, &to_world);
  if ((st = xml__bool(B, o, "flipNormals", 0, &m->flip_normals, NULL)) != LMC_OK) return st;
  /* faceNormals adds to what the shape itself asks (a cube, a serialized
   * mesh with its face-normal flag); it never turns that off. */
  int face_normals = 0;
  if ((st = xml__bool(B, o, "faceNormals", 0, &face_normals, NULL)) != LMC_OK) return st;
  m->face_normals = m->face_normals || face_normals;
  snprintf(m->name, sizeof m->name, "%s", o->id[0] ? o->id : label);
  m->light = -1;
  return mesh_validate(m, o->file, o->line, B->err);
}

/* Adds mesh m (owned from here) and its area emitter of radiance value. */
static lmc_status xml__shape_add(builder *B, mesh *m, pset *emitter, rgb radiance) {
  /* An empty mesh (mesh_validate has warned) is left out, with its emitter:
   * a light of zero area could only produce 0/0 when sampled. */
  if (m->n_triangles == 0) {
    if (emitter) {
      lmc_warn(emitter->file, emitter->line, "area emitter on an empty mesh: ignored");
      B->emitters_ignored++;
    }
    mesh_free(m);
    return LMC_OK;
  }
  int mi = scene_add_mesh(B->s, m, B->err);
  if (mi < 0) {
    mesh_free(m);
    return (lmc_status)mi;
  }
  if (!emitter) return LMC_OK;
  light l;
  memset(&l, 0, sizeof l);
  l.value = radiance;
  l.type = LIGHT_AREA;
  l.mesh = mi;
  l.scale = 1.0;
  l.to_world = xform_identity();
  int li = scene_add_light(B->s, &l, B->err);
  if (li < 0) return (lmc_status)li;
  B->s->meshes[mi].light = li;
  return LMC_OK;
}

static lmc_status xml__shape(builder *B, pset *o) {
  mesh m;
  memset(&m, 0, sizeof m);
  const char *label;
  int skip;
  lmc_status st = xml__shape_mesh(B, o, &m, &label, &skip);
  if (st != LMC_OK || skip) {
    mesh_free(&m);
    return st;
  }
  int bsdf_index = -1;
  pset *emitter = NULL;
  rgb radiance = rgb_gray(1.0);
  if ((st = xml__shape_place(B, o, label, &m)) != LMC_OK) goto fail;
  if ((st = xml__shape_children(B, o, &m, &bsdf_index, &emitter, &skip)) != LMC_OK) goto fail;
  if (skip) {
    for (int i = 0; i < o->n_props; i++) o->props[i].used = 1;
    mesh_free(&m);
    return LMC_OK;
  }
  m.bsdf = bsdf_index;
  if (bsdf_index >= 0 && B->s->bsdfs[bsdf_index].bumped && !m.uv)
    lmc_warn(o->file, o->line,
             "a bump map on a shape without texture coordinates is ignored (as in Mitsuba)");
  if (emitter) {
    int found;
    if ((st = xml__rgb(B, emitter, "radiance", rgb_gray(1.0), &radiance, &found)) != LMC_OK)
      goto fail;
    if (!found) {
      st = xml__missing(B, emitter, "radiance");
      goto fail;
    }
    static const char *const silent[] = {"samplingWeight", NULL};
    xml__accept(emitter, silent);
    xml__warn_unused(emitter);
  }
  xml__warn_unused(o);
  return xml__shape_add(B, &m, emitter, radiance);
fail:
  mesh_free(&m);
  return st;
}

/* ---- Sensor, film, filter. ---------------------------------------------- */

static pset *xml__child(pset *o, const char *tag, int *count) {
  pset *first = NULL;
  *count = 0;
  for (int i = 0; i < o->n_props; i++) {
    prop *p = &o->props[i];
    if (p->kind == PROP_OBJECT && strcmp(p->obj->tag, tag) == 0) {
      p->used = 1;
      if (!first) first = p->obj;
      else lmc_warn(p->obj->file, p->obj->line, "more than one <%s>: using the first", tag);
      (*count)++;
    }
  }
  return first;
}

static lmc_status xml__film(builder *B, pset *f, int *w, int *h) {
  lmc_status st;
  long long lw = 768, lh = 576;
  filter_type ft = FILTER_GAUSSIAN;
  if (f) {
    if (strcmp(f->type, "ldrfilm") == 0) {
      /* Mitsuba's ldrfilm writes one tonemapped 8-bit image; lmc writes
       * what it writes for hdrfilm, and says where its tonemapping differs. */
      double exposure, gamma;
      const char *tm;
      prop *tp;
      if ((st = xml__float(B, f, "exposure", 0.0, &exposure, NULL)) != LMC_OK) return st;
      if ((st = xml__float(B, f, "gamma", -1.0, &gamma, NULL)) != LMC_OK) return st;
      if ((st = xml__string(B, f, "tonemapMethod", "gamma", &tm, &tp)) != LMC_OK) return st;
      char note[160] = "";
      if (strcmp(tm, "gamma") != 0)
        snprintf(note, sizeof note, "; its tonemapMethod \"%s\" is not applied", tm);
      else if (exposure != 0.0 || (gamma != -1.0 && gamma != 2.2))
        snprintf(note, sizeof note,
                 "; its exposure %g and gamma %g are not applied (lmc render --exposure %g "
                 "sets the PNG's exposure)", exposure, gamma, exposure);
      lmc_warn(f->file, f->line,
               "film type \"ldrfilm\": lmc writes OUT.exr (linear radiance) and OUT.png (sRGB, "
               "clamped to [0, 1]) as for hdrfilm%s", note);
    } else if (strcmp(f->type, "hdrfilm") != 0) {
      lmc_warn(f->file, f->line,
               "film type \"%s\": treated as hdrfilm (lmc writes OUT.exr and an sRGB OUT.png)",
               f->type);
    }
    if ((st = xml__int(B, f, "width", 768, &lw, NULL)) != LMC_OK) return st;
    if ((st = xml__int(B, f, "height", 576, &lh, NULL)) != LMC_OK) return st;
    static const char *const silent[] = {
        "banner", "filename", "pixelFormat", "componentFormat", "fileFormat", "attachLog",
        "highQualityEdges", "cropOffsetX", "cropOffsetY", "cropWidth", "cropHeight",
        "gamma", "exposure", "tonemapMethod", "key", "burn", "dithering", NULL};
    xml__accept(f, silent);
    int nr;
    pset *r = xml__child(f, "rfilter", &nr);
    if (r) {
      if (strcmp(r->type, "box") == 0) ft = FILTER_BOX;
      else if (strcmp(r->type, "tent") == 0) ft = FILTER_TENT;
      else if (strcmp(r->type, "gaussian") == 0) {
        double sd;
        int has_sd;
        if ((st = xml__float(B, r, "stddev", 0.5, &sd, &has_sd)) != LMC_OK) return st;
        if (has_sd && sd != 0.5)
          lmc_warn(r->file, r->line, "gaussian stddev %g is not supported: using 0.5", sd);
      } else {
        lmc_warn(r->file, r->line, "unsupported rfilter \"%s\": using gaussian", r->type);
        for (int i = 0; i < r->n_props; i++) r->props[i].used = 1;
      }
      xml__warn_unused(r);
    }
    xml__warn_unused(f);
  }
  if (lw <= 0 || lh <= 0 || lw > 65536 || lh > 65536)
    return xml__fail(B, LMC_EPARSE, f ? f->file : NULL, f ? f->line : 0, "bad film size %lldx%lld",
                     lw, lh);
  filter_init(&B->s->filter, ft);
  *w = (int)lw;
  *h = (int)lh;
  return LMC_OK;
}

/* The medium around the camera: the sensor's <medium> (or <ref> to one). */
static lmc_status xml__sensor_medium(builder *B, pset *o, camera *c) {
  pset *m;
  prop *next;
  lmc_status st = xml__nested(B, o, "medium", &m, &next);
  if (st != LMC_OK || !m) return st;
  int mi;
  if ((st = xml__medium(B, m, &mi)) != LMC_OK) return st;
  c->medium = mi + 1;
  return LMC_OK;
}

static lmc_status xml__sensor(builder *B, pset *o) {
  lmc_status st;
  const char *t = o->type;
  if (B->have_sensor) {
    lmc_warn(o->file, o->line, "more than one sensor: using the first");
    for (int i = 0; i < o->n_props; i++) o->props[i].used = 1;
    return LMC_OK;
  }
  if (strcmp(t, "thinlens") == 0) {
    lmc_warn(o->file, o->line, "thinlens sensor: rendered as a pinhole (no depth of field)");
    static const char *const lens[] = {"apertureRadius", NULL};
    xml__accept(o, lens);
  } else if (strcmp(t, "perspective") != 0) {
    lmc_warn(o->file, o->line, "unsupported sensor type \"%s\": ignored", t);
    for (int i = 0; i < o->n_props; i++) o->props[i].used = 1;
    return LMC_OK;
  }
  camera *c = &B->s->cam;

  /* Film first: the field of view depends on its aspect. */
  int nf, w = 0, h = 0;
  pset *film_set = xml__child(o, "film", &nf);
  if ((st = xml__film(B, film_set, &w, &h)) != LMC_OK) return st;
  int ns;
  pset *sampler = xml__child(o, "sampler", &ns);
  if (sampler) {
    long long spp;
    int found;
    if ((st = xml__int(B, sampler, "sampleCount", 4, &spp, &found)) != LMC_OK) return st;
    if (found && !B->spp_from_dpt && spp > 0) {
      B->s->settings.spp = spp;
      B->s->settings.set |= SET_SPP;
    }
    /* Mitsuba's ldsampler is padded (0,2)-sequences, as our sobol; its other
     * stratifying samplers are rendered with ours. Under --sampler the
     * command line decides. */
    const char *kind = sampler->type[0] ? sampler->type : "independent";
    if (strcmp(kind, "independent") == 0) {
      B->s->settings.sampler = LMC_SAMPLER_INDEPENDENT;
    } else if (strcmp(kind, "ldsampler") == 0 || strcmp(kind, "sobol") == 0) {
      B->s->settings.sampler = LMC_SAMPLER_SOBOL;
    } else if (strcmp(kind, "stratified") == 0 || strcmp(kind, "halton") == 0 ||
               strcmp(kind, "hammersley") == 0) {
      lmc_warn(sampler->file, sampler->line,
               "sampler \"%s\": rendered with lmc's scrambled Sobol sampler", kind);
      B->s->settings.sampler = LMC_SAMPLER_SOBOL;
    } else {
      lmc_warn(sampler->file, sampler->line,
               "unsupported sampler type \"%s\": using the independent sampler", kind);
    }
    static const char *const silent[] = {"scramble", "dimension", NULL};
    xml__accept(sampler, silent);
    xml__warn_unused(sampler);
  }

  /* Projection: fov, or a 35 mm equivalent focal length on the diagonal. */
  double fov;
  int has_fov;
  const char *axis;
  prop *fov_prop = NULL;
  if ((st = xml__float(B, o, "fov", 0.0, &fov, &has_fov)) != LMC_OK) return st;
  if (has_fov) {
    for (int i = 0; i < o->n_props; i++)
      if (strcmp(o->props[i].name, "fov") == 0) fov_prop = &o->props[i];
    if ((st = xml__string(B, o, "fovAxis", "x", &axis, NULL)) != LMC_OK) return st;
  } else {
    const char *fl;
    prop *flp;
    if ((st = xml__string(B, o, "focalLength", "50mm", &fl, &flp)) != LMC_OK) return st;
    double mm = atof(fl);
    if (!(mm > 0.0))
      return xml__fail(B, LMC_EPARSE, flp ? flp->file : o->file, flp ? flp->line : o->line,
                       "bad focalLength '%s'", fl);
    /* fov = 2 atan(d / (2 f)) with the 36 x 24 mm frame's diagonal d. */
    fov = 2.0 * atan(sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2.0 * mm)) * 180.0 / XML_PI;
    axis = "diagonal";
    static const char *const fa[] = {"fovAxis", NULL};
    xml__accept(o, fa);
  }
  if (strcmp(axis, "x") != 0 && strcmp(axis, "y") != 0 && strcmp(axis, "diagonal") != 0 &&
      strcmp(axis, "smaller") != 0 && strcmp(axis, "larger") != 0)
    return xml__fail(B, LMC_EPARSE, o->file, o->line, "bad fovAxis '%s'", axis);
  c->width = w;
  c->height = h;
  if (!camera_set_fov(c, fov, axis, w, h))
    return xml__fail(B, LMC_EPARSE, fov_prop ? fov_prop->file : o->file,
                     fov_prop ? fov_prop->line : o->line, "fov %g is outside (0, 180)", fov);

  /* Pose and clipping. */
  xform tw;
  if ((st = xml__xform(B, o, "toWorld", &tw, NULL)) != LMC_OK) return st;
  double dx = v3_len(xform_vector(&tw, v3(1, 0, 0))), dy = v3_len(xform_vector(&tw, v3(0, 1, 0))),
         dz = v3_len(xform_vector(&tw, v3(0, 0, 1)));
  if (fabs(dx - 1.0) > 1e-6 || fabs(dy - 1.0) > 1e-6 || fabs(dz - 1.0) > 1e-6)
    lmc_warn(o->file, o->line, "the sensor's toWorld scales (%g, %g, %g): scale ignored", dx, dy,
             dz);
  if (!(dx > 0.0 && dy > 0.0 && dz > 0.0))
    return xml__fail(B, LMC_EPARSE, o->file, o->line, "singular sensor toWorld");
  if (fabs(dx - 1.0) > 1e-6 || fabs(dy - 1.0) > 1e-6 || fabs(dz - 1.0) > 1e-6) {
    /* Rebuild with unit axes (keeps a mirroring sign). */
    double v[16];
    double len[3] = {dx, dy, dz};
    for (int i = 0; i < 4; i++)
      for (int j = 0; j < 4; j++) v[4 * i + j] = tw.m[i][j] / (j < 3 && i < 3 ? len[j] : 1.0);
    if (!xform_from_matrix(v, &tw))
      return xml__fail(B, LMC_EPARSE, o->file, o->line, "singular sensor toWorld");
  }
  c->to_world = tw;
  c->pos = xform_point(&tw, v3(0, 0, 0));
  c->forward = v3_normalize(xform_vector(&tw, v3(0, 0, 1)));
  if ((st = xml__float(B, o, "nearClip", 1e-2, &c->near_clip, NULL)) != LMC_OK) return st;
  if ((st = xml__float(B, o, "farClip", 1e4, &c->far_clip, NULL)) != LMC_OK) return st;
  if (!(c->near_clip > 0.0 && c->far_clip > c->near_clip))
    return xml__fail(B, LMC_EPARSE, o->file, o->line, "bad clip range [%g, %g]", c->near_clip,
                     c->far_clip);
  static const char *const silent[] = {"focusDistance", "shutterOpen", "shutterClose", NULL};
  xml__accept(o, silent);
  if ((st = xml__sensor_medium(B, o, c)) != LMC_OK) return st;
  xml__warn_unused(o);
  B->have_sensor = 1;
  return LMC_OK;
}

/* ---- The scene. --------------------------------------------------------- */

/* An image that cannot be right says so before it is rendered: a scene
 * left without an emitter that gives light (none in the file, all of them
 * ignored, or all black) renders black in every integrator. */
static void xml__check_light(builder *B, const pset *root) {
  const scene *s = B->s;
  for (int i = 0; i < s->n_lights; i++)
    if (light_power(&s->lights[i], s) > 0.0) return; /* one that gives light is enough */
  if (B->emitters_ignored > 0)
    lmc_warn(root->file, 0,
             "no emitter left: the scene's %d emitter%s ignored (see above); the image will be "
             "black", B->emitters_ignored, B->emitters_ignored == 1 ? " was" : "s were all");
  else if (s->n_lights > 0)
    lmc_warn(root->file, 0, "every emitter of the scene is black: the image will be black");
  else
    lmc_warn(root->file, 0, "the scene has no emitter: the image will be black");
}

/* A top-level <medium>: built (its parameters checked), for the shapes and
 * the sensor that refer to it. */
static lmc_status xml__top_medium(builder *B, pset *o) {
  int mi;
  return xml__medium(B, o, &mi);
}

static lmc_status xml__build(builder *B, pset *root) {
  lmc_status st;
  if ((st = xml__register_ids(B, root)) != LMC_OK) return st;
  for (int i = 0; i < root->n_props; i++) {
    prop *p = &root->props[i];
    p->used = 1;
    if (p->kind != PROP_OBJECT) {
      if (p->kind == PROP_REF)
        lmc_warn(p->file, p->line, "<ref id=\"%s\"> at the top level: ignored", p->ref);
      else
        lmc_warn(p->file, p->line, "property '%s' (<%s>) at the top level: ignored", p->name,
                 p->tag);
      continue;
    }
    pset *o = p->obj;
    const char *tag = o->tag;
    int dummy;
    if (strcmp(tag, "sensor") == 0) st = xml__sensor(B, o);
    else if (strcmp(tag, "bsdf") == 0) st = xml__bsdf(B, o, &dummy);
    else if (strcmp(tag, "texture") == 0) st = LMC_OK; /* built when referenced */
    else if (strcmp(tag, "medium") == 0) st = xml__top_medium(B, o);
    else if (strcmp(tag, "shape") == 0) st = xml__shape(B, o);
    else if (strcmp(tag, "emitter") == 0) st = xml__emitter(B, o);
    else if (strcmp(tag, "integrator") == 0) st = xml__integrator(B, o, 0);
    else if (strcmp(tag, "dpt") == 0) st = xml__dpt(B, o);
    else lmc_warn(o->file, o->line, "unsupported element <%s>: ignored", tag);
    if (st != LMC_OK) return st;
  }
  if (!B->have_sensor)
    return xml__fail(B, LMC_EPARSE, root->file, root->line,
                     "the scene has no (supported) sensor");

  /* All images are in: point bitmap textures at them. */
  for (int i = 0; i < B->n_fix; i++) {
    const tex_fixup *f = &B->fix[i];
    bsdf *b = &B->s->bsdfs[f->bsdf];
    texture *t = xml__tex_slot(b, f->which);
    t->image = &B->s->images[f->image];
    tex_update_mean(t); /* BSDFs choose lobes by the mean; cache it once */
  }
  if ((st = scene_finalize(B->s, B->err)) != LMC_OK) return st;
  xml__check_light(B, root);
  return LMC_OK;
}

lmc_status scene_load_xml(const char *path, const char *const *defines, int n_defines,
                          scene **OUT_scene, lmc_error *err) {
  return scene_load_xml_opts(path, defines, n_defines, NULL, OUT_scene, err);
}

lmc_status scene_load_xml_opts(const char *path, const char *const *defines, int n_defines,
                               const scene_load_options *opts, scene **OUT_scene,
                               lmc_error *err) {
  *OUT_scene = NULL;
  pdoc doc;
  spectrum_interp interp = opts ? opts->spectra : SPECTRUM_INTERP_LINEAR;
  lmc_status st = pdoc_parse(&doc, path, defines, n_defines, interp, err);
  if (st != LMC_OK) return st;
  scene *s = NULL;
  st = scene_create(&s, err);
  if (st != LMC_OK) {
    pdoc_free(&doc);
    return st;
  }
  snprintf(s->path, sizeof s->path, "%s", path);
  builder B;
  memset(&B, 0, sizeof B);
  B.s = s;
  B.err = err;
  B.doc = &doc;
  B.spectra = interp;
  B.default_bsdf[0] = B.default_bsdf[1] = -1;
  st = xml__build(&B, doc.root);
  free(B.ids);
  free(B.fix);
  pdoc_free(&doc);
  if (st != LMC_OK) {
    scene_destroy(s);
    return st;
  }
  *OUT_scene = s;
  return LMC_OK;
}
