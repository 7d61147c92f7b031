#include "renderer/environment_format.h"

#include "renderer/checked_math.h"
#include "renderer/error.h"
#include "renderer/image_lookup.h"
#include "renderer/latlong.h"
#include "renderer/memory_budget.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace glaze {
namespace {

// Lookups along each axis of a lat-long texel when reading a probe: 2N x N texels are no
// larger than an N-pixel probe's pixels anywhere (the mirror ball's rim packs many texels
// into a pixel, never the reverse), so a few lookups spread over each texel average it.
constexpr int kTexelSamples = 2;
// And of a probe pixel when writing one: towards a mirror ball's rim a pixel spans many
// texels.
constexpr int kPixelSamples = 4;
// How far inside the rim (in pixels) lookups stay: a bilinear lookup there reads only
// pixels whose centres lie inside the circle.
constexpr double kRimMarginPixels = 1.5;
// Pixels outside the circle count as black when below this fraction of the brightest one
// (room for a lossy or dithered file's noise).
constexpr float kBlackFraction = 1e-4f;

// theta (the angle from +Z) at disc radius r, and back.
double probe_theta(EnvironmentFormat format, double r) {
  return format == EnvironmentFormat::angular ? kPiD * r : 2.0 * std::asin(std::min(r, 1.0));
}
double probe_radius(EnvironmentFormat format, double theta) {
  return format == EnvironmentFormat::angular ? theta / kPiD : std::sin(0.5 * theta);
}

void require_square(const Image& image, EnvironmentFormat format, const std::string& source) {
  if (image.width != image.height)
    throw Error(source + ": an environment in the " + environment_format_name(format) +
                " format must be a square image, but it is " + std::to_string(image.width) + "x" +
                std::to_string(image.height) + "; give the format it is in (latlong for a 2:1 map)");
}

// Disc coordinates of pixel position (px, py) of an N x N image (pixel units, y down), and back.
Vec2d disc_of_pixel(double px, double py, int n) { return {2.0 * px / n - 1.0, 1.0 - 2.0 * py / n}; }
Vec2d pixel_of_disc(const Vec2d& p, int n) { return {0.5 * (p.x() + 1.0) * n, 0.5 * (1.0 - p.y()) * n}; }

}  // namespace

EnvironmentFormat parse_environment_format(const std::string& name, const std::string& where) {
  if (name == "auto") return EnvironmentFormat::automatic;
  if (name == "latlong") return EnvironmentFormat::latlong;
  if (name == "angular") return EnvironmentFormat::angular;
  if (name == "mirror_ball") return EnvironmentFormat::mirror_ball;
  throw Error(where + ": environment format \"" + name + "\" is not one of latlong, angular, mirror_ball (or auto)");
}

const char* environment_format_name(EnvironmentFormat format) {
  switch (format) {
    case EnvironmentFormat::automatic:
      return "auto";
    case EnvironmentFormat::latlong:
      return "latlong";
    case EnvironmentFormat::angular:
      return "angular";
    case EnvironmentFormat::mirror_ball:
      return "mirror_ball";
  }
  return "?";
}

Vec3d probe_direction(EnvironmentFormat format, const Vec2d& p) {
  const double r = p.norm();
  if (!(r > 0.0)) return Vec3d::UnitZ();
  const double theta = probe_theta(format, r);
  const double s = std::sin(theta) / r;
  return {s * p.x(), s * p.y(), std::cos(theta)};
}

Vec2d probe_position(EnvironmentFormat format, const Vec3d& d) {
  const double rho = std::hypot(d.x(), d.y());
  if (!(rho > 0.0)) return d.z() >= 0.0 ? Vec2d::Zero() : Vec2d(1.0, 0.0);  // -Z: any point of the rim
  const double r = probe_radius(format, std::atan2(rho, d.z()));
  return Vec2d(d.x(), d.y()) * (r / rho);
}

