#include "renderer/environment.h"

#include "renderer/checked_math.h"
#include "renderer/error.h"
#include "renderer/latlong.h"
#include "renderer/memory_budget.h"
#include "renderer/procedural_environment.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

namespace glaze {

Environment::Environment(Image radiance, const EnvironmentOptions& options, std::string source)
    : map_(std::move(radiance)), scale_(options.scale), source_(std::move(source)) {
  if (map_.width <= 0 || map_.height <= 0 || map_.pixels.size() != size_t(map_.width) * map_.height * 3)
    throw Error(source_ + ": environment map is empty");
  if (!std::isfinite(scale_) || scale_ < 0.0f)
    throw Error(source_ + ": environment scale must be finite and >= 0, got " + std::to_string(scale_));
  if (!std::isfinite(options.rotation_degrees))
    throw Error(source_ + ": environment rotation must be a finite number of degrees");
  const Mat3& to_world = options.to_world;
  if (!to_world.allFinite() || (to_world.transpose() * to_world - Mat3::Identity()).norm() > 1e-3f ||
      to_world.determinant() <= 0.0f) {
    std::ostringstream message;
    message << source_ << ": environment to_world must be a rotation (orthonormal, determinant +1), got\n" << to_world;
    throw Error(message.str());
  }
  if (map_.width != 2 * map_.height) {
    warn(source_ + ": environment map is " + std::to_string(map_.width) + "x" + std::to_string(map_.height) +
         ", not 2:1; it is still read as lat-long (u spans 360 degrees, v 180), which stretches it");
  }
  size_t repaired = 0;
  for (float& value : map_.pixels) {
    if (!std::isfinite(value) || value < 0.0f) {
      value = 0.0f;
      ++repaired;
    }
  }
  if (repaired > 0) {
    warn(source_ + ": " + std::to_string(repaired) +
         " texel values were negative, NaN or infinite and are treated as 0");
  }
  // Float overflows beyond this in the sampling weights, the alias table's sums and the
  // paths' throughput over their pdf, which would put Inf in the pixels. Real maps stay
  // below 1e9 (the sun is about 1e5 in HDR photographs of the sky).
  constexpr double kMaxRadiance = 1e20;
  const auto brightest = std::max_element(map_.pixels.begin(), map_.pixels.end());
  if (const double radiance = double(*brightest) * scale_; radiance > kMaxRadiance) {
    const size_t texel = size_t(brightest - map_.pixels.begin()) / 3;
    std::ostringstream message;
    message << source_ << ": texel (" << texel % map_.width << ", " << texel / map_.width << ") has radiance "
            << *brightest;
    if (scale_ != 1.0f) message << " times the scale " << scale_ << " = " << radiance;
    message << ", above the " << kMaxRadiance
            << " that rendering handles without overflow: scale the map down (or lower --env-scale)";
    throw Error(message.str());
  }
  local_to_world_ = rotation_about_y(options.rotation_degrees) * to_world;
}

Environment Environment::load(const std::string& path, const EnvironmentOptions& options) {
  return Environment(read_environment_map(path, options.format), options, path);
}

Vec2 Environment::direction_to_uv(const Vec3& w) const { return direction_to_latlong(local_to_world_.transpose() * w); }

Vec3 Environment::uv_to_direction(const Vec2& uv) const { return local_to_world_ * latlong_to_direction(uv); }

void Environment::prefetch(const EnvironmentLookup& at, bool density) const {
  const float* texels = map_.pixels.data();
  // One line per row of the footprint: x0 and x1 share it but for one texel in 5.
  const BilinearFootprint& footprint = at.footprint;
  for (int y : {footprint.y0, footprint.y1}) __builtin_prefetch(texels + (size_t(y) * map_.width + footprint.x0) * 3);
  if (density) sampling().texels.prefetch(at.texel);
}

namespace {

// Weights of the sampling distribution: luminance times sin(theta), each texel taking
// the largest luminance of its 3x3 neighbourhood so that every direction the bilinear
// lookup lights can be sampled.
std::vector<float> sampling_weights(const Image& map) {
  const int width = map.width, height = map.height;
  std::vector<float> texel_luminance(size_t(width) * height);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) texel_luminance[size_t(j) * width + i] = luminance(map.at(i, j));
  std::vector<float> weights(size_t(width) * height);
  for (int j = 0; j < height; ++j) {
    const float sin_theta = std::sin(kPi * (j + 0.5f) / height);
    for (int i = 0; i < width; ++i) {
      float neighbourhood_max = 0.0f;
      for (int dj = -1; dj <= 1; ++dj) {
        const int jj = std::clamp(j + dj, 0, height - 1);
        for (int di = -1; di <= 1; ++di) {
          const int ii = (i + di + width) % width;
          neighbourhood_max = std::max(neighbourhood_max, texel_luminance[size_t(jj) * width + ii]);
        }
      }
      weights[size_t(j) * width + i] = neighbourhood_max * sin_theta;
    }
  }
  return weights;
}

// sin and cos of (start angle + delta) for 0 <= delta <= 0.05, from those of the start:
// the series below are exact to float rounding there (truncation < 3e-11).
Eigen::Vector2f rotate_angle(const Eigen::Vector2f& start, float delta) {
  const float d2 = delta * delta;
  const float sin_delta = delta * (1.0f - d2 / 6.0f * (1.0f - d2 / 20.0f));
  const float cos_delta = 1.0f - d2 / 2.0f * (1.0f - d2 / 12.0f);
  return {start.x() * cos_delta + start.y() * sin_delta, start.y() * cos_delta - start.x() * sin_delta};
}

}  // namespace

