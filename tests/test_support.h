// test_support.h: helpers shared by the test suites: where the real data lives, a
// temporary directory, capturing warnings, a chi-square goodness-of-fit test, and the
// unit sphere seen from the front that many renderer tests look at.
#pragma once

#include "renderer/camera.h"
#include "renderer/error.h"
#include "renderer/scene.h"

#include <gtest/gtest.h>
#include <sys/wait.h>

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

#define GLAZE_REQUIRE_ENVMAP(variable, name)                                                        \
  const std::filesystem::path variable = ::glaze::testing::envmap(name);                            \
  if (variable.empty())                                                                             \
  GTEST_SKIP() << "real environment map " << name << " not found under "                            \
               << ::glaze::testing::data_dir() << "/envmaps (set GLAZE_DATA_DIR); skipping"

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

// The result of running the glaze command.
struct CommandResult {
  int exit_code;
  bool crashed;  // killed by a signal (or a shell-reported one)
  std::string out, err;
};

// Runs `glaze ARGUMENTS` (the build's executable), capturing stdout and stderr.
// `prefix` runs glaze under another command (env, xvfb-run).
inline CommandResult run_glaze(const std::string& arguments, const TemporaryDirectory& dir, const std::string& prefix = "") {
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