EnvironmentFormat recognise_environment_format(const Image& image, const std::string& source) {
  if (image.width != image.height) return EnvironmentFormat::latlong;
  const int n = image.width;
  float outside = 0.0f, inside = 0.0f;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const float brightest = image.at(i, j).maxCoeff();
      // A pixel wholly outside the circle: its centre more than half a diagonal beyond.
      if (disc_of_pixel(i + 0.5, j + 0.5, n).norm() > 1.0 + 1.5 / n)
        outside = std::max(outside, brightest);
      else
        inside = std::max(inside, brightest);
    }
  }
  if (!(outside <= kBlackFraction * inside))
    throw Error(source +
                ": a square image with light outside its inscribed circle is neither a lat-long map (2:1) "
                "nor a light probe; give its format (--env-format latlong|angular|mirror_ball, or "
                "\"format\" in the scene's or capture set's environment)");
  warn(source +
       ": square with black outside its circle: read as an angular map (Debevec's light-probe format); if it "
       "is a mirror-ball image, give the format mirror_ball (--env-format, or \"format\" in the environment)");
  return EnvironmentFormat::angular;
}

Image probe_to_latlong(const Image& probe, EnvironmentFormat format, const std::string& source) {
  require_square(probe, format, source);
  const int n = probe.width;
  if (n > (1 << 28)) throw Error(source + ": a probe image of " + std::to_string(n) + " pixels across is too large");
  const int width = 2 * n, height = n;
  require_memory(saturating_mul(uint64_t(width) * uint64_t(height), sizeof(RGB)), "the lat-long map of " + source);
  Image map(width, height);
  const double largest_radius = std::max(0.0, 1.0 - 2.0 * kRimMarginPixels / n);
  // Rows are independent: the result does not depend on the thread count.
  tbb::parallel_for(0, height, [&](int j) {
    for (int i = 0; i < width; ++i) {
      RGBd sum = RGBd::Zero();
      double weight = 0.0;
      for (int b = 0; b < kTexelSamples; ++b) {
        for (int a = 0; a < kTexelSamples; ++a) {
          const Vec2 uv((i + (a + 0.5f) / kTexelSamples) / width, (j + (b + 0.5f) / kTexelSamples) / height);
          float sin_theta = 0.0f;
          const Vec3 d = latlong_to_direction(uv, &sin_theta);
          Vec2d p = probe_position(format, d.cast<double>());
          if (const double r = p.norm(); r > largest_radius) p *= largest_radius / r;
          const Vec2d pixel = pixel_of_disc(p, n);
          const RGB value =
              bilinear(probe, bilinear_footprint(float(pixel.x()), float(pixel.y()), n, n, Wrap::clamp, Wrap::clamp));
          sum += sin_theta * value.cast<double>();
          weight += sin_theta;
        }
      }
      map.set(i, j, (sum / weight).cast<float>());
    }
  });
  return map;
}

Image latlong_to_probe(const Image& latlong, EnvironmentFormat format, int size) {
  if (format != EnvironmentFormat::angular && format != EnvironmentFormat::mirror_ball)
    throw Error(std::string("a probe image is angular or mirror_ball, not ") + environment_format_name(format));
  if (size <= 0) throw Error("a probe image needs a positive size, not " + std::to_string(size));
  require_memory(saturating_mul(uint64_t(size) * uint64_t(size), sizeof(RGB)), "a probe image");
  Image probe(size, size);
  tbb::parallel_for(0, size, [&](int j) {
    for (int i = 0; i < size; ++i) {
      RGBd sum = RGBd::Zero();
      int count = 0;
      for (int b = 0; b < kPixelSamples; ++b) {
        for (int a = 0; a < kPixelSamples; ++a) {
          const Vec2d p = disc_of_pixel(i + (a + 0.5) / kPixelSamples, j + (b + 0.5) / kPixelSamples, size);
          if (p.norm() >= 1.0) continue;
          const Vec2 uv = direction_to_latlong(probe_direction(format, p).cast<float>());
          sum += bilinear(latlong, bilinear_footprint(uv, latlong.width, latlong.height, Wrap::repeat, Wrap::clamp))
                     .cast<double>();
          ++count;
        }
      }
      if (count > 0) probe.set(i, j, (sum / count).cast<float>());
    }
  });
  return probe;
}

Image read_environment_map(const std::string& path, EnvironmentFormat format) {
  Image image = read_image(path);
  if (format == EnvironmentFormat::automatic) format = recognise_environment_format(image, path);
  if (format == EnvironmentFormat::latlong) return image;
  return probe_to_latlong(image, format, path);
}

}  // namespace glaze
