// photo_bracket.h: exposure brackets synthesised for the HDR merge's tests and benchmark:
// a known linear scene, photographed at known exposures through a known tone curve that
// is not a power law, with shot and read noise and 8-bit quantisation.
#pragma once

#include "inverse/photos/bracket.h"
#include "inverse/photos/shoot_simulator.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/rng.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace glaze::testing {

// The tone curve is the shoot simulator's film_curve (not a power law) unless a test
// names another: a curve from signal (1 at full well) to code / 255, and its inverse.
using glaze::film_curve;
using glaze::film_curve_inverse;
struct ToneCurve {
  double (*forward)(double);
  double (*inverse)(double);
};
inline constexpr ToneCurve kFilmCurve{film_curve, film_curve_inverse};
// sRGB's encoding (a linear toe and a 1/2.4 power: the renderer's), and a pure 1/2.2 power.
inline constexpr ToneCurve kSrgbCurve{[](double x) { return double(linear_to_srgb(float(std::clamp(x, 0.0, 1.0)))); },
                                      [](double v) { return double(srgb_to_linear(float(v))); }};
inline constexpr ToneCurve kGamma22Curve{[](double x) { return std::pow(std::clamp(x, 0.0, 1.0), 1.0 / 2.2); },
                                         [](double v) { return std::pow(v, 2.2); }};
// A filmic S-curve: Narkowicz's fit of ACES's, a(x) = x (2.51 x + 0.03) / (x (2.43 x +
// 0.59) + 0.14) at x = 4 times the signal, scaled so that the full well gives code 255;
// and its inverse, the root x >= 0 of the quadratic.
inline double aces_filmic(double x) { return x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14); }
inline constexpr ToneCurve kAcesCurve{
    [](double s) { return aces_filmic(4.0 * std::clamp(s, 0.0, 1.0)) / aces_filmic(4.0); },
    [](double v) {
      const double y = v * aces_filmic(4.0);
      const double a = 2.43 * y - 2.51, b = 0.59 * y - 0.03, c = 0.14 * y;
      return (-b - std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a) / 4.0;
    }};

// The scene: a gradient over five decades along x (0.02 to 2000), a texture, a colour,
// and a hot spot (radius height/8, 50000) that saturates every exposure.
struct SyntheticScene {
  int width = 0, height = 0;
  std::vector<double> radiance;  // width * height * 3
  std::vector<uint8_t> hot;      // 1 in the hot spot
};
inline SyntheticScene synthetic_scene(int width, int height) {
  SyntheticScene scene{width, height, std::vector<double>(size_t(width) * height * 3), {}};
  scene.hot.assign(size_t(width) * height, 0);
  const double colour[3] = {1.0, 0.6, 0.35};
  const double r = height / 8.0, cx = width * 0.85, cy = height * 0.3;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t p = size_t(y) * width + x;
      const double gradient = 0.02 * std::pow(1e5, (x + 0.5) / width);
      const double texture = 1.0 + 0.3 * std::sin(x * 0.7) * std::sin(y * 0.45);
      scene.hot[p] = (x - cx) * (x - cx) + (y - cy) * (y - cy) < r * r;
      for (int c = 0; c < 3; ++c) scene.radiance[p * 3 + c] = scene.hot[p] ? 5e4 : gradient * texture * colour[c];
    }
  return scene;
}

// The scene photographed for `seconds` through `curve`: 60000 electrons at E = 1 (a
// full-frame sensor at base ISO), Poisson shot noise (as a Gaussian) and 5 electrons of
// read noise, unless `noise` is off.
inline PhotoCodes photograph(const SyntheticScene& scene, double seconds, uint64_t seed, bool noise = true,
                             const ToneCurve& curve = kFilmCurve) {
  constexpr double kFullWell = 60000.0, kReadNoise = 5.0;
  PhotoCodes photo{scene.width, scene.height, 8, false, std::vector<uint16_t>(scene.radiance.size())};
  Pcg32 rng(seed, uint64_t(seconds * 1e6));
  auto gaussian = [&rng] {  // Box-Muller
    const double u = std::max<double>(rng.next_float(), 1e-9), v = rng.next_float();
    return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * M_PI * v);
  };
  for (size_t i = 0; i < scene.radiance.size(); ++i) {
    double electrons = scene.radiance[i] * seconds * kFullWell;
    if (noise) electrons += std::sqrt(electrons) * gaussian() + kReadNoise * gaussian();
    photo.codes[i] = uint16_t(std::lround(255.0 * curve.forward(electrons / kFullWell)));
  }
  return photo;
}

// Writes `photo` (8- or 16-bit, by its bits) to `path` with metadata attributes (EXIF
// "ExposureTime", "FNumber", ... as numbers) and the EXIF ISO when `iso` > 0.
inline void write_photo(const std::string& path, const PhotoCodes& photo,
                        const std::map<std::string, float>& attributes = {}, int iso = 0) {
  auto output = OIIO::ImageOutput::create(path);
  if (!output) throw Error(path + ": no writer");
  OIIO::ImageSpec spec(photo.width, photo.height, 3, photo.bits == 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16);
  for (const auto& [key, value] : attributes) spec.attribute(key, value);
  if (iso > 0) spec.attribute("Exif:PhotographicSensitivity", iso);  // an integer, as EXIF stores it
  if (photo.bits == 8) spec.attribute("Compression", "jpeg:100");
  std::vector<uint8_t> bytes(photo.codes.begin(), photo.codes.end());
  const bool ok = output->open(path, spec) &&
                  (photo.bits == 8 ? output->write_image(OIIO::TypeDesc::UINT8, bytes.data())
                                   : output->write_image(OIIO::TypeDesc::UINT16, photo.codes.data())) &&
                  output->close();
  if (!ok) throw Error(path + ": " + output->geterror());
}

}  // namespace glaze::testing
