// Tests of reading capture sets (docs/design.md §4): round trips through write_transforms,
// shared and per-frame intrinsics, paths resolved against the directory of
// transforms.json, and one test per malformed input, each checking that the message
// names the file and the key or problem at fault.
//
// Every capture set is written by the test into a temporary directory, with small EXR
// images for its frames; malformed ones are a valid set with one thing broken.
#include "renderer/camera.h"
#include "renderer/capture_set.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace glaze {
namespace {

using nlohmann::json;
using testing::TemporaryDirectory;

// ---------------------------------------------------------------------------------------
// Helpers: poses, images, a valid set to break, and checking rejections.
// ---------------------------------------------------------------------------------------

// A rigid camera-to-world pose: rotation by `degrees` about `axis`, then translation `t`.
Eigen::Affine3f rigid(float degrees, const Vec3& axis, const Vec3& t) {
  Eigen::Affine3f pose = Eigen::Affine3f::Identity();
  pose.linear() = Eigen::AngleAxisf(degrees * kPi / 180.0f, axis.normalized()).toRotationMatrix();
  pose.translation() = t;
  return pose;
}

PinholeCamera camera(const std::string& name, int w, int h, float fl_x, float fl_y, float cx, float cy,
                     const Eigen::Affine3f& pose) {
  PinholeCamera c;
  c.name = name;
  c.width = w, c.height = h;
  c.fl_x = fl_x, c.fl_y = fl_y, c.cx = cx, c.cy = cy;
  c.camera_to_world = pose;
  return c;
}

// A small image at DIR/NAME (creating folders), for a frame or mask to point at.
void write_view(const TemporaryDirectory& dir, const std::string& name) {
  const std::filesystem::path path = dir.path() / name;
  std::filesystem::create_directories(path.parent_path());
  write_image(path.string(), Image(4, 3));
}

void write_text(const std::filesystem::path& path, const std::string& text) { std::ofstream(path) << text; }

json sphere_object() { return {{"type", "sphere"}, {"center", {0.0, 0.0, 0.0}}, {"radius", 1.0}}; }

// A camera-to-world pose as transforms.json writes it: 4 rows of 4 numbers.
json pose_json(const Eigen::Affine3f& pose) {
  json rows = json::array();
  for (int r = 0; r < 4; ++r) rows.push_back({pose(r, 0), pose(r, 1), pose(r, 2), pose(r, 3)});
  return rows;
}

json frame_json(const std::string& file, const Eigen::Affine3f& pose) {
  return {{"file_path", file}, {"transform_matrix", pose_json(pose)}};
}

// A valid set in `dir`: shared intrinsics, two 4x3 views (their images written), a sphere.
json valid_transforms(const TemporaryDirectory& dir) {
  write_view(dir, "view_000.exr");
  write_view(dir, "view_001.exr");
  return {{"w", 4},
          {"h", 3},
          {"fl_x", 5.0},
          {"fl_y", 5.0},
          {"cx", 2.0},
          {"cy", 1.5},
          {"frames",
           {frame_json("view_000.exr", rigid(0, Vec3::UnitY(), Vec3(0, 0, 4))),
            frame_json("view_001.exr", rigid(90, Vec3::UnitY(), Vec3(4, 0, 0)))}},
          {"object", sphere_object()}};
}

// Success if `read` throws glaze::Error whose message mentions every one of `words`.
::testing::AssertionResult fails_mentioning(const std::function<void()>& read, const std::vector<std::string>& words) {
  try {
    read();
  } catch (const Error& e) {
    const std::string message = e.what();
    for (const std::string& word : words)
      if (message.find(word) == std::string::npos)
        return ::testing::AssertionFailure() << "the message does not mention '" << word << "': " << message;
    return ::testing::AssertionSuccess() << message;
  } catch (const std::exception& e) {
    return ::testing::AssertionFailure() << "threw something other than glaze::Error: " << e.what();
  }
  return ::testing::AssertionFailure() << "read_transforms accepted it";
}

// Writes `transforms` as DIR/transforms.json; success if reading it fails with a message
// that names the file and every one of `words`.
::testing::AssertionResult rejected(const TemporaryDirectory& dir, const json& transforms,
                                    std::vector<std::string> words) {
  write_text(dir.path() / "transforms.json", transforms.dump(2));
  words.push_back(dir.file("transforms.json"));
  return fails_mentioning([&] { read_transforms(dir.path().string()); }, words);
}

// The set read back from `transforms` written as DIR/transforms.json.
CaptureSet read_back(const TemporaryDirectory& dir, const json& transforms) {
  write_text(dir.path() / "transforms.json", transforms.dump(2));
  return read_transforms(dir.path().string());
}

void expect_same_material(const PolishedMaterial& read, const PolishedMaterial& written) {
  EXPECT_EQ(read.R0(), written.R0());
  EXPECT_TRUE((read.Rd() == written.Rd()).all()) << read.Rd().transpose() << " written " << written.Rd().transpose();
}

void expect_same_camera(const PinholeCamera& read, const PinholeCamera& written) {
  EXPECT_EQ(read.name, written.name);
  EXPECT_EQ(read.width, written.width) << written.name;
  EXPECT_EQ(read.height, written.height) << written.name;
  EXPECT_EQ(read.fl_x, written.fl_x) << written.name;
  EXPECT_EQ(read.fl_y, written.fl_y) << written.name;
  EXPECT_EQ(read.cx, written.cx) << written.name;
  EXPECT_EQ(read.cy, written.cy) << written.name;
  EXPECT_TRUE(read.camera_to_world.matrix().isApprox(written.camera_to_world.matrix(), 1e-6f))
      << written.name << "\n"
      << read.camera_to_world.matrix() << "\nwritten\n"
      << written.camera_to_world.matrix();
}

// ---------------------------------------------------------------------------------------
// 1. Round trips and what comes back.
// ---------------------------------------------------------------------------------------

// Three cameras with the same intrinsics: written once at the top, read into each frame.
TEST(CaptureSet, RoundTripWithSharedIntrinsics) {
  TemporaryDirectory dir;
  CaptureSet set;
  set.object = CaptureSphere{Vec3(0.25f, -1, 3), 1.5f};
  set.environment = CaptureEnvironment{"", "constant", {2.0f, 30.0f}};
  set.material = CaptureMaterial{PolishedMaterial(0.04f, RGB(0.6f, 0.5f, 0.4f)), ""};
  set.saturation = 60000.0f;
  const std::vector<Eigen::Affine3f> poses = {rigid(0, Vec3::UnitY(), Vec3(0, 0, 4)),
                                              rigid(90, Vec3::UnitY(), Vec3(4, 0.5f, 0)),
                                              rigid(-37, Vec3(1, 2, 3), Vec3(-1.25f, 3, 0.1f))};
  for (size_t i = 0; i < poses.size(); ++i) {
    const std::string file = "view_00" + std::to_string(i) + ".exr";
    write_view(dir, file);
    set.frames.push_back({file, camera("cam_" + std::to_string(i), 32, 24, 30.5f, 31.25f, 16.1f, 11.9f, poses[i]), ""});
  }
  write_transforms(dir.path().string(), set);
  std::ifstream stream(dir.path() / "transforms.json");
  const json written = json::parse(stream);
  ASSERT_TRUE(written.contains("fl_x")) << "intrinsics should be shared at the top level";
  ASSERT_FALSE(written["frames"][0].contains("fl_x"));

  const CaptureSet back = read_transforms(dir.path().string());
  ASSERT_EQ(back.frames.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    expect_same_camera(back.frames[i].camera, set.frames[i].camera);
    EXPECT_EQ(back.frames[i].file_path, (dir.path() / set.frames[i].file_path).string());
    EXPECT_EQ(back.frames[i].mask_path, "");
  }
  EXPECT_EQ(back.directory, dir.path().string());
  ASSERT_TRUE(back.saturation.has_value());
  EXPECT_EQ(*back.saturation, 60000.0f);
  const CaptureSphere* sphere = std::get_if<CaptureSphere>(&back.object);
  ASSERT_NE(sphere, nullptr);
  EXPECT_TRUE(sphere->center == Vec3(0.25f, -1, 3)) << sphere->center.transpose();
  EXPECT_EQ(sphere->radius, 1.5f);
  ASSERT_TRUE(back.environment.has_value());
  EXPECT_EQ(back.environment->file, "");
  EXPECT_EQ(back.environment->procedural, "constant");
  EXPECT_EQ(back.environment->options.scale, 2.0f);
  EXPECT_EQ(back.environment->options.rotation_degrees, 30.0f);
  EXPECT_TRUE(back.environment->options.to_world == Mat3::Identity());
  ASSERT_TRUE(back.material.has_value());
  expect_same_material(back.material->material, set.material->material);
  EXPECT_EQ(back.material->texture, "");
  EXPECT_FALSE(back.renderer.has_value());
}

// Cameras with different intrinsics: written per frame, read back per frame; without a
// saturation, environment or material, those come back absent.
TEST(CaptureSet, RoundTripWithPerFrameIntrinsics) {
  TemporaryDirectory dir;
  CaptureSet set;
  write_view(dir, "a.exr");
  write_view(dir, "b.exr");
  set.frames.push_back({"a.exr", camera("wide", 64, 48, 20, 20, 32, 24, rigid(10, Vec3::UnitX(), Vec3(0, 1, 5))), ""});
  set.frames.push_back(
      {"b.exr", camera("tele", 40, 30, 80, 81, 19.5f, 15.5f, rigid(200, Vec3(0, 1, 1), Vec3(3, -2, 1))), ""});
  write_transforms(dir.path().string(), set);
  std::ifstream stream(dir.path() / "transforms.json");
  const json written = json::parse(stream);
  ASSERT_FALSE(written.contains("fl_x")) << "intrinsics differ, so they should be per frame";
  ASSERT_TRUE(written["frames"][1].contains("fl_x"));

  const CaptureSet back = read_transforms(dir.path().string());
  ASSERT_EQ(back.frames.size(), 2u);
  for (size_t i = 0; i < 2; ++i) expect_same_camera(back.frames[i].camera, set.frames[i].camera);
  EXPECT_FALSE(back.saturation.has_value());
  EXPECT_FALSE(back.environment.has_value());
  EXPECT_FALSE(back.material.has_value());
  EXPECT_FALSE(back.renderer.has_value());
}

// Every typed field, written and read back: a glTF object (its path resolved), an
// environment with a file, a procedural name and every option, a material with a
// texture (resolved, though it need not exist), and each integrator the renderer names.
TEST(CaptureSet, TypedFieldsComeBackAsWritten) {
  TemporaryDirectory dir;
  write_view(dir, "view.exr");
  write_view(dir, "env.exr");
  write_text(dir.path() / "object.gltf", "{}");
  CaptureSet set;
  set.frames.push_back({"view.exr", camera("cam", 4, 3, 5, 5, 2, 1.5f, rigid(0, Vec3::UnitY(), Vec3(0, 0, 4))), ""});
  set.object = CaptureGltf{"object.gltf"};
  const Mat3 to_world = Eigen::AngleAxisf(0.3f, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  set.environment = CaptureEnvironment{"env.exr", "office", {0.75f, -45.5f, to_world, EnvironmentFormat::mirror_ball}};
  set.material = CaptureMaterial{PolishedMaterial(0.1f, RGB(0.2f, 0.3f, 0.45f)), "albedo.png"};
  set.renderer = CaptureRenderer{.integrator = CaptureRenderer::Integrator::sh, .supersampling = 3, .lmax = 7};
  write_transforms(dir.path().string(), set);

  CaptureSet back = read_transforms(dir.path().string());
  ASSERT_TRUE(std::holds_alternative<CaptureGltf>(back.object));
  EXPECT_EQ(std::get<CaptureGltf>(back.object).file, dir.file("object.gltf"));
  ASSERT_TRUE(back.environment.has_value());
  EXPECT_EQ(back.environment->file, dir.file("env.exr"));
  EXPECT_EQ(back.environment->procedural, "office");
  EXPECT_EQ(back.environment->options.scale, 0.75f);
  EXPECT_EQ(back.environment->options.rotation_degrees, -45.5f);
  EXPECT_TRUE(back.environment->options.to_world == to_world) << back.environment->options.to_world;
  EXPECT_EQ(back.environment->options.format, EnvironmentFormat::mirror_ball);
  ASSERT_TRUE(back.material.has_value());
  expect_same_material(back.material->material, set.material->material);
  EXPECT_EQ(back.material->texture, dir.file("albedo.png"));
  ASSERT_TRUE(back.renderer.has_value());
  EXPECT_EQ(back.renderer->integrator, CaptureRenderer::Integrator::sh);
  EXPECT_EQ(back.renderer->supersampling, 3);
  EXPECT_EQ(back.renderer->lmax, 7);

  set.renderer = CaptureRenderer{.integrator = CaptureRenderer::Integrator::path, .spp = 64};
  write_transforms(dir.path().string(), set);
  back = read_transforms(dir.path().string());
  ASSERT_TRUE(back.renderer.has_value());
  EXPECT_EQ(back.renderer->integrator, CaptureRenderer::Integrator::path);
  EXPECT_EQ(back.renderer->spp, 64);
}

// A frame's own intrinsic overrides the top-level one; the others stay shared.
TEST(CaptureSet, PerFrameIntrinsicOverridesTopLevel) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][1]["fl_x"] = 7.5;
  transforms["frames"][1]["w"] = 8;
  const CaptureSet set = read_back(dir, transforms);
  EXPECT_EQ(set.frames[0].camera.fl_x, 5.0f);
  EXPECT_EQ(set.frames[0].camera.width, 4);
  EXPECT_EQ(set.frames[1].camera.fl_x, 7.5f);
  EXPECT_EQ(set.frames[1].camera.width, 8);
  EXPECT_EQ(set.frames[1].camera.fl_y, 5.0f);
  EXPECT_EQ(set.frames[1].camera.cy, 1.5f);
}

