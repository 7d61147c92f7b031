// Tests of image reading and writing (round trips and every kind of bad file) and of the
// bilinear lookup in each wrap mode, against values worked out by hand.
#include "renderer/environment.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/image_lookup.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <fstream>
#include <vector>

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
  EXPECT_GT(maximum, 1000.0f);  // the map's published maximum luminance is about 3350
}

// ---------------------------------------------------------------------------------------
// The bilinear lookup (image_lookup.h). A 4 x 2 image of powers of two, so that every
// blend below is exact in float:
//   row 0:  1   2   4   8
//   row 1: 16  32  64 128
// Texel (i, j)'s centre is at (i + 0.5, j + 0.5).
// ---------------------------------------------------------------------------------------

Image powers_of_two() {
  Image image(4, 2);
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 4; ++i) {
      const float v = float(1 << (i + 4 * j));
      image.set(i, j, RGB(v, -2.0f * v, 0.5f * v));
    }
  return image;
}

// The red channel of the lookup at pixel coordinates (x, y), checking the other two.
float lookup(const Image& image, float x, float y, Wrap wrap_x, Wrap wrap_y) {
  const RGB value = bilinear(image, bilinear_footprint(x, y, image.width, image.height, wrap_x, wrap_y));
  EXPECT_EQ(value[1], -2.0f * value[0]) << x << ", " << y;
  EXPECT_EQ(value[2], 0.5f * value[0]) << x << ", " << y;
  return value[0];
}

void expect_footprint(const BilinearFootprint& at, int x0, int x1, int y0, int y1, float fx, float fy) {
  EXPECT_EQ(at.x0, x0);
  EXPECT_EQ(at.x1, x1);
  EXPECT_EQ(at.y0, y0);
  EXPECT_EQ(at.y1, y1);
  EXPECT_EQ(at.fx, fx);
  EXPECT_EQ(at.fy, fy);
}

TEST(ImageLookup, InsideTheImageEveryModeBlendsTheFourTexelsAround) {
  const Image image = powers_of_two();
  for (const Wrap wrap : {Wrap::repeat, Wrap::clamp, Wrap::mirrored_repeat}) {
    // Texel centres give the texel itself.
    EXPECT_EQ(lookup(image, 1.5f, 0.5f, wrap, wrap), 2.0f);
    EXPECT_EQ(lookup(image, 2.5f, 1.5f, wrap, wrap), 64.0f);
    // (1.75, 1): a quarter of the way from column 1 to 2, half way between the rows:
    // 0.5 (0.75 * 2 + 0.25 * 4) + 0.5 (0.75 * 32 + 0.25 * 64) = 0.5 * 2.5 + 0.5 * 40.
    expect_footprint(bilinear_footprint(1.75f, 1.0f, 4, 2, wrap, wrap), 1, 2, 0, 1, 0.25f, 0.5f);
    EXPECT_EQ(lookup(image, 1.75f, 1.0f, wrap, wrap), 21.25f);
    // Map coordinates are pixel coordinates over the size.
    expect_footprint(bilinear_footprint(Vec2(1.75f / 4, 0.5f), 4, 2, wrap, wrap), 1, 2, 0, 1, 0.25f, 0.5f);
  }
}

// Catmull-Rom: the pixel itself at its centre; any linear ramp exactly between centres
// (its weights sum to 1 and their first moment is the offset); the edge pixels repeated
// outside; and a one-pixel spot read half a pixel off keeps more of its peak than the
// bilinear lookup, which is why the light probe uses it.
TEST(ImageLookup, CatmullRomInterpolatesCentresAndRampsAndBlursLess) {
  Image image(6, 5);
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 6; ++i)
      image.set(i, j, RGB(2.0f + 0.5f * i - 0.25f * j, float(i * j), float((i * 7 + j * 3) % 5)));
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 6; ++i) {
      const RGB value = catmull_rom(image, catmull_rom_footprint(i + 0.5f, j + 0.5f, 6, 5));
      EXPECT_EQ(value[0], image.at(i, j)[0]) << i << ", " << j;
      EXPECT_EQ(value[2], image.at(i, j)[2]) << i << ", " << j;
    }
  for (const float x : {1.5f, 2.1f, 3.73f, 4.5f})
    for (const float y : {1.5f, 2.2f, 3.5f})
      EXPECT_NEAR(catmull_rom(image, catmull_rom_footprint(x, y, 6, 5))[0],
                  2.0f + 0.5f * (x - 0.5f) - 0.25f * (y - 0.5f), 1e-5f)
          << x << ", " << y;
  const CubicFootprint corner = catmull_rom_footprint(0.2f, 0.1f, 6, 5);
  for (int k = 0; k < 4; ++k) {
    EXPECT_GE(corner.x[k], 0);
    EXPECT_GE(corner.y[k], 0);
  }
  Image flat(6, 5);
  for (float& value : flat.pixels) value = 3.0f;
  for (const float x : {0.0f, 0.2f, 2.7f, 5.9f, 6.0f})
    EXPECT_FLOAT_EQ(catmull_rom(flat, catmull_rom_footprint(x, 0.1f, 6, 5))[1], 3.0f) << x;

  Image spot(5, 5);
  spot.set(2, 2, RGB::Constant(1.0f));
  const float cubic = catmull_rom(spot, catmull_rom_footprint(3.0f, 2.5f, 5, 5))[0];
  const float linear = bilinear(spot, bilinear_footprint(3.0f, 2.5f, 5, 5, Wrap::clamp, Wrap::clamp))[0];
  EXPECT_FLOAT_EQ(linear, 0.5f);
  EXPECT_FLOAT_EQ(cubic, 0.5625f);  // w1(0.5) = 9/16
}

