#include "renderer/scene.h"

#include "renderer/error.h"

#include <cmath>

namespace glaze {

const CameraSpec& Scene::camera(const std::string& name) const {
  for (const CameraSpec& camera : cameras)
    if (camera.name == name) return camera;
  std::string known;
  for (const CameraSpec& camera : cameras) known += (known.empty() ? "" : ", ") + camera.name;
  throw Error(path + ": no camera named '" + name + "' (cameras: " + (known.empty() ? "none" : known) + ")");
}

PinholeCamera Scene::make_camera(const CameraSpec& spec, std::optional<std::pair<int, int>> resolution) const {
  std::pair<int, int> size;
  if (resolution) {
    size = *resolution;
  } else if (film) {
    size = *film;
  } else {
    const float aspect = spec.aspect > 0.0f ? spec.aspect : 1.0f;
    size = {std::max(1, static_cast<int>(std::lround(512.0f * aspect))), 512};
  }
  return PinholeCamera::from_vertical_fov(spec.name, spec.camera_to_world, spec.yfov, size.first, size.second);
}

PolishedMaterial Scene::material_at(int material, const Vec2& uv) const {
  const SceneMaterial& m = materials[material];
  if (m.texture < 0) return PolishedMaterial(m.R0, m.Rd);
  return PolishedMaterial(m.R0, (m.Rd * textures[m.texture].lookup(uv)).min(1.0f).max(0.0f));
}

}  // namespace glaze
