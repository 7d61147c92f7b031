// display.h: from linear radiance to the 8-bit sRGB a screen shows, one transform for
// every picture glaze shows or writes for people (the preview window, `glaze render
// --out FILE.png`, the preview's saved PNGs), so that they agree pixel for pixel.
//
//   value -> value * 2^EV -> tone mapping -> sRGB encoding (IEC 61966-2-1) -> 8 bits
//
// Tone mappings, applied per channel to the exposed value x:
//   clamp   min(x, 1): the plain linear image, highlights clipped.
//   filmic  Hable's filmic curve (the "Uncharted 2" operator), shoulder at a linear
//           white of 11.2, with its customary exposure bias of 2: mid-grey 0.18 shows
//           a little darker than under clamp, highlights roll off instead of clipping.
//   aces    Narkowicz's rational fit of the ACES reference rendering transform, on
//           x * 0.6 (his normalisation): more contrast than filmic, also rolls off.
// False colour maps a scalar (an error, n.v) onto a perceptually ordered ramp
// (viridis' key colours: dark violet for low, yellow for high); pixels without a
// value are black.
#pragma once

#include "renderer/image.h"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace glaze {

enum class ToneMapping { clamp, filmic, aces };

// "clamp", "filmic" or "aces"; throws glaze::Error naming the known ones otherwise.
ToneMapping parse_tone_mapping(const std::string& name);
const char* tone_mapping_name(ToneMapping mapping);

struct DisplaySettings {
  float exposure_ev = 0.0f;  // stops: each +1 doubles the radiance
  ToneMapping tone_mapping = ToneMapping::filmic;
};

// A tone-mapped value in [0, 1] (before sRGB encoding); NaN and negative give 0.
float tone_map(float linear, const DisplaySettings& settings);
// The sRGB transfer function (IEC 61966-2-1) of a value in [0, 1], as the 8-bit code.
uint8_t srgb_encode_8bit(float value);

// Row-major 8-bit sRGB, 3 bytes a pixel, of `image` under `settings`.
std::vector<uint8_t> display_image(const Image& image, const DisplaySettings& settings);

// False colour of one value per pixel (row-major, width * height): t = (v - low) /
// (high - low), or the same of log10 when `logarithmic`, clamped to [0, 1]; values that
// are NaN (or not positive, when logarithmic) are black.
std::vector<uint8_t> false_colour_image(std::span<const float> values, int width, int height, float low, float high,
                                        bool logarithmic);

}  // namespace glaze
