// Tests of the `glaze` command as a user meets it: output formats, and bad input giving
// a clear message and a non-zero exit status, never a crash.
#include "renderer/environment.h"
#include "renderer/image.h"
#include "renderer/procedural_environment.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>

namespace glaze {
namespace {

using testing::CommandResult;
using testing::expect_clear_failure;
using testing::run_glaze;

TEST(Cli, ShPrintsJsonWithTheRequestedBand) {
  testing::TemporaryDirectory dir;
  const CommandResult run = run_glaze("sh procedural:constant --lmax 3 --res 64x32", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["lmax"], 3);
  ASSERT_EQ(json["L_lm"].size(), 16u);
  EXPECT_NEAR(json["L_lm"][0][1].get<double>(), 2 * std::sqrt(kPiD), 1e-9);
  EXPECT_LT(std::abs(json["L_lm"][5][0].get<double>()), 1e-6);
  // Integers are decimal: 010 is ten, not octal eight.
  EXPECT_EQ(nlohmann::json::parse(run_glaze("sh procedural:constant --lmax 010 --res 64x32", dir).out)["lmax"], 10);
  // A float option is float(strtod(text)): 1 + 2^-24 + 2^-60 is rounded to a double (the
  // midpoint 1 + 2^-24), then to 1, not to the float above 1 that one rounding would give.
  const std::string sh = "sh procedural:constant --lmax 0 --res 64x32 --scale ";
  EXPECT_EQ(run_glaze(sh + "1.0000000596046447762579867379884035472", dir).out, run_glaze(sh + "1", dir).out);
}

TEST(Cli, ProceduralMapWrittenToFileProjectsLikeTheGeneratedOne) {
  testing::TemporaryDirectory dir;
  ASSERT_EQ(run_glaze("env procedural blue-room --out " + dir.file("blue.exr") + " --res 128x64", dir).exit_code, 0);
  const CommandResult from_file = run_glaze("sh " + dir.file("blue.exr") + " --scale 2 --rotation 45", dir);
  const CommandResult generated = run_glaze("sh procedural:blue-room --res 128x64 --scale 2 --rotation 45", dir);
  ASSERT_EQ(from_file.exit_code, 0) << from_file.err;
  const auto a = nlohmann::json::parse(from_file.out)["L_lm"], b = nlohmann::json::parse(generated.out)["L_lm"];
  ASSERT_EQ(a.size(), 25u);
  for (size_t i = 0; i < a.size(); ++i)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[i][c].get<double>(), b[i][c].get<double>(), 1e-9) << i;
}

TEST(Cli, BadInputGivesClearErrors) {
  testing::TemporaryDirectory dir;
  expect_clear_failure(run_glaze("sh " + dir.file("missing.exr"), dir), "missing.exr");
  std::ofstream(dir.file("text.hdr")) << "not an image";
  expect_clear_failure(run_glaze("sh " + dir.file("text.hdr"), dir), "text.hdr");
  write_image(dir.file("full.exr"), make_procedural_environment("office", 128, 64));
  std::filesystem::copy_file(dir.file("full.exr"), dir.file("cut.exr"));
  std::filesystem::resize_file(dir.file("cut.exr"), std::filesystem::file_size(dir.file("full.exr")) / 3);
  expect_clear_failure(run_glaze("sh " + dir.file("cut.exr"), dir), "cut.exr");
  expect_clear_failure(run_glaze("sh procedural:attic", dir), "known: constant, office, blue-room");
  expect_clear_failure(run_glaze("sh procedural:office --lmax 99", dir), "lmax");
  expect_clear_failure(run_glaze("sh procedural:office --lmax two", dir), "--lmax");
  expect_clear_failure(run_glaze("sh procedural:office --to-world 1,0,0,0,1,0", dir), "--to-world");
  expect_clear_failure(run_glaze("sh procedural:office --to-world 2,0,0,0,1,0,0,0,1", dir), "rotation");
  expect_clear_failure(run_glaze("sh procedural:office --bogus 1", dir), "--bogus");
  expect_clear_failure(run_glaze("sh procedural:office --lmx 2", dir), "did you mean --lmax?");
  expect_clear_failure(run_glaze("frobnicate", dir), "frobnicate");
  expect_clear_failure(run_glaze("sh procedural:office --rotation 1e40", dir), "--rotation");
  expect_clear_failure(run_glaze("sh procedural:office --res 99999999999x5", dir), "--res");
  expect_clear_failure(run_glaze("sh procedural:office --lmax 2 --lmax 3", dir), "twice");
  std::ofstream(dir.file("empty.exr"));  // a zero-byte file
  expect_clear_failure(run_glaze("sh " + dir.file("empty.exr"), dir), "empty.exr");
  expect_clear_failure(run_glaze("env procedural office --out " + dir.file("no/such/dir/x.exr"), dir), "x.exr");
  expect_clear_failure(run_glaze("env procedural office --out " + dir.file("no/such/dir/x.exr"), dir),
                       "does not exist");
  expect_clear_failure(run_glaze("env procedural office --out " + dir.file("x.nosuchformat"), dir), ".png or .jpg");
}

// Every command with the options it takes: its --help lists each.
const std::map<std::string, std::vector<std::string>> kCommandOptions = {
    {"demo", {"--out", "--spp", "--res", "--photos"}},
    {"sh", {"--env-format", "--lmax", "--scale", "--rotation", "--to-world", "--res"}},
    {"env", {"--out", "--res"}},
    {"env-convert", {"--env-format", "--to", "--out", "--size", "--res"}},
    {"render", {"--out",         "--captures",  "--camera",       "--res",       "--holdout",    "--env",
                "--env-format",  "--env-scale", "--env-rotation", "--threads",   "--integrator", "--spp",
                "--time-budget", "--max-depth", "--estimator",    "--seed",      "--lmax",       "--ss",
                "--ss-refine",   "--exposure",  "--tone-map",     "--look-from", "--look-at",    "--fov"}},
    {"convergence",
     {"--out", "--camera", "--res", "--ref-spp", "--ref", "--ref-noise", "--max-spp", "--seed", "--threads",
      "--max-depth", "--env", "--env-format", "--env-scale", "--env-rotation", "--look-from", "--look-at", "--fov"}},
    {"invert-fit", {"--mode",        "--out",        "--lmax",         "--pixel-footprint",
                    "--points",      "--seed",       "--min-cos",      "--max-iterations",
                    "--env",         "--env-format", "--env-scale",    "--env-rotation",
                    "--holdout-dir", "--threads",    "--loss",         "--loss-scale",
                    "--texture-res", "--R0",         "--Rd",           "--env-res",
                    "--solve-res",   "--ridge",      "--diffuse-lmax", "--max-passes",
                    "--preview",     "--frames",     "--screenshot",   "--exposure",
                    "--tone-map"}},
    {"register", {"--out"}},
    {"captures", {"--out", "--response", "--probe-res", "--threads"}},
    {"simulate-shoot",
     {"--out", "--env", "--radius", "--views", "--elevation", "--distance", "--res", "--fov", "--lens", "--board",
      "--square", "--calibration", "--exposures", "--ev-step", "--format", "--seed", "--reflectance",
      "--known-intrinsics", "--threads"}},
#if GLAZE_HAVE_PREVIEW
    {"preview",
     {"--camera",   "--res",       "--integrator", "--lmax",      "--ss",           "--max-spp",  "--seed",
      "--threads",  "--max-depth", "--env",        "--env-scale", "--env-rotation", "--exposure", "--tone-map",
      "--save-dir", "--frames",    "--screenshot", "--spin",      "--look-from",    "--look-at",  "--fov"}},
#else
    {"preview", {}},
#endif
    {"reproduce",
     {"--out", "--quick", "--res", "--spp", "--seed", "--texture-res", "--env-res", "--lighting", "--real-maps",
      "--scenes", "--no-convergence", "--threads"}},
    {"help", {}},
};

// A line of `help` that lists `option`, or "".
std::string help_line(const std::string& help, const std::string& option) {
  const size_t at = help.find("\n  " + option + " ");
  return at == std::string::npos ? "" : help.substr(at + 1, help.find('\n', at + 1) - at - 1);
}

TEST(Cli, EveryCommandHasItsOwnHelp) {
  testing::TemporaryDirectory dir;
  const CommandResult overview = run_glaze("help", dir);
  EXPECT_EQ(overview.exit_code, 0) << overview.err;
  EXPECT_EQ(run_glaze("--help", dir).out, overview.out);
  EXPECT_EQ(run_glaze("", dir).exit_code, 2);  // no command: the overview, and a failure
  for (const auto& [command, options] : kCommandOptions) {
    EXPECT_NE(overview.out.find("\n  " + command + " "), std::string::npos) << command << "\n" << overview.out;
    const CommandResult run = run_glaze(command + " --help", dir);
    EXPECT_EQ(run.exit_code, 0) << command << " --help: " << run.err;
    EXPECT_NE(run.out.find("Usage: glaze " + command), std::string::npos) << command << " --help\n" << run.out;
    for (const std::string& option : options)
      EXPECT_NE(help_line(run.out, option), "") << command << " --help does not list " << option << "\n" << run.out;
    EXPECT_EQ(run_glaze(command + " -h", dir).out, run.out) << command;
    EXPECT_EQ(run_glaze("help " + command, dir).out, run.out) << command;
  }
#if !GLAZE_HAVE_PREVIEW
  EXPECT_NE(run_glaze("preview --help", dir).out.find("GLAZE_PREVIEW=OFF"), std::string::npos);
#endif
}

// Declared once, the options that several commands take have the same bounds in each.
TEST(Cli, SharedOptionsHaveOneBound) {
  testing::TemporaryDirectory dir;
  std::map<std::string, std::string> helps;  // each command's, asked once
  for (const std::string option :
       {"--threads", "--seed", "--max-depth", "--env-scale", "--exposure", "--tone-map", "--fov"}) {
    std::string bounds;
    for (const auto& [command, options] : kCommandOptions) {
      if (std::find(options.begin(), options.end(), option) == options.end()) continue;
      if (!helps.count(command)) helps[command] = run_glaze(command + " --help", dir).out;
      // The notes after the help, "[0 to 1024; default 0; needs --x]", less what it needs.
      const std::string line = help_line(helps[command], option);
      std::string these = line.substr(std::min(line.size(), line.rfind('[')));
      these = these.substr(0, std::min({these.find("; needs"), these.find("; not with"), these.find(']')}));
      if (bounds.empty()) bounds = these;
      EXPECT_EQ(these, bounds) << command << " " << option;
    }
  }
}

// Before any work, every command refuses an option it does not know and a value out of
// the option's range, naming the option.
TEST(Cli, UnknownOptionsAndOutOfRangeValuesNameTheOption) {
  testing::TemporaryDirectory dir;
  const std::string scene = std::string(GLAZE_SOURCE_DIR) + "/scenes/red_sphere_office.gltf";
  const std::string out = " --out " + dir.file("out");
  const std::map<std::string, std::pair<std::string, std::string>> commands = {
    // command line: an out-of-range option, and the option it names
    {"demo" + out, {"--spp 0", "--spp"}},
    {"sh procedural:office", {"--lmax 65", "--lmax"}},
    {"env procedural office" + out + ".exr", {"--res 0x512", "--res"}},
    {"render " + scene + out + ".exr", {"--threads 1025", "--threads"}},
    {"convergence " + scene + out, {"--seed -1", "--seed"}},
    {"invert-fit " + dir.file("captures") + " --mode material" + out, {"--pixel-footprint 17", "--pixel-footprint"}},
#if GLAZE_HAVE_PREVIEW
    {"preview " + scene, {"--max-spp 0", "--max-spp"}},
#endif
    {"reproduce" + out, {"--env-res 64x0", "--env-res"}},
    {"help", {"--bogus 1", "--bogus"}},
  };
  for (const auto& [command, bad] : commands) {
    // (No display: preview would fail at once, after its options.)
    expect_clear_failure(run_glaze(command + " --no-such-option 1", dir, "env -u DISPLAY "), "--no-such-option");
    expect_clear_failure(run_glaze(command + " " + bad.first, dir, "env -u DISPLAY "), bad.second);
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("out")));  // nothing ran
  // A value of an option that several commands take: refused by each alike.
  expect_clear_failure(run_glaze("render " + scene + out + ".exr --threads -1", dir), "--threads");
  expect_clear_failure(run_glaze("reproduce" + out + " --threads 1025", dir), "--threads");
  expect_clear_failure(run_glaze("invert-fit x --mode material" + out + " --seed 1.5", dir), "--seed");
}

