// Tests of the guards every input passes: checked arithmetic on numbers from files,
// regular-file checks, bounded JSON nesting and the memory limit.
#include "renderer/checked_math.h"
#include "renderer/error.h"
#include "renderer/input_file.h"
#include "renderer/json_input.h"
#include "renderer/memory_budget.h"
#include "tests/test_support.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <string>

namespace glaze {
namespace {

// Runs `action`, which must throw glaze::Error mentioning each of `words`.
template <typename Action>
void expect_error(Action action, std::initializer_list<std::string> words) {
  try {
    action();
    ADD_FAILURE() << "no error";
  } catch (const Error& error) {
    for (const auto& word : words) EXPECT_NE(std::string(error.what()).find(word), std::string::npos) << error.what();
  }
}

TEST(CheckedMath, SumsAndProductsThatOverflowAreReported) {
  EXPECT_EQ(checked_add(UINT64_MAX - 1, 1), UINT64_MAX);
  EXPECT_FALSE(checked_add(UINT64_MAX, 1));
  EXPECT_FALSE(checked_add(uint64_t(1) << 63, uint64_t(1) << 63));
  EXPECT_EQ(checked_mul(uint64_t(1) << 31, uint64_t(1) << 32), uint64_t(1) << 63);
  EXPECT_FALSE(checked_mul(uint64_t(1) << 32, uint64_t(1) << 32));
  // A count of (2^64 + 2) / 3 three-float elements: the wrapped product would be 2.
  EXPECT_FALSE(checked_mul((UINT64_MAX / 3) + 1, 3));
  EXPECT_EQ(saturating_mul(uint64_t(1) << 40, uint64_t(1) << 40), UINT64_MAX);
  EXPECT_EQ(saturating_mul(1000, 1000), 1000000u);
}

TEST(CheckedMath, OnlyWholeFiniteNumbersInRangeBecomeIntegers) {
  constexpr int64_t kIntMax = std::numeric_limits<int32_t>::max();
  EXPECT_EQ(integer_from(7.0, 0, kIntMax), 7);
  EXPECT_EQ(integer_from(-3.0, -5, 5), -3);
  EXPECT_EQ(integer_from(2147483647.0, 0, kIntMax), kIntMax);
  for (const double bad :
       {1e300, -1e300, 4294967296.0, 2147483648.0, -1.0, 2.5, std::nan(""), HUGE_VAL, -HUGE_VAL, 9223372036854775808.0})
    EXPECT_FALSE(integer_from(bad, 0, kIntMax)) << bad;
  EXPECT_FALSE(integer_from(9223372036854775808.0, 0, std::numeric_limits<int64_t>::max()));
  EXPECT_EQ(integer_from(-9223372036854775808.0, std::numeric_limits<int64_t>::min(), 0),
            std::numeric_limits<int64_t>::min());
}

TEST(MemoryBudget, SizesAreReadWithBinaryUnits) {
  EXPECT_EQ(parse_memory_size("2048"), 2048u);
  EXPECT_EQ(parse_memory_size("512M"), uint64_t(512) << 20);
  EXPECT_EQ(parse_memory_size("16G"), uint64_t(16) << 30);
  EXPECT_EQ(parse_memory_size("16GiB"), uint64_t(16) << 30);
  EXPECT_EQ(parse_memory_size("16GB"), uint64_t(16) << 30);
  EXPECT_EQ(parse_memory_size("1.5k"), 1536u);
  EXPECT_EQ(parse_memory_size("none"), UINT64_MAX);
  for (const char* bad : {"", "12X", "-1", "0", "nan", "inf", "1e30G", "G", "16 G"})
    EXPECT_FALSE(parse_memory_size(bad)) << bad;
  EXPECT_EQ(format_bytes(1536), "1.5 KiB");
  EXPECT_EQ(format_bytes(100), "100 bytes");
  EXPECT_EQ(format_bytes(uint64_t(320) << 30), "320.0 GiB");
}

TEST(MemoryBudget, AllocationsAboveTheLimitAreRefusedWithTheNumbers) {
  set_memory_limit(uint64_t(1) << 30);
  EXPECT_EQ(memory_limit(), uint64_t(1) << 30);
  EXPECT_NO_THROW(require_memory(uint64_t(1) << 30, "a film"));
  expect_error([] { require_memory((uint64_t(1) << 30) + 1, "rendering 20000x20000"); },
               {"rendering 20000x20000 needs 1.0 GiB", "the limit is 1.0 GiB", "--memory-limit"});
  expect_error([] { require_memory(UINT64_MAX, "a film"); }, {"more than 16 EiB"});
  set_memory_limit(std::nullopt);
  // The default is a share of this machine's memory: more than nothing, less than 16 EiB
  // (unless GLAZE_MEMORY_LIMIT says otherwise).
  if (!std::getenv("GLAZE_MEMORY_LIMIT")) {
    EXPECT_GT(memory_limit(), uint64_t(64) << 20);
    EXPECT_LT(memory_limit(), UINT64_MAX);
  }
}

TEST(InputFile, OnlyRegularFilesAreOpened) {
  testing::TemporaryDirectory dir;
  { std::ofstream(dir.file("a.txt")) << "hello"; }
  EXPECT_EQ(require_regular_file(dir.file("a.txt"), "scene"), 5u);
  EXPECT_EQ(read_whole_file(dir.file("a.txt"), "scene"), "hello");
  expect_error([&] { require_regular_file(dir.file("missing.gltf"), "scene"); },
               {"missing.gltf", "scene", "not found"});
  expect_error([&] { require_regular_file(dir.path().string(), "environment"); }, {"is a folder"});
  expect_error([] { read_whole_file("/dev/zero", "environment"); }, {"/dev/zero", "character device"});
  // A FIFO with no writer: open() would block for ever without O_NONBLOCK.
  ASSERT_EQ(mkfifo(dir.file("pipe").c_str(), 0600), 0);
  const auto start = std::chrono::steady_clock::now();
  expect_error([&] { read_whole_file(dir.file("pipe"), "environment"); }, {"pipe", "FIFO", "not a regular file"});
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
}

TEST(InputFile, FilesLargerThanTheMemoryLimitAreRefusedBeforeReading) {
  testing::TemporaryDirectory dir;
  { std::ofstream(dir.file("big.json")) << std::string(4096, ' '); }
  set_memory_limit(1024);
  expect_error([&] { read_whole_file(dir.file("big.json"), "capture set"); }, {"big.json", "needs 4.0 KiB"});
  set_memory_limit(std::nullopt);
}

TEST(JsonInput, DeepNestingIsRefusedWithoutOverflowingTheStack) {
  // Written as text: a 20,000-deep json value would overflow the test's own dump().
  const std::string deep = std::string(20000, '[') + std::string(20000, ']');
  expect_error([&] { parse_json_limited(deep, "transforms.json"); }, {"transforms.json", "nested deeper than 100"});
  const std::string deep_object = "{\"extras\":" + std::string(5000, '[') + "1" + std::string(5000, ']') + "}";
  expect_error([&] { parse_json_limited(deep_object, "scene.gltf"); }, {"scene.gltf", "nested deeper"});
  // 100 levels are allowed, 101 are not.
  EXPECT_NO_THROW(parse_json_limited(std::string(100, '[') + std::string(100, ']'), "f.json"));
  EXPECT_THROW(parse_json_limited(std::string(101, '[') + std::string(101, ']'), "f.json"), Error);
  EXPECT_EQ(parse_json_limited(R"({"a": [1, 2]})", "f.json")["a"][1], 2);
}

TEST(JsonInput, InvalidJsonNamesTheFileAndExcerptsAreShort) {
  expect_error([] { parse_json_limited("{\"a\": ", "fit.json"); }, {"fit.json", "not valid JSON"});
  const nlohmann::json big(std::vector<int>(1000000, 7));
  const std::string excerpt = json_excerpt(big, 200);
  EXPECT_EQ(excerpt.size(), 203u);
  EXPECT_TRUE(excerpt.starts_with("[7,7,"));
  EXPECT_TRUE(excerpt.ends_with("..."));
  EXPECT_EQ(json_excerpt(nlohmann::json{{"a", 1}}), R"({"a":1})");
}

TEST(Cli, MemoryLimitIsAnOptionOfEveryCommand) {
  testing::TemporaryDirectory dir;
  testing::expect_clear_failure(testing::run_glaze("env procedural office --memory-limit 12X --out x.exr", dir),
                                "--memory-limit");
  // 4096x2048 float RGB is 96 MiB of pixels: refused under a 1 MiB limit, before it is made.
  testing::expect_clear_failure(
      testing::run_glaze("env procedural office --res 4096x2048 --memory-limit 1M --out " + dir.file("x.exr"), dir),
      "needs");
  EXPECT_FALSE(std::filesystem::exists(dir.file("x.exr")));
  const auto help = testing::run_glaze("render --help", dir);
  EXPECT_NE(help.out.find("--memory-limit"), std::string::npos);
}

}  // namespace
}  // namespace glaze
