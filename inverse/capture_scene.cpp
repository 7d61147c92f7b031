#include "inverse/capture_scene.h"

#include "renderer/error.h"

namespace glaze {
namespace {

float finite_number(const nlohmann::json& value, const std::string& what) {
  if (!value.is_number() || !std::isfinite(value.get<double>())) throw Error(what + " must be a finite number");
  return value.get<float>();
}

}  // namespace

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
  if (object.value("type", "") != "sphere" || !object.contains("center") || !object["center"].is_array() ||
      object["center"].size() != 3 || !object.contains("radius"))
    throw Error(where + " must be {\"type\": \"sphere\", \"center\": [x, y, z], \"radius\": r} or {\"gltf\": FILE}");
  Vec3 center;
  for (int k = 0; k < 3; ++k) center[k] = finite_number(object["center"][k], where + " center");
  const float radius = finite_number(object["radius"], where + " radius");
  if (!(radius > 0.0f)) throw Error(where + " radius must be positive");
  scene.path = where;
  scene.materials.push_back({"fitted", material.R0(), material.Rd(), -1});
  scene.spheres.push_back({"object", center, radius, 0, Mat3::Identity()});
  return scene;
}

std::optional<EnvironmentSpec> capture_environment(const CaptureSet& captures) {
  const nlohmann::json& entry = captures.environment;
  if (entry.is_null()) return std::nullopt;
  const std::string where = captures.directory + ": environment";
  EnvironmentSpec spec;
  if (entry.contains("file")) {
    spec.source = entry["file"].get<std::string>();
  } else if (entry.contains("procedural")) {
    spec.source = "procedural:" + entry["procedural"].get<std::string>();
  } else {
    throw Error(where + " needs \"file\" or \"procedural\"");
  }
  if (entry.contains("scale")) spec.options.scale = finite_number(entry["scale"], where + " scale");
  if (entry.contains("rotation")) spec.options.rotation_degrees = finite_number(entry["rotation"], where + " rotation");
  if (entry.contains("to_world")) {
    const nlohmann::json& rows = entry["to_world"];
    if (!rows.is_array() || rows.size() != 3) throw Error(where + " to_world must be 3 rows of 3 numbers");
    for (int r = 0; r < 3; ++r) {
      if (!rows[r].is_array() || rows[r].size() != 3) throw Error(where + " to_world must be 3 rows of 3 numbers");
      for (int c = 0; c < 3; ++c) spec.options.to_world(r, c) = finite_number(rows[r][c], where + " to_world");
    }
  }
  return spec;
}

}  // namespace glaze
