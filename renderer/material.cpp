#include "renderer/material.h"

#include "renderer/error.h"
#include "renderer/lanes.h"

#include <array>
#include <cmath>
#include <sstream>

namespace glaze {

const ParameterSpec& parameter_spec(MaterialParameter id) {
  for (const ParameterSpec& spec : kMaterialParameters)
    if (spec.id == id) return spec;
  throw std::logic_error("parameter_spec: unregistered material parameter");
}

namespace {

void check_in_bounds(MaterialParameter id, float value) {
  const ParameterSpec& spec = parameter_spec(id);
  if (!(value >= spec.lower && value <= spec.upper)) {  // also rejects NaN
    std::ostringstream message;
    message << "material parameter " << spec.name << " = " << value << " is outside [" << spec.lower << ", "
            << spec.upper << "] (" << spec.description << ")";
    throw Error(message.str());
  }
}

// CDF of mu under the diffuse-lobe density (21/10) g(mu) mu on [0, 1]:
// (21/10) (5/3 mu^3 - 5/2 mu^4 + 2 mu^5 - 5/6 mu^6 + 1/7 mu^7), with its derivative.
double diffuse_lobe_cdf(double mu, double* density) {
  *density = 2.1 * mu * coat_transmittance_g(mu);
  return 2.1 * mu * mu * mu * (5.0 / 3.0 + mu * (-2.5 + mu * (2.0 + mu * (-5.0 / 6.0 + mu * (1.0 / 7.0)))));
}

// Solves C(mu) = target on [low, high] (which must bracket the root) from the guess mu,
// by Newton's method safeguarded by bisection: the CDF is a monotone polynomial.
double invert_diffuse_lobe_cdf(double target, double mu, double low, double high) {
  for (int iteration = 0; iteration < 50; ++iteration) {
    double density = 0.0;
    const double error = diffuse_lobe_cdf(mu, &density) - target;
    if (error > 0.0)
      high = mu;
    else
      low = mu;
    double next = density > 0.0 ? mu - error / density : 0.5 * (low + high);
    if (!(next > low && next < high)) next = 0.5 * (low + high);
    const bool converged = std::abs(next - mu) < 1e-10;
    mu = next;
    if (converged || high - low < 1e-12) break;
  }
  return std::clamp(mu, 0.0, 1.0);
}

// mu at u = k / kSteps, so that sampling starts Newton's method next to the root and
// converges in one or two steps instead of five or more.
constexpr int kInverseSteps = 256;
const std::array<double, kInverseSteps + 1>& diffuse_lobe_inverse_table() {
  static const std::array<double, kInverseSteps + 1> table = [] {
    std::array<double, kInverseSteps + 1> mu{};
    for (int k = 0; k <= kInverseSteps; ++k) {
      const double target = double(k) / kInverseSteps;
      mu[k] = invert_diffuse_lobe_cdf(target, std::cbrt(target / 3.5), 0.0, 1.0);  // C ~ 3.5 mu^3 near 0
    }
    return mu;
  }();
  return table;
}

// Where solving C(mu) = u starts: the target, the table interval that brackets the root
// and the linear guess inside it.
struct LobeInverseStart {
  double target;
  int interval;
  double low, high, guess;
};

LobeInverseStart diffuse_lobe_inverse_start(const std::array<double, kInverseSteps + 1>& table, float u) {
  const double target = std::clamp(static_cast<double>(u), 0.0, 1.0);
  const double t = target * kInverseSteps;
  const int k = std::min(static_cast<int>(t), kInverseSteps - 1);
  return {target, k, table[k], table[k + 1], table[k] + (t - k) * (table[k + 1] - table[k])};
}

}  // namespace

float diffuse_lobe_cos_theta(float u) {
  const LobeInverseStart start = diffuse_lobe_inverse_start(diffuse_lobe_inverse_table(), u);
  return static_cast<float>(invert_diffuse_lobe_cdf(start.target, start.guess, start.low, start.high));
}

void diffuse_lobe_cos_theta(std::span<const float> u, std::span<float> cos_theta) {
  const auto& table = diffuse_lobe_inverse_table();
  for (size_t first = 0; first < u.size(); first += kLanes) {
    const int n = static_cast<int>(std::min<size_t>(kLanes, u.size() - first));
    alignas(64) float mu[kLanes];
    alignas(64) int converged[kLanes];
    // SIMD: three Newton steps from the table's guess, inside the table's bracket. Past
    // the first table interval mu(C) is smooth (the guess is within 3% of the root there)
    // and three steps reach double precision; lanes that did not converge (the first
    // interval, where C ~ 3.5 mu^3) take the safeguarded scalar solver.
    for (int k = 0; k < kLanes; ++k) {
      const LobeInverseStart start = diffuse_lobe_inverse_start(table, u[first + std::min(k, n - 1)]);
      double x = start.guess, step = 1.0;
      for (int iteration = 0; iteration < 3; ++iteration) {
        double density = 0.0;
        const double error = diffuse_lobe_cdf(x, &density) - start.target;
        const double next = std::clamp(density > 0.0 ? x - error / density : x, start.low, start.high);
        step = next - x;
        x = next;
      }
      mu[k] = static_cast<float>(x);
      converged[k] = start.interval > 0 && std::abs(step) < 1e-10 ? 1 : 0;
    }
    for (int k = 0; k < n; ++k) cos_theta[first + k] = converged[k] ? mu[k] : diffuse_lobe_cos_theta(u[first + k]);
  }
}

Vec3 sample_diffuse_lobe(const Vec2& u) { return diffuse_lobe_direction(diffuse_lobe_cos_theta(u.x()), u.y()); }

PolishedMaterial::PolishedMaterial(float R0, const RGB& Rd) : R0_(R0), Rd_(Rd) {
  check_in_bounds(MaterialParameter::R0, R0);
  for (int c = 0; c < 3; ++c) check_in_bounds(MaterialParameter::Rd, Rd[c]);
}

RGB PolishedMaterial::eval_diffuse(const Vec3& wo, const Vec3& wi) const {
  if (!(wo.z() > 0.0f && wi.z() > 0.0f)) return RGB::Zero();
  return Rd_ * diffuse_factor(R0_, wi.z(), wo.z());
}

float PolishedMaterial::specular_probability(const Vec3& wo) const {
  const float specular = fresnel(wo.z());
  const float diffuse = Rd_.mean() * (1.0f - specular);
  const float total = specular + diffuse;
  return total > 0.0f ? specular / total : 0.0f;
}

std::optional<MaterialSample> PolishedMaterial::sample(const Vec3& wo, float u_lobe, const Vec2& u) const {
  if (!(wo.z() > 0.0f)) return std::nullopt;
  const float mu_o = wo.z();
  const float specular = fresnel(mu_o);
  if (specular <= 0.0f && (Rd_ <= 0.0f).all()) return std::nullopt;  // reflects nothing
  const float p_specular = specular_probability(wo);
  if (u_lobe < p_specular) {
    return MaterialSample{Vec3(-wo.x(), -wo.y(), wo.z()), RGB::Constant(specular / p_specular), p_specular, true};
  }
  MaterialSample diffuse = *sample_diffuse(wo, u);
  const float p_diffuse = 1.0f - p_specular;
  diffuse.weight /= p_diffuse;
  diffuse.pdf *= p_diffuse;
  return diffuse;
}

std::optional<MaterialSample> PolishedMaterial::sample_diffuse(const Vec3& wo, const Vec2& u) const {
  if (!(wo.z() > 0.0f)) return std::nullopt;
  const Vec3 wi = sample_diffuse_lobe(u);
  return MaterialSample{wi, Rd_ * diffuse_lobe_weight(R0_, wo.z()), diffuse_lobe_pdf(wi.z()), false};
}

float PolishedMaterial::pdf_diffuse(const Vec3& wo, const Vec3& wi) const {
  if (!(wo.z() > 0.0f)) return 0.0f;
  return (1.0f - specular_probability(wo)) * diffuse_lobe_pdf(wi.z());
}

RGB PolishedMaterial::albedo(float mu_o) const {
  if (!(mu_o > 0.0f)) return RGB::Zero();
  const float F = fresnel(mu_o);
  return F + Rd_ * (1.0f - F);
}

}  // namespace glaze
