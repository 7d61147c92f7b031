#include "app/scene_options.h"

#include "renderer/error.h"

namespace glaze {

EnvironmentSpec environment_spec(const Scene& scene, const Arguments& args) {
  EnvironmentSpec spec;
  if (args.has("env")) {
    spec.source = args.text("env", "");
  } else if (scene.environment) {
    spec = *scene.environment;
  } else {
    throw Error(scene.path + ": the scene names no environment (scene.extras.glaze.environment); give --env FILE or --env procedural:office");
  }
  spec.options.scale = args.real("env-scale", spec.options.scale);
  spec.options.rotation_degrees = args.real("env-rotation", spec.options.rotation_degrees);
  return spec;
}

}  // namespace glaze
