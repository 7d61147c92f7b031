// capture_scene.h: what a capture set describes, turned into the renderer's own objects:
// the object as a Scene (an analytic sphere, or the glTF it names) that the renderer's
// ray tracer intersects, and the known environment, if the set has one. The inverse
// module renders and samples through these, never through copies.
#pragma once

#include "renderer/capture_set.h"
#include "renderer/scene.h"

#include <optional>

namespace glaze {

// Both take a set as read_transforms() returns it (checked).
//
// The object of `captures` as a scene of its own (no cameras, no environment). A sphere
// gets one material; a glTF keeps its materials and textures. Every material is set to
// `material` so that re-renders show the fitted one.
Scene capture_object_scene(const CaptureSet& captures, const PolishedMaterial& material);

// The environment of `captures` to build: its file, else its procedural map, with its
// options; or nothing if the set names none.
std::optional<EnvironmentSpec> capture_environment(const CaptureSet& captures);

}  // namespace glaze
