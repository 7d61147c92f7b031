// Capture sets as other tools write them (docs/design.md §4): a NeRF-synthetic (Blender)
// set, whose intrinsics are "camera_angle_x" and the image's size, whose "file_path"
// has no extension and whose PNGs carry the object's mask as alpha; and a nerfstudio
// set whose poses went through "applied_transform". Each is made from a set that glaze
// rendered (the writer's cameras are the truth) and read back: its cameras, its paths,
// its masks, and a fit on it against the rendered material.
#include "inverse/capture_scene.h"
#include "inverse/samples.h"
#include "renderer/capture_set.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "test_support.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace glaze {
namespace {

using nlohmann::json;
using testing::TemporaryDirectory;
namespace fs = std::filesystem;

// A noise-free capture set of the red sphere (glaze's sh integrator), 64x64.
CaptureSet rendered_set(const TemporaryDirectory& dir) {
  const testing::CommandResult run =
      testing::run_glaze("render " + testing::scenes_dir() + "red_sphere_office.gltf --captures " + dir.file("glaze") +
                             " --integrator sh --ss 1 --lmax 16 --res 64x64",
                         dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return read_transforms(dir.file("glaze"));
}

// The glaze-only keys (what was photographed, under which light) of the set at `folder`,
// which foreign sets gain by hand; "environment" keeps its file's absolute path.
json glaze_keys(const std::string& folder) {
  json root = testing::read_json(folder + "/transforms.json");
  json keys = {{"object", root["object"]}, {"material", root["material"]}, {"renderer", root["renderer"]}};
  keys["environment"] = root["environment"];
  keys["environment"]["file"] = (fs::path(folder) / root["environment"]["file"].get<std::string>()).string();
  return keys;
}

json rows(const Eigen::Matrix4f& m, int count = 4) {
  json result = json::array();
  for (int r = 0; r < count; ++r) result.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  return result;
}

// Writes `image` as an 8-bit sRGB PNG with `alpha` (0 or 1 per pixel) as its fourth
// channel, scaled so that no code clips (clipped pixels would be dropped as saturated).
void write_png_with_alpha(const std::string& path, const Image& image, const std::vector<float>& alpha) {
  const float scale = 0.9f / *std::max_element(image.pixels.begin(), image.pixels.end());
  std::vector<unsigned char> rgba;
  for (size_t p = 0; p < alpha.size(); ++p) {
    for (int c = 0; c < 3; ++c)
      rgba.push_back(
          (unsigned char)std::lround(255.0f * linear_to_srgb(std::max(0.0f, scale * image.pixels[3 * p + c]))));
    rgba.push_back(alpha[p] > 0.5f ? 255 : 0);
  }
  fs::create_directories(fs::path(path).parent_path());
  auto out = OIIO::ImageOutput::create(path);
  OIIO::ImageSpec spec(image.width, image.height, 4, OIIO::TypeDesc::UINT8);
  spec.alpha_channel = 3;
  ASSERT_TRUE(out && out->open(path, spec) && out->write_image(OIIO::TypeDesc::UINT8, rgba.data()) && out->close());
}

// NeRF-synthetic: "camera_angle_x" at the top, "./train/r_N" without extension, RGBA
// PNGs whose alpha is 0 over the left third of each image.
TEST(ForeignCaptureSet, NerfSyntheticCameraAnglePathsAndAlpha) {
  TemporaryDirectory dir;
  const CaptureSet truth = rendered_set(dir);
  const PinholeCamera& first = truth.frames.front().camera;
  const double angle = 2.0 * std::atan(0.5 * first.width / double(first.fl_x));
  const std::string folder = dir.file("blender");
  json root = glaze_keys(dir.file("glaze"));
  root["camera_angle_x"] = angle;
  root["frames"] = json::array();
  size_t alpha_zero_columns = size_t(first.width / 3);
  for (size_t f = 0; f < truth.frames.size(); ++f) {
    const Image image = read_image(truth.frames[f].file_path);
    std::vector<float> alpha(size_t(image.width) * image.height, 1.0f);
    for (int y = 0; y < image.height; ++y)
      for (size_t x = 0; x < alpha_zero_columns; ++x) alpha[size_t(y) * image.width + x] = 0.0f;
    write_png_with_alpha(folder + "/train/r_" + std::to_string(f) + ".png", image, alpha);
    root["frames"].push_back({{"file_path", "./train/r_" + std::to_string(f)},
                              {"transform_matrix", rows(truth.frames[f].camera.camera_to_world.matrix())}});
  }
  std::ofstream(folder + "/transforms.json") << root.dump(2);

  const CaptureSet read = read_transforms(folder);
  ASSERT_EQ(read.frames.size(), truth.frames.size());
  for (size_t f = 0; f < read.frames.size(); ++f) {
    const PinholeCamera& camera = read.frames[f].camera;
    EXPECT_EQ(fs::path(read.frames[f].file_path), fs::path(folder) / ("./train/r_" + std::to_string(f) + ".png"));
    EXPECT_EQ(camera.width, first.width);  // from the PNG's header
    EXPECT_EQ(camera.height, first.height);
    // The reader holds the angle as a float (as every number of the file).
    const float focal = float(0.5 * first.width / std::tan(0.5 * double(float(angle))));
    EXPECT_EQ(camera.fl_x, focal);
    EXPECT_EQ(camera.fl_y, focal);
    EXPECT_NEAR(camera.fl_x, first.fl_x, 1e-3f);
    EXPECT_EQ(camera.cx, 0.5f * first.width);
    EXPECT_EQ(camera.cy, 0.5f * first.height);
    // The read camera's rays are the writer's.
    for (const Vec2& pixel : {Vec2(0.5f, 0.5f), Vec2(40.3f, 21.7f), Vec2(63.5f, 63.5f)}) {
      const Ray a = camera.generate_ray(pixel.x(), pixel.y());
      const Ray b = truth.frames[f].camera.generate_ray(pixel.x(), pixel.y());
      testing::expect_vec_near(a.origin, b.origin, 1e-6f, "origin");
      testing::expect_vec_near(a.direction, b.direction, 1e-5f, "direction");
    }
  }

  // Alpha as the mask: the samples lost are exactly those the left third would give.
  const Scene scene = capture_object_scene(read, PolishedMaterial(0.04f, RGB::Constant(0.5f)));
  const RayTracer tracer(scene);
  const SampleSet with_alpha = collect_samples(read, tracer, scene, {});
  const SampleSet unmasked = collect_samples(truth, tracer, scene, {});
  for (size_t f = 0; f < read.frames.size(); ++f) {
    size_t left = 0;
    size_t begin = 0;
    for (size_t g = 0; g < f; ++g) begin += unmasked.per_frame[g];
    for (size_t k = begin; k < begin + unmasked.per_frame[f]; ++k)
      left += unmasked.samples[k].film.x() < float(alpha_zero_columns);
    EXPECT_GT(left, 0u);
    EXPECT_EQ(with_alpha.dropped[f].masked, left) << "frame " << f;
    EXPECT_EQ(with_alpha.dropped[f].saturated, 0u);
    EXPECT_EQ(with_alpha.dropped[f].masked + with_alpha.per_frame[f], unmasked.per_frame[f]);
  }
}

// An extensionless path that names nothing: the message lists both paths tried.
TEST(ForeignCaptureSet, MissingExtensionlessPathNamesWhatWasTried) {
  TemporaryDirectory dir;
  const std::string folder = dir.file("blender");
  fs::create_directories(folder);
  write_image(folder + "/r_0.exr", Image(4, 4));
  json root = {{"camera_angle_x", 0.7},
               {"object", {{"type", "sphere"}, {"center", {0, 0, 0}}, {"radius", 1}}},
               {"frames", {{{"file_path", "./train/r_0"}, {"transform_matrix", rows(Eigen::Matrix4f::Identity())}}}}};
  std::ofstream(folder + "/transforms.json") << root.dump(2);
  try {
    read_transforms(folder);
    FAIL() << "read a set whose image does not exist";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("train/r_0,"), std::string::npos) << message;
    EXPECT_NE(message.find("train/r_0.png"), std::string::npos) << message;
  }
  // A path that exists as given is taken as it is (here an EXR), and so is its size.
  root["frames"][0]["file_path"] = "r_0.exr";
  std::ofstream(folder + "/transforms.json") << root.dump(2);
  const CaptureSet read = read_transforms(folder);
  EXPECT_EQ(read.frames[0].camera.width, 4);
  EXPECT_FLOAT_EQ(read.frames[0].camera.fl_x, float(2.0 / std::tan(0.35)));
}

// nerfstudio (ns-process-data from COLMAP): poses as written are A times the original
// ones, positions then scaled by "applied_scale"; the object and environment are in the
// original frame. The read poses are the writer's, and a fit recovers the material.
TEST(ForeignCaptureSet, NerfstudioAppliedTransformIsUndone) {
  TemporaryDirectory dir;
  const CaptureSet truth = rendered_set(dir);
  // nerfstudio's COLMAP-to-z-up rows (x, z, -y), with a translation added.
  Eigen::Matrix4f applied = Eigen::Matrix4f::Identity();
  applied.topLeftCorner<3, 3>() << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  applied.topRightCorner<3, 1>() = Vec3(0.5f, -1.0f, 2.0f);
  const float scale = 0.25f;
  const std::string folder = dir.file("nerfstudio");
  fs::create_directories(folder);
  json root = glaze_keys(dir.file("glaze"));
  const PinholeCamera& first = truth.frames.front().camera;
  root.update({{"w", first.width},
               {"h", first.height},
               {"fl_x", first.fl_x},
               {"fl_y", first.fl_y},
               {"cx", first.cx},
               {"cy", first.cy},
               {"camera_model", "PINHOLE"},
               {"applied_transform", rows(applied, 3)},
               {"applied_scale", scale}});
  root["frames"] = json::array();
  for (size_t f = 0; f < truth.frames.size(); ++f) {
    Eigen::Matrix4f written = applied * truth.frames[f].camera.camera_to_world.matrix();
    written.topRightCorner<3, 1>() *= scale;
    const std::string name = "images/frame_" + std::to_string(f + 1) + ".exr";
    fs::create_directories(folder + "/images");
    fs::copy_file(truth.frames[f].file_path, folder + "/" + name);
    root["frames"].push_back({{"file_path", name}, {"transform_matrix", rows(written)}});
  }
  std::ofstream(folder + "/transforms.json") << root.dump(2);

  const CaptureSet read = read_transforms(folder);
  for (size_t f = 0; f < read.frames.size(); ++f) {
    const Eigen::Matrix4f expected = truth.frames[f].camera.camera_to_world.matrix();
    const Eigen::Matrix4f actual = read.frames[f].camera.camera_to_world.matrix();
    EXPECT_LT((actual - expected).cwiseAbs().maxCoeff(), 1e-5f) << "frame " << f << "\n" << actual;
  }

  const testing::CommandResult fit =
      testing::run_glaze("invert-fit " + folder + " --mode material --out " + dir.file("fit"), dir);
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const json result = testing::read_json(dir.file("fit") + "/fit.json");
  const CaptureMaterial& material = *truth.material;
  EXPECT_NEAR(result["R0"].get<double>(), material.material.R0(), 2e-4);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(result["Rd"][c].get<double>(), material.material.Rd()[c], 1e-3);
}

// A transform that is not rigid is refused, naming the key.
TEST(ForeignCaptureSet, NonRigidAppliedTransformIsRefused) {
  TemporaryDirectory dir;
  const std::string folder = dir.file("set");
  fs::create_directories(folder);
  write_image(folder + "/a.exr", Image(4, 4));
  json root = {{"w", 4},
               {"h", 4},
               {"fl_x", 4},
               {"fl_y", 4},
               {"cx", 2},
               {"cy", 2},
               {"applied_transform", {{2, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}},
               {"object", {{"type", "sphere"}, {"center", {0, 0, 0}}, {"radius", 1}}},
               {"frames", {{{"file_path", "a.exr"}, {"transform_matrix", rows(Eigen::Matrix4f::Identity())}}}}};
  std::ofstream(folder + "/transforms.json") << root.dump(2);
  try {
    read_transforms(folder);
    FAIL() << "read a scaling applied_transform";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("\"applied_transform\""), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not a rotation"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace glaze
