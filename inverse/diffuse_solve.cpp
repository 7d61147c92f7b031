#include "inverse/diffuse_solve.h"

#include "renderer/error.h"
#include "renderer/material.h"

namespace glaze {

DiffuseSolve solve_diffuse_reflectance(std::span<const RGB> observed, std::span<const RGB> specular,
                                       std::span<const RGB> diffuse_basis, std::span<const float> weights) {
  const size_t count = observed.size();
  if (specular.size() != count || diffuse_basis.size() != count || (!weights.empty() && weights.size() != count))
    throw Error("solve_diffuse_reflectance: sample arrays differ in length");
  for (size_t k = 0; k < count; ++k) {
    if (!observed[k].allFinite() || !specular[k].allFinite() || !diffuse_basis[k].allFinite() ||
        (!weights.empty() && !(weights[k] >= 0.0f && std::isfinite(weights[k]))))
      throw Error("solve_diffuse_reflectance: sample " + std::to_string(k) +
                  " is not finite or has a negative weight; drop such samples before fitting");
  }

  DiffuseNormalEquations<double> equations;
  for (size_t k = 0; k < count; ++k) {
    const double w = weights.empty() ? 1.0 : weights[k];
    for (int c = 0; c < 3; ++c) equations.add<double>(c, w, observed[k][c], specular[k][c], diffuse_basis[k][c]);
  }
  DiffuseSolve result;
  for (int c = 0; c < 3; ++c) {
    result.unclamped[c] = static_cast<float>(equations.unclamped(c));
    result.Rd[c] = static_cast<float>(equations.solve(c));
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