// Frames without a "camera" are named by their index; a whole-number float is a size.
TEST(CaptureSet, FramesWithoutCameraNamesAreNumbered) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["w"] = 4.0;
  const CaptureSet set = read_back(dir, transforms);
  ASSERT_EQ(set.frames.size(), 2u);
  EXPECT_EQ(set.frames[0].camera.name, "frame_000");
  EXPECT_EQ(set.frames[1].camera.name, "frame_001");
  EXPECT_EQ(set.frames[0].camera.width, 4);
  // Frame 1 looks along -X: Ry(90) takes the camera's -Z to world -X.
  const Vec3 forward = set.frames[1].camera.camera_to_world.linear() * Vec3(0, 0, -1);
  EXPECT_NEAR(forward.x(), -1.0f, 1e-6f);
  EXPECT_NEAR(set.frames[1].camera.position().x(), 4.0f, 1e-6f);
}

// The same set whether named by its directory or by its transforms.json.
TEST(CaptureSet, ReadsByDirectoryOrByFile) {
  TemporaryDirectory dir;
  write_text(dir.path() / "transforms.json", valid_transforms(dir).dump());
  const CaptureSet by_directory = read_transforms(dir.path().string());
  const CaptureSet by_file = read_transforms(dir.file("transforms.json"));
  EXPECT_EQ(by_directory.directory, dir.path().string());
  EXPECT_EQ(by_file.directory, dir.path().string());
  ASSERT_EQ(by_file.frames.size(), by_directory.frames.size());
  for (size_t i = 0; i < by_file.frames.size(); ++i) {
    EXPECT_EQ(by_file.frames[i].file_path, by_directory.frames[i].file_path);
    expect_same_camera(by_file.frames[i].camera, by_directory.frames[i].camera);
  }
}

