#include "renderer/capture_set.h"

#include "renderer/error.h"

#include <filesystem>
#include <fstream>

namespace glaze {

nlohmann::json pose_to_json(const Eigen::Affine3f& camera_to_world) {
  nlohmann::json rows = nlohmann::json::array();
  const Eigen::Matrix4f m = camera_to_world.matrix();
  for (int r = 0; r < 4; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  return rows;
}

namespace {

nlohmann::json intrinsics(const PinholeCamera& c) {
  return {{"w", c.width}, {"h", c.height}, {"fl_x", c.fl_x}, {"fl_y", c.fl_y}, {"cx", c.cx}, {"cy", c.cy}};
}

}  // namespace

void write_transforms(const std::string& directory, const CaptureSet& captures) {
  if (captures.frames.empty()) throw Error(directory + ": a capture set needs at least one frame");
  nlohmann::json root = nlohmann::json::object();
  const nlohmann::json shared = intrinsics(captures.frames.front().camera);
  bool all_shared = true;
  for (const CaptureFrame& frame : captures.frames) all_shared = all_shared && intrinsics(frame.camera) == shared;
  if (all_shared) root.update(shared);
  nlohmann::json frames = nlohmann::json::array();
  for (const CaptureFrame& frame : captures.frames) {
    nlohmann::json entry = {{"file_path", frame.file_path},
                            {"camera", frame.camera.name},
                            {"transform_matrix", pose_to_json(frame.camera.camera_to_world)}};
    if (!frame.mask_path.empty()) entry["mask_path"] = frame.mask_path;
    if (!all_shared) entry.update(intrinsics(frame.camera));
    frames.push_back(entry);
  }
  root["frames"] = frames;
  root["object"] = captures.object;
  if (!captures.environment.is_null()) root["environment"] = captures.environment;
  if (!captures.material.is_null()) root["material"] = captures.material;

  const std::filesystem::path target = std::filesystem::path(directory) / "transforms.json";
  const std::filesystem::path temporary = std::filesystem::path(directory) / ".transforms.json.tmp";
  {
    std::ofstream out(temporary);
    out << root.dump(2) << '\n';
    if (!out) throw Error(target.string() + ": could not be written");
  }
  std::error_code ec;
  std::filesystem::rename(temporary, target, ec);
  if (ec) throw Error(target.string() + ": could not be written (" + ec.message() + ")");
}

}  // namespace glaze
