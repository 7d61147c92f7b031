// Hostile inputs through the glaze command: capture sets with deep or wrongly typed
// values, FIFOs and devices where files belong, sizes that would exhaust memory, and
// unbounded time budgets. Each must end in exit 1 with a message naming the file or the
// option, quickly, never in a crash, a hang or "internal error".
#include "renderer/capture_set.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/path_tracer.h"
#include "renderer/ray_tracer.h"
#include "renderer/render.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/stat.h>

#include <fstream>
#include <string>
#include <vector>

namespace glaze {
namespace {

using nlohmann::json;
using testing::expect_clear_failure;
using testing::quoted;
using testing::run_glaze;
using testing::TemporaryDirectory;

// Under `timeout`, so that a hang fails the test (as a crash: exit status 124) instead
// of stopping the suite.
constexpr const char* kTimeout = "timeout 20 ";

// A capture set of two 4x3 views of the unit sphere in `dir` (images written), as JSON.
json small_capture_set(const TemporaryDirectory& dir) {
  for (const char* name : {"view_000.exr", "view_001.exr"}) write_image(dir.file(name), Image(4, 3));
  const auto frame = [](const std::string& file, float z) {
    return json{{"file_path", file}, {"transform_matrix", {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, z}, {0, 0, 0, 1}}}};
  };
  return {{"w", 4},
          {"h", 3},
          {"fl_x", 5.0},
          {"fl_y", 5.0},
          {"cx", 2.0},
          {"cy", 1.5},
          {"frames", {frame("view_000.exr", 4.0f), frame("view_001.exr", 5.0f)}},
          {"object", {{"type", "sphere"}, {"center", {0, 0, 0}}, {"radius", 1}}}};
}

void write_text(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

// `glaze invert-fit` of the capture set in `dir`: the command that reads one.
testing::CommandResult fit(const TemporaryDirectory& dir) {
  return run_glaze("invert-fit " + quoted(dir.path().string()) + " --mode material --out " + quoted(dir.file("fit")),
                   dir, kTimeout);
}

// transforms.json holding `transforms` with `key`'s value replaced by `value_text`
// (raw JSON: a value too deep to build as a json in the test).
void write_with_raw_value(const TemporaryDirectory& dir, json transforms, const std::string& key,
                          const std::string& value_text) {
  transforms[key] = "@";
  std::string text = transforms.dump();
  text.replace(text.find("\"@\""), 3, value_text);
  write_text(dir.file("transforms.json"), text);
}

std::string nested(size_t depth) { return std::string(depth, '[') + std::string(depth, ']'); }

TEST(HostileInput, DeepOrHugeValuesInTransformsGiveAShortMessage) {
  TemporaryDirectory dir;
  const json transforms = small_capture_set(dir);
  // A million levels: printing it for the message overflowed the stack.
  write_with_raw_value(dir, transforms, "frames", nested(1000000));
  testing::CommandResult run = fit(dir);
  expect_clear_failure(run, "nested deeper than 100");
  EXPECT_NE(run.err.find(dir.file("transforms.json")), std::string::npos) << run.err;

  write_with_raw_value(dir, transforms, "object", "{\"type\": \"sphere\", \"center\": " + nested(1000000) + "}");
  expect_clear_failure(fit(dir), "nested deeper than 100");

  // A megabyte of numbers where one is expected: refused, and the message excerpts it.
  json huge = transforms;
  huge["w"] = std::vector<int>(250000, 1);
  write_text(dir.file("transforms.json"), huge.dump());
  run = fit(dir);
  expect_clear_failure(run, "\"w\" must be a whole number of pixels");
  EXPECT_LT(run.err.size(), 1024u) << run.err.substr(0, 2000);
}

TEST(HostileInput, WronglyTypedValuesInTransformsNameTheKey) {
  TemporaryDirectory dir;
  const json valid = small_capture_set(dir);
  struct Case {
    std::vector<std::string> path;  // of the key to replace
    json value;
    std::string mention;
  };
  const std::vector<Case> cases = {
      {{"renderer"}, {{"integrator", 5}}, "\"integrator\" must be \"path\" or \"sh\", not 5"},
      {{"renderer"}, {{"integrator", nullptr}}, "\"integrator\" must be \"path\" or \"sh\", not null"},
      {{"renderer"}, {{"integrator", "path"}, {"spp", "4"}}, "\"spp\" must be a whole number"},
      {{"renderer"}, json::array(), "\"renderer\": must be"},
      {{"renderer"}, "sh", "\"renderer\": must be"},
      {{"frames", "0", "camera_model"}, 5, "\"camera_model\" must be a string"},
      {{"frames", "0", "camera"}, json::object(), "\"camera\" must be the camera's name"},
      // Found by fuzzing: an empty name was read, then dropped by write_transforms.
      {{"environment"}, {{"procedural", ""}}, "not a procedural environment"},
      // Beyond what Embree takes (it aborts on such rays).
      {{"frames", "0", "transform_matrix"},
       {{1, 0, 0, 0}, {0, 1, 0, 1e38}, {0, 0, 1, 4}, {0, 0, 0, 1}},
       "a finite number within +-1e15"},
      {{"object", "center"}, {0, 1e20, 0}, "a finite number within +-1e15"},
  };
  for (const Case& c : cases) {
    json transforms = valid;
    json* target = &transforms;
    for (size_t k = 0; k + 1 < c.path.size(); ++k)
      target = target->is_array() ? &(*target)[std::stoul(c.path[k])] : &(*target)[c.path[k]];
    (*target)[c.path.back()] = c.value;
    write_text(dir.file("transforms.json"), transforms.dump());
    // Read in the process (anything but glaze::Error fails the test) ...
    try {
      read_transforms(dir.path().string());
      ADD_FAILURE() << "accepted " << c.mention;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(c.mention), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(dir.file("transforms.json")), std::string::npos) << e.what();
    }
    // ... and the issue's case through the command: exit 1, never 3.
    if (&c == &cases.front()) expect_clear_failure(fit(dir), c.mention);
  }
}

TEST(HostileInput, FifosAndDevicesAreRefusedAsInputs) {
  TemporaryDirectory dir;
  const std::string fifo = dir.file("pipe.exr");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string scene = quoted(testing::scenes_dir() + "red_sphere_office.gltf");
  // Each of these blocked in open() or read /dev/zero for ever.
  for (const std::string& input : {fifo, std::string("/dev/zero")}) {
    const testing::CommandResult sh = run_glaze("sh " + quoted(input), dir, kTimeout);
    expect_clear_failure(sh, input + ": image is");
    EXPECT_NE(sh.err.find("not a regular file"), std::string::npos) << sh.err;
    const testing::CommandResult render = run_glaze(
        "render " + scene + " --env " + quoted(input) + " --res 8x8 --spp 1 --out " + quoted(dir.file("a.exr")), dir,
        kTimeout);
    expect_clear_failure(render, input + ": image is");
    EXPECT_NE(render.err.find("not a regular file"), std::string::npos) << render.err;
  }
  // In a capture set: a frame, a mask, the transforms.json itself.
  json transforms = small_capture_set(dir);
  transforms["frames"][0]["file_path"] = "pipe.exr";
  transforms["frames"][1]["mask_path"] = "/dev/zero";
  write_text(dir.file("transforms.json"), transforms.dump());
  testing::CommandResult run = fit(dir);
  expect_clear_failure(run, fifo + ": \"file_path\" is a FIFO (named pipe), not a regular file");
  transforms["frames"][0]["file_path"] = "view_000.exr";
  write_text(dir.file("transforms.json"), transforms.dump());
  expect_clear_failure(fit(dir), "/dev/zero: \"mask_path\" is a character device, not a regular file");
  run = run_glaze("invert-fit " + quoted(fifo) + " --mode material --out " + quoted(dir.file("fit")), dir, kTimeout);
  expect_clear_failure(run, fifo + ": capture set (transforms.json) is a FIFO (named pipe), not a regular file");
}

// What a refusal for memory says: the need, and the option that raises the limit.
void expect_memory_refusal(const testing::CommandResult& run, const std::string& what) {
  expect_clear_failure(run, what);
  EXPECT_NE(run.err.find(" needs "), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("--memory-limit"), std::string::npos) << run.err;
}

TEST(HostileInput, HugeFilmsAreRefusedBeforeAllocating) {
  TemporaryDirectory dir;
  const std::string render = "render " + quoted(testing::scenes_dir() + "red_sphere_office.gltf") + " --out " +
                             quoted(dir.file("a.exr")) + " --memory-limit 1G --res 65536x65536";
  // 2^32 pixels: std::bad_alloc (exit 3) for the path tracer's sums and the sh image.
  expect_memory_refusal(run_glaze(render, dir, kTimeout), "film of camera 'view_0' (65536x65536) needs 320.0 GiB");
  expect_memory_refusal(run_glaze(render + " --integrator sh", dir, kTimeout),
                        "sh film of camera 'view_0' (65536x65536) needs 64.0 GiB");
}

// The backstop behind the estimates: with the limit off, a film beyond the address space
// that `ulimit -v` leaves ends in std::bad_alloc, which is exit 1 asking for a report.
TEST(HostileInput, OutOfMemoryIsAnErrorNotAnInternalError) {
#if defined(GLAZE_SANITIZED)
  GTEST_SKIP() << "ASan reserves more address space than the ulimit below leaves";
#endif
  TemporaryDirectory dir;
  const std::string render = "render " + quoted(testing::scenes_dir() + "red_sphere_office.gltf") + " --out " +
                             quoted(dir.file("a.exr")) + " --memory-limit none --res 20000x20000";
  expect_clear_failure(run_glaze(render, dir, std::string("ulimit -v 4000000; ") + kTimeout),
                       "out of memory (glaze's estimate missed this: please report it)");
}

// Found by the fuzzer: a Radiance HDR header declaring 2147483 x 4 pixels (a few hundred
// MB in all, under the memory limit) made OpenImageIO's scanline reader ask for gigabytes.
TEST(HostileInput, ImagesWiderThan65536AreRefusedBeforeDecoding) {
  TemporaryDirectory dir;
  const std::string map = dir.file("wide.hdr");
  write_text(map, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 2147483\n" + std::string(64, '\x80'));
  try {
    read_image(map);
    ADD_FAILURE() << "read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("2147483x4"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("65536 a side"), std::string::npos) << e.what();
  }
}

TEST(HostileInput, LargeMapsAreRefusedBeforeDecodingAndSampling) {
  TemporaryDirectory dir;
  const std::string map = dir.file("map.exr");
  write_image(map, Image(1024, 512));
  // Decoding: 512 Ki pixels at 28 bytes or more each.
  expect_memory_refusal(run_glaze("sh " + quoted(map) + " --memory-limit 4M", dir, kTimeout), "decoding " + map);
  // Decoded (under 16 MiB) but its sampling tables (48 bytes a texel: 24 MiB) refused.
  const std::string render = "render " + quoted(testing::scenes_dir() + "red_sphere_office.gltf") + " --env " +
                             quoted(map) + " --res 8x8 --spp 1 --out " + quoted(dir.file("a.exr"));
  expect_memory_refusal(run_glaze(render + " --memory-limit 20M", dir, kTimeout),
                        "building the sampling tables of " + map + " needs 24.0 MiB");
}

TEST(HostileInput, FitAllocationsAreRefusedBeforeAllocating) {
  TemporaryDirectory dir;
  const std::string captures = dir.file("captures");
  ASSERT_EQ(run_glaze("render " + quoted(testing::scenes_dir() + "red_sphere_office.gltf") + " --captures " +
                          quoted(captures) + " --res 16x16 --integrator sh",
                      dir)
                .exit_code,
            0);
  const std::string fit = "invert-fit " + quoted(captures) + " --out " + quoted(dir.file("fit"));
  // 2^26 points of 12 bytes; a 1024x512 texture of 400 bytes a texel.
  expect_memory_refusal(run_glaze(fit + " --mode material --points 67108864 --memory-limit 256M", dir, kTimeout),
                        "--points 67108864 needs 768.0 MiB");
  expect_memory_refusal(run_glaze(fit + " --mode texture --texture-res 1024x512 --memory-limit 150M", dir, kTimeout),
                        "the 1024x512 texture fit (--texture-res) needs 200.0 MiB");
}

TEST(HostileInput, TimeBudgetAndSamplesAreBounded) {
  TemporaryDirectory dir;
  const std::string render = "render " + quoted(testing::scenes_dir() + "red_sphere_office.gltf") +
                             " --res 8x8 --out " + quoted(dir.file("a.exr"));
  // 1e30 seconds rendered for ever; 8 days is past the 7 allowed.
  expect_clear_failure(run_glaze(render + " --time-budget 1e30", dir, kTimeout), "--time-budget");
  expect_clear_failure(run_glaze(render + " --time-budget 691200", dir, kTimeout), "--time-budget");
  expect_clear_failure(run_glaze(render + " --spp 2147483648", dir, kTimeout), "--spp");
}

// The samples of a pixel are numbered pass * spp + s in 32 bits: a render takes at most
// 2^30, and a pass that would go past that is refused before it starts.
TEST(HostileInput, SamplesPerPixelStayBelowTheirCount) {
  const Scene scene = testing::sphere_scene(0.04f, RGB(0.8f, 0.1f, 0.1f));
  const Environment environment(Image(16, 8), {});
  const RayTracer tracer(scene);
  const PathTracer path(scene, tracer, environment, PathTracerOptions{});
  RenderOptions options;
  options.spp = kMaxSamplesPerPixel + 1;
  EXPECT_THROW(ProgressiveRender(path, testing::front_camera(1), options), Error);
  options.spp = kMaxSamplesPerPixel;
  const ProgressiveRender passes(path, testing::front_camera(1), options);
  EXPECT_FALSE(passes.full());  // one pass of 2^30 fits
}

}  // namespace
}  // namespace glaze
