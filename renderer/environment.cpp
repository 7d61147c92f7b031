#include "renderer/environment.h"

#include "renderer/error.h"
#include "renderer/latlong.h"
#include "renderer/procedural_environment.h"

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
    message << source_ << ": environment to_world must be a rotation (orthonormal, determinant +1), got\n"
            << to_world;
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
  local_to_world_ = rotation_about_y(options.rotation_degrees) * to_world;
}

Environment Environment::load(const std::string& path, const EnvironmentOptions& options) {
  return Environment(read_image(path), options, path);
}

Vec2 Environment::direction_to_uv(const Vec3& w) const {
  return direction_to_latlong(local_to_world_.transpose() * w);
}

Vec3 Environment::uv_to_direction(const Vec2& uv) const {
  return local_to_world_ * latlong_to_direction(uv);
}

RGB Environment::eval(const Vec3& w) const {
  const Vec2 uv = direction_to_uv(w);
  const float x = uv.x() * map_.width - 0.5f, y = uv.y() * map_.height - 0.5f;
  const float x_floor = std::floor(x), y_floor = std::floor(y);
  const float fx = x - x_floor, fy = y - y_floor;
  const int width = map_.width, height = map_.height;
  const int x0 = ((static_cast<int>(x_floor) % width) + width) % width;
  const int x1 = (x0 + 1) % width;
  const int y0 = std::clamp(static_cast<int>(y_floor), 0, height - 1);
  const int y1 = std::clamp(static_cast<int>(y_floor) + 1, 0, height - 1);
  const RGB top = (1.0f - fx) * map_.at(x0, y0) + fx * map_.at(x1, y0);
  const RGB bottom = (1.0f - fx) * map_.at(x0, y1) + fx * map_.at(x1, y1);
  return scale_ * ((1.0f - fy) * top + fy * bottom);
}

const Distribution2D& Environment::distribution() const {
  std::call_once(distribution_once_, [this] {
    const int width = map_.width, height = map_.height;
    std::vector<float> texel_luminance(size_t(width) * height);
    for (int j = 0; j < height; ++j)
      for (int i = 0; i < width; ++i) texel_luminance[size_t(j) * width + i] = luminance(map_.at(i, j));
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
    distribution_ = std::make_unique<Distribution2D>(weights, width, height);
  });
  return *distribution_;
}

EnvironmentSample Environment::sample(const Vec2& u) const {
  float pdf_uv = 0.0f;
  const Vec2 uv = distribution().sample(u, &pdf_uv);
  float sin_theta = 0.0f;
  const Vec3 d = latlong_to_direction(uv, &sin_theta);
  if (!(sin_theta > 0.0f) || !(pdf_uv > 0.0f)) return {Vec3::UnitY(), 0.0f};
  // (u, v) -> direction has Jacobian 2 pi^2 sin(theta).
  return {local_to_world_ * d, pdf_uv / (2.0f * kPi * kPi * sin_theta)};
}

float Environment::pdf(const Vec3& w) const {
  const Vec3 d = local_to_world_.transpose() * w;
  const float sin_theta = latlong_sin_theta(d);
  if (!(sin_theta > 0.0f)) return 0.0f;
  return distribution().pdf(direction_to_latlong(d)) / (2.0f * kPi * kPi * sin_theta);
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

Environment make_environment(const std::string& spec, const EnvironmentOptions& options, int width,
                             int height) {
  const std::string prefix = "procedural:";
  if (spec.starts_with(prefix)) {
    const std::string name = spec.substr(prefix.size());
    return Environment(make_procedural_environment(name, width, height), options, spec);
  }
  return Environment::load(spec, options);
}

}  // namespace glaze
