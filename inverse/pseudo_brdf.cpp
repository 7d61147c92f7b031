#include "inverse/pseudo_brdf.h"

#include "renderer/error.h"

#include <ceres/ceres.h>

#include <array>
#include <cmath>

namespace glaze {
namespace {

constexpr int kWavelengths = 31;  // 400, 410, ..., 700 nm
using Spectrum = Eigen::Matrix<double, kWavelengths, 1>;

Spectrum gaussian(double centre, double width) {
  Spectrum s;
  for (int k = 0; k < kWavelengths; ++k) {
    const double t = (400.0 + 10.0 * k - centre) / width;
    s[k] = std::exp(-0.5 * t * t);
  }
  return s;
}

// Rows: the camera's sensitivities, each summing to 1 (a flat spectrum of 1 reads 1).
Eigen::Matrix<double, 3, kWavelengths> camera() {
  Eigen::Matrix<double, 3, kWavelengths> s;
  s.row(0) = gaussian(610, 28).transpose(), s.row(1) = gaussian(540, 28).transpose(),
  s.row(2) = gaussian(455, 25).transpose();
  for (int c = 0; c < 3; ++c) s.row(c) /= s.row(c).sum();
  return s;
}

// Columns: the light basis, smooth Gaussians mixed so that camera() * B = identity.
Eigen::Matrix<double, kWavelengths, 3> light_basis() {
  Eigen::Matrix<double, kWavelengths, 3> b;
  b.col(0) = gaussian(610, 45), b.col(1) = gaussian(540, 45), b.col(2) = gaussian(460, 45);
  const Eigen::Matrix3d seen = camera() * b;
  return b * seen.inverse();
}

// A physical reflectance (smooth, in (0, 1) at every wavelength): the sigmoid of a
// quadratic in wavelength (Jakob and Hanika 2019), t = (lambda - 550) / 150.
template <typename T>
T sigmoid_reflectance(const T* c, double wavelength) {
  const double t = (wavelength - 550.0) / 150.0;
  return T(1) / (T(1) + exp(-(c[0] + c[1] * t + c[2] * t * t)));
}

// Residual: what the camera sees of the reflectance under RGB-white light, minus Rd.
struct SeenUnderWhite {
  template <typename T>
  bool operator()(const T* c, T* residual) const {
    for (int channel = 0; channel < 3; ++channel) residual[channel] = T(-Rd[channel]);
    for (int k = 0; k < kWavelengths; ++k) {
      const T r = sigmoid_reflectance(c, 400.0 + 10.0 * k);
      for (int channel = 0; channel < 3; ++channel) residual[channel] += T(weight(channel, k)) * r;
    }
    return true;
  }
  Eigen::Matrix<double, 3, kWavelengths> weight;  // camera sensitivity x white spectrum
  Eigen::Vector3d Rd;
};

}  // namespace

Mat3 spectral_diffuse_matrix(const RGB& Rd) {
  const auto s = camera();
  const auto light = light_basis();
  const Spectrum white = light.rowwise().sum();  // the spectrum the camera sees as (1, 1, 1)
  auto* residual = new SeenUnderWhite{s * white.asDiagonal(), Rd.cast<double>().matrix()};
  double c[3] = {0.0, 0.0, 0.0};
  ceres::Problem problem;
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SeenUnderWhite, 3, 3>(residual), nullptr, c);
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 500;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  Spectrum reflectance;
  for (int k = 0; k < kWavelengths; ++k) reflectance[k] = sigmoid_reflectance(c, 400.0 + 10.0 * k);
  Eigen::Matrix3d M;
  for (int i = 0; i < 3; ++i) M.col(i) = s * reflectance.cwiseProduct(light.col(i));
  return M.cast<float>();
}

Image render_sh_spectral(const Scene& scene, const RayTracer& tracer, const Environment& environment,
                         const PinholeCamera& camera, const ShIntegratorOptions& options, const Mat3& M) {
  if (scene.materials.size() != 1 || scene.materials[0].texture >= 0)
    throw Error("render_sh_spectral: the scene needs exactly one untextured material");
  // Mirror term: the material with Rd = 0.
  Scene mirror = scene;
  mirror.materials[0].Rd = RGB::Zero();
  Image total = render_sh(mirror, tracer, environment, camera, options);
  EnvironmentOptions same_frame;
  same_frame.scale = environment.scale();
  same_frame.to_world = environment.local_to_world();
  const Image& map = environment.map();
  // The diffuse term is linear in Rd: rendered with Rd = 1 (minus the mirror term) under
  // light primary i alone, seen equally in every channel, it is E_i's diffuse response,
  // which M's column i spreads over the channels.
  Scene unit = scene;
  unit.materials[0].Rd = RGB::Ones();
  for (int i = 0; i < 3; ++i) {
    Image primary(map.width, map.height);
    for (size_t p = 0; p * 3 < map.pixels.size(); ++p)
      for (int c = 0; c < 3; ++c) primary.pixels[3 * p + c] = map.pixels[3 * p + i];
    const Environment light(std::move(primary), same_frame,
                            environment.source() + " (primary " + std::to_string(i) + ")");
    const Image with = render_sh(unit, tracer, light, camera, options);
    const Image without = render_sh(mirror, tracer, light, camera, options);
    for (size_t k = 0; k < total.pixels.size(); ++k)
      total.pixels[k] += M(k % 3, i) * (with.pixels[k] - without.pixels[k]);
  }
  return total;
}

}  // namespace glaze