TEST(ImageLookup, RepeatTilesTheImage) {
  const Image image = powers_of_two();
  // Left of column 0's centre: between column 3 (of the tile before) and column 0.
  // x = 0.25: 0.25 * 8 + 0.75 * 1; the rows at y = 0.5 are row 0 alone.
  expect_footprint(bilinear_footprint(0.25f, 0.5f, 4, 2, Wrap::repeat, Wrap::repeat), 3, 0, 0, 1, 0.75f, 0.0f);
  EXPECT_EQ(lookup(image, 0.25f, 0.5f, Wrap::repeat, Wrap::repeat), 2.75f);
  // Past the right edge the same again.
  EXPECT_EQ(lookup(image, 4.25f, 0.5f, Wrap::repeat, Wrap::repeat), 2.75f);
  // Above row 0's centre: between row 1 and row 0, 0.25 * 32 + 0.75 * 2.
  expect_footprint(bilinear_footprint(1.5f, 0.25f, 4, 2, Wrap::repeat, Wrap::repeat), 1, 2, 1, 0, 0.0f, 0.75f);
  EXPECT_EQ(lookup(image, 1.5f, 0.25f, Wrap::repeat, Wrap::repeat), 9.5f);
  // Any whole number of tiles away (exactly, even 2^20 texels off): the same footprint.
  for (const float x : {0.25f, 1.75f, 2.875f, 3.5f})
    for (const float tiles : {-262144.0f, -3.0f, -1.0f, 1.0f, 5.0f, 262144.0f}) {
      const BilinearFootprint at = bilinear_footprint(x, 1.25f, 4, 2, Wrap::repeat, Wrap::repeat);
      const BilinearFootprint away =
          bilinear_footprint(x + 4.0f * tiles, 1.25f + 2.0f * tiles, 4, 2, Wrap::repeat, Wrap::repeat);
      expect_footprint(away, at.x0, at.x1, at.y0, at.y1, at.fx, at.fy);
    }
}

TEST(ImageLookup, ClampContinuesTheEdgeTexels) {
  const Image image = powers_of_two();
  // Left of and above texel (0, 0)'s centre, and far beyond: texel (0, 0) alone.
  expect_footprint(bilinear_footprint(0.25f, 0.25f, 4, 2, Wrap::clamp, Wrap::clamp), 0, 0, 0, 0, 0.75f, 0.75f);
  EXPECT_EQ(lookup(image, 0.25f, 0.25f, Wrap::clamp, Wrap::clamp), 1.0f);
  EXPECT_EQ(lookup(image, -5.0f, -9.0f, Wrap::clamp, Wrap::clamp), 1.0f);
  // Right of and below texel (3, 1)'s centre: texel (3, 1) alone.
  expect_footprint(bilinear_footprint(4.0f, 2.0f, 4, 2, Wrap::clamp, Wrap::clamp), 3, 3, 1, 1, 0.5f, 0.5f);
  EXPECT_EQ(lookup(image, 4.0f, 2.0f, Wrap::clamp, Wrap::clamp), 128.0f);
  // Past one edge only: the edge column, blended between the rows as inside,
  // 0.5 * 8 + 0.5 * 128.
  EXPECT_EQ(lookup(image, 7.0f, 1.0f, Wrap::clamp, Wrap::clamp), 68.0f);
}

