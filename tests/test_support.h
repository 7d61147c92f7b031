// test_support.h: helpers shared by the test suites: where the real data lives, a
// temporary directory, capturing warnings, running the glaze command, capture sets
// (a sphere scene of any material, rewriting or adding noise to its frames), a
// chi-square goodness-of-fit test, and the unit sphere seen from the front that many
// renderer tests look at.
#pragma once

#include "renderer/camera.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/rng.h"
#include "renderer/scene.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace glaze::testing {

// One unit sphere at the origin with material (R0, Rd).
inline Scene sphere_scene(float R0, const RGB& Rd) {
  Scene scene;
  scene.path = "test-sphere";
  scene.materials.push_back({"test", R0, Rd, -1});
  scene.spheres.push_back({"ball", Vec3::Zero(), 1.0f, 0, Mat3::Identity()});
  return scene;
}

// A size x size camera at (0, 0, 4) looking at the origin, 30 degree field of view.
inline PinholeCamera front_camera(int size) {
  Eigen::Affine3f pose = Eigen::Affine3f::Identity();
  pose.translation() = Vec3(0, 0, 4);
  return PinholeCamera::from_vertical_fov("front", pose, 30.0f * kPi / 180.0f, size, size);
}

// ../shared/data by default (relative to the source tree); GLAZE_DATA_DIR overrides.
inline std::filesystem::path data_dir() {
  if (const char* env = std::getenv("GLAZE_DATA_DIR")) return env;
  return std::filesystem::path(GLAZE_SOURCE_DIR) / ".." / "shared" / "data";
}

// Path of a real environment map, or empty (the caller skips, saying why).
inline std::filesystem::path envmap(const std::string& name) {
  const auto path = data_dir() / "envmaps" / name;
  return std::filesystem::exists(path) ? path : std::filesystem::path();
}

#define GLAZE_REQUIRE_ENVMAP(variable, name)                                                             \
  const std::filesystem::path variable = ::glaze::testing::envmap(name);                                 \
  if (variable.empty())                                                                                  \
  GTEST_SKIP() << "real environment map " << name << " not found under " << ::glaze::testing::data_dir() \
               << "/envmaps (set GLAZE_DATA_DIR); skipping"

// A fresh directory under the system temp dir, removed at scope exit.
class TemporaryDirectory {
 public:
  TemporaryDirectory() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            ("glaze_test_" + std::string(info ? info->name() : "x") + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TemporaryDirectory() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// Collects warnings while alive.
class CapturedWarnings {
 public:
  CapturedWarnings() {
    previous_ = set_warning_sink([this](const std::string& message) { messages.push_back(message); });
  }
  ~CapturedWarnings() { set_warning_sink(previous_); }
  std::vector<std::string> messages;

 private:
  WarningSink previous_;
};

// Each component of `actual` within `tolerance` of `expected`.
inline void expect_vec_near(const Vec3& actual, const Vec3& expected, float tolerance, const std::string& what = "") {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(actual[k], expected[k], tolerance) << what << " component " << k;
}

// `text` with the temporary directory's path replaced by "DIR", so that a word cannot be
// found in the path (the test's name, the process id) instead of in the message.
inline std::string without_directory(std::string text, const TemporaryDirectory& dir) {
  const std::string directory = dir.path().string();
  for (size_t at; (at = text.find(directory)) != std::string::npos;) text.replace(at, directory.size(), "DIR");
  return text;
}

// A path quoted for the shell command line of run_glaze.
inline std::string quoted(const std::string& path) { return "'" + path + "'"; }

// The result of running the glaze command.
struct CommandResult {
  int exit_code;
  bool crashed;  // killed by a signal (or a shell-reported one)
  std::string out, err;
};

// Runs `glaze ARGUMENTS` (the build's executable), capturing stdout and stderr.
// `prefix` runs glaze under another command (env, xvfb-run).
inline CommandResult run_glaze(const std::string& arguments, const TemporaryDirectory& dir,
                               const std::string& prefix = "") {
  const std::string err_file = dir.file("stderr.txt");
  const std::string command = prefix + std::string(GLAZE_EXECUTABLE) + " " + arguments + " 2>" + err_file;
  FILE* pipe = popen(command.c_str(), "r");
  CommandResult run{};
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) run.out.append(buffer.data(), n);
  const int status = pclose(pipe);
  run.crashed = WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) >= 128);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream stream(err_file);
  run.err.assign(std::istreambuf_iterator<char>(stream), {});
  return run;
}

// A failure as users should meet it: exit status 1, no crash, "glaze: error:" and a
// message that mentions `must_mention`.
inline void expect_clear_failure(const CommandResult& run, const std::string& must_mention) {
  EXPECT_FALSE(run.crashed) << run.err;
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("glaze: error:"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find(must_mention), std::string::npos) << run.err;
}

// `glaze render PATH --out x.exr [extra]` must fail cleanly and mention `word`.
inline void expect_render_refused(const TemporaryDirectory& dir, const std::string& path, const std::string& word,
                                  const std::string& extra = "") {
  const CommandResult run =
      run_glaze("render " + quoted(path) + " --out " + quoted(dir.file("x.exr")) + " --res 8x8 --spp 1 " + extra, dir);
  EXPECT_FALSE(run.crashed) << run.err;
  EXPECT_EQ(run.exit_code, 1) << run.err;
  const std::string err = without_directory(run.err, dir);
  const size_t error = err.find("glaze: error:");
  ASSERT_NE(error, std::string::npos) << run.err;
  // The error itself (not a warning printed before it) must mention the word.
  EXPECT_NE(err.find(word, error), std::string::npos) << "'" << word << "' not in the error: " << err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("x.exr")));
}

