/*
 * accel_embree.c: ray queries with Embree 3 (the only file that includes it).
 *
 * One Embree device and one scene; each mesh becomes a triangle geometry
 * attached with its mesh index as geometry ID, sharing the mesh's float
 * position and index buffers (mesh.h pads positions for Embree's 16-byte
 * loads). Built with high quality BVH settings since scenes are static and
 * rendered for a long time. Errors raised by Embree go to an error
 * callback that records the first message; accel_create reports it.
 */
#include "render/accel.h"

#include <embree3/rtcore.h>
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct accel {
  RTCDevice device;
  RTCScene scene;
  char first_error[256];
};

static void accel__on_error(void *user, enum RTCError code, const char *str) {
  accel *a = user;
  if (a->first_error[0]) return;
  snprintf(a->first_error, sizeof a->first_error, "Embree error %d: %s", (int)code,
           str ? str : "(no message)");
}

lmc_status accel_create(accel **out, const mesh *meshes, int n_meshes, int with_null,
                        lmc_error *err) {
  *out = NULL;
  accel *a = calloc(1, sizeof *a);
  if (!a) return lmc_error_set(err, LMC_ENOMEM, NULL, 0, "out of memory building the accelerator");
  a->device = rtcNewDevice(NULL);
  if (!a->device) {
    free(a);
    return lmc_error_set(err, LMC_EUNSUPPORTED, NULL, 0, "cannot create an Embree device");
  }
  rtcSetDeviceErrorFunction(a->device, accel__on_error, a);
  a->scene = rtcNewScene(a->device);
  rtcSetSceneBuildQuality(a->scene, RTC_BUILD_QUALITY_HIGH);
  rtcSetSceneFlags(a->scene, RTC_SCENE_FLAG_ROBUST);

  /* Attach every non-empty mesh under its own index. */
  for (int i = 0; i < n_meshes; i++) {
    const mesh *m = &meshes[i];
    if (m->n_triangles <= 0 || m->n_vertices <= 0 || (m->bsdf < 0 && !with_null)) continue;
    RTCGeometry g = rtcNewGeometry(a->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, m->p, 0,
                               3 * sizeof(float), (size_t)m->n_vertices);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, m->idx, 0,
                               3 * sizeof(uint32_t), (size_t)m->n_triangles);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(a->scene, g, (unsigned)i);
    rtcReleaseGeometry(g);
  }
  rtcCommitScene(a->scene);
  if (a->first_error[0]) {
    lmc_error_set(err, LMC_EUNSUPPORTED, NULL, 0, "%s", a->first_error);
    accel_destroy(a);
    return LMC_EUNSUPPORTED;
  }
  *out = a;
  return LMC_OK;
}

void accel_destroy(accel *a) {
  if (!a) return;
  if (a->scene) rtcReleaseScene(a->scene);
  if (a->device) rtcReleaseDevice(a->device);
  free(a);
}

static void accel__fill_ray(struct RTCRay *ray, vec3 org, vec3 dir, double tmin, double tmax) {
  ray->org_x = (float)org.x;
  ray->org_y = (float)org.y;
  ray->org_z = (float)org.z;
  ray->dir_x = (float)dir.x;
  ray->dir_y = (float)dir.y;
  ray->dir_z = (float)dir.z;
  ray->tnear = (float)tmin;
  ray->tfar = tmax < (double)FLT_MAX ? (float)tmax : FLT_MAX;
  ray->time = 0.0f;
  ray->mask = 0xFFFFFFFFu;
  ray->id = 0;
  ray->flags = 0;
}

int accel_intersect(const accel *a, vec3 org, vec3 dir, double tmin, double tmax,
                    accel_hit *OUT_hit) {
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  struct RTCRayHit rh;
  accel__fill_ray(&rh.ray, org, dir, tmin, tmax);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(a->scene, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return 0;
  OUT_hit->t = rh.ray.tfar;
  OUT_hit->mesh = (int)rh.hit.geomID;
  OUT_hit->prim = rh.hit.primID;
  OUT_hit->b1 = rh.hit.u;
  OUT_hit->b2 = rh.hit.v;
  return 1;
}

int accel_occluded(const accel *a, vec3 org, vec3 dir, double tmin, double tmax) {
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  struct RTCRay ray;
  accel__fill_ray(&ray, org, dir, tmin, tmax);
  rtcOccluded1(a->scene, &ctx, &ray);
  return ray.tfar < 0.0f;
}
