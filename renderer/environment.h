// environment.h: distant lighting from a lat-long map (docs/design.md §3), the one environment
// lookup used by the path tracer, the SH integrator and the inverse fits.
//
// A world direction w (pointing away from the scene) is turned into the map's frame,
// d = local_to_world^T w, then u = atan2(d.x, -d.z) / (2 pi) mod 1, v = acos(d.y) / pi;
// texel (i, j) has its centre at ((i + 0.5) / W, (j + 0.5) / H), row 0 is the top (+Y).
// Lookups are bilinear (image_lookup.h), wrapping in u and clamping in v. local_to_world
// is the `rotation` option (degrees about +Y, +Z turning towards +X) applied after
// `to_world`.
#pragma once

#include "renderer/environment_format.h"
#include "renderer/image.h"
#include "renderer/image_lookup.h"
#include "renderer/lanes.h"
#include "renderer/latlong.h"
#include "renderer/math.h"
#include "renderer/rng.h"
#include "renderer/sampling.h"
#include "renderer/sh.h"

#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>

namespace glaze {

struct EnvironmentOptions {
  float scale = 1.0f;
  float rotation_degrees = 0.0f;
  Mat3 to_world = Mat3::Identity();  // must be a rotation
  // How load() reads a file (environment_format.h); a probe becomes a lat-long map before
  // the orientation applies.
  EnvironmentFormat format = EnvironmentFormat::automatic;
};

// A direction located in the map: what eval() and pdf() read, computed once so that a
// caller can prefetch the texels (see prefetch()) and do other work while they arrive.
struct EnvironmentLookup {
  BilinearFootprint footprint;  // the map's texels eval() blends
  Vec2 uv;
  float sin_theta;
  int texel;  // row-major index of the texel containing uv (its sampling density)
};

struct EnvironmentSample {
  Vec3 direction;  // world space, unit length
  float pdf;       // solid-angle density; 0 if the sample is unusable (at a pole)
};

class Environment {
 public:
  // `radiance` is the map as stored (before scale). Non-finite or negative texels are
  // set to zero with a warning naming `source` and the count. Throws glaze::Error for
  // an empty map, a to_world that is not a rotation, or a texel whose radiance times
  // the scale exceeds 1e20 (rendering would overflow float); warns if the map is not 2:1.
  Environment(Image radiance, const EnvironmentOptions& options, std::string source = "environment");
  // Loads any image OpenImageIO reads: a lat-long map, or an angular or mirror-ball image
  // (options.format, recognised when automatic) resampled into one.
  static Environment load(const std::string& path, const EnvironmentOptions& options = {});

  const std::string& source() const { return source_; }
  const Image& map() const { return map_; }
  float scale() const { return scale_; }
  const Mat3& local_to_world() const { return local_to_world_; }

  // Radiance arriving from world direction w (scale included).
  RGB eval(const Vec3& w) const { return eval(locate(w)); }
  RGB eval(const EnvironmentLookup& at) const { return scale_ * bilinear(map_, at.footprint); }

  // Inline and free of branches, so that a loop locating many directions vectorises.
  [[gnu::always_inline]] EnvironmentLookup locate(const Vec3& w) const {
    const Vec3 d = local_to_world_.transpose() * w;
    EnvironmentLookup at;
    at.uv = direction_to_latlong(d, &at.sin_theta);
    at.footprint = bilinear_footprint(at.uv, map_.width, map_.height, Wrap::repeat, Wrap::clamp);
    at.texel = texel_of(at.uv, map_.width, map_.height);
    return at;
  }
  // Asks the memory system for the texels eval(at) reads (and, with `density`, the
  // sampling density pdf(at) reads) without waiting for them.
  void prefetch(const EnvironmentLookup& at, bool density) const;