// Images, masks, the object's glTF and the environment map are found relative to the
// directory of transforms.json (not the working directory); absolute paths stay.
TEST(CaptureSet, PathsAreResolvedAgainstTheFilesDirectory) {
  TemporaryDirectory dir;
  const std::filesystem::path set_dir = dir.path() / "captures";
  write_view(dir, "captures/images/view_000.exr");
  write_view(dir, "captures/masks/mask_000.png");
  write_view(dir, "elsewhere/mask_001.png");
  write_view(dir, "captures/view_001.exr");
  write_view(dir, "env.exr");
  write_text(dir.path() / "object.gltf", "{}");
  const std::string absolute_mask = dir.file("elsewhere/mask_001.png");

  json transforms = valid_transforms(dir);
  transforms["frames"][0]["file_path"] = "images/view_000.exr";
  transforms["frames"][0]["mask_path"] = "masks/mask_000.png";
  transforms["frames"][1]["mask_path"] = absolute_mask;
  transforms["object"] = {{"gltf", "../object.gltf"}};
  transforms["environment"] = {{"file", "../env.exr"}, {"scale", 1.0}};
  write_text(set_dir / "transforms.json", transforms.dump());

  const CaptureSet set = read_transforms((set_dir / "transforms.json").string());
  EXPECT_EQ(set.directory, set_dir.string());
  ASSERT_EQ(set.frames.size(), 2u);
  EXPECT_EQ(set.frames[0].file_path, (set_dir / "images/view_000.exr").string());
  EXPECT_EQ(set.frames[0].mask_path, (set_dir / "masks/mask_000.png").string());
  EXPECT_EQ(set.frames[1].file_path, (set_dir / "view_001.exr").string());
  EXPECT_EQ(set.frames[1].mask_path, absolute_mask);
  ASSERT_TRUE(std::holds_alternative<CaptureGltf>(set.object));
  EXPECT_TRUE(std::filesystem::equivalent(std::get<CaptureGltf>(set.object).file, dir.path() / "object.gltf"));
  ASSERT_TRUE(set.environment.has_value());
  EXPECT_TRUE(std::filesystem::equivalent(set.environment->file, dir.path() / "env.exr"));
  EXPECT_EQ(set.environment->options.scale, 1.0f);
  // The resolved paths open as they are.
  EXPECT_EQ(read_image(set.frames[0].file_path).width, 4);
}

