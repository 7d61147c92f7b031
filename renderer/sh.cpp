#include "renderer/sh.h"

#include <array>
#include <experimental/simd>

#include "renderer/error.h"
#include "renderer/material.h"
#include "renderer/quadrature.h"

#include <Eigen/QR>
#include <tbb/parallel_for.h>

#include <string>

namespace glaze {
namespace detail {

LegendreTable::LegendreTable() {
  const int size = (kShMaxLmax + 1) * (kShMaxLmax + 2) / 2;
  a.assign(size, 0.0);
  b.assign(size, 0.0);
  diagonal_step.assign(kShMaxLmax + 1, 1.0);
  first_step.assign(kShMaxLmax + 1, 0.0);
  for (int m = 0; m <= kShMaxLmax; ++m) {
    if (m > 0) diagonal_step[m] = std::sqrt((2.0 * m + 1.0) / (2.0 * m));
    first_step[m] = std::sqrt(2.0 * m + 3.0);
  }
  for (int l = 2; l <= kShMaxLmax; ++l) {
    for (int m = 0; m <= l - 2; ++m) {
      const int k = l * (l + 1) / 2 + m;
      const double l2 = double(l) * l, m2 = double(m) * m, lm1 = l - 1.0;
      a[k] = std::sqrt((4.0 * l2 - 1.0) / (l2 - m2));
      b[k] = std::sqrt((lm1 * lm1 - m2) / (4.0 * lm1 * lm1 - 1.0));
    }
  }
}

const LegendreTable& legendre_table() {
  static const LegendreTable table;
  return table;
}

void check_lmax(int lmax) {
  if (lmax < 0 || lmax > kShMaxLmax)
    throw Error("SH band limit lmax = " + std::to_string(lmax) + " is outside [0, " + std::to_string(kShMaxLmax) + "]");
}

}  // namespace detail

double sh_lambda(int l) { return std::sqrt(4.0 * kPiD / (2.0 * l + 1.0)); }

namespace {

// N_l^0(mu) = sqrt((2l+1)/(4 pi)) P_l(mu): the zonal basis function Y_l0 at cos(theta) = mu.
double zonal_basis(int l, double mu) {
  double value = 0.0;
  for_each_sh(l, 0.0, 0.0, mu, [&](int index, double y) {
    if (index == sh_index(l, 0)) value = y;
  });
  return value;
}

}  // namespace

double sh_kernel_coefficient(int l) {
  detail::check_lmax(l);
  // g(mu) mu has degree 6 and N_l^0 degree l: n points are exact up to degree 2n - 1.
  const QuadratureRule rule = gauss_legendre((l + 8) / 2 + 1, 0.0, 1.0);
  double sum = 0.0;
  for (size_t k = 0; k < rule.nodes.size(); ++k) {
    const double mu = rule.nodes[k];
    sum += rule.weights[k] * coat_transmittance_g(mu) * mu * zonal_basis(l, mu);
  }
  return 2.0 * kPiD * sum;
}

double sh_kernel_energy_fraction(int lmax) {
  detail::check_lmax(lmax);
  // Squared norm of the kernel on the sphere: 2 pi int_0^1 (g(mu) mu)^2 dmu (degree 12).
  const QuadratureRule rule = gauss_legendre(8, 0.0, 1.0);
  double total = 0.0;
  for (size_t k = 0; k < rule.nodes.size(); ++k) {
    const double kernel = coat_transmittance_g(rule.nodes[k]) * rule.nodes[k];
    total += rule.weights[k] * kernel * kernel;
  }
  total *= 2.0 * kPiD;
  double kept = 0.0;
  for (int l = 0; l <= lmax; ++l) kept += std::pow(sh_kernel_coefficient(l), 2);
  return kept / total;
}

ShCoefficients::ShCoefficients(int lmax_) : lmax(lmax_) {
  detail::check_lmax(lmax);
  values.assign(sh_count(lmax), RGBd::Zero());
}

RGB ShCoefficients::eval(const Vec3& d) const {
  RGBd sum = RGBd::Zero();
  for_each_sh(lmax, double(d.x()), double(d.y()), double(d.z()), [&](int i, double y) { sum += y * values[i]; });
  return sum.cast<float>();
}

namespace {

// Directions spread evenly over the sphere (Fibonacci lattice), deterministic.
std::vector<Vec3d> fibonacci_directions(int count) {
  std::vector<Vec3d> directions(count);
  const double golden_angle = kPiD * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < count; ++k) {
    const double z = 1.0 - (2.0 * k + 1.0) / count;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    directions[k] = Vec3d(r * std::cos(golden_angle * k), r * std::sin(golden_angle * k), z);
  }
  return directions;
}

}  // namespace