TEST(ImageLookup, MirroredRepeatMirrorsEveryOtherTile) {
  const Image image = powers_of_two();
  // Columns beyond the right edge run back: 3 2 1 0 | 0 1 2 3 | 3 2 1 0.
  // x = 6.25 (5.75 from the centres' origin): columns 2 and 1, 0.25 * 4 + 0.75 * 2.
  expect_footprint(bilinear_footprint(6.25f, 0.5f, 4, 2, Wrap::mirrored_repeat, Wrap::mirrored_repeat), 2, 1, 0, 1,
                   0.75f, 0.0f);
  EXPECT_EQ(lookup(image, 6.25f, 0.5f, Wrap::mirrored_repeat, Wrap::mirrored_repeat), 2.5f);
  // At either edge the edge texel meets its own mirror image.
  EXPECT_EQ(lookup(image, 0.25f, 0.5f, Wrap::mirrored_repeat, Wrap::mirrored_repeat), 1.0f);
  EXPECT_EQ(lookup(image, 4.25f, 0.5f, Wrap::mirrored_repeat, Wrap::mirrored_repeat), 8.0f);
  // x = -1.5 is column 1's mirror image: 2.
  EXPECT_EQ(lookup(image, -1.5f, 0.5f, Wrap::mirrored_repeat, Wrap::mirrored_repeat), 2.0f);
  // Rows: 1 0 | 0 1 | 1 0; y = 2.75 is between row 1 and row 0 of the mirrored tile,
  // 0.75 * 32 + 0.25 * 2.
  expect_footprint(bilinear_footprint(1.5f, 2.75f, 4, 2, Wrap::mirrored_repeat, Wrap::mirrored_repeat), 1, 2, 1, 0,
                   0.0f, 0.25f);
  EXPECT_EQ(lookup(image, 1.5f, 2.75f, Wrap::mirrored_repeat, Wrap::mirrored_repeat), 24.5f);
  // The whole is symmetric about the image's edges, and repeats every two tiles (the
  // weights are multiples of 1/8, so every blend is exact).
  for (const float x : {0.125f, 0.75f, 1.5f, 2.25f, 3.875f, 5.5f, 7.75f})
    for (const float y : {0.25f, 1.0f, 1.75f}) {
      const float value = lookup(image, x, y, Wrap::mirrored_repeat, Wrap::mirrored_repeat);
      EXPECT_EQ(lookup(image, -x, y, Wrap::mirrored_repeat, Wrap::mirrored_repeat), value) << x << ", " << y;
      EXPECT_EQ(lookup(image, x, 4.0f - y, Wrap::mirrored_repeat, Wrap::mirrored_repeat), value) << x << ", " << y;
      EXPECT_EQ(lookup(image, x + 8.0f, y - 4.0f, Wrap::mirrored_repeat, Wrap::mirrored_repeat), value)
          << x << ", " << y;
    }
}

// Every texel index against integer arithmetic, for image sizes 1 to 64 and points up to
// 2^21 texels away (the float quotient behind repeating must not step early or late);
// points absurdly far away still read texels of the image.
TEST(ImageLookup, IndicesAreExactFarFromTheImageAndInsideItBeyond) {
  const auto repeat = [](long t, long n) { return ((t % n) + n) % n; };
  const auto mirror = [&](long t, long n) {
    const long r = repeat(t, 2 * n);
    return r < n ? r : 2 * n - 1 - r;
  };
  for (int n = 1; n <= 64; ++n) {
    std::vector<long> points;
    for (long t = -9L * n; t <= 9L * n; ++t) points.push_back(t);
    for (long t = (1L << 21) - 3L * n; t <= (1L << 21) + 3L * n; ++t) points.push_back(t), points.push_back(-t);
    for (const long t : points) {
      // A quarter of a texel past texel t's centre: texels t and t + 1.
      const float x = float(t) + 0.75f;
      const BilinearFootprint repeated = bilinear_footprint(x, 0.5f, n, 1, Wrap::repeat, Wrap::clamp);
      ASSERT_EQ(repeated.x0, repeat(t, n)) << "n " << n << ", t " << t;
      ASSERT_EQ(repeated.x1, repeat(t + 1, n)) << "n " << n << ", t " << t;
      const BilinearFootprint mirrored = bilinear_footprint(x, 0.5f, n, 1, Wrap::mirrored_repeat, Wrap::clamp);
      ASSERT_EQ(mirrored.x0, mirror(t, n)) << "n " << n << ", t " << t;
      ASSERT_EQ(mirrored.x1, mirror(t + 1, n)) << "n " << n << ", t " << t;
      ASSERT_EQ(repeated.fx, 0.25f);
    }
  }
  for (const float far : {3e7f, -3e7f, 1e30f, -1e30f})
    for (const Wrap wrap : {Wrap::repeat, Wrap::clamp, Wrap::mirrored_repeat}) {
      const BilinearFootprint at = bilinear_footprint(far, far, 5, 3, wrap, wrap);
      for (const int x : {at.x0, at.x1}) EXPECT_TRUE(x >= 0 && x < 5) << far << ": column " << x;
      for (const int y : {at.y0, at.y1}) EXPECT_TRUE(y >= 0 && y < 3) << far << ": row " << y;
    }
}

// Each axis wraps by its own mode: here repeating across the left edge and clamped above
// the top, so 0.25 * 8 + 0.75 * 1 from row 0 alone.
TEST(ImageLookup, EachAxisHasItsOwnMode) {
  const Image image = powers_of_two();
  expect_footprint(bilinear_footprint(0.25f, 0.25f, 4, 2, Wrap::repeat, Wrap::clamp), 3, 0, 0, 0, 0.75f, 0.75f);
  EXPECT_EQ(lookup(image, 0.25f, 0.25f, Wrap::repeat, Wrap::clamp), 2.75f);
  expect_footprint(bilinear_footprint(0.25f, 0.25f, 4, 2, Wrap::clamp, Wrap::repeat), 0, 0, 1, 0, 0.75f, 0.75f);
  EXPECT_EQ(lookup(image, 0.25f, 0.25f, Wrap::clamp, Wrap::repeat), 0.25f * 16 + 0.75f * 1);
}

}  // namespace
}  // namespace glaze
