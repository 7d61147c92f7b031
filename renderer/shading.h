// shading.h: the dual angular/frequency-space shading model (DESIGN §2), per channel:
//
//   Lo(n, v) = F(n.v) L(r)  +  21/(20 pi) Rd (1 - R0) g(n.v) E(n),   r = 2 (n.v) n - v
//
// with L(r) an environment lookup (angular space) and E(n) the SH diffuse sum
// (frequency space, ShDiffuseSum). The SH integrator and every inverse fit call these
// functions; they are templates so that Ceres can differentiate them.
//
// Since F = 1 - (1 - R0) g (Schlick), the model is affine in three per-ray terms,
//
//   Lo = L  -  (1 - R0) gL  +  21/(20 pi) Rd (1 - R0) gE,   gL = g(n.v) L(r), gE = g(n.v) E(n),
//
// so the mean of Lo over several rays (a pixel's footprint) is the same formula applied
// to the means of L, gL and gE. ShadingBasis holds them; polished_radiance is written on
// it alone, so a single ray and a whole pixel go through one routine.
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

// The mirror term F L = L - (1 - R0) gL.
template <typename T, typename S>
T polished_specular_radiance(T R0, const ShadingBasis<S>& basis) {
  return T(basis.L) - (T(1) - R0) * T(basis.gL);
}

// The diffuse term 21/(20 pi) Rd (1 - R0) gE.
template <typename T, typename S>
T polished_diffuse_radiance(T R0, T Rd, const ShadingBasis<S>& basis) {
  return T(kDiffuseNormalisation) * Rd * (T(1) - R0) * T(basis.gE);
}

// Full outgoing radiance for one channel: mirror term plus diffuse term.
template <typename T, typename S>
T polished_radiance(T R0, T Rd, const ShadingBasis<S>& basis) {
  return polished_specular_radiance(R0, basis) + polished_diffuse_radiance(R0, Rd, basis);
}

// RGB over one ray.
inline RGB polished_radiance(const PolishedMaterial& material, float mu_o, const RGB& L_reflected, const RGB& E) {
  RGB result;
  for (int c = 0; c < 3; ++c)
    result[c] = polished_radiance(material.R0(), material.Rd()[c], ShadingBasis<float>(mu_o, L_reflected[c], E[c]));
  return result;
}

}  // namespace glaze
