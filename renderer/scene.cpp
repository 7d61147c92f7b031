#include "renderer/scene.h"

#include "renderer/error.h"

#include <cmath>
#include <vector>

namespace glaze {

const CameraSpec& Scene::camera(const std::string& name) const {
  for (const CameraSpec& camera : cameras)
    if (camera.name == name) return camera;
  std::vector<const CameraSpec*> by_camera_name;
  for (const CameraSpec& camera : cameras)
    if (!camera.camera_name.empty() && camera.camera_name == name) by_camera_name.push_back(&camera);
  if (by_camera_name.size() == 1) return *by_camera_name.front();
  auto quoted_names = [](const std::vector<const CameraSpec*>& list) {
    std::string text;
    for (const CameraSpec* camera : list) text += (text.empty() ? "'" : ", '") + camera->name + "'";
    return text;
  };
  if (by_camera_name.size() > 1)
    throw Error(path + ": the glTF camera '" + name + "' is used by " + std::to_string(by_camera_name.size()) +
                " nodes; name one of them: " + quoted_names(by_camera_name));
  std::string known;
  for (const CameraSpec& camera : cameras) {
    known += (known.empty() ? "" : ", ") + camera.name;
    if (!camera.camera_name.empty() && camera.camera_name != camera.name)
      known += " (glTF camera '" + camera.camera_name + "')";
  }
  throw Error(path + ": no camera named '" + name + "' (cameras: " +
              (known.empty() ? "none in the file; without --camera, glaze renders a default view" : known) +
              "; a camera is named by its node's name or its glTF camera's name)");
}

PinholeCamera Scene::make_camera(const CameraSpec& spec, std::optional<std::pair<int, int>> resolution) const {
  if (!(spec.camera_to_world.translation().cwiseAbs().maxCoeff() <= kLargestCoordinate))
    throw Error(path + ": camera " + spec.name + " lies beyond +-1e15 (or at a non-finite position); move it closer");
  std::pair<int, int> size;
  if (resolution) {
    size = *resolution;
  } else if (film) {
    size = *film;
  } else {
    const float aspect = spec.aspect > 0.0f ? spec.aspect : 1.0f;
    size = {std::max(1, static_cast<int>(std::lround(512.0f * aspect))), 512};
  }
  if (spec.projection == Projection::orthographic)
    return PinholeCamera::orthographic(spec.name, spec.camera_to_world, spec.ymag, size.first, size.second);
  return PinholeCamera::from_vertical_fov(spec.name, spec.camera_to_world, spec.yfov, size.first, size.second);
}

PolishedMaterial Scene::material_at(int material, const Vec2& uv, const RGB& color) const {
  const SceneMaterial& m = materials[material];
  RGB Rd = m.Rd * color;
  if (m.texture >= 0) Rd *= textures[m.texture].lookup(m.uv_transform * uv.homogeneous());
  return PolishedMaterial(m.R0, Rd.min(1.0f).max(0.0f));
}

}  // namespace glaze
