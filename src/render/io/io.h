/*
 * io.h: the scene loader and the mesh readers.
 *
 * scene_load_xml parses the Mitsuba 0.5/0.6 XML subset (see README.md) into
 * property sets, then builds the scene from them: plugins never see XML.
 * Every error carries the file and line of the element that caused it.
 * Mesh readers produce meshes in their own object space; the loader applies
 * toWorld.
 */
#ifndef LMC_RENDER_IO_H
#define LMC_RENDER_IO_H

#include "render/error.h"
#include "render/mesh.h"
#include "render/scene.h"
#include "render/spectrum.h"

/* `defines` holds n_defines strings "name=value" that override the scene's
 * <default> elements (the -D flag). The result is finalized. */
lmc_status scene_load_xml(const char *path, const char *const *defines, int n_defines,
                          scene **OUT_scene, lmc_error *err);

/* How a scene is read, beyond its file (the command line's loader flags). */
typedef struct scene_load_options {
  spectrum_interp spectra; /* --spectra: how sampled spectra are read (spectrum.h) */
} scene_load_options;

/* scene_load_xml with options (NULL: the defaults, all zero). */
lmc_status scene_load_xml_opts(const char *path, const char *const *defines, int n_defines,
                               const scene_load_options *opts, scene **OUT_scene,
                               lmc_error *err);

lmc_status mesh_read_obj(const char *path, mesh *OUT_mesh, lmc_error *err);
/* ASCII and binary (little and big endian) PLY. */
lmc_status mesh_read_ply(const char *path, mesh *OUT_mesh, lmc_error *err);
/* Mitsuba's serialized format (versions 3 and 4), shape number shape_index. */
lmc_status mesh_read_serialized(const char *path, int shape_index, mesh *OUT_mesh, lmc_error *err);

/* Mitsuba's built-in shapes, in their object space, as triangle meshes:
 *  rectangle  [-1,1]^2 in the z=0 plane, normal +z
 *  cube       [-1,1]^3, outward normals
 *  sphere     center, radius (tessellated finely; smooth vertex normals)
 *  disk       unit disk in z=0, normal +z
 *  cylinder   from p0 to p1 with radius, open ends, outward normals */
lmc_status shape_rectangle(mesh *OUT_mesh, lmc_error *err);
lmc_status shape_cube(mesh *OUT_mesh, lmc_error *err);
lmc_status shape_sphere(vec3 center, double radius, mesh *OUT_mesh, lmc_error *err);
lmc_status shape_disk(mesh *OUT_mesh, lmc_error *err);
lmc_status shape_cylinder(vec3 p0, vec3 p1, double radius, mesh *OUT_mesh, lmc_error *err);

#endif