ShCoefficients sh_rotate(const ShCoefficients& coefficients, const Mat3d& rotation) {
  const int lmax = coefficients.lmax;
  detail::check_lmax(lmax);
  ShCoefficients rotated(lmax);
  // f(R^T w) = sum_m' c_m' Y_m'(R^T w) and Y_m'(R^T w) = sum_m X_mm' Y_m(w) within band l,
  // so the rotated coefficients are X c. X solves A X = B with A_km = Y_m(w_k) and
  // B_km' = Y_m'(R^T w_k) over more directions w_k than the band has functions.
  const std::vector<Vec3d> directions = fibonacci_directions(4 * lmax + 8);
  const int count = static_cast<int>(directions.size());
  Eigen::MatrixXd basis(count, sh_count(lmax)), turned(count, sh_count(lmax));
  for (int k = 0; k < count; ++k) {
    const Vec3d& w = directions[k];
    const Vec3d w_turned = rotation.transpose() * w;
    for_each_sh(lmax, w.x(), w.y(), w.z(), [&](int i, double y) { basis(k, i) = y; });
    for_each_sh(lmax, w_turned.x(), w_turned.y(), w_turned.z(), [&](int i, double y) { turned(k, i) = y; });
  }
  for (int l = 0; l <= lmax; ++l) {
    const int first = sh_index(l, -l), size = 2 * l + 1;
    const Eigen::MatrixXd band_matrix =
        basis.middleCols(first, size).colPivHouseholderQr().solve(turned.middleCols(first, size));
    for (int c = 0; c < 3; ++c) {
      Eigen::VectorXd band(size);
      for (int i = 0; i < size; ++i) band[i] = coefficients.values[first + i][c];
      const Eigen::VectorXd result = band_matrix * band;
      for (int i = 0; i < size; ++i) rotated.values[first + i][c] = result[i];
    }
  }
  return rotated;
}