Environment::Sampling::Sampling(const Image& map)
    : texels(sampling_weights(map)),
      tables_exact(kPi / map.height <= 0.05f && 2.0f * kPi / map.width <= 0.05f),
      row_start(map.height),
      column_start(map.width) {
  for (int j = 0; j < map.height; ++j) {
    const double theta = kPiD * j / map.height;
    row_start[j] = Eigen::Vector2f(float(std::sin(theta)), float(std::cos(theta)));
  }
  for (int i = 0; i < map.width; ++i) {
    const double phi = 2.0 * kPiD * i / map.width;
    column_start[i] = Eigen::Vector2f(float(std::sin(phi)), float(std::cos(phi)));
  }
}

const Environment::Sampling& Environment::sampling() const {
  std::call_once(sampling_once_, [this] {
    // Peak bytes per texel while the alias table is built: the weights (4) and luminance
    // (4), Vose's probabilities and scaled weights (8 + 8), its worklists (up to 8) and
    // the entries (16). Measured with /usr/bin/time -v (maximum resident size) for
    // `glaze render --env` of a 4096x2048 map against 512x256: 41 bytes besides the map.
    constexpr uint64_t kSamplingBytesPerTexel = 48;
    require_memory(saturating_mul(uint64_t(map_.width) * uint64_t(map_.height), kSamplingBytesPerTexel),
                   "building the sampling tables of " + source_);
    sampling_ = std::make_unique<Sampling>(map_);
  });
  return *sampling_;
}

Environment::SampleNumbers Environment::draw(Pcg32& rng) {
  SampleNumbers u;
  u.bits = uint64_t(rng.next_uint()) << 32;
  u.bits |= rng.next_uint();
  u.coin = rng.next_float();
  u.x = rng.next_float();
  u.y = rng.next_float();
  return u;
}

EnvironmentSample Environment::sample(Pcg32& rng) const {
  EnvironmentSample result;
  sample(rng, std::span(&result, 1));
  return result;
}

void Environment::sample(Pcg32& rng, std::span<EnvironmentSample> out) const {
  const AliasTable& table = sampling().texels;
  constexpr size_t kChunk = 16;
  std::array<SampleNumbers, kChunk> u;
  std::array<int, kChunk> slot;
  for (size_t first = 0; first < out.size(); first += kChunk) {
    const size_t n = std::min(kChunk, out.size() - first);
    for (size_t k = 0; k < n; ++k) {
      u[k] = draw(rng);
      slot[k] = table.slot(u[k].bits);
      table.prefetch(slot[k]);
    }
    for (size_t k = 0; k < n; ++k) {
      float pmf = 0.0f;
      const int texel = table.sample(slot[k], u[k].coin, &pmf);
      out[first + k] = sample_at(texel, u[k].x, u[k].y, pmf);
    }
  }
}

EnvironmentSample Environment::sample_at(int texel, float x, float y, float pmf) const {
  const Sampling& tables = sampling();
  const float pdf_uv = texel_density(pmf);
  if (!(pdf_uv > 0.0f)) return {Vec3::UnitY(), 0.0f};
  const int i = texel % map_.width, j = texel / map_.width;
  Vec3 d;
  float sin_theta = 0.0f;
  if (tables.tables_exact) {
    const Eigen::Vector2f theta = rotate_angle(tables.row_start[j], y * (kPi / map_.height));
    const Eigen::Vector2f phi = rotate_angle(tables.column_start[i], x * (2.0f * kPi / map_.width));
    sin_theta = theta.x();
    d = Vec3(sin_theta * phi.x(), theta.y(), -sin_theta * phi.y());
  } else {
    // Kept inside the texel where (i + x) / W rounds up to its edge.
    const Vec2 uv(std::min((i + x) / map_.width, std::nextafter((i + 1.0f) / map_.width, 0.0f)),
                  std::min((j + y) / map_.height, std::nextafter((j + 1.0f) / map_.height, 0.0f)));
    d = latlong_to_direction(uv, &sin_theta);
  }
  if (!(sin_theta > 0.0f)) return {Vec3::UnitY(), 0.0f};
  // (u, v) -> direction has Jacobian 2 pi^2 sin(theta).
  return {local_to_world_ * d, pdf_uv / (2.0f * kPi * kPi * sin_theta)};
}

float Environment::pdf(const EnvironmentLookup& at) const {
  if (!(at.sin_theta > 0.0f)) return 0.0f;
  return texel_density(sampling().texels.pmf(at.texel)) / (2.0f * kPi * kPi * at.sin_theta);
}

const ShCoefficients& Environment::sh(int lmax) const {
  std::lock_guard lock(sh_mutex_);
  auto it = sh_cache_.find(lmax);
  if (it == sh_cache_.end()) {
    ShCoefficients coefficients = sh_project_latlong(map_, local_to_world_, lmax);
    for (RGBd& value : coefficients.values) value *= scale_;
    it = sh_cache_.emplace(lmax, std::move(coefficients)).first;
  }
  return it->second;
}

Environment make_environment(const std::string& spec, const EnvironmentOptions& options, int width, int height) {
  const std::string prefix = "procedural:";
  if (spec.starts_with(prefix)) {
    const std::string name = spec.substr(prefix.size());
    return Environment(make_procedural_environment(name, width, height), options, spec);
  }
  return Environment::load(spec, options);
}

}  // namespace glaze
