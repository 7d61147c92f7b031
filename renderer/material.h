// material.h: the polished material (docs/design.md §1), the one formula shared by the path
// tracer, the SH integrator and every inverse fit.
//
// A diffuse base under a perfectly smooth dielectric coat, after Shirley, Hu, Smits and
// Lafortune (1997) in its energy-conserving form:
//
//   F(mu)  = R0 + (1 - R0) (1 - mu)^5                 Schlick Fresnel of the coat
//   f_s    = F(cos theta_o) * mirror delta
//   f_d    = 21/(20 pi) * Rd * (1 - R0) * g(cos theta_i) * g(cos theta_o)
//   g(mu)  = 1 - (1 - mu)^5
//
// The source paper prints the diffuse factor as 21/(20 pi (1 - R0)); that misprint
// creates energy and is singular at R0 = 1, so it is deliberately not used. With the
// form above the directional albedo is exactly F(mu_o) + Rd (1 - F(mu_o)).
//
// Directions are in the local shading frame (normal = +Z). The scalar building blocks
// are templates so that Ceres can differentiate through them with its Jet type.
#pragma once

#include "renderer/math.h"

#include <array>
#include <optional>
#include <span>
#include <string_view>

namespace glaze {

// g(mu) = 1 - (1 - mu)^5 in Horner form: the direct form cancels catastrophically for
// small mu in float. mu is clamped to [0, 1], and so is g: rounding near mu = 1 can
// give 1 + ulp, which would make the Fresnel term of R0 = 0 slightly negative.
template <typename T>
T coat_transmittance_g(T mu) {
  using std::max;
  using std::min;
  mu = min(max(mu, T(0)), T(1));
  return min(mu * (T(5) + mu * (T(-10) + mu * (T(10) + mu * (T(-5) + mu)))), T(1));
}

// Schlick Fresnel F(mu) = R0 + (1 - R0)(1 - mu)^5 = 1 - (1 - R0) g(mu), mu clamped.
template <typename T, typename S>
T schlick_fresnel(T R0, S mu) {
  return T(1) - (T(1) - R0) * coat_transmittance_g(mu);
}

// 21 / (20 pi): normalises g(mu_i) mu_i over the hemisphere, whose integral is 20 pi / 21.
inline constexpr double kDiffuseNormalisation = 21.0 / (20.0 * std::numbers::pi);

// The scalar part of f_d: f_d = Rd * diffuse_factor(R0, mu_i, mu_o).
template <typename T, typename S>
T diffuse_factor(T R0, S mu_i, S mu_o) {
  return T(kDiffuseNormalisation) * (T(1) - R0) * coat_transmittance_g(mu_i) * coat_transmittance_g(mu_o);
}

// --- Parameter registry (Mitsuba-style): the one list forward and inverse code share. ---

enum class MaterialParameter { R0, Rd };

struct ParameterSpec {
  MaterialParameter id;
  std::string_view name;  // as in glTF extras, fit.json and the command line
  int dimension;          // 1 = scalar, 3 = RGB
  double lower, upper;    // physical bounds, used by the fits
  double default_value;   // per component
  std::string_view description;
};

inline constexpr std::array<ParameterSpec, 2> kMaterialParameters = {{
    {MaterialParameter::R0, "R0", 1, 0.0, 1.0, 0.04,
     "specular reflectance of the coat at normal incidence (0.04 = ior 1.5)"},
    {MaterialParameter::Rd, "Rd", 3, 0.0, 1.0, 0.5, "diffuse reflectance of the base, linear RGB"},
}};

const ParameterSpec& parameter_spec(MaterialParameter id);

// --- The material as a BSDF for the path tracer. ---

struct MaterialSample {
  Vec3 wi;           // sampled incident direction (local frame)
  RGB weight;        // f * cos(theta_i) / pdf, including the lobe-selection probability
  float pdf;         // solid-angle density of wi; for the mirror, the selection probability
  bool is_specular;  // true: wi is the mirror direction (a delta lobe)
};

class PolishedMaterial {
 public:
  // Throws glaze::Error unless R0 and every Rd component are finite and in [0, 1].
  PolishedMaterial(float R0, const RGB& Rd);

  float R0() const { return R0_; }
  const RGB& Rd() const { return Rd_; }

  float fresnel(float mu) const { return schlick_fresnel(R0_, mu); }

  // f_d(wo, wi): the diffuse BRDF value (zero below either horizon). The mirror lobe is a
  // delta and is not part of eval(); its weight is fresnel(cos theta_o).
  RGB eval_diffuse(const Vec3& wo, const Vec3& wi) const;

  // Chooses the mirror with probability specular_probability(wo), else samples the
  // diffuse lobe exactly proportional to g(mu_i) mu_i (zero-variance for the BRDF part).
  std::optional<MaterialSample> sample(const Vec3& wo, float u_lobe, const Vec2& u) const;

  // The diffuse lobe alone (no lobe choice), for estimators that take the mirror term
  // deterministically: weight Rd diffuse_lobe_weight(R0, mu_o), pdf diffuse_lobe_pdf.
  std::optional<MaterialSample> sample_diffuse(const Vec3& wo, const Vec2& u) const;

  // Solid-angle density of sample() producing wi through the diffuse lobe.
  float pdf_diffuse(const Vec3& wo, const Vec3& wi) const;

  // Probability that sample() picks the mirror: its share of the directional albedo.
  float specular_probability(const Vec3& wo) const;

  // Directional albedo F(mu_o) + Rd (1 - F(mu_o)) (closed form; tests check it against
  // quadrature of eval_diffuse).
  RGB albedo(float mu_o) const;

 private:
  float R0_;
  RGB Rd_;
};

// Density of the diffuse-lobe sampling alone, g(mu) mu / (20 pi / 21) on the upper
// hemisphere, and the routine that draws from it (next to each other, pbrt-style).
inline float diffuse_lobe_pdf(float cos_theta) {
  return cos_theta > 0.0f ? static_cast<float>(kDiffuseNormalisation) * coat_transmittance_g(cos_theta) * cos_theta
                          : 0.0f;
}
// The weight f_d cos(theta_i) / pdf per unit of Rd of a direction drawn from that density:
// it is exactly proportional to the incident factor g(mu_i) mu_i, so only the outgoing
// factor (1 - R0) g(mu_o) remains (and the estimate has no noise from the BRDF itself).
template <typename T, typename S>
T diffuse_lobe_weight(T R0, S mu_o) {
  return (T(1) - R0) * coat_transmittance_g(mu_o);
}
Vec3 sample_diffuse_lobe(const Vec2& u);
// sample_diffuse_lobe() in two steps: cos(theta) = C^-1(u.x) for the lobe's CDF C (by
// Newton's method; for many u at once, SIMD lanes that agree with the one-at-a-time
// solver to double precision), then the direction at azimuth 2 pi u.y.
float diffuse_lobe_cos_theta(float u);
void diffuse_lobe_cos_theta(std::span<const float> u, std::span<float> cos_theta);
inline Vec3 diffuse_lobe_direction(float cos_theta, float u_azimuth) {
  const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
  float sin_phi, cos_phi;
  sin_cos_turns(u_azimuth, &sin_phi, &cos_phi);
  return {sin_theta * cos_phi, sin_theta * sin_phi, cos_theta};
}

}  // namespace glaze