ShCoefficients sh_project_latlong(const Image& map, const Mat3& local_to_world, int lmax) {
  detail::check_lmax(lmax);
  const int width = map.width, height = map.height;
  if (width <= 0 || height <= 0) throw Error("SH projection of an empty map");

  // Work in the frame "p" whose pole is the map's +Y and whose azimuth runs along the
  // map's rows: p = (-d.z, -d.x, d.y) for a map-frame direction d. There theta = v pi
  // and phi = -2 pi u, so the basis separates into a per-row and a per-column factor
  // and each texel's integral is a product of two 1D integrals:
  //   Y_lm(p) = T_l|m|(theta) * {cos(|m| phi) for m >= 0, sin(|m| phi) for m < 0},
  // with T the basis at phi = 0. The result is then rotated into world space.
  const int bands = lmax + 1;

  // Column factors: exact integrals of cos(m phi), sin(m phi) over each column.
  std::vector<double> column_cos(size_t(width) * bands), column_sin(size_t(width) * bands);
  for (int i = 0; i < width; ++i) {
    const double phi_low = -2.0 * kPiD * (i + 1) / width, phi_high = -2.0 * kPiD * i / width;
    for (int m = 0; m < bands; ++m) {
      double integral_cos = phi_high - phi_low, integral_sin = 0.0;
      if (m > 0) {
        integral_cos = (std::sin(m * phi_high) - std::sin(m * phi_low)) / m;
        integral_sin = (std::cos(m * phi_low) - std::cos(m * phi_high)) / m;
      }
      column_cos[size_t(i) * bands + m] = integral_cos;
      column_sin[size_t(i) * bands + m] = integral_sin;
    }
  }

  // Row factors: int T_lm(theta) sin(theta) dtheta over each row, by Gauss-Legendre in
  // theta. The integrand is a trigonometric polynomial of degree lmax + 1, not an
  // algebraic one, so no rule is exact, but lmax + 12 points reach rounding error even
  // for a single row spanning [0, pi] (a 1x1 map); narrower rows converge faster.
  const QuadratureRule unit_rule = gauss_legendre(lmax + 12, 0.0, 1.0);
  const int count = sh_count(lmax);

  // Per row and channel: sums of radiance times the column factors (double), reduced
  // over rows in a fixed order so the result does not depend on the thread count.
  std::vector<ShCoefficients> row_sums(height, ShCoefficients(lmax));
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
    std::vector<double> row_factor(count);
    std::vector<RGBd> sum_cos(bands), sum_sin(bands);
    for (int j = rows.begin(); j != rows.end(); ++j) {
      std::fill(row_factor.begin(), row_factor.end(), 0.0);
      const double theta_low = kPiD * j / height, theta_high = kPiD * (j + 1) / height;
      for (size_t q = 0; q < unit_rule.nodes.size(); ++q) {
        const double theta = theta_low + (theta_high - theta_low) * unit_rule.nodes[q];
        const double weight = (theta_high - theta_low) * unit_rule.weights[q] * std::sin(theta);
        for_each_sh(lmax, std::sin(theta), 0.0, std::cos(theta), [&](int i, double y) { row_factor[i] += weight * y; });
      }
      std::fill(sum_cos.begin(), sum_cos.end(), RGBd::Zero());
      std::fill(sum_sin.begin(), sum_sin.end(), RGBd::Zero());
      const float* texel = &map.pixels[size_t(j) * width * 3];
      for (int i = 0; i < width; ++i, texel += 3) {
        const RGBd radiance(texel[0], texel[1], texel[2]);
        const double* cos_factors = &column_cos[size_t(i) * bands];
        const double* sin_factors = &column_sin[size_t(i) * bands];
        for (int m = 0; m < bands; ++m) {
          sum_cos[m] += radiance * cos_factors[m];
          sum_sin[m] += radiance * sin_factors[m];
        }
      }
      ShCoefficients& out = row_sums[j];
      for (int l = 0; l <= lmax; ++l) {
        out(l, 0) = row_factor[sh_index(l, 0)] * sum_cos[0];
        for (int m = 1; m <= l; ++m) {
          out(l, m) = row_factor[sh_index(l, m)] * sum_cos[m];
          out(l, -m) = row_factor[sh_index(l, m)] * sum_sin[m];
        }
      }
    }
  });

  ShCoefficients in_p_frame(lmax);
  for (const ShCoefficients& row : row_sums)
    for (int i = 0; i < count; ++i) in_p_frame.values[i] += row.values[i];

  // World direction w = local_to_world * d and d = P^T p, so the p frame reaches world
  // space through local_to_world * P^T.
  Mat3d p_to_local;
  p_to_local << 0, -1, 0,  //
      0, 0, 1,             //
      -1, 0, 0;
  return sh_rotate(in_p_frame, local_to_world.cast<double>() * p_to_local);
}

namespace {

// The basis functions of bands 0..4 up to a constant factor each: Re and Im of
// (x + i y)^|m| times the Legendre polynomial in z, the very polynomials for_each_sh's
// recurrence builds, written out (no table, no loop).
template <typename T>
std::array<T, 25> low_band_polynomials(T x, T y, T z) {
  const T z2 = z * z, xy = x * y, re2 = x * x - y * y;
  const T re3 = x * re2 - y * (2 * xy), im3 = y * re2 + x * (2 * xy);  // (x + i y)^3
  const T re4 = x * re3 - y * im3, im4 = y * re3 + x * im3;            // (x + i y)^4
  return {T(1),
          y,
          z,
          x,
          xy,
          y * z,
          3 * z2 - 1,
          x * z,
          re2,
          im3,
          xy * z,
          y * (5 * z2 - 1),
          z * (5 * z2 - 3),
          x * (5 * z2 - 1),
          z * re2,
          re3,
          im4,
          z * im3,
          xy * (7 * z2 - 1),
          y * z * (7 * z2 - 3),
          (35 * z2 - 30) * z2 + 3,
          x * z * (7 * z2 - 3),
          re2 * (7 * z2 - 1),
          z * re3,
          re4};
}

}  // namespace

