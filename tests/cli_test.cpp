// Tests of the `glaze` command as a user meets it: output formats, and bad input giving
// a clear message and a non-zero exit status, never a crash.
#include "renderer/environment.h"
#include "renderer/image.h"
#include "renderer/procedural_environment.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <map>
#include <sstream>

namespace glaze {
namespace {

using testing::CommandResult;
using testing::expect_clear_failure;

CommandResult glaze(const std::string& arguments, const testing::TemporaryDirectory& dir) {
  return testing::run_glaze(arguments, dir);
}

TEST(Cli, ShPrintsJsonWithTheRequestedBand) {
  testing::TemporaryDirectory dir;
  const CommandResult run = glaze("sh procedural:constant --lmax 3 --res 64x32", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["lmax"], 3);
  ASSERT_EQ(json["L_lm"].size(), 16u);
  EXPECT_NEAR(json["L_lm"][0][1].get<double>(), 2 * std::sqrt(kPiD), 1e-9);
  EXPECT_LT(std::abs(json["L_lm"][5][0].get<double>()), 1e-6);
}

TEST(Cli, ProceduralMapWrittenToFileProjectsLikeTheGeneratedOne) {
  testing::TemporaryDirectory dir;
  ASSERT_EQ(glaze("env procedural blue-room --out " + dir.file("blue.exr") + " --res 128x64", dir).exit_code, 0);
  const CommandResult from_file = glaze("sh " + dir.file("blue.exr") + " --scale 2 --rotation 45", dir);
  const CommandResult generated = glaze("sh procedural:blue-room --res 128x64 --scale 2 --rotation 45", dir);
  ASSERT_EQ(from_file.exit_code, 0) << from_file.err;
  const auto a = nlohmann::json::parse(from_file.out)["L_lm"], b = nlohmann::json::parse(generated.out)["L_lm"];
  ASSERT_EQ(a.size(), 25u);
  for (size_t i = 0; i < a.size(); ++i)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[i][c].get<double>(), b[i][c].get<double>(), 1e-9) << i;
}

TEST(Cli, BadInputGivesClearErrors) {
  testing::TemporaryDirectory dir;
  expect_clear_failure(glaze("sh " + dir.file("missing.exr"), dir), "missing.exr");
  std::ofstream(dir.file("text.hdr")) << "not an image";
  expect_clear_failure(glaze("sh " + dir.file("text.hdr"), dir), "text.hdr");
  write_image(dir.file("full.exr"), make_procedural_environment("office", 128, 64));
  std::filesystem::copy_file(dir.file("full.exr"), dir.file("cut.exr"));
  std::filesystem::resize_file(dir.file("cut.exr"), std::filesystem::file_size(dir.file("full.exr")) / 3);
  expect_clear_failure(glaze("sh " + dir.file("cut.exr"), dir), "cut.exr");
  expect_clear_failure(glaze("sh procedural:attic", dir), "known: constant, office, blue-room");
  expect_clear_failure(glaze("sh procedural:office --lmax 99", dir), "lmax");
  expect_clear_failure(glaze("sh procedural:office --lmax two", dir), "--lmax");
  expect_clear_failure(glaze("sh procedural:office --to-world 1,0,0,0,1,0", dir), "--to-world");
  expect_clear_failure(glaze("sh procedural:office --to-world 2,0,0,0,1,0,0,0,1", dir), "rotation");
  expect_clear_failure(glaze("sh procedural:office --bogus 1", dir), "--bogus");
  expect_clear_failure(glaze("sh procedural:office --lmx 2", dir), "did you mean --lmax?");
  expect_clear_failure(glaze("frobnicate", dir), "frobnicate");
  expect_clear_failure(glaze("sh procedural:office --rotation 1e40", dir), "--rotation");
  expect_clear_failure(glaze("sh procedural:office --res 99999999999x5", dir), "--res");
  expect_clear_failure(glaze("sh procedural:office --lmax 2 --lmax 3", dir), "twice");
  std::ofstream(dir.file("empty.exr"));  // a zero-byte file
  expect_clear_failure(glaze("sh " + dir.file("empty.exr"), dir), "empty.exr");
  expect_clear_failure(glaze("env procedural office --out " + dir.file("no/such/dir/x.exr"), dir), "x.exr");
  expect_clear_failure(glaze("env procedural office --out " + dir.file("no/such/dir/x.exr"), dir), "does not exist");
  expect_clear_failure(glaze("env procedural office --out " + dir.file("x.nosuchformat"), dir), ".png or .jpg");
}

TEST(Cli, HelpAfterACommandPrintsTheHelp) {
  testing::TemporaryDirectory dir;
  for (const char* command : {"render --help", "invert-fit -h", "preview --help"}) {
    const CommandResult run = glaze(command, dir);
    EXPECT_EQ(run.exit_code, 0) << command << ": " << run.err;
    EXPECT_NE(run.out.find("options of `invert-fit`"), std::string::npos) << command;
  }
}

TEST(Cli, NonTwoToOneMapWarnsButWorks) {
  testing::TemporaryDirectory dir;
  Image square(16, 16);
  std::fill(square.pixels.begin(), square.pixels.end(), 1.0f);
  write_image(dir.file("square.exr"), square);
  const CommandResult run = glaze("sh " + dir.file("square.exr") + " --lmax 1", dir);
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_NE(run.err.find("not 2:1"), std::string::npos) << run.err;
}

TEST(Cli, RenderWithTheShIntegrator) {
  testing::TemporaryDirectory dir;
  const std::string scenes = std::string(GLAZE_SOURCE_DIR) + "/scenes/";
  const CommandResult run = glaze("render " + scenes + "red_sphere_office.gltf --integrator sh --lmax 6 --ss 2 --res 32x32 --out " + dir.file("sh.exr"), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const Image image = read_image(dir.file("sh.exr"));
  EXPECT_EQ(image.width, 32);
  EXPECT_GT(image.at(16, 16)[0], image.at(16, 16)[1]);  // a red sphere
  // Not a single convex object: rendered, with a warning that occlusion is ignored.
  const CommandResult still = glaze("render " + scenes + "still_life_office.gltf --integrator sh --res 32x24 --out " + dir.file("still.exr"), dir);
  EXPECT_EQ(still.exit_code, 0) << still.err;
  EXPECT_NE(still.err.find("occlusion"), std::string::npos) << still.err;
  expect_clear_failure(glaze("render " + scenes + "red_sphere_office.gltf --integrator sh --lmax 99 --out " + dir.file("x.exr"), dir), "--lmax");
  expect_clear_failure(glaze("render " + scenes + "red_sphere_office.gltf --integrator sh --spp 4 --out " + dir.file("x.exr"), dir), "--spp");
  expect_clear_failure(glaze("render " + scenes + "red_sphere_office.gltf --lmax 4 --out " + dir.file("x.exr"), dir), "--lmax");
  expect_clear_failure(glaze("render " + scenes + "red_sphere_office.gltf --integrator photon --out " + dir.file("x.exr"), dir), "photon");
  // Refinement: reported, only for sh, and not for capture sets.
  const CommandResult refined = glaze("render " + scenes + "red_sphere_office.gltf --integrator sh --ss 1 --ss-refine 4 --res 32x32 --out " + dir.file("refined.exr"), dir);
  ASSERT_EQ(refined.exit_code, 0) << refined.err;
  EXPECT_NE(refined.err.find("refined 4"), std::string::npos) << refined.err;
  expect_clear_failure(glaze("render " + scenes + "red_sphere_office.gltf --ss-refine 4 --out " + dir.file("x.exr"), dir), "--ss-refine");
  expect_clear_failure(glaze("render " + scenes + "red_sphere_office.gltf --integrator sh --ss-refine 4 --captures " + dir.file("set"), dir), "--ss-refine");
}

// The study on a tiny frame: every row and file is there, the path tracer's error falls
// like 1/sqrt(spp) and the sh integrator's with lmax, and the plot has ink on it.
TEST(Cli, ConvergenceWritesTheStudy) {
  testing::TemporaryDirectory dir;
  const std::string scene = std::string(GLAZE_SOURCE_DIR) + "/scenes/red_sphere_office.gltf";
  const CommandResult run = glaze("convergence " + scene + " --res 32x32 --ref-spp 512 --max-spp 16 --out " + dir.file("study"), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("relative RMSE 1%"), std::string::npos) << run.out;

  std::map<std::string, double> error;  // setting -> relative RMSE
  std::ifstream csv(dir.file("study/convergence.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "integrator,setting,seconds,relative_rmse,max_error,relative_rmse_beyond_reference_noise");
  int rows = 0;
  while (std::getline(csv, line)) {
    std::stringstream fields(line);
    std::string integrator, setting, seconds, rmse;
    std::getline(fields, integrator, ',');
    std::getline(fields, setting, ',');
    std::getline(fields, seconds, ',');
    std::getline(fields, rmse, ',');
    error[setting] = std::stod(rmse);
    EXPECT_GT(std::stod(seconds), 0.0) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 5 + 25);  // 1..16 spp, 5 lmax x (ss 1, 2, 4, and ss 1 and 2 refined to 8)
  EXPECT_LT(error["16 spp"], 0.5 * error["1 spp"]);  // 1/4 expected
  EXPECT_GT(error["16 spp"], 0.1 * error["1 spp"]);
  EXPECT_LT(error["lmax 12 ss 4"], error["lmax 2 ss 4"]);
  // Refining the pixels whose 2 x 2 samples show an edge removes most of ss 2's aliasing.
  EXPECT_LT(error["lmax 12 ss 2 refined 8"], error["lmax 12 ss 2"]);

  std::ifstream split(dir.file("study/split.csv"));
  int split_rows = -1;
  while (std::getline(split, line)) ++split_rows;
  EXPECT_EQ(split_rows, 25);
  const nlohmann::json summary = nlohmann::json::parse(std::ifstream(dir.file("study/summary.json")));
  EXPECT_GT(summary["reference"]["relative_noise"].get<double>(), 0.0);
  EXPECT_TRUE(summary["time_to"].contains("0.01"));
  // A target the reference's own noise cannot resolve has no time, and says why.
  const double noise = summary["reference"]["relative_noise"].get<double>();
  for (const char* target : {"0.01", "0.003"})
    EXPECT_EQ(summary["time_to"][target].contains("resolvable"), noise > 0.5 * std::stod(target)) << target << ", noise " << noise;
  const Image plot = read_image(dir.file("study/convergence.png"));
  EXPECT_EQ(plot.width, 960);
  int ink = 0;
  for (float value : plot.pixels) ink += value < 0.5f;
  EXPECT_GT(ink, 1000);

  expect_clear_failure(glaze("convergence " + scene + " --res 16x16 --ref " + dir.file("study/reference.exr") + " --out " + dir.file("x"), dir), "--res");
  expect_clear_failure(glaze("convergence " + scene + " --ref a.exr --ref-spp 8 --out " + dir.file("x"), dir), "--ref");
  expect_clear_failure(glaze("convergence " + scene + " --res 8x8 --ref-spp 64 --max-spp 32 --out " + dir.file("x"), dir), "--max-spp");
}

TEST(Cli, DemoRunsOnTheEmbeddedDefault) {
  testing::TemporaryDirectory dir;
  const CommandResult run = glaze("demo --out " + dir.file("demo") + " --spp 16 --res 96x96", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("recovered against true"), std::string::npos) << run.out;
  const nlohmann::json fit = nlohmann::json::parse(std::ifstream(dir.file("demo/fit/fit.json")));
  EXPECT_NEAR(fit["R0"].get<double>(), 0.0452, 0.005);
  EXPECT_NEAR(fit["Rd"][0].get<double>(), 0.9765, 0.01);
  EXPECT_EQ(fit["holdout"].size(), 2u);
}

}  // namespace
}  // namespace glaze