// What render --captures writes for a procedural environment: both "file" and
// "procedural"; the file is resolved, the name kept.
TEST(CaptureSet, ProceduralEnvironmentWithItsFile) {
  TemporaryDirectory dir;
  write_view(dir, "environment.exr");
  json transforms = valid_transforms(dir);
  transforms["environment"] = {{"file", "environment.exr"}, {"procedural", "office"}, {"rotation", -90.0}};
  const CaptureSet set = read_back(dir, transforms);
  ASSERT_TRUE(set.environment.has_value());
  EXPECT_EQ(set.environment->file, dir.file("environment.exr"));
  EXPECT_EQ(set.environment->procedural, "office");
  EXPECT_EQ(set.environment->options.rotation_degrees, -90.0f);
  transforms["environment"] = {{"procedural", "blue-room"}};
  const CaptureSet procedural = read_back(dir, transforms);
  ASSERT_TRUE(procedural.environment.has_value());
  EXPECT_EQ(procedural.environment->file, "");
  EXPECT_EQ(procedural.environment->procedural, "blue-room");
}

// OPENCV and PINHOLE with zero distortion are pinholes; a pose off orthonormal by float
// rounding is still rigid.
TEST(CaptureSet, AcceptsUndistortedCameraModelsAndRoundedPoses) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["camera_model"] = "OPENCV";
  for (const char* key : {"k1", "k2", "k3", "k4", "p1", "p2"}) transforms[key] = 0.0;
  transforms["frames"][1]["camera_model"] = "PINHOLE";
  transforms["frames"][0]["transform_matrix"] = {{1.00001, 0, 0, 0}, {0, 0.99999, 0, 0}, {0, 0, 1, 4}, {0, 0, 0, 1}};
  EXPECT_EQ(read_back(dir, transforms).frames.size(), 2u);
}

// ---------------------------------------------------------------------------------------
// 2. The file itself.
// ---------------------------------------------------------------------------------------

TEST(CaptureSet, MissingPathIsAnError) {
  TemporaryDirectory dir;
  const std::string path = dir.file("no_such_captures");
  EXPECT_TRUE(fails_mentioning([&] { read_transforms(path); }, {path, "no such file"}));
}

TEST(CaptureSet, DirectoryWithoutTransformsIsAnError) {
  TemporaryDirectory dir;
  EXPECT_TRUE(
      fails_mentioning([&] { read_transforms(dir.path().string()); }, {dir.file("transforms.json"), "not found"}));
}

TEST(CaptureSet, MalformedJsonIsAnError) {
  TemporaryDirectory dir;
  write_text(dir.path() / "transforms.json", "{\"frames\": [");
  EXPECT_TRUE(fails_mentioning([&] { read_transforms(dir.path().string()); },
                               {dir.file("transforms.json"), "not valid JSON", "parse_error"}));
}

// A literal beyond double range is nlohmann's overflow error, reported the same way.
TEST(CaptureSet, OverflowingNumberIsAnError) {
  TemporaryDirectory dir;
  std::string text = valid_transforms(dir).dump();
  text.replace(text.find("\"fl_x\":5.0"), std::string("\"fl_x\":5.0").size(), "\"fl_x\":1e999");
  write_text(dir.path() / "transforms.json", text);
  EXPECT_TRUE(fails_mentioning([&] { read_transforms(dir.path().string()); },
                               {dir.file("transforms.json"), "not valid JSON", "1e999"}));
}

TEST(CaptureSet, TopLevelNotAnObjectIsAnError) {
  TemporaryDirectory dir;
  EXPECT_TRUE(rejected(dir, json::array({1, 2}), {"top level", "array"}));
}

// ---------------------------------------------------------------------------------------
// 3. Frames and their files.
// ---------------------------------------------------------------------------------------

TEST(CaptureSet, MissingFramesIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms.erase("frames");
  EXPECT_TRUE(rejected(dir, transforms, {"no \"frames\""}));
}

