// sh.h: real spherical harmonics and the SH half of the shading model (docs/design.md §2).
//
// Convention: real SH *without* the Condon-Shortley phase (Ramamoorthi-Hanrahan,
// three.js), polar axis +Z of world space, flat index l(l+1)+m, so that
// Y00 = 0.282095, Y1-1 = 0.488603 y, Y10 = 0.488603 z, Y11 = 0.488603 x.
// The basis is evaluated by the stable recurrence of the fully normalised associated
// Legendre functions, for any lmax up to kShMaxLmax.
#pragma once

#include "renderer/image.h"
#include "renderer/math.h"

#include <array>
#include <span>
#include <type_traits>
#include <vector>

namespace glaze {

inline constexpr int kShMaxLmax = 64;
// Where the coat's diffuse term counts as full band: up to this band its kernel keeps all
// but 1.5e-5 of its energy (sh_kernel_energy_fraction), where lmax 4 loses 2.7e-3 and
// errs by 1-3% under point-lit rooms. Photographs and the path tracer carry every band;
// the fits model them up to this one, and simulated photographs are rendered at it.
inline constexpr int kFullBandDiffuseLmax = 16;

constexpr int sh_count(int lmax) { return (lmax + 1) * (lmax + 1); }
constexpr int sh_index(int l, int m) { return l * (l + 1) + m; }

namespace detail {
// Recurrence factors a_lm, b_lm of the normalised Legendre recurrence, index l(l+1)/2+m.
struct LegendreTable {
  std::vector<double> a, b;
  std::vector<double> diagonal_step;  // N_m^m / N_(m-1)^(m-1) = sqrt((2m + 1) / (2m))
  std::vector<double> first_step;     // N_(m+1)^m / (z N_m^m) = sqrt(2m + 3)
  LegendreTable();
};
const LegendreTable& legendre_table();
void check_lmax(int lmax);
// A constant of the recurrence as a T: a float or a double, or SIMD lanes of floats
// (std::experimental::simd, which is not built from a double it would have to round).
template <typename T>
T sh_constant(double value) {
  if constexpr (std::is_floating_point_v<T>)
    return T(value);
  else
    return T(typename T::value_type(value));
}
}  // namespace detail

// Calls visit(index, Y_index(d)) for every basis function with l <= lmax, for a unit
// direction d = (x, y, z). Y_lm = sqrt(2) N_l^|m|(z) Re/Im (x + i y)^|m| for m > 0 / m < 0,
// where N_l^m(z) sin^m(theta) is the normalised associated Legendre function; writing it
// with (x + i y)^m avoids atan2 and square roots and is exact at the poles.
// `lmax` is an int, or a std::integral_constant when the band limit is known at compile
// time: the same recurrence then unrolls into straight-line code (ShDiffuseSum's hot path).
// T is float, double or SIMD lanes of floats (one direction per lane).
template <typename T, typename Lmax, typename Visit>
void for_each_sh(Lmax lmax, T x, T y, T z, Visit&& visit) {
  const detail::LegendreTable& table = detail::legendre_table();
  const T sqrt2 = detail::sh_constant<T>(1.4142135623730951);
  T diagonal = detail::sh_constant<T>(0.28209479177387814);  // N_0^0 = 1 / sqrt(4 pi)
  T re = T(1), im = T(0);                                    // (x + i y)^m
  for (int m = 0; m <= lmax; ++m) {
    if (m > 0) {
      diagonal *= detail::sh_constant<T>(table.diagonal_step[m]);
      const T next_re = re * x - im * y;
      im = re * y + im * x;
      re = next_re;
    }
    auto emit = [&](int l, T legendre) {
      if (m == 0) {
        visit(sh_index(l, 0), legendre);
      } else {
        visit(sh_index(l, m), sqrt2 * legendre * re);
        visit(sh_index(l, -m), sqrt2 * legendre * im);
      }
    };
    emit(m, diagonal);
    if (m == lmax) break;
    T previous = diagonal;
    T current = detail::sh_constant<T>(table.first_step[m]) * z * diagonal;
    emit(m + 1, current);
    for (int l = m + 2; l <= lmax; ++l) {
      const int k = l * (l + 1) / 2 + m;
      const T next = detail::sh_constant<T>(table.a[k]) * (z * current - detail::sh_constant<T>(table.b[k]) * previous);
      emit(l, next);
      previous = current;
      current = next;
    }
  }
}

// All sh_count(lmax) basis values at unit direction d.
template <typename T>
void sh_eval(int lmax, const Eigen::Matrix<T, 3, 1>& d, std::span<T> out) {
  detail::check_lmax(lmax);
  for_each_sh(lmax, d.x(), d.y(), d.z(), [&](int i, T value) { out[i] = value; });
}

// Sums of the basis over unit directions d_k, SIMD lanes of them at a time: for every
// index i (l <= lmax), sums[i] = sum_k Y_i(d_k) and weighted[i] = sum_k w_k Y_i(d_k)
// (summed in float).
void sh_sum(int lmax, std::span<const Vec3> directions, std::span<const float> weights, std::span<double> sums,
            std::span<double> weighted);

// Lambda_l = sqrt(4 pi / (2l + 1)).
double sh_lambda(int l);

// h_l = 2 pi int_0^1 g(mu) mu N_l^0(mu) dmu: the SH coefficients of the clamped coat
// kernel g(mu) max(mu, 0). Computed by Gauss-Legendre quadrature that is exact for the
// polynomial integrand, for any l (h_0..h_4 = 0.8440, 1.0051, 0.5308, 0.0326, -0.1271).
double sh_kernel_coefficient(int l);

// Fraction of the kernel's energy (its squared L2 norm on the sphere) kept by l <= lmax;
// 99.73% at lmax = 4. The kernel is not band-limited, so this is < 1 for every lmax.
double sh_kernel_energy_fraction(int lmax);

// SH coefficients of an RGB function on the sphere (lighting L_lm).
struct ShCoefficients {
  int lmax = 0;
  std::vector<RGBd> values;  // sh_count(lmax), index l(l+1)+m

