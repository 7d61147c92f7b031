// shading.h: the dual angular/frequency-space shading model (docs/design.md §2), per channel:
//
//   Lo(n, v) = F(n.v) L(r)  +  21/(20 pi) Rd (1 - R0) g(n.v) E(n),   r = 2 (n.v) n - v
//
// with L(r) an environment lookup (angular space) and E(n) the SH diffuse sum
// (frequency space, ShDiffuseSum). The SH integrator and every inverse fit call these
// functions; they are templates so that Ceres can differentiate them.
//
// Since F = 1 - (1 - R0) g (Schlick), the model is affine in three per-ray terms,
//
//   Lo = L  -  q gL  +  s gE,   q = 1 - R0,  s = 21/(20 pi) Rd q,   gL = g(n.v) L(r), gE = g(n.v) E(n),
//
// so the mean of Lo over several rays (a pixel's footprint) is the same formula applied
// to the means of L, gL and gE. ShadingBasis holds those terms and ShadingCoefficients
// the material's q and s, which the SH integrator and every fit (their linear systems'
// rows included) take from here rather than writing them out.
#pragma once

#include "renderer/material.h"

namespace glaze {

// Mirror direction of v (towards the viewer) about n; both unit length.
inline Vec3 reflect(const Vec3& v, const Vec3& n) { return 2.0f * n.dot(v) * n - v; }

// The material-independent terms of one channel, for one ray or averaged over rays.
template <typename S>
struct ShadingBasis {
  S L = S(0), gL = S(0), gE = S(0);

  ShadingBasis() = default;
  ShadingBasis(S mu_o, S L_reflected, S E) {
    const S g = coat_transmittance_g(mu_o);
    L = L_reflected, gL = g * L_reflected, gE = g * E;
  }
  ShadingBasis& operator+=(const ShadingBasis& other) {
    L += other.L, gL += other.gL, gE += other.gE;
    return *this;
  }
  ShadingBasis& operator*=(S factor) {
    L *= factor, gL *= factor, gE *= factor;
    return *this;
  }
};

// The material's coefficients of the affine form, for one channel. Fits that solve for
// Rd after R0 make them with Rd = 1, per unit of Rd: `diffuse` is then 21/(20 pi) q,
// which times Rd is s up to the rounding of the product's order.
template <typename T>
struct ShadingCoefficients {
  T transmittance;  // q = 1 - R0: the coat passes 1 - F(mu) = q g(mu), so F L = L - q gL
  T diffuse;        // s = 21/(20 pi) Rd q, the weight of gE

  explicit ShadingCoefficients(T R0, T Rd = T(1))
      : transmittance(T(1) - R0), diffuse(T(kDiffuseNormalisation) * Rd * transmittance) {}

  // The mirror term F L = L - q gL.
  template <typename S>
  T specular_radiance(const ShadingBasis<S>& basis) const {
    return T(basis.L) - transmittance * T(basis.gL);
  }
  // The diffuse term s gE.
  template <typename S>
  T diffuse_radiance(const ShadingBasis<S>& basis) const {
    return diffuse * T(basis.gE);
  }
  // Full outgoing radiance: mirror term plus diffuse term.
  template <typename S>
  T radiance(const ShadingBasis<S>& basis) const {
    return specular_radiance(basis) + diffuse_radiance(basis);
  }
};

// RGB over one ray.
inline RGB polished_radiance(const PolishedMaterial& material, float mu_o, const RGB& L_reflected, const RGB& E) {
  RGB result;
  for (int c = 0; c < 3; ++c) {
    const ShadingCoefficients<float> coefficients(material.R0(), material.Rd()[c]);
    result[c] = coefficients.radiance(ShadingBasis<float>(mu_o, L_reflected[c], E[c]));
  }
  return result;
}

}  // namespace glaze