// Options that exclude each other, or that only some modes take, are refused together.
TEST(Cli, RefusedCombinationsNameTheOptions) {
  testing::TemporaryDirectory dir;
  const std::string scene = std::string(GLAZE_SOURCE_DIR) + "/scenes/red_sphere_office.gltf";
  const std::string render = "render " + scene + " --out " + dir.file("x.exr");
  const std::string fit = "invert-fit " + dir.file("captures") + " --out " + dir.file("fit");
  expect_clear_failure(run_glaze(render + " --captures " + dir.file("c"), dir), "--captures");
  expect_clear_failure(run_glaze("render " + scene, dir), "--out");
  expect_clear_failure(run_glaze(render + " --holdout novel_0", dir), "--holdout");
  expect_clear_failure(run_glaze(render + " --exposure 1", dir), "--exposure");
  expect_clear_failure(run_glaze("convergence " + scene + " --out " + dir.file("c") + " --ref-noise 0.1", dir),
                       "--ref-noise");
  expect_clear_failure(run_glaze(fit + " --mode material --texture-res 8x8", dir), "--texture-res");
  expect_clear_failure(run_glaze(fit + " --mode material --R0 0.04 --Rd 0.5,0.5,0.5", dir), "--R0");
  expect_clear_failure(run_glaze(fit + " --mode texture --ridge 1e-3", dir), "--ridge");
  expect_clear_failure(run_glaze(fit + " --mode joint --loss huber", dir), "--loss");
  expect_clear_failure(run_glaze(fit + " --mode lighting --lmax 9", dir), "--lmax");
  expect_clear_failure(run_glaze(fit + " --mode material --frames 2", dir), "--frames");
  expect_clear_failure(run_glaze(fit + " --mode material --loss-scale 0.1", dir), "--loss-scale");
  expect_clear_failure(run_glaze(fit + " --mode material --holdout novel_0", dir), "--holdout-dir");
  expect_clear_failure(run_glaze(fit + " --mode lighting --Rd 0.5,0.5", dir), "--Rd");
  for (const char* output : {"x.exr", "c", "fit"}) EXPECT_FALSE(std::filesystem::exists(dir.file(output))) << output;
}

