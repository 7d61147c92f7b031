#include "renderer/ray_tracer.h"

#include "renderer/error.h"
#include "renderer/latlong.h"
#include "renderer/sphere_intersection.h"

#include <array>
#include <cmath>
#include <string>

namespace glaze {
namespace {

void check_device(RTCDevice device, const char* what) {
  const RTCError error = rtcGetDeviceError(device);
  if (error != RTC_ERROR_NONE)
    throw Error(std::string("Embree failed to ") + what + " (error " + std::to_string(int(error)) + ")");
}

// The outward normal, unnormalised, at distance t along the ray: p - c, in double.
Vec3 sphere_hit_normal(const Sphere& sphere, const Vec3& origin, const Vec3& direction, double t) {
  return (origin.cast<double>() + t * direction.cast<double>() - sphere.center.cast<double>()).cast<float>();
}

void sphere_bounds(const RTCBoundsFunctionArguments* args) {
  const auto* spheres = static_cast<const std::vector<Sphere>*>(args->geometryUserPtr);
  const Sphere& s = (*spheres)[args->primID];
  const float r = s.radius * (1.0f + 1e-5f);
  *args->bounds_o = RTCBounds{s.center.x() - r, s.center.y() - r, s.center.z() - r, 0.0f,
                              s.center.x() + r, s.center.y() + r, s.center.z() + r, 0.0f};
}

// The sphere callbacks take packets of N rays (rtcIntersect16 / rtcOccluded16) as well
// as single rays (N = 1); each valid lane gets the same double-precision root.
void sphere_intersect(const RTCIntersectFunctionNArguments* args) {
  const auto* spheres = static_cast<const std::vector<Sphere>*>(args->geometryUserPtr);
  const Sphere& s = (*spheres)[args->primID];
  const unsigned n = args->N;
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, n);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, n);
  for (unsigned i = 0; i < n; ++i) {
    if (!args->valid[i]) continue;
    const Vec3 origin(RTCRayN_org_x(ray, n, i), RTCRayN_org_y(ray, n, i), RTCRayN_org_z(ray, n, i));
    const Vec3 direction(RTCRayN_dir_x(ray, n, i), RTCRayN_dir_y(ray, n, i), RTCRayN_dir_z(ray, n, i));
    const double t =
        sphere_hit_distance(origin, direction, s.center, s.radius, RTCRayN_tnear(ray, n, i), RTCRayN_tfar(ray, n, i));
    if (std::isnan(t)) continue;
    RTCRayN_tfar(ray, n, i) = static_cast<float>(t);
    const Vec3 normal = sphere_hit_normal(s, origin, direction, t);
    RTCHitN_Ng_x(hit, n, i) = normal.x();
    RTCHitN_Ng_y(hit, n, i) = normal.y();
    RTCHitN_Ng_z(hit, n, i) = normal.z();
    RTCHitN_u(hit, n, i) = RTCHitN_v(hit, n, i) = 0.0f;
    RTCHitN_primID(hit, n, i) = args->primID;
    RTCHitN_geomID(hit, n, i) = args->geomID;
    RTCHitN_instID(hit, n, i, 0) = RTC_INVALID_GEOMETRY_ID;
  }
}

void sphere_occluded(const RTCOccludedFunctionNArguments* args) {
  const auto* spheres = static_cast<const std::vector<Sphere>*>(args->geometryUserPtr);
  const Sphere& s = (*spheres)[args->primID];
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (!args->valid[i]) continue;
    const Vec3 origin(RTCRayN_org_x(args->ray, n, i), RTCRayN_org_y(args->ray, n, i), RTCRayN_org_z(args->ray, n, i));
    const Vec3 direction(RTCRayN_dir_x(args->ray, n, i), RTCRayN_dir_y(args->ray, n, i),
                         RTCRayN_dir_z(args->ray, n, i));
    if (!std::isnan(sphere_hit_distance(origin, direction, s.center, s.radius, RTCRayN_tnear(args->ray, n, i),
                                        RTCRayN_tfar(args->ray, n, i))))
      RTCRayN_tfar(args->ray, n, i) = -std::numeric_limits<float>::infinity();
  }
}