TEST(CaptureSet, FramesNotAnArrayIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"] = transforms["frames"][0];
  EXPECT_TRUE(rejected(dir, transforms, {"\"frames\" must be a non-empty array"}));
}

TEST(CaptureSet, EmptyFramesIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"] = json::array();
  EXPECT_TRUE(rejected(dir, transforms, {"\"frames\" must be a non-empty array", "[]"}));
}

TEST(CaptureSet, FrameNotAnObjectIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][1] = "view_001.exr";
  EXPECT_TRUE(rejected(dir, transforms, {"frame 1", "must be an object"}));
}

TEST(CaptureSet, FrameWithoutFilePathIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][1].erase("file_path");
  EXPECT_TRUE(rejected(dir, transforms, {"frame 1", "no \"file_path\""}));
}

TEST(CaptureSet, FilePathNotAStringIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][0]["file_path"] = 42;
  EXPECT_TRUE(rejected(dir, transforms, {"frame 0", "\"file_path\" must be a file name", "42"}));
}

TEST(CaptureSet, EmptyFilePathIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][0]["file_path"] = "";
  EXPECT_TRUE(rejected(dir, transforms, {"frame 0", "\"file_path\" must be a file name"}));
}

TEST(CaptureSet, MissingImageIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][1]["file_path"] = "images/gone.exr";
  EXPECT_TRUE(rejected(dir, transforms,
                       {"frame 1 (\"images/gone.exr\")", (dir.path() / "images/gone.exr").string(), "does not exist"}));
}

TEST(CaptureSet, ImagePathNamingADirectoryIsAnError) {
  TemporaryDirectory dir;
  std::filesystem::create_directories(dir.path() / "images");
  json transforms = valid_transforms(dir);
  transforms["frames"][1]["file_path"] = "images";
  EXPECT_TRUE(rejected(dir, transforms, {"frame 1", "not a file"}));
}

TEST(CaptureSet, MissingMaskIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][0]["mask_path"] = "mask_000.png";
  EXPECT_TRUE(rejected(dir, transforms,
                       {"frame 0 (\"view_000.exr\")", "\"mask_path\"", dir.file("mask_000.png"), "does not exist"}));
}

TEST(CaptureSet, CameraNameNotAStringIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][0]["camera"] = 3;
  EXPECT_TRUE(rejected(dir, transforms, {"frame 0", "\"camera\" must be the camera's name"}));
}

// ---------------------------------------------------------------------------------------
// 4. Intrinsics.
// ---------------------------------------------------------------------------------------

// Neither at the top level nor in frame 1: the message names the key and the frame.
TEST(CaptureSet, MissingIntrinsicIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms.erase("fl_x");
  transforms["frames"][0]["fl_x"] = 5.0;
  EXPECT_TRUE(rejected(dir, transforms, {"frame 1 (\"view_001.exr\")", "no \"fl_x\"", "top level"}));
}

TEST(CaptureSet, IntrinsicNotANumberIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][1]["cy"] = "1.5";
  EXPECT_TRUE(rejected(dir, transforms, {"frame 1", "\"cy\" must be a finite number", "\"1.5\""}));
}

TEST(CaptureSet, FractionalWidthIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["w"] = 4.5;
  EXPECT_TRUE(rejected(dir, transforms, {"\"w\" must be a whole number of pixels", "4.5"}));
}

TEST(CaptureSet, ZeroHeightIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][0]["h"] = 0;
  EXPECT_TRUE(rejected(dir, transforms, {"frame 0", "\"h\" must be a whole number of pixels from 1"}));
}

TEST(CaptureSet, AbsurdWidthIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["w"] = 100000;
  EXPECT_TRUE(rejected(dir, transforms, {"\"w\"", "to 65536", "100000"}));
}

TEST(CaptureSet, ZeroFocalLengthIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["fl_x"] = 0;
  EXPECT_TRUE(rejected(dir, transforms, {"\"fl_x\" must be a finite number > 0"}));
}

TEST(CaptureSet, NegativeFocalLengthIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][1]["fl_y"] = -5.0;
  EXPECT_TRUE(rejected(dir, transforms, {"frame 1", "\"fl_y\" must be a finite number > 0", "-5.0"}));
}

// 1e300 is a double but no float: the camera would hold infinity.
TEST(CaptureSet, FocalLengthBeyondFloatIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["fl_x"] = 1e300;
  EXPECT_TRUE(rejected(dir, transforms, {"\"fl_x\" must be a finite number", "1e+300"}));
}

TEST(CaptureSet, PrincipalPointBeyondFloatIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["cx"] = -1e300;
  EXPECT_TRUE(rejected(dir, transforms, {"\"cx\" must be a finite number", "-1e+300"}));
}

// ---------------------------------------------------------------------------------------
// 5. Lens distortion and camera models.
// ---------------------------------------------------------------------------------------

TEST(CaptureSet, OpencvDistortionIsReadAsGivenTopLevelOrPerFrame) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["camera_model"] = "OPENCV";
  transforms["k1"] = -0.12;
  transforms["k2"] = 0.031;
  transforms["frames"][1]["p2"] = 0.001;
  const CaptureSet set = read_back(dir, transforms);
  for (const CaptureFrame& frame : set.frames) {
    EXPECT_EQ(frame.camera.distortion.model, LensDistortion::Model::opencv);
    EXPECT_EQ(frame.camera.distortion.k1, -0.12) << "read as a double, not rounded through a float";
    EXPECT_EQ(frame.camera.distortion.k2, 0.031);
  }
  EXPECT_EQ(set.frames[0].camera.distortion.p2, 0.0);
  EXPECT_EQ(set.frames[1].camera.distortion.p2, 0.001);
}

