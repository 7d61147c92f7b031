// integrator_registry.h: glaze's integrators by name, the one place that lists them: the
// names the command line accepts (--integrator), and the integrator each one makes.
#pragma once

#include "renderer/environment.h"
#include "renderer/integrator.h"
#include "renderer/path_tracer.h"
#include "renderer/ray_tracer.h"
#include "renderer/render.h"
#include "renderer/scene.h"
#include "renderer/sh_integrator.h"

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace glaze {

// Every integrator's options, each in its own struct; an integrator reads only its own.
struct IntegratorOptions {
  PathTracerOptions path;     // "path": its estimators and depth
  RenderOptions path_render;  // "path": samples per pixel, time budget, seed, threads, progress
  ShIntegratorOptions sh;     // "sh"
};

// The registered names ("path", "sh"), in the order help texts list them.
const std::vector<std::string>& integrator_names();

// Throws glaze::Error, naming the known integrators, unless `name` is one of them.
void require_integrator(std::string_view name);

// The integrator registered as `name`, rendering `scene` (traced by `tracer`) under
// `environment`, all of which it refers to and must outlive it. Throws as
// require_integrator() for an unknown name.
std::unique_ptr<Integrator> make_integrator(std::string_view name, const Scene& scene, const RayTracer& tracer,
                                            const Environment& environment, const IntegratorOptions& options);

}  // namespace glaze
