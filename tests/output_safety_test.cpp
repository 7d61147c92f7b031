// Outputs whole or not at all (text_file.h, output_folder.h): a run killed midway, two
// runs into one folder, a view copied in from another set, and output paths that cannot
// be written. Runs are killed deterministically with GLAZE_FAULT_KILL_AFTER_COMMITS.
#include "renderer/capture_set.h"
#include "renderer/output_folder.h"
#include "renderer/text_file.h"
#include "test_support.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

namespace glaze {
namespace {

namespace fs = std::filesystem;
using testing::quoted;
using testing::run_glaze;
using testing::TemporaryDirectory;

std::string file_text(const fs::path& path) {
  std::ifstream stream(path);
  return std::string(std::istreambuf_iterator<char>(stream), {});
}

// The names in `folder` that look like TemporaryOutput's files.
std::vector<std::string> temporaries(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::recursive_directory_iterator(folder))
    if (entry.path().filename().string().find(".glaze-") != std::string::npos &&
        entry.path().filename() != ".glaze-lock" && entry.path().filename() != kIncompleteMarker)
      names.push_back(entry.path().string());
  return names;
}

// `glaze render --captures DIR` of the sphere scene (three input views, view_0..2; the
// novel views held out), 32x32 with the sh integrator: a small, deterministic set.
testing::CommandResult render_captures(const TemporaryDirectory& dir, const fs::path& captures,
                                       const std::string& prefix = "") {
  return run_glaze("render " + quoted(testing::scenes_dir() + "red_sphere_office.gltf") +
                       " --integrator sh --lmax 2 --ss 1 --res 32x32 --holdout novel_0,novel_1 --captures " +
                       quoted(captures.string()),
                   dir, prefix);
}

testing::CommandResult fit_material(const TemporaryDirectory& dir, const fs::path& captures, const fs::path& out,
                                    const std::string& prefix = "") {
  return run_glaze("invert-fit " + quoted(captures.string()) + " --mode material --lmax 2 --max-iterations 5 --out " +
                       quoted(out.string()),
                   dir, prefix);
}

const std::string kKillAfter = "GLAZE_FAULT_KILL_AFTER_COMMITS=";

TEST(OutputSafety, TwoTemporaryOutputsForOneTargetBothCommit) {
  TemporaryDirectory dir;
  const fs::path target = dir.path() / "fit.json";
  TemporaryOutput first(target), second(target);
  EXPECT_NE(first.path(), second.path());
  EXPECT_EQ(first.path().parent_path(), dir.path());
  EXPECT_EQ(first.path().extension(), ".json");  // image writers are chosen by it
  EXPECT_TRUE(first.path().filename().string().starts_with(".fit.glaze-" + std::to_string(::getpid()) + "-"))
      << first.path();
  first.write("first\n");
  second.write("second\n");
  first.commit();
  EXPECT_EQ(file_text(target), "first\n");
  second.commit();
  EXPECT_EQ(file_text(target), "second\n");
  EXPECT_TRUE(temporaries(dir.path()).empty());
  {
    TemporaryOutput abandoned(target);
    abandoned.write("never committed\n");
    EXPECT_TRUE(fs::exists(abandoned.path()));
  }
  EXPECT_TRUE(temporaries(dir.path()).empty());
  EXPECT_EQ(file_text(target), "second\n");
}

// 4.1: a re-render killed after two of its three views leaves no transforms.json, and
// the marker; the fit refuses the set.
TEST(OutputSafety, CapturesKilledMidwayAreRefused) {
  TemporaryDirectory dir;
  const fs::path captures = dir.path() / "set";
  ASSERT_EQ(render_captures(dir, captures).exit_code, 0);
  const std::string old_run = testing::read_json((captures / "transforms.json").string())["run"];
  EXPECT_EQ(old_run.size(), 32u);
  EXPECT_EQ(image_attribute((captures / "view_002.exr").string(), "glaze:run"), old_run);
  EXPECT_FALSE(fs::exists(captures / kIncompleteMarker));

  // Commits: the marker, environment.exr, view_000, view_001: killed there.
  const testing::CommandResult killed = render_captures(dir, captures, kKillAfter + "4 ");
  EXPECT_TRUE(killed.crashed) << killed.err;
  EXPECT_FALSE(fs::exists(captures / "transforms.json"));
  EXPECT_TRUE(fs::exists(captures / kIncompleteMarker));
  const std::string new_run = image_attribute((captures / "view_001.exr").string(), "glaze:run");
  EXPECT_NE(new_run, old_run);
  EXPECT_EQ(image_attribute((captures / "view_002.exr").string(), "glaze:run"), old_run);  // not reached
  EXPECT_TRUE(temporaries(captures).empty());

  const testing::CommandResult fit = fit_material(dir, captures, dir.path() / "fit");
  testing::expect_clear_failure(fit, "incomplete capture set");
  EXPECT_NE(fit.err.find("render it again"), std::string::npos) << fit.err;
  EXPECT_FALSE(fs::exists(dir.path() / "fit"));

  // Rendered again, whole: readable, every view of the new run.
  ASSERT_EQ(render_captures(dir, captures).exit_code, 0);
  EXPECT_FALSE(fs::exists(captures / kIncompleteMarker));
  const CaptureSet set = read_transforms(captures.string());
  EXPECT_EQ(set.frames.size(), 3u);
  EXPECT_EQ(read_transforms((captures / "holdout").string()).frames.size(), 2u);
}

// A view copied in from another run of the set: "mixed set".
TEST(OutputSafety, ViewOfAnotherRunIsRefused) {
  TemporaryDirectory dir;
  const fs::path captures = dir.path() / "set";
  ASSERT_EQ(render_captures(dir, captures).exit_code, 0);
  fs::copy_file(captures / "view_001.exr", dir.path() / "old_view.exr");
  ASSERT_EQ(render_captures(dir, captures).exit_code, 0);
  EXPECT_NO_THROW(read_transforms(captures.string()));
  fs::copy_file(dir.path() / "old_view.exr", captures / "view_001.exr", fs::copy_options::overwrite_existing);

  const testing::CommandResult fit = fit_material(dir, captures, dir.path() / "fit");
  testing::expect_clear_failure(fit, "view_001.exr was written by another run");
  EXPECT_NE(fit.err.find("mixed set"), std::string::npos) << fit.err;

  // An image without the attribute (a photograph, a hand-made set) is not checked.
  write_image((captures / "view_001.exr").string(), read_image((dir.path() / "old_view.exr").string()));
  EXPECT_EQ(read_transforms(captures.string()).frames.size(), 3u);
}

// 4.2: a fit killed after its first file leaves no fit.json (the old one is gone) and the
// marker; a finished fit carries its run.
TEST(OutputSafety, FitKilledMidwayLeavesNoFitJson) {
  TemporaryDirectory dir;
  const fs::path captures = dir.path() / "set", out = dir.path() / "fit";
  ASSERT_EQ(render_captures(dir, captures).exit_code, 0);
  const testing::CommandResult first = fit_material(dir, captures, out);
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const nlohmann::json fit = testing::read_json((out / "fit.json").string());
  EXPECT_EQ(fit["run"].get<std::string>().size(), 32u);
  EXPECT_EQ(image_attribute((out / "render_view_000.exr").string(), "glaze:run"), fit["run"]);
  EXPECT_FALSE(fs::exists(out / kIncompleteMarker));

  // Commits: the marker, render_view_000.exr: killed there.
  const testing::CommandResult killed = fit_material(dir, captures, out, kKillAfter + "2 ");
  EXPECT_TRUE(killed.crashed) << killed.err;
  EXPECT_FALSE(fs::exists(out / "fit.json"));
  EXPECT_TRUE(fs::exists(out / kIncompleteMarker));
  EXPECT_NE(image_attribute((out / "render_view_000.exr").string(), "glaze:run"), fit["run"]);
  EXPECT_TRUE(temporaries(out).empty());
}

// 4.3: a second run into a folder that a run holds stops before writing anything.
TEST(OutputSafety, SecondRunIntoALockedFolderStops) {
  TemporaryDirectory dir;
  const fs::path captures = dir.path() / "set", out = dir.path() / "fit";
  ASSERT_EQ(render_captures(dir, captures).exit_code, 0);
  ASSERT_EQ(fit_material(dir, captures, out).exit_code, 0);
  const std::string before = file_text(out / "fit.json");

  const int lock = ::open((out / ".glaze-lock").c_str(), O_RDWR);
  ASSERT_GE(lock, 0);
  ASSERT_EQ(::flock(lock, LOCK_EX | LOCK_NB), 0);
  const std::string pid = std::to_string(::getpid());
  ASSERT_EQ(::ftruncate(lock, 0), 0);
  ASSERT_EQ(::pwrite(lock, pid.data(), pid.size(), 0), ssize_t(pid.size()));
  const testing::CommandResult second = fit_material(dir, captures, out);
  testing::expect_clear_failure(second, "is being written by another glaze run (pid " + pid + ")");
  testing::expect_clear_failure(render_captures(dir, out), "another glaze run");
  ::close(lock);
  EXPECT_EQ(file_text(out / "fit.json"), before);
  EXPECT_FALSE(fs::exists(out / kIncompleteMarker));
}

// 4.4: output paths that cannot be written: exit 1 naming the path and the reason, never
// "Success", and no temporary file left.
TEST(OutputSafety, UnwritableOutputPathsAreClearErrors) {
  TemporaryDirectory dir;
  const std::string scene = quoted(testing::scenes_dir() + "red_sphere_office.gltf");
  const std::string render = "render " + scene + " --integrator sh --lmax 2 --ss 1 --res 8x8 ";
  const fs::path file = dir.path() / "file";
  std::ofstream(file) << "a regular file\n";
  fs::create_directories(dir.path() / "folder");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--out " + quoted((file / "x.exr").string()), (file / "x.exr").string()},
      {"--camera all --out " + quoted((file / "sub").string()), (file / "sub").string()},
      {"--captures " + quoted((file / "sub").string()), (file / "sub").string()},
      {"--captures /proc/glaze-x", "/proc/glaze-x"},
      {"--out " + quoted((dir.path() / "folder").string()), "folder: could not be written (it is a folder"},
      {"--out ''", "(no file name given)"},
  };
  for (const auto& [arguments, mentioned] : cases) {
    const testing::CommandResult run = run_glaze(render + arguments, dir);
    SCOPED_TRACE(arguments);
    testing::expect_clear_failure(run, mentioned);
    EXPECT_EQ(run.err.find("Success"), std::string::npos) << run.err;
  }
  EXPECT_TRUE(temporaries(dir.path()).empty());
  EXPECT_EQ(file_text(file), "a regular file\n");
}

// 4.4: a file over `ulimit -f` fails its write (EFBIG, not SIGXFSZ), and the old file stays.
TEST(OutputSafety, FileSizeLimitKeepsTheOldFile) {
  TemporaryDirectory dir;
  const std::string render = "render " + quoted(testing::scenes_dir() + "red_sphere_office.gltf") +
                             " --integrator sh --lmax 2 --ss 1 --res 96x96 --out " + quoted(dir.file("big.exr"));
  ASSERT_EQ(run_glaze(render, dir).exit_code, 0);
  const std::string before = file_text(dir.file("big.exr"));
  ASSERT_GT(before.size(), 16384u);
  const testing::CommandResult limited = run_glaze(render, dir, "ulimit -f 8; ");
  testing::expect_clear_failure(limited, "big.exr: could not be written");
  EXPECT_EQ(file_text(dir.file("big.exr")), before);
  EXPECT_TRUE(temporaries(dir.path()).empty());
}

}  // namespace
}  // namespace glaze