// nerfstudio reads coefficients without a "camera_model" as OPENCV.
TEST(CaptureSet, CoefficientsWithoutAModelAreOpencv) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][1]["p2"] = 0.001;
  const CaptureSet set = read_back(dir, transforms);
  EXPECT_EQ(set.frames[0].camera.distortion.model, LensDistortion::Model::none);
  EXPECT_EQ(set.frames[1].camera.distortion.model, LensDistortion::Model::opencv);
}

TEST(CaptureSet, FisheyeIsReadEvenWithZeroCoefficients) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["camera_model"] = "OPENCV_FISHEYE";
  transforms["frames"][0]["k4"] = 0.002;
  const CaptureSet set = read_back(dir, transforms);
  // k = 0 is the equidistant fisheye (theta' = theta), not a pinhole.
  EXPECT_EQ(set.frames[1].camera.distortion.model, LensDistortion::Model::opencv_fisheye);
  EXPECT_EQ(set.frames[0].camera.distortion.k4, 0.002);
}

TEST(CaptureSet, CoefficientsOfAnotherModelAreAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][0]["k4"] = 0.3;  // k4 is the fisheye's; without a model, OPENCV is assumed
  EXPECT_TRUE(rejected(dir, transforms, {"frame 0", "\"k4\"", "OPENCV camera model", "assumed", "OPENCV_FISHEYE"}));
  transforms = valid_transforms(dir);
  transforms["camera_model"] = "PINHOLE";
  transforms["frames"][1]["k1"] = -0.1;
  EXPECT_TRUE(rejected(dir, transforms, {"\"k1\"", "PINHOLE camera model"}));
  transforms = valid_transforms(dir);
  transforms["camera_model"] = "OPENCV_FISHEYE";
  transforms["p1"] = 0.01;
  EXPECT_TRUE(rejected(dir, transforms, {"\"p1\"", "OPENCV_FISHEYE camera model"}));
}

TEST(CaptureSet, DistortionNotANumberIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["k2"] = "none";
  EXPECT_TRUE(rejected(dir, transforms, {"\"k2\" must be a finite number"}));
}

TEST(CaptureSet, CameraModelsGlazeCannotCastRaysThroughAreAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["camera_model"] = "SIMPLE_RADIAL";
  EXPECT_TRUE(rejected(dir, transforms,
                       {"\"camera_model\"", "SIMPLE_RADIAL", "not supported", "OPENCV_FISHEYE", "image_undistorter"}));
}

// A barrel term strong enough to fold the image back inside the film leaves pixels with
// no ray: refused, naming the film point.
TEST(CaptureSet, LensThatFoldsInsideTheFilmIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["k1"] = -0.5;  // r (1 - 0.5 r^2) peaks at 0.544; the 4x3 film's corners at f 5 are at 0.5 ...
  EXPECT_EQ(read_back(dir, transforms).frames[0].camera.distortion.k1, -0.5);
  transforms["fl_x"] = transforms["fl_y"] = 2.0;  // ... and at f 2 at 1.25
  EXPECT_TRUE(rejected(dir, transforms, {"OPENCV lens model", "folds back", "4x3 film"}));
}

TEST(CaptureSet, DistortedCamerasRoundTripThroughTheWriter) {
  TemporaryDirectory dir;
  CaptureSet set;
  set.object = CaptureSphere{};
  for (int i = 0; i < 3; ++i) {
    PinholeCamera c =
        camera("view_" + std::to_string(i), 4, 3, 5, 5.5f, 2, 1.5f, rigid(40.0f * i, Vec3::UnitY(), Vec3(0, 0, 4)));
    c.distortion = i == 2 ? LensDistortion{LensDistortion::Model::opencv_fisheye, 0.01, -0.002, 0.0003, -0.00004}
                          : LensDistortion{LensDistortion::Model::opencv, -0.1, 0.02, 0.003, 0, 0.0011, -0.0007};
    set.frames.push_back({"view_" + std::to_string(i) + ".exr", c, {}});
    write_view(dir, set.frames.back().file_path);
  }
  write_transforms(dir.path().string(), set);
  const CaptureSet read = read_transforms(dir.path().string());
  ASSERT_EQ(read.frames.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const LensDistortion &a = read.frames[i].camera.distortion, &b = set.frames[i].camera.distortion;
    EXPECT_EQ(a.model, b.model) << i;
    EXPECT_EQ(std::vector<double>({a.k1, a.k2, a.k3, a.k4, a.p1, a.p2}),
              std::vector<double>({b.k1, b.k2, b.k3, b.k4, b.p1, b.p2}))
        << i;
  }
}

// ---------------------------------------------------------------------------------------
// 6. Poses.
// ---------------------------------------------------------------------------------------

TEST(CaptureSet, MissingTransformMatrixIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][1].erase("transform_matrix");
  EXPECT_TRUE(rejected(dir, transforms, {"frame 1 (\"view_001.exr\")", "no \"transform_matrix\""}));
}

TEST(CaptureSet, ThreeRowTransformMatrixIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][0]["transform_matrix"].erase(3);
  EXPECT_TRUE(rejected(dir, transforms, {"frame 0", "\"transform_matrix\" must be 4 rows of 4 numbers"}));
}

TEST(CaptureSet, ShortTransformMatrixRowIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][0]["transform_matrix"][2] = {0, 0, 1};
  EXPECT_TRUE(rejected(dir, transforms, {"frame 0", "\"transform_matrix[2]\" must be an array of 4 numbers"}));
}