// Rays [0, count) in Embree's 16-wide layout; the other lanes are invalid.
void fill_packet(const Ray* rays, int count, RTCRay16& packet, int* valid) {
  for (int k = 0; k < kLanes; ++k) {
    valid[k] = k < count ? -1 : 0;
    const Ray& ray = rays[std::min(k, count - 1)];
    packet.org_x[k] = ray.origin.x();
    packet.org_y[k] = ray.origin.y();
    packet.org_z[k] = ray.origin.z();
    packet.dir_x[k] = ray.direction.x();
    packet.dir_y[k] = ray.direction.y();
    packet.dir_z[k] = ray.direction.z();
    packet.tnear[k] = 0.0f;
    packet.tfar[k] = std::numeric_limits<float>::infinity();
    packet.mask[k] = ~0u;
    packet.time[k] = 0.0f;
    packet.flags[k] = 0;
  }
}

// Every vertex and sphere within kLargestCoordinate (scene.h), or glaze::Error.
void check_extent(const Scene& scene) {
  const auto inside = [](const Vec3& p) { return p.cwiseAbs().maxCoeff() <= kLargestCoordinate; };
  for (const TriangleMesh& mesh : scene.meshes)
    for (const Vec3& position : mesh.positions)
      if (!inside(position))
        throw Error(scene.path + ": a vertex of mesh '" + mesh.name + "' lies beyond +-1e15; scale the scene down");
  for (const Sphere& sphere : scene.spheres)
    if (!inside(sphere.center) || !(sphere.radius <= kLargestCoordinate))
      throw Error(scene.path + ": sphere '" + sphere.name + "' reaches beyond +-1e15; scale the scene down");
}

}  // namespace

RayTracer::RayTracer(const Scene& scene) : scene_(scene) {
  check_extent(scene);
  device_ = rtcNewDevice(nullptr);
  if (!device_) throw Error("Embree device could not be created");
  rtc_scene_ = rtcNewScene(device_);
  rtcSetSceneFlags(rtc_scene_, RTC_SCENE_FLAG_ROBUST);

  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const TriangleMesh& mesh = scene.meshes[m];
    RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                 3 * sizeof(float), mesh.positions.size()));
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(uint32_t), mesh.triangles.size()));
    check_device(device_, "allocate a triangle mesh");
    for (size_t v = 0; v < mesh.positions.size(); ++v)
      for (int k = 0; k < 3; ++k) vertices[3 * v + k] = mesh.positions[v][k];
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) indices[3 * t + k] = mesh.triangles[t][k];
    rtcCommitGeometry(geometry);
    rtcAttachGeometryByID(rtc_scene_, geometry, static_cast<unsigned>(m));
    rtcReleaseGeometry(geometry);
  }
  if (!scene.spheres.empty()) {
    RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geometry, static_cast<unsigned>(scene.spheres.size()));
    rtcSetGeometryUserData(geometry, const_cast<std::vector<Sphere>*>(&scene.spheres));
    rtcSetGeometryBoundsFunction(geometry, sphere_bounds, nullptr);
    rtcSetGeometryIntersectFunction(geometry, sphere_intersect);
    rtcSetGeometryOccludedFunction(geometry, sphere_occluded);
    rtcCommitGeometry(geometry);
    sphere_geometry_ = static_cast<unsigned>(scene.meshes.size());
    rtcAttachGeometryByID(rtc_scene_, geometry, sphere_geometry_);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(rtc_scene_);
  check_device(device_, "build the scene");
  lone_sphere_ = scene.meshes.empty() && scene.spheres.size() == 1;
}

RayTracer::~RayTracer() {
  if (rtc_scene_) rtcReleaseScene(rtc_scene_);
  if (device_) rtcReleaseDevice(device_);
}

std::optional<SurfaceHit> RayTracer::intersect(const Ray& ray, float max_distance, bool texture_coordinates) const {
  float distance;
  unsigned geometry, primitive;
  Vec3 geometric_normal;  // unnormalised
  float u = 0.0f, v = 0.0f;
  if (lone_sphere_) {
    const Sphere& sphere = scene_.spheres.front();
    const double t = sphere_hit_distance(ray.origin, ray.direction, sphere.center, sphere.radius, 0.0, max_distance);
    if (std::isnan(t)) return std::nullopt;
    distance = static_cast<float>(t);
    geometry = sphere_geometry_;
    primitive = 0;
    geometric_normal = sphere_hit_normal(sphere, ray.origin, ray.direction, t);
  } else {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rayhit{};
    rayhit.ray.org_x = ray.origin.x();
    rayhit.ray.org_y = ray.origin.y();
    rayhit.ray.org_z = ray.origin.z();
    rayhit.ray.dir_x = ray.direction.x();
    rayhit.ray.dir_y = ray.direction.y();
    rayhit.ray.dir_z = ray.direction.z();
    rayhit.ray.tnear = 0.0f;
    rayhit.ray.tfar = max_distance;
    rayhit.ray.mask = ~0u;
    rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(rtc_scene_, &context, &rayhit);
    if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    distance = rayhit.ray.tfar;
    geometry = rayhit.hit.geomID;
    primitive = rayhit.hit.primID;
    geometric_normal = Vec3(rayhit.hit.Ng_x, rayhit.hit.Ng_y, rayhit.hit.Ng_z);
    u = rayhit.hit.u;
    v = rayhit.hit.v;
  }

  return surface_hit(ray, distance, geometry, primitive, geometric_normal, u, v, texture_coordinates);
}

