// diffuse_solve.h: the inner step of the nested material fits (docs/design.md §5).
//
// For a fixed R0 the shading model is linear in Rd, per channel:
//   observed_k = specular_k + Rd * diffuse_basis_k,
// with specular_k = F(n.v) L(r) and diffuse_basis_k = 21/(20 pi)(1 - R0) g(n.v) E(n).
// The weighted least-squares Rd is sum w b (o - s) / sum w b^2; because the objective is
// a convex parabola in Rd, clamping that minimiser to Rd's registered bounds is the exact
// bounded solution, so the outer (Ceres) search over R0 sees a closed-form inner solve.
// DiffuseNormalEquations is that solve for any scalar type, so that Ceres's Jets carry
// derivatives through it; solve_diffuse_reflectance applies it to arrays of samples.
#pragma once

#include "renderer/material.h"

#include <span>

namespace glaze {

template <typename T>
struct DiffuseNormalEquations {
  T numerator[3] = {T(0), T(0), T(0)};    // sum w b (o - s)
  T denominator[3] = {T(0), T(0), T(0)};  // sum w b^2

  template <typename S>
  void add(int channel, S weight, S observed, const T& specular, const T& basis) {
    numerator[channel] += T(weight) * basis * (T(observed) - specular);
    denominator[channel] += T(weight) * basis * basis;
  }
  // The unconstrained minimiser (0 where nothing constrains the channel).
  T unclamped(int channel) const {
    return denominator[channel] > T(0) ? numerator[channel] / denominator[channel] : T(0);
  }
  // The bounded minimiser: the unconstrained one clamped to the registered bounds of Rd.
  T solve(int channel) const {
    const ParameterSpec& bounds = parameter_spec(MaterialParameter::Rd);
    const T x = unclamped(channel);
    if (x < T(bounds.lower)) return T(bounds.lower);
    if (x > T(bounds.upper)) return T(bounds.upper);
    return x;
  }
};

struct DiffuseSolve {
  RGB Rd;                       // clamped to the bounds of MaterialParameter::Rd
  RGB unclamped;                // the unconstrained minimiser (reported: far outside means misfit)
  RGBd weighted_squared_error;  // sum w (o - s - Rd b)^2 at the clamped Rd
};

// All spans have one entry per sample; `weights` may be empty (all 1). A channel whose
// basis is zero in every sample (nothing constrains it) gets Rd = 0. Throws glaze::Error
// for non-finite samples or negative weights.
DiffuseSolve solve_diffuse_reflectance(std::span<const RGB> observed, std::span<const RGB> specular,
                                       std::span<const RGB> diffuse_basis, std::span<const float> weights = {});

}  // namespace glaze