TEST(CaptureSet, TransformMatrixEntryNotANumberIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][0]["transform_matrix"][1][3] = "up";
  EXPECT_TRUE(rejected(dir, transforms, {"frame 0", "\"transform_matrix[1][3]\" must be a finite number"}));
}

TEST(CaptureSet, TransformMatrixEntryBeyondFloatIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][1]["transform_matrix"][0][3] = 1e300;
  EXPECT_TRUE(rejected(dir, transforms, {"frame 1", "\"transform_matrix[0][3]\" must be a finite number"}));
}

TEST(CaptureSet, ProjectiveLastRowIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][0]["transform_matrix"][3] = {0, 0, 0.1, 1};
  EXPECT_TRUE(rejected(dir, transforms, {"frame 0", "last row of \"transform_matrix\"", "rigid camera-to-world"}));
}

TEST(CaptureSet, ScaledPoseIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][0]["transform_matrix"] = {{2, 0, 0, 0}, {0, 2, 0, 0}, {0, 0, 2, 4}, {0, 0, 0, 1}};
  EXPECT_TRUE(
      rejected(dir, transforms, {"frame 0", "\"transform_matrix\" is not a rotation", "rigid camera-to-world"}));
}

TEST(CaptureSet, SingularPoseIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][1]["transform_matrix"] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 0, 4}, {0, 0, 0, 1}};
  EXPECT_TRUE(rejected(dir, transforms, {"frame 1", "not a rotation", "det R = 0", "rigid camera-to-world"}));
}

// Orthonormal but a mirror image (determinant -1).
TEST(CaptureSet, MirroredPoseIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["frames"][0]["transform_matrix"] = {{-1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 4}, {0, 0, 0, 1}};
  EXPECT_TRUE(rejected(dir, transforms, {"frame 0", "not a rotation", "det R = -1", "rigid camera-to-world"}));
}

// ---------------------------------------------------------------------------------------
// 7. The object.
// ---------------------------------------------------------------------------------------

TEST(CaptureSet, MissingObjectIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms.erase("object");
  EXPECT_TRUE(rejected(dir, transforms, {"no \"object\"", "sphere", "gltf"}));
}

TEST(CaptureSet, UnknownObjectTypeIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["object"]["type"] = "cube";
  EXPECT_TRUE(rejected(dir, transforms, {"\"object\"", "cube", "\"type\": \"sphere\""}));
}

TEST(CaptureSet, ObjectNotAnObjectIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["object"] = "sphere";
  EXPECT_TRUE(rejected(dir, transforms, {"\"object\"", "must be"}));
}

TEST(CaptureSet, SphereAndGltfTogetherIsAnError) {
  TemporaryDirectory dir;
  write_text(dir.path() / "object.gltf", "{}");
  json transforms = valid_transforms(dir);
  transforms["object"]["gltf"] = "object.gltf";
  EXPECT_TRUE(rejected(dir, transforms, {"\"object\"", "must be"}));
}

TEST(CaptureSet, SphereWithoutRadiusIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["object"].erase("radius");
  EXPECT_TRUE(rejected(dir, transforms, {"\"object\"", "no \"radius\""}));
}

TEST(CaptureSet, NegativeSphereRadiusIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["object"]["radius"] = -1.0;
  EXPECT_TRUE(rejected(dir, transforms, {"\"object\"", "\"radius\" must be a finite number > 0"}));
}

TEST(CaptureSet, SphereCenterOfTwoNumbersIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["object"]["center"] = {0.0, 1.0};
  EXPECT_TRUE(rejected(dir, transforms, {"\"object\"", "\"center\" must be an array of 3 numbers"}));
}

TEST(CaptureSet, SphereCenterBeyondFloatIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["object"]["center"][1] = 1e300;
  EXPECT_TRUE(rejected(dir, transforms, {"\"object\"", "\"center[1]\" must be a finite number"}));
}

TEST(CaptureSet, SphereRadiusNotANumberIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["object"]["radius"] = "1";
  EXPECT_TRUE(rejected(dir, transforms, {"\"object\"", "\"radius\" must be a finite number > 0"}));
}

TEST(CaptureSet, GltfNotAStringIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["object"] = {{"gltf", 5}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"object\"", "\"gltf\" must be a file name"}));
}

TEST(CaptureSet, MissingGltfFileIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["object"] = {{"gltf", "object.glb"}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"object\"", "\"gltf\"", dir.file("object.glb"), "does not exist"}));
}

// ---------------------------------------------------------------------------------------
// 8. The known material.
// ---------------------------------------------------------------------------------------

TEST(CaptureSet, MaterialNotAnObjectIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["material"] = 0.04;
  EXPECT_TRUE(rejected(dir, transforms, {"\"material\"", "must be {\"R0\""}));
}

TEST(CaptureSet, MaterialWithoutR0IsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["material"] = {{"Rd", {0.5, 0.5, 0.5}}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"material\"", "no \"R0\""}));
}

TEST(CaptureSet, R0AboveOneIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["material"] = {{"R0", 1.5}, {"Rd", {0.5, 0.5, 0.5}}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"material\"", "\"R0\" must be a number in [0, 1]", "1.5"}));
}

TEST(CaptureSet, RdOfTwoNumbersIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["material"] = {{"R0", 0.04}, {"Rd", {0.5, 0.5}}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"material\"", "\"Rd\" must be an array of 3 numbers"}));
}

TEST(CaptureSet, NegativeRdIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["material"] = {{"R0", 0.04}, {"Rd", {0.5, -0.1, 0.5}}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"material\"", "\"Rd[1]\" must be a number in [0, 1]"}));
}