SurfaceHit RayTracer::surface_hit(const Ray& ray, float distance, unsigned geometry, unsigned primitive,
                                  const Vec3& geometric_normal, float u, float v, bool texture_coordinates) const {
  SurfaceHit hit;
  hit.distance = distance;
  if (geometry == sphere_geometry_) {
    const Sphere& sphere = scene_.spheres[primitive];
    const Vec3 n = geometric_normal.normalized();
    hit.position = sphere.center + sphere.radius * n;  // exactly on the surface
    hit.normal = hit.geometric_normal = n;
    hit.uv = texture_coordinates ? direction_to_latlong(sphere.rotation.transpose() * n) : Vec2::Zero();
    hit.material = sphere.material;
  } else {
    const TriangleMesh& mesh = scene_.meshes[geometry];
    const auto& t = mesh.triangles[primitive];
    const float w = 1.0f - u - v;
    hit.position = ray.origin + hit.distance * ray.direction;
    hit.geometric_normal = geometric_normal.normalized();
    hit.normal = hit.geometric_normal;  // flat, where the mesh has no normals
    if (!mesh.normals.empty()) {
      const Vec3 shading = w * mesh.normals[t[0]] + u * mesh.normals[t[1]] + v * mesh.normals[t[2]];
      if (shading.norm() > 0.0f) hit.normal = shading.normalized();
      if (hit.geometric_normal.dot(hit.normal) < 0.0f) hit.geometric_normal = -hit.geometric_normal;
    }
    hit.uv = mesh.uvs.empty() || !texture_coordinates
                 ? Vec2::Zero()
                 : Vec2(w * mesh.uvs[t[0]] + u * mesh.uvs[t[1]] + v * mesh.uvs[t[2]]);
    if (!mesh.colors.empty()) hit.color = w * mesh.colors[t[0]] + u * mesh.colors[t[1]] + v * mesh.colors[t[2]];
    hit.material = mesh.material;
  }
  if (hit.geometric_normal.dot(ray.direction) > 0.0f) {  // two-sided: face the viewer
    hit.geometric_normal = -hit.geometric_normal;
    hit.normal = -hit.normal;
  }
  return hit;
}

