// Tests of the display transform (renderer/display.h) and 8-bit pictures: closed forms
// of the tone curves and of sRGB, and a write-then-read round trip.
#include "renderer/display.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace glaze {
namespace {

TEST(Display, ClampIsTheExposedValueAndSrgbIsTheStandardCurve) {
  const DisplaySettings clamp{0.0f, ToneMapping::clamp};
  EXPECT_FLOAT_EQ(tone_map(0.5f, clamp), 0.5f);
  EXPECT_FLOAT_EQ(tone_map(3.0f, clamp), 1.0f);
  EXPECT_FLOAT_EQ(tone_map(0.25f, {1.0f, ToneMapping::clamp}), 0.5f);    // +1 EV doubles
  EXPECT_FLOAT_EQ(tone_map(0.5f, {-2.0f, ToneMapping::clamp}), 0.125f);  // -2 EV quarters
  // IEC 61966-2-1: 1.055 x^(1/2.4) - 0.055 above 0.0031308, 12.92 x below.
  for (float x : {0.0f, 0.002f, 0.01f, 0.18f, 0.5f, 0.9f, 1.0f}) {
    const double encoded = x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(double(x), 1 / 2.4) - 0.055;
    EXPECT_EQ(srgb_encode_8bit(x), int(std::lround(255 * encoded))) << x;
  }
  EXPECT_EQ(srgb_encode_8bit(0.5f), 188);
  EXPECT_EQ(srgb_encode_8bit(std::numeric_limits<float>::quiet_NaN()), 0);
  EXPECT_EQ(srgb_encode_8bit(-1.0f), 0);
  EXPECT_EQ(srgb_encode_8bit(7.0f), 255);
}

TEST(Display, FilmicAndAcesFollowTheirCurvesAndRollOff) {
  // Hable's curve with its constants, normalised at the white point 11.2, exposure bias 2.
  auto hable = [](double x) {
    const double A = 0.15, B = 0.50, C = 0.10, D = 0.20, E = 0.02, F = 0.30;
    return (x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F) - E / F;
  };
  auto narkowicz = [](double x) {
    const double v = 0.6 * x;
    return std::min(1.0, v * (2.51 * v + 0.03) / (v * (2.43 * v + 0.59) + 0.14));
  };
  for (double x : {0.01, 0.18, 0.5, 1.0, 2.0, 4.0}) {
    EXPECT_NEAR(tone_map(float(x), {0.0f, ToneMapping::filmic}), hable(2 * x) / hable(11.2), 1e-5) << x;
    EXPECT_NEAR(tone_map(float(x), {0.0f, ToneMapping::aces}), narkowicz(x), 1e-5) << x;
  }
  EXPECT_NEAR(tone_map(5.6f, {0.0f, ToneMapping::filmic}), 1.0f, 1e-5);  // 2 x 5.6 = the white point
  for (ToneMapping mapping : {ToneMapping::clamp, ToneMapping::filmic, ToneMapping::aces}) {
    const DisplaySettings settings{0.0f, mapping};
    float previous = -1.0f;
    for (float x = 0.0f; x < 100.0f; x = x * 1.1f + 1e-3f) {
      const float y = tone_map(x, settings);
      EXPECT_GE(y, previous) << tone_mapping_name(mapping) << " at " << x;  // monotonic
      EXPECT_LE(y, 1.0f);
      previous = y;
    }
    EXPECT_EQ(tone_map(0.0f, settings), 0.0f);
    EXPECT_EQ(tone_map(-1.0f, settings), 0.0f);
    EXPECT_EQ(tone_map(std::numeric_limits<float>::quiet_NaN(), settings), 0.0f);
    EXPECT_EQ(tone_map(std::numeric_limits<float>::infinity(), settings), 1.0f);
    EXPECT_EQ(tone_map(3e38f, {10.0f, mapping}), 1.0f);  // overflows the exposure: still 1, not NaN
  }
  EXPECT_EQ(parse_tone_mapping("aces"), ToneMapping::aces);
  EXPECT_THROW(parse_tone_mapping("reinhard"), Error);
}

TEST(Display, FalseColourRunsFromLowToHighAndLeavesUnknownBlack) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> values = {0.0f, 1.0f, 0.5f, nan, -3.0f, 7.0f};
  const std::vector<uint8_t> linear = false_colour_image(values, 6, 1, 0.0f, 1.0f, false);
  // viridis: dark violet at the low end, yellow at the high end; clamped outside.
  EXPECT_EQ(linear[0], 68);
  EXPECT_EQ(linear[1], 1);
  EXPECT_EQ(linear[2], 84);
  EXPECT_EQ(linear[3], 253);
  EXPECT_EQ(linear[4], 231);
  EXPECT_EQ(linear[5], 37);
  EXPECT_EQ(linear[6], 33);
  EXPECT_EQ(linear[7], 145);
  EXPECT_NEAR(linear[8], 141, 1);                     // the middle stop
  EXPECT_EQ(linear[9] + linear[10] + linear[11], 0);  // NaN: black
  EXPECT_EQ(linear[12], 68);                          // below: low end
  EXPECT_EQ(linear[15], 253);                         // above: high end
  // Logarithmic: 1e-3 .. 1 puts 10^-1.5 at the middle; zero and negatives are black.
  const std::vector<float> logs = {float(std::pow(10.0, -1.5)), 0.0f};
  const std::vector<uint8_t> log_colours = false_colour_image(logs, 2, 1, 1e-3f, 1.0f, true);
  EXPECT_EQ(log_colours[1], 145);
  EXPECT_EQ(log_colours[3] + log_colours[4] + log_colours[5], 0);
}

TEST(Display, PicturesRoundTripThroughPngAsSrgb) {
  testing::TemporaryDirectory dir;
  Image image(4, 2);
  for (size_t k = 0; k < image.pixels.size(); ++k) image.pixels[k] = 0.05f * float(k);
  const DisplaySettings settings{0.5f, ToneMapping::aces};
  const std::vector<uint8_t> picture = display_image(image, settings);
  write_picture(dir.file("p.png"), 4, 2, picture);
  const Image read = read_image(dir.file("p.png"));  // decoded from sRGB to linear
  ASSERT_EQ(read.width, 4);
  for (size_t k = 0; k < picture.size(); ++k) {
    EXPECT_EQ(picture[k], srgb_encode_8bit(tone_map(image.pixels[k], settings)));
    EXPECT_NEAR(read.pixels[k], srgb_to_linear(picture[k] / 255.0f), 1e-6) << k;
  }
  EXPECT_THROW(write_picture(dir.file("q.png"), 4, 3, picture), Error);  // wrong size
  try {
    write_picture(dir.file("q.nosuchformat"), 4, 2, picture);
    FAIL() << "no writer for the extension should throw";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("q.nosuchformat"), std::string::npos) << error.what();
    EXPECT_EQ(std::string(error.what()).find(".tmp"), std::string::npos)
        << "names the temporary file: " << error.what();
  }
}

}  // namespace
}  // namespace glaze