  // Throws glaze::Error unless 0 <= lmax <= kShMaxLmax.
  explicit ShCoefficients(int lmax_ = 0);
  RGBd& operator()(int l, int m) { return values[sh_index(l, m)]; }
  const RGBd& operator()(int l, int m) const { return values[sh_index(l, m)]; }

  // sum_lm L_lm Y_lm(d): the band-limited reconstruction at unit direction d.
  RGB eval(const Vec3& d) const;
};

// Coefficients of f(R^T w) given those of f(w): f rotated by the rotation R. Each band
// is rotated by the (2l+1)^2 matrix that maps the band's basis onto its rotated self,
// found by least squares over well-spread directions (exact to rounding, any lmax).
ShCoefficients sh_rotate(const ShCoefficients& coefficients, const Mat3d& rotation);

// Projects a lat-long RGB map (docs/design.md §3 mapping, in the map's own frame) whose frame is
// turned into world space by `local_to_world`: L_lm = sum over texels of L * the exact
// integral of Y_lm over the texel's solid angle, accumulated in double. Integrating the
// basis over each texel (rather than sampling it at the centre) makes the projection
// exact for the piecewise-constant map: a constant map has L00 = 2 sqrt(pi) and every
// other coefficient zero to rounding, at any resolution, down to 1x1.
ShCoefficients sh_project_latlong(const Image& map, const Mat3& local_to_world, int lmax);

// The SH half of docs/design.md §2: E(n) = sum_l Lambda_l h_l sum_m L_lm Y_lm(n). The diffuse
// radiance is then 21/(20 pi) Rd (1 - R0) g(n.v) E(n) (see shading.h). For a constant
// environment of radiance c, E = 20 pi / 21 * c.
class ShDiffuseSum {
 public:
  explicit ShDiffuseSum(const ShCoefficients& lighting);
  int lmax() const { return lmax_; }
  RGB operator()(const Vec3& n) const;
  // E at each of `normals`, into `out` (the same size): the same sums, a SIMD lane per
  // normal above lmax 4, where the basis recurrence, the same for every normal, is most
  // of the cost (equal to the one-normal form to float rounding).
  void operator()(std::span<const Vec3> normals, std::span<RGB> out) const;

 private:
  template <typename Lmax>
  RGB sum(Lmax lmax, const Vec3& n) const;
  template <typename Lmax>
  void sum_lanes(Lmax lmax, std::span<const Vec3> normals, std::span<RGB> out) const;
  // lmax <= 4 (the integrator's default): the 25 basis polynomials written out.
  RGB sum_low_bands(const Vec3& n) const;

  int lmax_;
  std::vector<float> weighted_;  // Lambda_l h_l L_lm, channel-major: [c * sh_count(lmax) + index]
  // For lmax <= 4: the same times each basis function's constant, per channel; bands
  // above lmax are 0.
  std::array<std::array<float, 25>, 3> low_band_{};
};

}  // namespace glaze