void RayTracer::intersect(const Ray* rays, int count, SurfaceHit* hits, bool* hit, RayCoherence coherence,
                          bool texture_coordinates) const {
  // Scattered rays gain nothing from a packet (measured: docs/performance.md), and a lone
  // sphere needs no traversal at all: one ray at a time.
  if (lone_sphere_ || coherence == RayCoherence::incoherent) {
    for (int k = 0; k < count; ++k) {
      const std::optional<SurfaceHit> found =
          intersect(rays[k], std::numeric_limits<float>::infinity(), texture_coordinates);
      hit[k] = found.has_value();
      if (found) hits[k] = *found;
    }
    return;
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;  // (scattered rays went one at a time above)
  alignas(64) int valid[kLanes];
  alignas(64) RTCRayHit16 packet;
  fill_packet(rays, count, packet.ray, valid);
  std::fill(std::begin(packet.hit.geomID), std::end(packet.hit.geomID), RTC_INVALID_GEOMETRY_ID);
  std::fill(std::begin(packet.hit.instID[0]), std::end(packet.hit.instID[0]), RTC_INVALID_GEOMETRY_ID);
  rtcIntersect16(valid, rtc_scene_, &context, &packet);
  for (int k = 0; k < count; ++k) {
    hit[k] = packet.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
    if (!hit[k]) continue;
    const Vec3 geometric_normal(packet.hit.Ng_x[k], packet.hit.Ng_y[k], packet.hit.Ng_z[k]);
    hits[k] = surface_hit(rays[k], packet.ray.tfar[k], packet.hit.geomID[k], packet.hit.primID[k], geometric_normal,
                          packet.hit.u[k], packet.hit.v[k], texture_coordinates);
  }
}

void RayTracer::occluded(const Ray* rays, int count, bool* blocked) const {
  if (lone_sphere_) {
    for (int k = 0; k < count; ++k) blocked[k] = occluded(rays[k]);
    return;
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  alignas(64) int valid[kLanes];
  alignas(64) RTCRay16 packet;
  fill_packet(rays, count, packet, valid);
  rtcOccluded16(valid, rtc_scene_, &context, &packet);
  for (int k = 0; k < count; ++k) blocked[k] = packet.tfar[k] < 0.0f;
}

void RayTracer::intersect(const Ray* rays, int count, SurfaceHits& out, bool texture_coordinates) const {
  if (!lone_sphere_) {
    // One packet; the unused lanes copy the last ray's hit.
    std::array<SurfaceHit, kLanes> hits;
    std::array<bool, kLanes> hit;
    intersect(rays, count, hits.data(), hit.data(), RayCoherence::coherent, texture_coordinates);
    for (int k = 0; k < kLanes; ++k) {
      const int j = std::min(k, count - 1);
      out.hit[k] = hit[j] ? 1 : 0;
      out.normal.set(k, hit[j] ? hits[j].normal : Vec3::UnitZ());
      out.material[k] = hit[j] ? hits[j].material : 0;
      out.uv[k] = hit[j] ? hits[j].uv : Vec2::Zero();
      out.color[k] = hit[j] ? hits[j].color : RGB::Ones();
    }
    return;
  }
  const Sphere& sphere = scene_.spheres.front();
  Directions view;
  alignas(64) double origin_x[kLanes], origin_y[kLanes], origin_z[kLanes];  // relative to the centre
  alignas(64) float facing[kLanes];  // -1 where the normal was turned to face the ray
  for (int k = 0; k < kLanes; ++k) {
    const Ray& ray = rays[std::min(k, count - 1)];
    view.set(k, ray.direction);
    origin_x[k] = double(ray.origin.x()) - sphere.center.x();
    origin_y[k] = double(ray.origin.y()) - sphere.center.y();
    origin_z[k] = double(ray.origin.z()) - sphere.center.z();
  }
  // SIMD: the root, then the unit normal p - c (double, then float, as above), turned
  // to face the viewer.
  for (int k = 0; k < kLanes; ++k) {
    const double t = sphere_hit_distance(origin_x[k], origin_y[k], origin_z[k], view.x[k], view.y[k], view.z[k],
                                         sphere.radius, 0.0, std::numeric_limits<double>::infinity());
    out.hit[k] = t == t ? 1 : 0;
    const double s = t == t ? t : 0.0;
    const float px = float(origin_x[k] + s * view.x[k]), py = float(origin_y[k] + s * view.y[k]),
                pz = float(origin_z[k] + s * view.z[k]);
    const float length = std::sqrt(px * px + py * py + pz * pz);
    facing[k] = px * view.x[k] + py * view.y[k] + pz * view.z[k] > 0.0f ? -1.0f : 1.0f;
    const float scale = length > 0.0f ? facing[k] / length : 0.0f;
    out.normal.x[k] = px * scale;
    out.normal.y[k] = py * scale;
    out.normal.z[k] = pz * scale;
    out.material[k] = sphere.material;
    out.color[k] = RGB::Ones();
  }
  for (int k = 0; k < kLanes; ++k)  // of the outward normal, whichever way it was turned
    out.uv[k] = texture_coordinates ? direction_to_latlong(sphere.rotation.transpose() * (facing[k] * out.normal[k]))
                                    : Vec2::Zero();
}

bool RayTracer::occluded(const Ray& ray, float max_distance) const {
  if (lone_sphere_) {
    const Sphere& sphere = scene_.spheres.front();
    return !std::isnan(sphere_hit_distance(ray.origin, ray.direction, sphere.center, sphere.radius, 0.0, max_distance));
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay r{};
  r.org_x = ray.origin.x();
  r.org_y = ray.origin.y();
  r.org_z = ray.origin.z();
  r.dir_x = ray.direction.x();
  r.dir_y = ray.direction.y();
  r.dir_z = ray.direction.z();
  r.tnear = 0.0f;
  r.tfar = max_distance;
  r.mask = ~0u;
  rtcOccluded1(rtc_scene_, &context, &r);
  return r.tfar < 0.0f;
}

}  // namespace glaze
