// capture_set.h: capture sets (DESIGN §4), nerfstudio-style: a directory with
// transforms.json and the HDR images it names. `glaze render --captures` writes them;
// the inverse module reads them. One format, one implementation, used both ways.
#pragma once

#include "renderer/camera.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace glaze {

struct CaptureFrame {
  std::string file_path;   // relative to the capture directory
  PinholeCamera camera;    // intrinsics and camera-to-world pose
  std::string mask_path;   // optional
};

struct CaptureSet {
  std::vector<CaptureFrame> frames;
  nlohmann::json object;       // {"type": "sphere", ...} or {"gltf": ...}
  nlohmann::json environment;  // optional: {"file": ..., "scale": ..., "rotation": ...}
  nlohmann::json material;     // optional: {"R0": ..., "Rd": [...]}
};

// Writes DIRECTORY/transforms.json (atomically). Intrinsics shared by every frame are
// written once at the top, others per frame.
void write_transforms(const std::string& directory, const CaptureSet& captures);

// The JSON form of a camera-to-world pose: a 4x4 row-major array.
nlohmann::json pose_to_json(const Eigen::Affine3f& camera_to_world);

}  // namespace glaze