ShDiffuseSum::ShDiffuseSum(const ShCoefficients& lighting)
    : lmax_(lighting.lmax), weighted_(size_t(sh_count(lighting.lmax)) * 3) {
  for (int l = 0; l <= lmax_; ++l) {
    const double factor = sh_lambda(l) * sh_kernel_coefficient(l);
    for (int m = -l; m <= l; ++m)
      for (int c = 0; c < 3; ++c)
        weighted_[size_t(c) * sh_count(lmax_) + sh_index(l, m)] = static_cast<float>(factor * lighting(l, m)[c]);
  }
  if (lmax_ <= 4) {
    // Each polynomial's constant, from the basis at one direction where none vanishes
    // (in double), folded into the weights.
    const Vec3d d = Vec3d(std::sqrt(0.1), std::sqrt(0.4), std::sqrt(0.5));
    std::array<double, 25> basis{};
    for_each_sh(4, d.x(), d.y(), d.z(), [&](int i, double v) { basis[i] = v; });
    const std::array<double, 25> shape = low_band_polynomials(d.x(), d.y(), d.z());
    for (int l = 0; l <= lmax_; ++l) {
      const double factor = sh_lambda(l) * sh_kernel_coefficient(l);
      for (int m = -l; m <= l; ++m) {
        const int i = sh_index(l, m);
        for (int c = 0; c < 3; ++c)
          low_band_[c][i] = static_cast<float>(factor * lighting(l, m)[c] * basis[i] / shape[i]);
      }
    }
  }
}

RGB ShDiffuseSum::sum_low_bands(const Vec3& n) const {
  const std::array<float, 25> p = low_band_polynomials(n.x(), n.y(), n.z());
  // Run-time-sized maps: Eigen vectorises those with unaligned AVX loads, whereas its
  // fixed sizes are held to the 16-byte alignment glaze builds with (CMakeLists.txt).
  const Eigen::Map<const Eigen::VectorXf> shape(p.data(), 25);
  return RGB(shape.dot(Eigen::Map<const Eigen::VectorXf>(low_band_[0].data(), 25)),
             shape.dot(Eigen::Map<const Eigen::VectorXf>(low_band_[1].data(), 25)),
             shape.dot(Eigen::Map<const Eigen::VectorXf>(low_band_[2].data(), 25)));
}

template <typename Lmax>
RGB ShDiffuseSum::sum(Lmax lmax, const Vec3& n) const {
  // The basis values first, then three independent dot products: one running sum per
  // channel would chain every multiply-add on the previous one.
  constexpr int kStack = sh_count(16);
  const int count = sh_count(lmax);
  float stack[kStack];
  std::vector<float> heap(count > kStack ? count : 0);
  float* basis = count > kStack ? heap.data() : stack;
  for_each_sh(lmax, n.x(), n.y(), n.z(), [&](int i, float y) { basis[i] = y; });
  const Eigen::Map<const Eigen::VectorXf> y(basis, count);
  RGB result;
  for (int c = 0; c < 3; ++c)
    result[c] = y.dot(Eigen::Map<const Eigen::VectorXf>(&weighted_[size_t(c) * count], count));
  return result;
}

