#include "renderer/camera_placement.h"

#include "renderer/error.h"

#include <cmath>

namespace glaze {

BoundingSphere bounding_sphere(const Scene& scene) {
  Eigen::AlignedBox3f box;
  for (const Sphere& s : scene.spheres)
    box.extend(s.center - Vec3::Constant(s.radius)), box.extend(s.center + Vec3::Constant(s.radius));
  for (const TriangleMesh& m : scene.meshes)
    for (const Vec3& p : m.positions) box.extend(p);
  if (box.isEmpty()) throw Error(scene.path + ": the scene has no geometry to frame");
  const Vec3 centre = box.center();
  float radius = 0.0f;
  for (const Sphere& s : scene.spheres) radius = std::max(radius, (s.center - centre).norm() + s.radius);
  for (const TriangleMesh& m : scene.meshes)
    for (const Vec3& p : m.positions) radius = std::max(radius, (p - centre).norm());
  return {centre, radius};
}

Eigen::Affine3f look_at(const Vec3& from, const Vec3& at) {
  const Vec3 back = (from - at).normalized();  // camera +Z
  Vec3 up(0.0f, 1.0f, 0.0f);
  if (back.cross(up).norm() < 1e-6f) up = Vec3(0.0f, 0.0f, back.y() > 0.0f ? -1.0f : 1.0f);
  const Vec3 right = up.cross(back).normalized();
  Eigen::Affine3f pose = Eigen::Affine3f::Identity();
  pose.linear() << right, back.cross(right), back;
  pose.translation() = from;
  return pose;
}

CameraSpec place_camera(const Scene& scene, const CameraPlacement& placement, float aspect, const std::string& name) {
  const float yfov = placement.yfov.value_or(kDefaultViewYfovDegrees * kPi / 180.0f);
  if (!(yfov > 0.0f && yfov < kPi))
    throw Error("camera '" + name + "': the vertical field of view must be in (0, 180) degrees, got " +
                std::to_string(yfov * 180.0f / kPi));
  const BoundingSphere bounds = bounding_sphere(scene);
  const Vec3 at = placement.at.value_or(bounds.centre);
  Vec3 from;
  if (placement.from) {
    from = *placement.from;
  } else {
    // The sphere about `at` that holds the bounding sphere, just inside the narrower
    // half field of view.
    const float half_fov = std::min(0.5f * yfov, std::atan(aspect * std::tan(0.5f * yfov)));
    const float radius = bounds.radius + (at - bounds.centre).norm();
    const float elevation = kDefaultViewElevationDegrees * kPi / 180.0f;
    from = at + radius / std::sin(half_fov) * Vec3(0.0f, std::sin(elevation), std::cos(elevation));
  }
  if (!((from - at).norm() > 1e-6f * std::max(1.0f, at.norm())))
    throw Error("camera '" + name + "': the position and the target coincide; give --look-from and --look-at apart");
  CameraSpec spec;
  spec.name = name;
  spec.camera_to_world = look_at(from, at);
  spec.yfov = yfov;
  spec.aspect = aspect;
  return spec;
}

}  // namespace glaze
