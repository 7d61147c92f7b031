// Tests of image reading and writing: round trips and every kind of bad file.
#include "renderer/environment.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <fstream>

namespace glaze {
namespace {

Image pattern(int w, int h) {
  Image image(w, h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) image.set(i, j, RGB(i * 0.25f, j * 1e3f, 1e-6f * (i + j)));
  return image;
}

std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ImageIo, ExrRoundTripIsExactAndKeepsMetadata) {
  testing::TemporaryDirectory dir;
  const Image image = pattern(17, 9);
  write_image(dir.file("a.exr"), image, {{"glaze:integrator", "path"}});
  const Image back = read_image(dir.file("a.exr"));
  ASSERT_EQ(back.width, 17);
  ASSERT_EQ(back.height, 9);
  EXPECT_EQ(back.pixels, image.pixels);
  // Only the target remains: no temporary file left behind.
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 1);
}

TEST(ImageIo, ReadsHdrAndPfm) {
  testing::TemporaryDirectory dir;
  const Image image = pattern(8, 4);
  write_image(dir.file("b.hdr"), image);
  {  // PFM written by hand (OpenImageIO reads it but has no writer): rows bottom to top,
     // negative scale = little endian.
    std::ofstream pfm(dir.file("c.pfm"), std::ios::binary);
    pfm << "PF\n8 4\n-1.0\n";
    for (int j = 3; j >= 0; --j)
      for (int i = 0; i < 8; ++i) pfm.write(reinterpret_cast<const char*>(&image.pixels[(j * 8 + i) * 3]), 12);
  }
  for (const char* name : {"b.hdr", "c.pfm"}) {
    const Image back = read_image(dir.file(name));
    ASSERT_EQ(back.width, 8);
    // RGBE (.hdr) shares one exponent per pixel: precision is relative to the pixel's maximum.
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 8; ++i)
        EXPECT_LT((back.at(i, j) - image.at(i, j)).abs().maxCoeff(), 0.01f * image.at(i, j).maxCoeff() + 1e-6f) << name;
  }
}

TEST(ImageIo, EightBitImagesAreDecodedFromSrgb) {
  testing::TemporaryDirectory dir;
  Image image(4, 2);
  std::fill(image.pixels.begin(), image.pixels.end(), 0.5f);  // stored as code value 128
  write_image(dir.file("grey.png"), image);
  const Image back = read_image(dir.file("grey.png"));
  ASSERT_EQ(back.width, 4);
  // sRGB code 128/255 = 0.50196 decodes to 0.21586 (IEC 61966-2-1).
  EXPECT_NEAR(back.pixels[0], 0.21586f, 1e-4f);
  EXPECT_NEAR(srgb_to_linear(0.04045f), 0.04045f / 12.92f, 1e-7f);
  EXPECT_NEAR(srgb_to_linear(1.0f), 1.0f, 1e-6f);
}

TEST(ImageIo, AbsurdHeaderIsRejectedBeforeAllocating) {
  testing::TemporaryDirectory dir;
  std::ofstream(dir.file("huge.pfm"), std::ios::binary) << "PF\n100000 50000\n-1.0\n";
  const std::string message = error_of([&] { read_image(dir.file("huge.pfm")); });
  EXPECT_NE(message.find("huge.pfm"), std::string::npos) << message;
}

TEST(ImageIo, MissingFileNamesThePath) {
  const std::string message = error_of([] { read_image("/nonexistent/map.exr"); });
  EXPECT_NE(message.find("/nonexistent/map.exr"), std::string::npos);
  EXPECT_NE(message.find("no such file"), std::string::npos);
}

TEST(ImageIo, NonImageFileIsRejected) {
  testing::TemporaryDirectory dir;
  std::ofstream(dir.file("notes.exr")) << "this is not an image\n";
  const std::string message = error_of([&] { read_image(dir.file("notes.exr")); });
  EXPECT_NE(message.find("notes.exr"), std::string::npos);
  EXPECT_NE(message.find("cannot be read"), std::string::npos);
  EXPECT_FALSE(error_of([&] { read_image(dir.path().string()); }).empty());  // a directory
}

TEST(ImageIo, TruncatedExrIsRejected) {
  testing::TemporaryDirectory dir;
  write_image(dir.file("full.exr"), pattern(256, 128));
  const auto size = std::filesystem::file_size(dir.file("full.exr"));
  std::filesystem::copy_file(dir.file("full.exr"), dir.file("cut.exr"));
  std::filesystem::resize_file(dir.file("cut.exr"), size / 2);
  const std::string message = error_of([&] { read_image(dir.file("cut.exr")); });
  EXPECT_NE(message.find("cut.exr"), std::string::npos) << message;
}

TEST(ImageIo, FailedWriteKeepsTheGoodFile) {
  testing::TemporaryDirectory dir;
  const std::string target = dir.file("good.exr");
  write_image(target, pattern(4, 2));
  const auto before = std::filesystem::file_size(target);
  EXPECT_THROW(write_image(target, Image()), Error);  // an empty image is refused
  EXPECT_THROW(write_image(dir.file("missing/dir/x.exr"), pattern(4, 2)), Error);
  EXPECT_THROW(write_image(dir.file("x.unknown_format"), pattern(4, 2)), Error);
  EXPECT_EQ(std::filesystem::file_size(target), before);
  EXPECT_EQ(read_image(target).pixels, pattern(4, 2).pixels);
}

TEST(ImageIo, EnvironmentLoadFromFileAndOneByOne) {
  testing::TemporaryDirectory dir;
  Image one(1, 1);
  one.set(0, 0, RGB(3, 2, 1));
  write_image(dir.file("one.exr"), one);
  const Environment env = Environment::load(dir.file("one.exr"));
  EXPECT_LT((env.eval(Vec3(0, 0, 1)) - RGB(3, 2, 1)).abs().maxCoeff(), 1e-6f);
  EXPECT_NEAR(env.sh(2)(0, 0)[0], 3 * 2 * std::sqrt(kPiD), 1e-6);
}

TEST(ImageIo, RealMapsLoadWithTheirDocumentedRange) {
  GLAZE_REQUIRE_ENVMAP(path, "studio_small_03_1k.hdr");
  const Image map = read_image(path.string());
  EXPECT_EQ(map.width, 1024);
  EXPECT_EQ(map.height, 512);
  float maximum = 0;
  for (int j = 0; j < map.height; ++j)
    for (int i = 0; i < map.width; ++i) maximum = std::max(maximum, luminance(map.at(i, j)));
  EXPECT_GT(maximum, 1000.0f);  // DESIGN data README: max luminance about 3350
}

}  // namespace
}  // namespace glaze
