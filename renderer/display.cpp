#include "renderer/display.h"

#include "renderer/error.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace glaze {
namespace {

// Hable's curve before normalisation by its value at the white point.
float hable(float x) {
  constexpr float A = 0.15f, B = 0.50f, C = 0.10f, D = 0.20f, E = 0.02f, F = 0.30f;
  return (x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F) - E / F;
}

// The tone curve of an exposed value x > 0.
float tone_curve(float x, ToneMapping mapping) {
  // Beyond 1e6 every curve is at 1 to float precision; the clamp keeps their rational
  // forms from overflowing into inf / inf.
  x = std::min(x, 1e6f);
  float y = 0.0f;
  switch (mapping) {
    case ToneMapping::clamp:
      y = x;
      break;
    case ToneMapping::filmic: {
      static const float white = hable(11.2f);
      y = hable(2.0f * x) / white;
      break;
    }
    case ToneMapping::aces: {
      const float v = 0.6f * x;
      y = (v * (2.51f * v + 0.03f)) / (v * (2.43f * v + 0.59f) + 0.14f);
      break;
    }
  }
  return std::clamp(y, 0.0f, 1.0f);
}

// Code k is the rounding of 255 x the encoding, so it changes at the linear values whose
// encoding is (k + 1/2) / 255: 255 thresholds, found in double precision once. Encoding
// is then a binary search (eight comparisons) instead of a power per value.
const std::array<float, 255>& srgb_thresholds() {
  static const std::array<float, 255> thresholds = [] {
    std::array<float, 255> t{};
    for (int k = 0; k < 255; ++k) {
      const double encoded = (k + 0.5) / 255.0;
      t[k] = float(encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4));
    }
    return t;
  }();
  return thresholds;
}

}  // namespace

ToneMapping parse_tone_mapping(const std::string& name) {
  if (name == "clamp") return ToneMapping::clamp;
  if (name == "filmic") return ToneMapping::filmic;
  if (name == "aces") return ToneMapping::aces;
  throw Error("unknown tone mapping '" + name + "' (known: clamp, filmic, aces)");
}

const char* tone_mapping_name(ToneMapping mapping) {
  switch (mapping) {
    case ToneMapping::clamp:
      return "clamp";
    case ToneMapping::filmic:
      return "filmic";
    case ToneMapping::aces:
      return "aces";
  }
  return "?";
}

float tone_map(float linear, const DisplaySettings& settings) {
  if (!(linear > 0.0f)) return 0.0f;  // also NaN
  return tone_curve(linear * std::exp2(settings.exposure_ev), settings.tone_mapping);
}

uint8_t srgb_encode_8bit(float value) {
  if (std::isnan(value)) return 0;
  const std::array<float, 255>& t = srgb_thresholds();
  return static_cast<uint8_t>(std::upper_bound(t.begin(), t.end(), value) - t.begin());
}

std::vector<uint8_t> display_image(const Image& image, const DisplaySettings& settings) {
  std::vector<uint8_t> out(image.pixels.size());
  const float scale = std::exp2(settings.exposure_ev);
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, image.pixels.size(), 1 << 14), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t k = range.begin(); k < range.end(); ++k) {
          const float linear = image.pixels[k];
          out[k] = linear > 0.0f ? srgb_encode_8bit(tone_curve(linear * scale, settings.tone_mapping)) : 0;
        }
      });
  return out;
}

std::vector<uint8_t> false_colour_image(std::span<const float> values, int width, int height, float low, float high,
                                        bool logarithmic) {
  if (values.size() != size_t(width) * size_t(height))
    throw Error("false colour: the values do not match the image size");
  // viridis at 0, 1/4, 1/2, 3/4 and 1.
  static constexpr std::array<std::array<float, 3>, 5> kStops = {{{0.267f, 0.005f, 0.329f},
                                                                  {0.229f, 0.322f, 0.546f},
                                                                  {0.128f, 0.567f, 0.551f},
                                                                  {0.369f, 0.789f, 0.383f},
                                                                  {0.993f, 0.906f, 0.144f}}};
  const float lo = logarithmic ? std::log10(low) : low, hi = logarithmic ? std::log10(high) : high;
  std::vector<uint8_t> out(values.size() * 3, 0);
  for (size_t p = 0; p < values.size(); ++p) {
    const float v = values[p];
    if (std::isnan(v) || (logarithmic && !(v > 0.0f))) continue;
    const float t = std::clamp(((logarithmic ? std::log10(v) : v) - lo) / (hi - lo), 0.0f, 1.0f);
    const float position = t * (kStops.size() - 1);
    const size_t i = std::min(size_t(position), kStops.size() - 2);
    const float f = position - float(i);
    for (int c = 0; c < 3; ++c) {
      const float colour = (1.0f - f) * kStops[i][c] + f * kStops[i + 1][c];
      out[3 * p + c] = static_cast<uint8_t>(std::lround(255.0f * colour));
    }
  }
  return out;
}

}  // namespace glaze
