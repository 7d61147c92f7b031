// capture_set.h: capture sets (DESIGN §4), nerfstudio-style: a directory with
// transforms.json and the HDR images it names. `glaze render --captures` writes them;
// the inverse module reads them. One format, one implementation, used both ways.
//
//   { "w": 512, "h": 512, "fl_x": .., "fl_y": .., "cx": ..,  "cy": ..,   (or per frame)
//     "saturation": s,                          (optional: pixel values >= s are saturated)
//     "frames": [ {"file_path": "view_000.exr", "camera": "name" (optional),
//                  "transform_matrix": [[4x4 row-major camera-to-world, OpenGL axes]],
//                  "mask_path": "mask_000.png" (optional)} ],
//     "object": {"type": "sphere", "center": [x, y, z], "radius": r}  or  {"gltf": FILE},
//     "environment": {"file": FILE or "procedural": NAME, "scale": s, "rotation": degrees},
//     "material": {"R0": x, "Rd": [r, g, b]} }    (both optional; material: a known one)
//
// Relative paths are relative to the directory holding transforms.json. A per-frame
// intrinsic overrides the top-level one. The camera is a pinhole: "camera_model" may only
// be PINHOLE or OPENCV, and lens distortion (k1..k4, p1, p2) must be zero.
#pragma once

#include "renderer/camera.h"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace glaze {

struct CaptureFrame {
  std::string file_path;   // to write: relative to the capture directory; as read: resolved
  PinholeCamera camera;    // intrinsics and camera-to-world pose
  std::string mask_path;   // optional; as read: resolved
};

struct CaptureSet {
  std::vector<CaptureFrame> frames;
  nlohmann::json object;       // {"type": "sphere", ...} or {"gltf": ...} (as read: resolved)
  nlohmann::json environment;  // optional: {"file": ..., "scale": ..., "rotation": ...} (as read: resolved)
  nlohmann::json material;     // optional: {"R0": ..., "Rd": [...]}
  // Default-initialised so that aggregate initialisers naming only the members above
  // (glaze render --captures) stay free of -Wmissing-field-initializers.
  std::string directory = {};            // holding the transforms.json read; empty if built in memory
  std::optional<float> saturation = {};  // pixel values at or above it are saturated
  // Optional: how glaze rendered the images, {"integrator": "sh", "ss": K, "lmax": L} or
  // {"integrator": "path", "spp": N}; invert-fit models the pixels to match.
  nlohmann::json renderer = {};
};

// Writes DIRECTORY/transforms.json (atomically). Intrinsics shared by every frame are
// written once at the top, others per frame.
void write_transforms(const std::string& directory, const CaptureSet& captures);

// Reads PATH, a transforms.json or a directory holding one, checking everything above
// (files exist, poses are rigid, numbers are finite and in range). File paths come back
// resolved against the file's directory, ready to open. Throws glaze::Error naming the
// file, the frame and the key at fault.
CaptureSet read_transforms(const std::string& path);

// The JSON form of a camera-to-world pose: a 4x4 row-major array.
nlohmann::json pose_to_json(const Eigen::Affine3f& camera_to_world);

}  // namespace glaze
