#include "inverse/diffuse_solve.h"

#include "renderer/error.h"
#include "renderer/material.h"

namespace glaze {

DiffuseSolve solve_diffuse_reflectance(std::span<const RGB> observed, std::span<const RGB> specular,
                                       std::span<const RGB> diffuse_basis, std::span<const float> weights) {
  const size_t count = observed.size();
  if (specular.size() != count || diffuse_basis.size() != count || (!weights.empty() && weights.size() != count))
    throw Error("solve_diffuse_reflectance: sample arrays differ in length");
  const ParameterSpec& bounds = parameter_spec(MaterialParameter::Rd);
  for (size_t k = 0; k < count; ++k) {
    if (!observed[k].allFinite() || !specular[k].allFinite() || !diffuse_basis[k].allFinite() ||
        (!weights.empty() && !(weights[k] >= 0.0f && std::isfinite(weights[k]))))
      throw Error("solve_diffuse_reflectance: sample " + std::to_string(k) +
                  " is not finite or has a negative weight; drop such samples before fitting");
  }

  RGBd numerator = RGBd::Zero(), denominator = RGBd::Zero();
  for (size_t k = 0; k < count; ++k) {
    const double w = weights.empty() ? 1.0 : weights[k];
    const RGBd b = diffuse_basis[k].cast<double>();
    numerator += w * b * (observed[k] - specular[k]).cast<double>();
    denominator += w * b * b;
  }
  DiffuseSolve result;
  for (int c = 0; c < 3; ++c) {
    const double minimiser = denominator[c] > 0.0 ? numerator[c] / denominator[c] : 0.0;
    result.unclamped[c] = static_cast<float>(minimiser);
    result.Rd[c] = static_cast<float>(std::clamp(minimiser, bounds.lower, bounds.upper));
  }
  result.weighted_squared_error = RGBd::Zero();
  for (size_t k = 0; k < count; ++k) {
    const double w = weights.empty() ? 1.0 : weights[k];
    const RGBd r = (observed[k] - specular[k] - result.Rd * diffuse_basis[k]).cast<double>();
    result.weighted_squared_error += w * r * r;
  }
  return result;
}

}  // namespace glaze
