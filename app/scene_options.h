// scene_options.h: the command-line options that every scene command (render,
// convergence, preview) shares, applied to a loaded glTF scene.
#pragma once

#include "app/arguments.h"
#include "renderer/scene.h"

namespace glaze {

// The scene's environment with --env, --env-scale and --env-rotation applied; throws
// glaze::Error if there is none.
EnvironmentSpec environment_spec(const Scene& scene, const Arguments& args);

}  // namespace glaze
