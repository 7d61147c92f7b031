// ray_tracer.h: the scene's geometry in Embree 3, the one ray caster used by the path
// tracer, the SH integrator and the inverse module's sample extraction.
//
// Triangle meshes are Embree triangles with interpolated shading normals and texture
// coordinates. Analytic spheres are Embree user geometry intersected in double
// precision, with exact normals (p - c) / r and hit points projected onto the surface:
// the inverse fits depend on exact normals. Surfaces are two-sided: the normals of a
// hit are turned to face the incoming ray, after the geometric normal is turned to the
// side of the shading normal: glTF's winding says nothing about which side is the outside
// when the file gives normals, and a mesh wound against its normals must not go black.
#pragma once

#include "renderer/camera.h"
#include "renderer/lanes.h"
#include "renderer/scene.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <limits>
#include <optional>

namespace glaze {

struct SurfaceHit {
  float distance = 0.0f;  // along the (unit) ray direction
  Vec3 position = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();            // shading normal, unit, facing the ray's origin side
  Vec3 geometric_normal = Vec3::UnitZ();  // unit, facing the ray's origin side
  Vec2 uv = Vec2::Zero();                 // texture coordinate (0, 0 if the mesh has none)
  RGB color = RGB::Ones();                // vertex colour (COLOR_0), white where the mesh has none
  int material = 0;
};

// The hits of up to 16 rays (lanes.h), for callers that shade under distant light and
// need only the surface's orientation: where hit[k] is 0 the other fields are finite
// but meaningless.
struct SurfaceHits {
  Directions normal;            // shading normal, unit, facing the ray's origin side
  alignas(64) int hit[kLanes];  // 1 where the ray hit (an int, to vectorise with floats)
  int material[kLanes];
  Vec2 uv[kLanes];    // texture coordinate, if asked for (else 0, 0)
  RGB color[kLanes];  // vertex colour, white where there is none
};

// Whether a packet's rays start together and point alike (camera rays of one pixel),
// which Embree traverses differently from scattered bounce rays.
enum class RayCoherence { coherent, incoherent };

class RayTracer {
 public:
  explicit RayTracer(const Scene& scene);
  ~RayTracer();
  RayTracer(const RayTracer&) = delete;
  RayTracer& operator=(const RayTracer&) = delete;

  // With `texture_coordinates` false the hit's uv is left (0, 0): a sphere's costs two
  // arc tangents, which callers that only need the geometry skip.
  std::optional<SurfaceHit> intersect(const Ray& ray, float max_distance = std::numeric_limits<float>::infinity(),
                                      bool texture_coordinates = true) const;
  // The same for rays[0..count), count <= kLanes; unused lanes repeat the last ray. A
  // lone sphere is intersected in SIMD lanes (the same root as above), anything else as
  // one Embree packet.
  void intersect(const Ray* rays, int count, SurfaceHits& out, bool texture_coordinates) const;
  // The hits of rays[0..count), count <= kLanes, as one Embree packet (rtcIntersect16):
  // hit[k] is false where ray k escaped, and hits[k] is then left as it was.
  void intersect(const Ray* rays, int count, SurfaceHit* hits, bool* hit, RayCoherence coherence,
                 bool texture_coordinates = true) const;
  // True if anything lies along the ray closer than max_distance.
  bool occluded(const Ray& ray, float max_distance = std::numeric_limits<float>::infinity()) const;
  // blocked[k]: anything along rays[k], k < count <= kLanes, as one packet (rtcOccluded16).
  void occluded(const Ray* rays, int count, bool* blocked) const;

  // How far to move a ray's origin off a surface at `position` so that it does not hit
  // that surface again: a few float ulps of the coordinates' magnitude.
  static float ray_offset(const Vec3& position) { return 1e-5f * std::max(1.0f, position.cwiseAbs().maxCoeff()); }

 private:
  // The hit, from what the traversal found: distance, geometry and primitive, the
  // unnormalised geometric normal and the barycentric u, v.
  SurfaceHit surface_hit(const Ray& ray, float distance, unsigned geometry, unsigned primitive,
                         const Vec3& geometric_normal, float u, float v, bool texture_coordinates) const;

  const Scene& scene_;
  RTCDevice device_ = nullptr;
  RTCScene rtc_scene_ = nullptr;
  unsigned sphere_geometry_ = RTC_INVALID_GEOMETRY_ID;
  // A scene of one analytic sphere and nothing else (every capture set's object, the
  // sh integrator's usual scene) is intersected directly, without Embree's traversal
  // and callback: the same double-precision root, at about half the cost.
  bool lone_sphere_ = false;
};

}  // namespace glaze
