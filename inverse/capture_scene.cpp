#include "inverse/capture_scene.h"

// The capture set's reader (renderer/capture_set.h) has checked every entry used here;
// this only converts them.
namespace glaze {

Scene capture_object_scene(const CaptureSet& captures, const PolishedMaterial& material) {
  const nlohmann::json& object = captures.object;
  const std::string where = (captures.directory.empty() ? std::string("capture set") : captures.directory) + ": object";
  Scene scene;
  if (object.contains("gltf")) {
    scene = load_scene(object["gltf"].get<std::string>());
    scene.cameras.clear();
    scene.environment.reset();
    for (SceneMaterial& m : scene.materials) {
      m.R0 = material.R0();
      m.Rd = material.Rd();
      m.texture = -1;
    }
    return scene;
  }
  Vec3 center;
  for (int k = 0; k < 3; ++k) center[k] = object["center"][k].get<float>();
  const float radius = object["radius"].get<float>();
  scene.path = where;
  scene.materials.push_back({"fitted", material.R0(), material.Rd(), -1});
  scene.spheres.push_back({"object", center, radius, 0, Mat3::Identity()});
  return scene;
}

std::optional<EnvironmentSpec> capture_environment(const CaptureSet& captures) {
  const nlohmann::json& entry = captures.environment;
  if (entry.is_null()) return std::nullopt;
  EnvironmentSpec spec;
  spec.source = entry.contains("file") ? entry["file"].get<std::string>() : "procedural:" + entry["procedural"].get<std::string>();
  if (entry.contains("scale")) spec.options.scale = entry["scale"].get<float>();
  if (entry.contains("rotation")) spec.options.rotation_degrees = entry["rotation"].get<float>();
  if (entry.contains("to_world"))
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) spec.options.to_world(r, c) = entry["to_world"][r][c].get<float>();
  return spec;
}

}  // namespace glaze
