// integrator.h: what every integrator does: render a camera's image of a scene (its
// geometry in a RayTracer, its light an Environment), and say how it rendered it.
//
// The integrators are the path tracer (PathIntegrator, render.h: Monte-Carlo, converging
// with samples) and the analytic sh integrator (ShIntegrator, sh_integrator.h: noise-free).
// Each is made with its scene, light and own options, so that a frame is one call,
// render(camera); integrator_registry.h makes one by the name the command line gives.
//
// Not part of this interface: the path tracer's passes one at a time (ProgressiveRender,
// render.h), which the preview window shows as they refine, with the Monte-Carlo error
// of their spread. Only a Monte-Carlo integrator has passes that refine one estimate and
// an error from their spread; the sh integrator's image is final at once. So the preview
// renders the sh image through this interface and the path passes through
// ProgressiveRender, rather than every integrator pretending to have passes.
#pragma once

#include "renderer/camera.h"
#include "renderer/image.h"

#include <cstdint>
#include <map>
#include <string>
#include <string_view>

namespace glaze {

struct IntegratorResult {
  Image image;
  double seconds = 0.0;  // wall-clock time of the render
  // How it was rendered, as an EXR records it: "glaze:integrator" (the name) and the
  // integrator's parameters ("glaze:spp", "glaze:lmax", ...).
  std::map<std::string, std::string> metadata;
  std::string summary;  // the same for people, e.g. "64 spp" or "sh, lmax 4, ss 2"
};

class Integrator {
 public:
  virtual ~Integrator() = default;

  // The name it is registered and recorded under ("path", "sh").
  virtual std::string_view name() const = 0;

  // Renders `camera`'s image. `camera_index`, the camera's index in its scene, keys the
  // path tracer's random streams, so that the views of one capture set carry independent
  // noise (render.h); a noise-free integrator does not use it.
  IntegratorResult render(const PinholeCamera& camera, uint64_t camera_index = 0) const {
    return render_camera(camera, camera_index);
  }

 private:
  // What render() does; a separate virtual, so that its default argument is declared once
  // (a default on a virtual function is taken from the type it is called through).
  virtual IntegratorResult render_camera(const PinholeCamera& camera, uint64_t camera_index) const = 0;
};

}  // namespace glaze