// The repository's scenes/ folder, with a trailing slash.
inline std::string scenes_dir() { return std::string(GLAZE_SOURCE_DIR) + "/scenes/"; }

inline nlohmann::json read_json(const std::string& path) {
  std::ifstream file(path);
  return nlohmann::json::parse(file);
}

// Rewrites every frame of the capture set in `folder`: each pixel value becomes
// `transform(value, rng)`, with one generator (seed 7) over all frames in order.
template <typename Transform>
void rewrite_frames(const std::string& folder, Transform transform) {
  const nlohmann::json transforms = read_json(folder + "/transforms.json");
  Pcg32 rng(7);
  for (const auto& frame : transforms["frames"]) {
    const std::string file = folder + "/" + frame["file_path"].get<std::string>();
    Image image = read_image(file);
    for (float& value : image.pixels) value = transform(value, rng);
    write_image(file, image);
  }
}

// Every number anywhere in `value` is finite. nlohmann writes NaN and infinities as
// null, so a null is one too.
inline void expect_all_finite(const nlohmann::json& value, const std::string& where) {
  if (value.is_null()) {
    ADD_FAILURE() << where << " is null (a NaN or an infinity written to JSON)";
  } else if (value.is_number()) {
    EXPECT_TRUE(std::isfinite(value.get<double>())) << where << " = " << value.dump();
  } else if (value.is_object()) {
    for (const auto& [key, item] : value.items()) expect_all_finite(item, where + "." + key);
  } else if (value.is_array()) {
    for (size_t i = 0; i < value.size(); ++i) expect_all_finite(value[i], where + "[" + std::to_string(i) + "]");
  }
}

// A draw of N(0, 1) from `rng` (Box-Muller, two uniform draws).
inline float standard_normal(Pcg32& rng) {
  const float u1 = std::max(rng.next_float(), 1e-7f), u2 = rng.next_float();
  return std::sqrt(-2.0f * std::log(u1)) * std::cos(2.0f * kPi * u2);
}

// Multiplies every pixel value of the capture set in `folder` by 1 + sigma * N(0, 1):
// sigma = 0.05 is "5% noise".
inline void add_multiplicative_noise(const std::string& folder, float sigma) {
  rewrite_frames(folder, [sigma](float value, Pcg32& rng) { return value * (1.0f + sigma * standard_normal(rng)); });
}

// A copy of scenes/red_sphere_office.gltf (the unit sphere, three input views and two
// novel ones, the procedural office) with material (R0, Rd), written to dir/NAME.
inline std::string sphere_scene_file(const TemporaryDirectory& dir, float R0, const RGB& Rd,
                                     const std::string& name = "sphere.gltf") {
  nlohmann::json scene = read_json(scenes_dir() + "red_sphere_office.gltf");
  scene["materials"][0]["extras"]["glaze"] = {{"R0", R0}, {"Rd", {Rd[0], Rd[1], Rd[2]}}};
  scene["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = {Rd[0], Rd[1], Rd[2], 1.0};
  const std::string file = dir.file(name);
  std::ofstream(file) << scene.dump();
  return file;
}

// Upper tail probability of the chi-square distribution (regularised incomplete gamma
// Q(k/2, x/2) by its series / continued fraction, Numerical Recipes style).
inline double chi_square_upper_tail(double x, double dof) {
  const double a = 0.5 * dof, z = 0.5 * x;
  if (z <= 0.0) return 1.0;
  const double log_prefix = -z + a * std::log(z) - std::lgamma(a);
  if (z < a + 1.0) {  // series for P
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 1000; ++n) {
      term *= z / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-15) break;
    }
    return 1.0 - sum * std::exp(log_prefix);
  }
  double b = z + 1.0 - a, c = 1e300, d = 1.0 / b, h = d;  // Lentz continued fraction for Q
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < 1e-300) d = 1e-300;
    c = b + an / c;
    if (std::abs(c) < 1e-300) c = 1e-300;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-15) break;
  }
  return std::exp(log_prefix) * h;
}

// Pearson's chi-square test of observed counts against expected counts (same total).
// Bins with expected count < 5 are pooled, as the test requires. Returns the p-value.
inline double chi_square_p_value(const std::vector<double>& observed, const std::vector<double>& expected) {
  double statistic = 0.0, pooled_observed = 0.0, pooled_expected = 0.0;
  int bins = 0;
  for (size_t i = 0; i < observed.size(); ++i) {
    if (expected[i] < 5.0) {
      pooled_observed += observed[i];
      pooled_expected += expected[i];
      continue;
    }
    statistic += std::pow(observed[i] - expected[i], 2) / expected[i];
    ++bins;
  }
  if (pooled_expected > 0.0) {
    statistic += std::pow(pooled_observed - pooled_expected, 2) / pooled_expected;
    ++bins;
  }
  return chi_square_upper_tail(statistic, bins - 1);
}

}  // namespace glaze::testing
