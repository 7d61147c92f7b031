// shading.h: the dual angular/frequency-space shading model (DESIGN §2), per channel:
//
//   Lo(n, v) = F(n.v) L(r)  +  21/(20 pi) Rd (1 - R0) g(n.v) E(n),   r = 2 (n.v) n - v
//
// with L(r) an environment lookup (angular space) and E(n) the SH diffuse sum
// (frequency space, ShDiffuseSum). The SH integrator and every inverse fit call these
// functions; they are templates so that Ceres can differentiate them.
#pragma once

#include "renderer/material.h"

namespace glaze {

// Mirror direction of v (towards the viewer) about n; both unit length.
inline Vec3 reflect(const Vec3& v, const Vec3& n) { return 2.0f * n.dot(v) * n - v; }

// Radiance of the diffuse part for diffuse sum E (one channel).
template <typename T, typename S>
T polished_diffuse_radiance(T R0, T Rd, S mu_o, S E) {
  return T(kDiffuseNormalisation) * Rd * (T(1) - R0) * coat_transmittance_g(mu_o) * E;
}

// Full outgoing radiance for one channel: mirror term plus diffuse term.
template <typename T, typename S>
T polished_radiance(T R0, T Rd, S mu_o, S L_reflected, S E) {
  return schlick_fresnel(R0, mu_o) * L_reflected + polished_diffuse_radiance(R0, Rd, mu_o, E);
}

// RGB convenience over the scalar model.
inline RGB polished_radiance(const PolishedMaterial& material, float mu_o, const RGB& L_reflected,
                             const RGB& E) {
  RGB result;
  for (int c = 0; c < 3; ++c)
    result[c] = polished_radiance(material.R0(), material.Rd()[c], mu_o, L_reflected[c], E[c]);
  return result;
}

}  // namespace glaze