TEST(Cli, NonTwoToOneMapWarnsButWorks) {
  testing::TemporaryDirectory dir;
  // Not square: a square image is a light probe or an error (environment_format.h).
  Image odd(16, 12);
  std::fill(odd.pixels.begin(), odd.pixels.end(), 1.0f);
  write_image(dir.file("odd.exr"), odd);
  const CommandResult run = run_glaze("sh " + dir.file("odd.exr") + " --lmax 1", dir);
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_NE(run.err.find("not 2:1"), std::string::npos) << run.err;
}

TEST(Cli, RenderWithTheShIntegrator) {
  testing::TemporaryDirectory dir;
  const std::string scenes = std::string(GLAZE_SOURCE_DIR) + "/scenes/";
  const CommandResult run =
      run_glaze("render " + scenes + "red_sphere_office.gltf --integrator sh --lmax 6 --ss 2 --res 32x32 --out " +
                    dir.file("sh.exr"),
                dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const Image image = read_image(dir.file("sh.exr"));
  EXPECT_EQ(image.width, 32);
  EXPECT_GT(image.at(16, 16)[0], image.at(16, 16)[1]);  // a red sphere
  // Not a single convex object: rendered, with a warning that occlusion is ignored.
  const CommandResult still = run_glaze(
      "render " + scenes + "still_life_office.gltf --integrator sh --res 32x24 --out " + dir.file("still.exr"), dir);
  EXPECT_EQ(still.exit_code, 0) << still.err;
  EXPECT_NE(still.err.find("occlusion"), std::string::npos) << still.err;
  expect_clear_failure(
      run_glaze("render " + scenes + "red_sphere_office.gltf --integrator sh --lmax 99 --out " + dir.file("x.exr"),
                dir),
      "--lmax");
  expect_clear_failure(
      run_glaze("render " + scenes + "red_sphere_office.gltf --integrator sh --spp 4 --out " + dir.file("x.exr"), dir),
      "--spp");
  expect_clear_failure(
      run_glaze("render " + scenes + "red_sphere_office.gltf --lmax 4 --out " + dir.file("x.exr"), dir), "--lmax");
  expect_clear_failure(
      run_glaze("render " + scenes + "red_sphere_office.gltf --integrator photon --out " + dir.file("x.exr"), dir),
      "photon");
  // Refinement: reported, only for sh, and not for capture sets.
  const CommandResult refined =
      run_glaze("render " + scenes + "red_sphere_office.gltf --integrator sh --ss 1 --ss-refine 4 --res 32x32 --out " +
                    dir.file("refined.exr"),
                dir);
  ASSERT_EQ(refined.exit_code, 0) << refined.err;
  EXPECT_NE(refined.err.find("refined 4"), std::string::npos) << refined.err;
  expect_clear_failure(
      run_glaze("render " + scenes + "red_sphere_office.gltf --ss-refine 4 --out " + dir.file("x.exr"), dir),
      "--ss-refine");
  expect_clear_failure(
      run_glaze(
          "render " + scenes + "red_sphere_office.gltf --integrator sh --ss-refine 4 --captures " + dir.file("set"),
          dir),
      "--ss-refine");
}

// The study on a tiny frame: every row and file is there, the path tracer's error falls
// like 1/sqrt(spp) and the sh integrator's with lmax, and the plot has ink on it.
TEST(Cli, ConvergenceWritesTheStudy) {
  testing::TemporaryDirectory dir;
  const std::string scene = std::string(GLAZE_SOURCE_DIR) + "/scenes/red_sphere_office.gltf";
  const CommandResult run =
      run_glaze("convergence " + scene + " --res 32x32 --ref-spp 512 --max-spp 16 --out " + dir.file("study"), dir);
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
  EXPECT_EQ(rows, 5 + 25);                           // 1..16 spp, 5 lmax x (ss 1, 2, 4, and ss 1 and 2 refined to 8)
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
    EXPECT_EQ(summary["time_to"][target].contains("resolvable"), noise > 0.5 * std::stod(target))
        << target << ", noise " << noise;
  const Image plot = read_image(dir.file("study/convergence.png"));
  EXPECT_EQ(plot.width, 960);
  int ink = 0;
  for (float value : plot.pixels) ink += value < 0.5f;
  EXPECT_GT(ink, 1000);

  expect_clear_failure(run_glaze("convergence " + scene + " --res 16x16 --ref " + dir.file("study/reference.exr") +
                                     " --out " + dir.file("x"),
                                 dir),
                       "--res");
  expect_clear_failure(run_glaze("convergence " + scene + " --ref a.exr --ref-spp 8 --out " + dir.file("x"), dir),
                       "--ref");
  expect_clear_failure(
      run_glaze("convergence " + scene + " --res 8x8 --ref-spp 64 --max-spp 32 --out " + dir.file("x"), dir),
      "--max-spp");
}

TEST(Cli, DemoRunsOnTheEmbeddedDefault) {
  testing::TemporaryDirectory dir;
  const CommandResult run = run_glaze("demo --out " + dir.file("demo") + " --spp 16 --res 96x96", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("recovered against true"), std::string::npos) << run.out;
  const nlohmann::json fit = nlohmann::json::parse(std::ifstream(dir.file("demo/fit/fit.json")));
  EXPECT_NEAR(fit["R0"].get<double>(), 0.0452, 0.005);
  EXPECT_NEAR(fit["Rd"][0].get<double>(), 0.9765, 0.01);
  EXPECT_EQ(fit["holdout"].size(), 2u);
}

// From photographs: the simulated shoot, `captures` and the fit, with the material
// recovered within the photo shoots' bounds (photo_shoot_test.cpp; measured R0 +0.0014,
// Rd within 0.0070).
TEST(Cli, DemoFromPhotographs) {
  testing::TemporaryDirectory dir;
  const CommandResult run = run_glaze("demo --photos --out " + dir.file("demo"), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("recovered against true"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("sphere centre off by"), std::string::npos) << run.out;
  const nlohmann::json truth = nlohmann::json::parse(std::ifstream(dir.file("demo/shoot/simulation.json")));
  const nlohmann::json fit = nlohmann::json::parse(std::ifstream(dir.file("demo/fit/fit.json")));
  EXPECT_NEAR(fit["R0"].get<double>(), truth["object"]["R0"].get<double>(), 0.003);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(fit["Rd"][c].get<double>(), truth["object"]["Rd"][c].get<double>(), 0.01);
  EXPECT_TRUE(std::filesystem::exists(dir.file("demo/captures/summary.txt")));
}

}  // namespace
}  // namespace glaze