TEST(CaptureSet, R0NotANumberIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["material"] = {{"R0", "0.04"}, {"Rd", {0.5, 0.5, 0.5}}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"material\"", "\"R0\" must be a number in [0, 1]", "\"0.04\""}));
}

TEST(CaptureSet, MaterialTextureNotAStringIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["material"] = {{"R0", 0.04}, {"Rd", {0.5, 0.5, 0.5}}, {"texture", 5}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"material\"", "\"texture\" must be a file name"}));
}

// ---------------------------------------------------------------------------------------
// 9. The environment and the saturation level.
// ---------------------------------------------------------------------------------------

TEST(CaptureSet, EnvironmentNotAnObjectIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["environment"] = "env.exr";
  EXPECT_TRUE(rejected(dir, transforms, {"\"environment\"", "must be {\"file\""}));
}

TEST(CaptureSet, EnvironmentWithoutFileOrProceduralIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["environment"] = {{"scale", 1.0}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"environment\"", "\"procedural\""}));
}

TEST(CaptureSet, MissingEnvironmentFileIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["environment"] = {{"file", "env.exr"}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"environment\"", "\"file\"", dir.file("env.exr"), "does not exist"}));
}

TEST(CaptureSet, ProceduralNotAStringIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["environment"] = {{"procedural", 1}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"environment\"", "\"procedural\" must be the name"}));
}

TEST(CaptureSet, NegativeEnvironmentScaleIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["environment"] = {{"procedural", "office"}, {"scale", -2.0}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"environment\"", "\"scale\" must be a finite number >= 0"}));
}

TEST(CaptureSet, EnvironmentRotationBeyondFloatIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["environment"] = {{"procedural", "office"}, {"rotation", 1e300}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"environment\"", "\"rotation\" must be a finite number"}));
}

TEST(CaptureSet, EnvironmentToWorldNotThreeRowsOfThreeNumbersIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["environment"] = {{"procedural", "office"}, {"to_world", {{1, 0, 0}, {0, 1, 0}}}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"environment\"", "\"to_world\" must be 3 rows of 3 numbers"}));
  transforms["environment"]["to_world"] = {{1, 0, 0}, {0, 1, 0}, {0, "one", 1}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"environment\"", "to_world[2]"}));
  // A well-formed one comes back as it was, for the fit to use.
  transforms["environment"]["to_world"] = {{0, 0, 1}, {0, 1, 0}, {-1, 0, 0}};
  const std::optional<CaptureEnvironment> environment = read_back(dir, transforms).environment;
  ASSERT_TRUE(environment.has_value());
  Mat3 expected;
  expected << 0, 0, 1, 0, 1, 0, -1, 0, 0;
  EXPECT_TRUE(environment->options.to_world == expected) << environment->options.to_world;
}

TEST(CaptureSet, ZeroSaturationIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["saturation"] = 0;
  EXPECT_TRUE(rejected(dir, transforms, {"\"saturation\" must be a finite number > 0"}));
}

TEST(CaptureSet, SaturationNotANumberIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["saturation"] = "high";
  EXPECT_TRUE(rejected(dir, transforms, {"\"saturation\" must be a finite number", "\"high\""}));
}

// ---------------------------------------------------------------------------------------
// 10. How glaze rendered the images.
// ---------------------------------------------------------------------------------------

TEST(CaptureSet, RendererNotAnObjectIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["renderer"] = "sh";
  EXPECT_TRUE(rejected(dir, transforms, {"\"renderer\"", "must be {\"integrator\""}));
}

TEST(CaptureSet, IntegratorNotAStringIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["renderer"] = {{"integrator", 5}, {"spp", 4}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"renderer\"", "\"integrator\" must be \"path\" or \"sh\", not 5"}));
}

TEST(CaptureSet, UnknownIntegratorIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["renderer"] = {{"integrator", "bidirectional"}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"renderer\"", "\"integrator\"", "bidirectional"}));
  transforms["renderer"] = {{"spp", 4}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"renderer\"", "no \"integrator\""}));
}

TEST(CaptureSet, IntegratorWithoutItsSettingsIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["renderer"] = {{"integrator", "path"}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"renderer\"", "no \"spp\""}));
  transforms["renderer"] = {{"integrator", "sh"}, {"lmax", 4}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"renderer\"", "no \"ss\""}));
  transforms["renderer"] = {{"integrator", "sh"}, {"ss", 2}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"renderer\"", "no \"lmax\""}));
}

// Formerly read as "not said" (and the fits' defaults used instead): now each names its key.
TEST(CaptureSet, IntegratorSettingOfTheWrongTypeIsAnError) {
  TemporaryDirectory dir;
  json transforms = valid_transforms(dir);
  transforms["renderer"] = {{"integrator", "path"}, {"spp", "many"}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"renderer\"", "\"spp\" must be a whole number", "\"many\""}));
  transforms["renderer"] = {{"integrator", "sh"}, {"ss", 2.5}, {"lmax", 4}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"renderer\"", "\"ss\" must be a whole number", "2.5"}));
  transforms["renderer"] = {{"integrator", "sh"}, {"ss", 0}, {"lmax", 4}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"renderer\"", "\"ss\" must be a whole number from 1"}));
  transforms["renderer"] = {{"integrator", "sh"}, {"ss", 2}, {"lmax", 65}};
  EXPECT_TRUE(rejected(dir, transforms, {"\"renderer\"", "\"lmax\" must be a whole number from 0 to 64", "65"}));
}

}  // namespace
}  // namespace glaze
