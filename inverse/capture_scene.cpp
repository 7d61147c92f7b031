#include "inverse/capture_scene.h"

// The capture set's reader (renderer/capture_set.h) has checked every value used here;
// this only converts them.
namespace glaze {

Scene capture_object_scene(const CaptureSet& captures, const PolishedMaterial& material) {
  Scene scene;
  if (const CaptureGltf* gltf = std::get_if<CaptureGltf>(&captures.object)) {
    scene = load_scene(gltf->file);
    scene.cameras.clear();
    scene.environment.reset();
    for (SceneMaterial& m : scene.materials) {
      m.R0 = material.R0();
      m.Rd = material.Rd();
      m.texture = -1;
    }
    return scene;
  }
  const CaptureSphere& sphere = std::get<CaptureSphere>(captures.object);
  scene.path = (captures.directory.empty() ? std::string("capture set") : captures.directory) + ": object";
  scene.materials.push_back({"fitted", material.R0(), material.Rd(), -1});
  scene.spheres.push_back({"object", sphere.center, sphere.radius, 0, Mat3::Identity()});
  return scene;
}

std::optional<EnvironmentSpec> capture_environment(const CaptureSet& captures) {
  if (!captures.environment) return std::nullopt;
  const CaptureEnvironment& environment = *captures.environment;
  EnvironmentSpec spec;
  spec.source = environment.file.empty() ? "procedural:" + environment.procedural : environment.file;
  spec.options = environment.options;
  return spec;
}

}  // namespace glaze
