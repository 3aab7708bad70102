/*
 * accel.h: ray queries against the scene's triangles. The only
 * implementation is accel_embree.c, the one file that includes Embree.
 *
 * Rays are given in double and traced in float; tmin should carry the
 * self-intersection offset (see scene_spawn_* in scene.h). Queries are
 * thread safe once the accelerator is built.
 */
#ifndef LMC_RENDER_ACCEL_H
#define LMC_RENDER_ACCEL_H

#include <stdint.h>

#include "render/error.h"
#include "render/mesh.h"

typedef struct accel accel;

typedef struct accel_hit {
  double t;      /* ray parameter (dir need not be unit) */
  int mesh;      /* index of the mesh */
  int64_t prim;  /* triangle index within the mesh */
  double b1, b2; /* barycentrics: p = (1-b1-b2) a + b1 b + b2 c */
} accel_hit;

/* Builds the accelerator over meshes (borrowed: they must outlive it);
 * the index-matched medium boundaries (mesh.h: bsdf -1) only with
 * with_null. */
lmc_status accel_create(accel **out, const mesh *meshes, int n_meshes, int with_null,
                        lmc_error *err);
void accel_destroy(accel *a);
/* Closest hit with t in (tmin, tmax); returns 1 on a hit. */
int accel_intersect(const accel *a, vec3 org, vec3 dir, double tmin, double tmax,
                    accel_hit *OUT_hit);
/* 1 when anything lies on the ray with t in (tmin, tmax). */
int accel_occluded(const accel *a, vec3 org, vec3 dir, double tmin, double tmax);

#endif