namespace {

using FloatLanes = std::experimental::native_simd<float>;

// sum(lmax) with the band limits people use as compile-time constants, so that the basis
// recurrence unrolls (faster than the loop: docs/notes/renderer.md, "The `sh` integrator's
// speed"), else as an int.
template <typename Sum>
decltype(auto) with_band_limit(int lmax, Sum&& sum) {
  switch (lmax) {
    case 4:
      return sum(std::integral_constant<int, 4>());
    case 6:
      return sum(std::integral_constant<int, 6>());
    case 8:
      return sum(std::integral_constant<int, 8>());
    case 12:
      return sum(std::integral_constant<int, 12>());
    case 16:
      return sum(std::integral_constant<int, 16>());
    default:
      return sum(lmax);
  }
}

// Lanes of the directions first, first + 1, ... (the last one repeated past the end).
std::array<FloatLanes, 3> direction_lanes(std::span<const Vec3> directions, size_t first) {
  auto axis = [&](int a) {
    return FloatLanes([&](size_t lane) { return directions[std::min(first + lane, directions.size() - 1)][a]; });
  };
  return {axis(0), axis(1), axis(2)};
}

template <typename Lmax>
void sh_sum_lanes(Lmax lmax, std::span<const Vec3> directions, std::span<const float> weights, std::span<double> sums,
                  std::span<double> weighted) {
  const int count = sh_count(lmax);
  thread_local std::vector<FloatLanes> plain, times_weight;  // per thread, their room reused
  plain.assign(size_t(count), FloatLanes(0.0f));
  times_weight.assign(size_t(count), FloatLanes(0.0f));
  for (size_t first = 0; first < directions.size(); first += FloatLanes::size()) {
    // Lanes past the end count 0 times.
    const FloatLanes present([&](size_t lane) { return first + lane < directions.size() ? 1.0f : 0.0f; });
    const FloatLanes weight(
        [&](size_t lane) { return first + lane < directions.size() ? weights[first + lane] : 0.0f; });
    const auto [x, y, z] = direction_lanes(directions, first);
    for_each_sh(lmax, x, y, z, [&](int i, const FloatLanes& basis) {
      plain[i] += present * basis;
      times_weight[i] += weight * basis;
    });
  }
  for (int i = 0; i < count; ++i) {
    sums[i] = double(std::experimental::reduce(plain[i]));
    weighted[i] = double(std::experimental::reduce(times_weight[i]));
  }
}

}  // namespace

void sh_sum(int lmax, std::span<const Vec3> directions, std::span<const float> weights, std::span<double> sums,
            std::span<double> weighted) {
  detail::check_lmax(lmax);
  const size_t count = size_t(sh_count(lmax));
  if (weights.size() != directions.size() || sums.size() < count || weighted.size() < count)
    throw Error("sh_sum: one weight per direction and room for every basis function");
  with_band_limit(lmax, [&](auto band_limit) { sh_sum_lanes(band_limit, directions, weights, sums, weighted); });
}

template <typename Lmax>
void ShDiffuseSum::sum_lanes(Lmax lmax, std::span<const Vec3> normals, std::span<RGB> out) const {
  const int count = sh_count(lmax);
  std::vector<FloatLanes> basis(static_cast<size_t>(count));
  for (size_t first = 0; first < normals.size(); first += FloatLanes::size()) {
    const auto [x, y, z] = direction_lanes(normals, first);
    for_each_sh(lmax, x, y, z, [&](int i, const FloatLanes& value) { basis[i] = value; });
    for (int c = 0; c < 3; ++c) {
      // Two running sums, so that each multiply-add does not wait on the one before.
      const float* weights = &weighted_[size_t(c) * count];
      FloatLanes even(0.0f), odd(0.0f);
      int i = 0;
      for (; i + 1 < count; i += 2) even += weights[i] * basis[i], odd += weights[i + 1] * basis[i + 1];
      if (i < count) even += weights[i] * basis[i];
      const FloatLanes total = even + odd;
      for (size_t lane = 0; lane < FloatLanes::size() && first + lane < normals.size(); ++lane)
        out[first + lane][c] = total[lane];
    }
  }
}

RGB ShDiffuseSum::operator()(const Vec3& n) const {
  if (lmax_ <= 4) return sum_low_bands(n);
  return with_band_limit(lmax_, [&](auto lmax) { return sum(lmax, n); });
}

void ShDiffuseSum::operator()(std::span<const Vec3> normals, std::span<RGB> out) const {
  if (out.size() != normals.size()) throw Error("ShDiffuseSum: one result per normal");
  if (lmax_ <= 4) {
    for (size_t k = 0; k < normals.size(); ++k) out[k] = sum_low_bands(normals[k]);
    return;
  }
  with_band_limit(lmax_, [&](auto lmax) { sum_lanes(lmax, normals, out); });
}

}  // namespace glaze
