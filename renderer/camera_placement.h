// camera_placement.h: cameras that glaze places itself, for a scene that has none or a
// camera given on the command line (--look-from, --look-at, --fov).
//
// The default view frames the scene's bounding sphere (centred on the bounding box of its
// meshes and spheres, through the point farthest from that centre): it looks at the
// centre from the front (+Z, where glTF models face) and 20 degrees above, with a
// 40-degree vertical field of view, from the distance at which the sphere just fits the
// narrower of the film's two fields of view. A placement that gives only some of the
// position, the target and the field of view takes the rest from that view; a target
// off the centre moves the camera back by its offset so that the whole sphere stays in
// view. Up is +Y (docs/design.md §3).
#pragma once

#include "renderer/scene.h"

#include <optional>
#include <string>

namespace glaze {

struct BoundingSphere {
  Vec3 centre;
  float radius;
};
// Throws glaze::Error for a scene without geometry.
BoundingSphere bounding_sphere(const Scene& scene);

inline constexpr float kDefaultViewYfovDegrees = 40.0f;
inline constexpr float kDefaultViewElevationDegrees = 20.0f;

struct CameraPlacement {
  std::optional<Vec3> from, at;
  std::optional<float> yfov;  // radians
};

// A perspective camera named `name` as `placement` gives it, the rest from the default
// view of `scene` on a film `aspect` (width / height) wide. Throws glaze::Error when the
// position and the target coincide or the field of view is not in (0, 180) degrees.
CameraSpec place_camera(const Scene& scene, const CameraPlacement& placement, float aspect, const std::string& name);

// The camera-to-world pose at `from` looking at `at`, +Y up (looking straight down,
// the picture's up is -Z; straight up, +Z).
Eigen::Affine3f look_at(const Vec3& from, const Vec3& at);

}  // namespace glaze
