#include "inverse/texture_fit.h"

#include "renderer/error.h"
#include "renderer/latlong.h"
#include "renderer/memory_budget.h"

#include <algorithm>
#include <cmath>

namespace glaze {

RecoveredTexture fit_texture(std::span<const Sample> samples, std::span<const ShadingTerms> terms, int width,
                             int height, const MaterialFit& homogeneous, const MaterialFitOptions& options) {
  // One Rd group per texel, each with 3x3 moments per channel: 1024x512 keeps that near 200 MB.
  if (width < 1 || height < 1 || width > 1024 || height > 512)
    throw Error("the texture resolution must be at most 1024x512, got " + std::to_string(width) + "x" +
                std::to_string(height));
  // Bytes per texel: the moments (3 channels x 3x3 doubles: 216), the fit's per-group
  // results (48) and the texture (16), with room for the solver's copies.
  constexpr uint64_t kBytesPerTexel = 400;
  require_memory(uint64_t(width) * uint64_t(height) * kBytesPerTexel + uint64_t(samples.size()) * 8,
                 "the " + std::to_string(width) + "x" + std::to_string(height) + " texture fit (--texture-res)");
  std::vector<int> group(samples.size());
  std::vector<float> weights(samples.size());
  for (size_t k = 0; k < samples.size(); ++k) {
    group[k] = texel_of(samples[k].uv, width, height);
    const RGB total = predict(terms[k], homogeneous.R0, homogeneous.Rd[0]);
    const RGB specular = predict(terms[k], homogeneous.R0, RGB::Zero());
    // Clamped: the unclamped SH sum can ring below zero, which must not make a weight negative.
    const float diffuse = std::max(0.0f, luminance(total - specular)), mirror = std::max(0.0f, luminance(specular));
    weights[k] = samples[k].weight * samples[k].mu * (diffuse + mirror > 0.0f ? diffuse / (diffuse + mirror) : 0.0f);
  }
  RecoveredTexture texture;
  texture.fit = fit_material(samples, terms, group, width * height, weights, options);
  texture.R0 = texture.fit.R0;
  texture.Rd = Image(width, height);
  texture.known.assign(size_t(width) * height, 0.0f);
  size_t known = 0;
  for (int t = 0; t < width * height; ++t) {
    if (!(texture.fit.constraint[t].minCoeff() > 0.0)) continue;  // some channel has no weighted sample
    texture.Rd.set(t % width, t / width, texture.fit.Rd[t]);
    texture.known[t] = 1.0f;
    ++known;
  }
  texture.coverage = double(known) / (double(width) * height);
  return texture;
}

double texture_rmse(const RecoveredTexture& texture, const Image& reference, const RGB& factor) {
  const int width = texture.Rd.width, height = texture.Rd.height;
  std::vector<RGBd> sum(size_t(width) * height, RGBd::Zero());
  std::vector<int> count(size_t(width) * height, 0);
  for (int y = 0; y < reference.height; ++y)
    for (int x = 0; x < reference.width; ++x) {
      const int t = texel_of(Vec2((x + 0.5f) / reference.width, (y + 0.5f) / reference.height), width, height);
      sum[t] += (factor * reference.at(x, y)).cast<double>();
      ++count[t];
    }
  double squared = 0.0;
  size_t known = 0;
  for (size_t t = 0; t < sum.size(); ++t) {
    if (!(texture.known[t] > 0.0f) || count[t] == 0) continue;
    squared += (texture.Rd.at(int(t % width), int(t / width)).cast<double>() - sum[t] / count[t]).square().sum();
    ++known;
  }
  return known > 0 ? std::sqrt(squared / (3.0 * known)) : 0.0;
}

}  // namespace glaze
