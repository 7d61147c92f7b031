// fuzz_transforms: capture-set files (transforms.json) through read_transforms, and what
// it accepts back through write_transforms.
//
// The input is written as transforms.json beside the fixtures view_000..003.exr,
// mask_000.png, env.exr and sphere.gltf (fuzz_support.h). glaze::Error is a clean
// refusal; any other exception or a sanitizer report is a finding. A set that reads must
// write, and read back with the same frames, cameras and object: what the reader accepts
// the writer must be able to express.
#include "renderer/capture_set.h"
#include "renderer/error.h"
#include "tests/fuzz/fuzz_support.h"

#include <cmath>
#include <filesystem>

namespace {

std::filesystem::path scratch, rewritten;

using namespace glaze;

bool near(float a, float b) { return std::abs(a - b) <= 1e-5f * std::max(1.0f, std::max(std::abs(a), std::abs(b))); }

bool same_camera(const PinholeCamera& a, const PinholeCamera& b) {
  if (a.width != b.width || a.height != b.height || a.projection != b.projection) return false;
  if (!near(a.fl_x, b.fl_x) || !near(a.fl_y, b.fl_y) || !near(a.cx, b.cx) || !near(a.cy, b.cy)) return false;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c)
      if (!near(a.camera_to_world.matrix()(r, c), b.camera_to_world.matrix()(r, c))) return false;
  const LensDistortion &lens_a = a.distortion, &lens_b = b.distortion;
  return lens_a.model == lens_b.model && lens_a.k1 == lens_b.k1 && lens_a.k2 == lens_b.k2 && lens_a.k3 == lens_b.k3 &&
         lens_a.k4 == lens_b.k4 && lens_a.p1 == lens_b.p1 && lens_a.p2 == lens_b.p2;
}

void check_round_trip(const CaptureSet& read) {
  write_transforms(rewritten.string(), read);
  CaptureSet again;
  try {
    again = read_transforms(rewritten.string());
  } catch (const Error& e) {
    fuzz::finding(std::string("write_transforms wrote a set read_transforms refuses: ") + e.what());
  }
  if (again.frames.size() != read.frames.size()) fuzz::finding("the rewritten set has another number of frames");
  for (size_t i = 0; i < read.frames.size(); ++i) {
    const CaptureFrame &a = read.frames[i], &b = again.frames[i];
    if (a.file_path != b.file_path || a.mask_path != b.mask_path)
      fuzz::finding("frame " + std::to_string(i) + ": paths changed: " + a.file_path + " -> " + b.file_path);
    if (!same_camera(a.camera, b.camera)) fuzz::finding("frame " + std::to_string(i) + ": the camera changed");
  }
  if (again.object.index() != read.object.index()) fuzz::finding("the object changed kind");
  if (again.environment.has_value() != read.environment.has_value()) fuzz::finding("the environment was lost");
  if (again.material.has_value() != read.material.has_value()) fuzz::finding("the material was lost");
  if (again.renderer.has_value() != read.renderer.has_value()) fuzz::finding("the renderer was lost");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  scratch = glaze::fuzz::initialize_target("transforms");
  glaze::fuzz::write_capture_fixtures(scratch);
  rewritten = scratch / "rewritten";
  std::filesystem::create_directories(rewritten);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  glaze::fuzz::write_bytes(scratch / "transforms.json", data, size);
  try {
    check_round_trip(read_transforms(scratch.string()));
  } catch (const glaze::Error& e) {
    glaze::fuzz::refused(e);
  }
  return 0;
}