  // Importance sampling: piecewise constant in (u, v) proportional to luminance times
  // sin(theta) (with each texel's weight the maximum over its 3x3 neighbourhood, so
  // that every direction where the bilinear lookup is non-zero can be sampled): a texel
  // from an alias table, then a uniform point in it. Draws five numbers from rng (64
  // bits for the table entry, a coin, the point). Built on first use: a scene that never
  // samples the environment never pays for it.
  EnvironmentSample sample(Pcg32& rng) const;
  // The same for out.size() samples, interleaved so that their table reads overlap.
  void sample(Pcg32& rng, std::span<EnvironmentSample> out) const;
  float pdf(const Vec3& w) const { return pdf(locate(w)); }
  float pdf(const EnvironmentLookup& at) const;

  // SH coefficients of the (scaled, oriented) environment, computed once per lmax.
  const ShCoefficients& sh(int lmax) const;

  // Map coordinates (u, v) in [0, 1)^2 of world direction w, and back.
  Vec2 direction_to_uv(const Vec3& w) const;
  Vec3 uv_to_direction(const Vec2& uv) const;

 private:
  // What importance sampling needs, built on first use: the alias table over texels
  // (row-major), and sin/cos of each row's and column's starting angle, so that a
  // sampled direction costs no trigonometric calls (angle addition with a short series
  // for the offset inside the texel, exact to float rounding for texels under 0.05 rad).
  struct Sampling {
    explicit Sampling(const Image& map);
    AliasTable texels;
    bool tables_exact;                          // texels small enough for the series
    std::vector<Eigen::Vector2f> row_start;     // (sin, cos) of theta = pi j / H
    std::vector<Eigen::Vector2f> column_start;  // (sin, cos) of phi = 2 pi i / W
  };
  const Sampling& sampling() const;
  // The five numbers of one sample.
  struct SampleNumbers {
    uint64_t bits;
    float coin, x, y;
  };
  static SampleNumbers draw(Pcg32& rng);
  // Density in (u, v) of a texel drawn with probability pmf: pmf over its area 1 / (W H).
  float texel_density(float pmf) const { return pmf * float(map_.width) * float(map_.height); }
  // The sample at offset (x, y) in [0, 1)^2 inside texel `texel`, whose pmf is given.
  EnvironmentSample sample_at(int texel, float x, float y, float pmf) const;

  Image map_;
  float scale_;
  Mat3 local_to_world_;
  std::string source_;

  mutable std::once_flag sampling_once_;
  mutable std::unique_ptr<Sampling> sampling_;
  mutable std::mutex sh_mutex_;
  mutable std::map<int, ShCoefficients> sh_cache_;
};

// Environment::locate of 16 directions, as structure of arrays (lanes.h).
struct EnvironmentLookups {
  alignas(64) int x0[kLanes];
  alignas(64) int x1[kLanes];
  alignas(64) int y0[kLanes];
  alignas(64) int y1[kLanes];
  alignas(64) float fx[kLanes];
  alignas(64) float fy[kLanes];
  alignas(64) float u[kLanes];
  alignas(64) float v[kLanes];
  alignas(64) float sin_theta[kLanes];
  alignas(64) int texel[kLanes];

  // Always inlined: in the caller, whose lanes are its own locals, the compiler can see
  // that the lookups, the directions and the map do not overlap, and vectorises.
  [[gnu::always_inline]] void locate(const Environment& environment, const Directions& d) {
    for (int k = 0; k < kLanes; ++k) {
      const EnvironmentLookup at = environment.locate(Vec3(d.x[k], d.y[k], d.z[k]));
      x0[k] = at.footprint.x0;
      x1[k] = at.footprint.x1;
      y0[k] = at.footprint.y0;
      y1[k] = at.footprint.y1;
      fx[k] = at.footprint.fx;
      fy[k] = at.footprint.fy;
      u[k] = at.uv.x();
      v[k] = at.uv.y();
      sin_theta[k] = at.sin_theta;
      texel[k] = at.texel;
    }
  }
  EnvironmentLookup operator[](int k) const {
    return {{x0[k], x1[k], y0[k], y1[k], fx[k], fy[k]}, Vec2(u[k], v[k]), sin_theta[k], texel[k]};
  }
};

// Parses an environment specification "procedural:NAME" or a file path and builds it;
// `resolution` (width, height) applies to procedural maps.
Environment make_environment(const std::string& spec, const EnvironmentOptions& options = {}, int width = 1024,
                             int height = 512);

}  // namespace glaze
