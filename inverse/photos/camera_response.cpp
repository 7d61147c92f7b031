#include "inverse/photos/camera_response.h"

#include "renderer/error.h"
#include "renderer/json_input.h"
#include "renderer/rng.h"

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <set>
#include <string>

namespace glaze {
namespace {

constexpr int kCodes = 256;   // recovery is for 8-bit photos
constexpr int kMiddle = 128;  // g(kMiddle) = 0 fixes the curve's free scale
constexpr const char* kChannels[3] = {"R", "G", "B"};
// A code counts as well constrained when at least this many samples saw it, and its hat
// weight is at least kMinWeight: the few codes next to the underexposed ones are noisy
// (read noise, shot noise of a few hundred electrons) and weigh so little that the
// smoothness term extrapolates the curve there (27% off at code 6 in the tests, 0.6% at 12).
constexpr int kMinObservations = 5;
constexpr float kMinWeight = 0.05f;

// Per channel, how often each code was seen with a non-zero weight in a pixel that
// other exposures see too.
std::array<std::vector<int>, 3> observations(std::span<const ResponseSamples> brackets, const CodeLimits& limits,
                                             const std::vector<float>& weight) {
  std::array<std::vector<int>, 3> count;
  for (auto& c : count) c.assign(kCodes, 0);
  for (const ResponseSamples& bracket : brackets) {
    const size_t exposures = bracket.exposures.size();
    for (size_t i = 0; i * exposures * 3 < bracket.codes.size(); ++i)
      for (size_t j = 0; j < exposures; ++j) {
        const uint16_t* rgb = &bracket.codes[(i * exposures + j) * 3];
        if (limits.saturated(rgb)) continue;
        for (int c = 0; c < 3; ++c)
          if (weight[rgb[c]] > 0.0f) ++count[c][rgb[c]];
      }
  }
  return count;
}

// Makes g non-decreasing (a tone curve is monotone; noise at the unconstrained ends may
// bend the solution back) and shifts it so that g(kMiddle) = 0.
void normalise(std::vector<double>& g) {
  for (int z = 1; z < kCodes; ++z) g[z] = std::max(g[z], g[z - 1]);
  const double middle = g[kMiddle];
  for (double& value : g) value -= middle;
}

// Debevec and Malik (1997), channel c: minimise
//   sum_ij [w(Z_ij) (g(Z_ij) - ln E_i - ln t_j)]^2 + lambda sum_z [w(z) g''(z)]^2
// over g and the samples' ln E_i. Each ln E_i enters only its own sample's terms, so it
// is eliminated in closed form (a Schur complement): what remains is a 256 x 256
// symmetric system in g, whatever the number of samples, solved by LDL^T.
std::vector<double> debevec(std::span<const ResponseSamples> brackets, const CodeLimits& limits,
                            const std::vector<float>& weight, int c) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(kCodes, kCodes);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(kCodes);
  double data_weight = 0.0;
  for (const ResponseSamples& bracket : brackets) {
    const size_t exposures = bracket.exposures.size();
    std::vector<int> code(exposures);
    std::vector<double> w2(exposures), log_t(exposures);
    for (size_t j = 0; j < exposures; ++j) log_t[j] = std::log(bracket.exposures[j]);
    for (size_t i = 0; i * exposures * 3 < bracket.codes.size(); ++i) {
      double d = 0.0, e = 0.0;  // sums of w^2 and w^2 ln t_j over the sample's exposures
      int used = 0;
      for (size_t j = 0; j < exposures; ++j) {
        const uint16_t* rgb = &bracket.codes[(i * exposures + j) * 3];
        code[j] = rgb[c];
        w2[j] = limits.saturated(rgb) ? 0.0 : double(weight[rgb[c]]) * weight[rgb[c]];
        d += w2[j], e += w2[j] * log_t[j];
        used += w2[j] > 0.0;
      }
      if (used < 2) continue;  // one exposure alone says nothing about g
      for (size_t j = 0; j < exposures; ++j) {
        if (w2[j] == 0.0) continue;
        a(code[j], code[j]) += w2[j];
        b(code[j]) += w2[j] * log_t[j];
        // Eliminating ln E_i = sum_k w2_k (g(Z_ik) - ln t_k) / d leaves these terms.
        for (size_t k = 0; k < exposures; ++k) a(code[j], code[k]) -= w2[j] * w2[k] / d;
        b(code[j]) -= w2[j] * e / d;
        data_weight += w2[j];
      }
    }
  }
  // Smoothness, scaled with the data so that its strength does not depend on how many
  // samples there are, weighted by the hat as Debevec and Malik do, with a floor so that
  // it still carries the curve through the codes no sample constrains. The penalty is
  // g'' + g' / z rather than g'': the second derivative of g in ln z, zero wherever f^-1
  // is locally a power law z^gamma, as a tone curve's toe is (sRGB's linear segment, a
  // gamma), so that a strong penalty does not bend the toe. It was made strong (10000
  // against 3000: three simulated shoots' curves within 1.0% against 1.3-1.7%) when it
  // alone held down the ripple with the bracket's period (sample_bracket). Now that
  // refine_forward mends the toe and the shoulder from the data and settles the ripple,
  // 1000 to 30000 give the same curves to 0.1% (docs/notes/hdr-merge.md).
  constexpr double kLambda = 10000.0;
  const double lambda = kLambda * data_weight / kCodes;
  for (int z = 1; z + 1 < kCodes; ++z) {
    const double w = std::max(double(weight[z]), 0.05);
    const double slope = 0.5 / (z + 0.5);  // g' / z at code z, its value z + 0.5
    const Eigen::Vector3d row = std::sqrt(lambda) * w * Eigen::Vector3d(1.0 - slope, -2.0, 1.0 + slope);
    a.block<3, 3>(z - 1, z - 1) += row * row.transpose();
  }
  a(kMiddle, kMiddle) += std::max(lambda, 1.0);  // g(kMiddle) = 0
  const Eigen::VectorXd g = a.ldlt().solve(b);
  return std::vector<double>(g.data(), g.data() + kCodes);
}

// The differences of the given order along a uniform grid, (D y)_k = sum_m stencil_m
// y_(k + m): binomial weights of alternating sign (1 -2 1 for the second).
Eigen::VectorXd difference_stencil(int order) {
  Eigen::VectorXd stencil(order + 1);
  double binomial = 1.0;
  for (int m = 0; m <= order; ++m) {
    stencil(m) = ((order - m) % 2 ? -1.0 : 1.0) * binomial;
    binomial = binomial * (order - m) / (m + 1);
  }
  return stencil;
}

// Adds weight * |D y|^2, D the differences of `order` along y, to the normal matrix a.
void add_difference_penalty(int order, double weight, Eigen::MatrixXd& a) {
  const Eigen::VectorXd stencil = difference_stencil(order);
  for (Eigen::Index k = 0; k + order < a.rows(); ++k)
    a.block(k, k, order + 1, order + 1) += weight * stencil * stencil.transpose();
}

// Debevec and Malik's least squares are in g, whose argument, the code, carries the
// noise: where g is steep (the toe, the shoulder) and where the codes are coarse for the
// noise, that errors-in-variables bias bends the curve, and more samples do not shrink
// it. One refinement regresses the other way round: each sample's exposure merged from
// its codes through Debevec and Malik's curve (as merge_bracket does), the codes' mean at
// each exposure is the forward curve f, whose noise is in what is regressed and leaves
// it unbiased; g becomes f's inverse at each well-constrained code. The samples'
// exposures come from several codes each, so their own noise is small beside the
// codes'. The codes are taken whatever their value, saturated and underexposed included:
// leaving them out would cut the noise's tail next to the limits and bias the mean there.
// f is piecewise linear in ln exposure, kKnotsPerUnit knots per unit (steps of 10%), with
// a smoothness on its second differences that carries it across the bracket's gaps.
//
// With the samples' exposures held where Debevec and Malik's curve put them, f keeps
// that curve's ripple with the bracket's period, which the data leave free
// (sample_bracket): shifting every exposure of a sample by the ripple's value there
// explains its codes as well. settle_ripple then picks, among the curves that the ripple
// relates, the one the data cannot: the smoothest by a measure under which common tone
// curves are their own smoothest (docs/notes/hdr-merge.md has the measurements).
constexpr double kKnotsPerUnit = 10.0;
constexpr double kForwardSmoothness = 1.0;  // in units of a knot's mean data weight
// The ripple is settled over the codes of at least this hat weight (refine_forward): 18
// to 237. Over all the well-constrained codes a gamma of 2.2 came out within 1.6% in the
// tests, against 0.9% at 0.1; at 0.25 the white and the red sphere's shoots in the office
// recovered a joint Rd 0.004-0.017 worse (docs/notes/hdr-merge.md).
constexpr float kRippleWeight = 0.1f;

// The forward curve on its knots (start, step), linear between them.
struct ForwardKnots {
  double start, step;
  int count;
  // The knot at or below x and the weights of it and the next; false outside the knots.
  bool locate(double x, int& k, Eigen::Vector2d& basis) const {
    const double u = (x - start) / step;
    if (!(u >= 0.0 && u < count - 1)) return false;
    k = int(u);
    basis = Eigen::Vector2d(1.0 - (u - k), u - k);
    return true;
  }
};

// The period, in ln exposure, of the ripple that the brackets leave free: when every
// bracket's exposures are whole multiples of one step apart (a bracket 2 EV apart: ln 4),
// shifting every exposure by a function of ln exposure with that period explains all
// codes as well (sample_bracket). Whole multiples to within 0.1 EV: EXIF records the
// nominal times (1/15 s for 2^-4), and the data's ambiguity is the true exposures'. The
// step is then fitted to every gap. 0 when the exposures share no step of 0.4 EV or more
// (settle_ripple also leaves alone one too short for its knots: under 0.43 EV at 10 a
// unit).
double free_ripple_period(std::span<const ResponseSamples> brackets) {
  std::vector<double> gaps;
  for (const ResponseSamples& bracket : brackets)
    for (size_t j = 1; j < bracket.exposures.size(); ++j) {
      const double gap = std::abs(std::log(bracket.exposures[j] / bracket.exposures[0]));
      if (gap > 1e-6) gaps.push_back(gap);
    }
  if (gaps.empty()) return 0.0;
  const double shortest = *std::min_element(gaps.begin(), gaps.end());
  constexpr double kShortestPeriod = 0.4 * M_LN2, kTolerance = 0.1 * M_LN2;
  for (int divisor = 1; shortest / divisor >= kShortestPeriod; ++divisor) {
    // The step that fits every gap's multiple of it best, in least squares.
    double sum_gap = 0.0, sum_multiple = 0.0;
    for (double gap : gaps) {
      const double multiple = std::round(gap / (shortest / divisor));
      sum_gap += multiple * gap, sum_multiple += multiple * multiple;
    }
    const double step = sum_gap / sum_multiple;
    if (std::all_of(gaps.begin(), gaps.end(),
                    [&](double gap) { return std::abs(gap - std::round(gap / step) * step) < kTolerance; }))
      return step;
  }
  return 0.0;
}

// A shift of ln exposure with the period of the ripple the brackets leave free
// (free_ripple_period): a few harmonics.
struct Ripple {
  double frequency = 0.0;        // radians per unit of ln exposure
  Eigen::VectorXd coefficients;  // cos, sin of each harmonic
  // Harmonic `column`'s value at u: cos, sin of the first harmonic, then the second's...
  double harmonic(int column, double u) const {
    const double phase = (column / 2 + 1) * frequency * u;
    return column % 2 ? std::sin(phase) : std::cos(phase);
  }
  double shift(double u) const {
    double value = 0.0;
    for (Eigen::Index column = 0; column < coefficients.size(); ++column)
      value += coefficients(column) * harmonic(int(column), u);
    return value;
  }
};

// The ripple that the data leave free, settled by the shape of the forward curve alone.
// The data cannot tell the curves that the ripple relates apart; a prior must pick one,
// and it must be one under which tone curves are their own best. A difference penalty is
// not quite: least second differences of f cancel the period's component of the true
// f'' (0.25% of exposure for the film curve of the tests, about 1% for sRGB and a gamma
// of 2.2), least third differences leave 0.1-0.2%, and fourth differences, within
// 0.01-0.08%, weigh the short wavelengths so much that they turn the forward curve's
// noise into ripple. Over the codes settled here (3 to 4 periods of a bracket 2 EV apart)
// a polynomial of degree 8 in ln exposure follows common tone curves to within a few
// hundredths of a percent of exposure, and a ripple of the bracket's period is far from
// any such polynomial: so this takes the ripple whose removal leaves f closest to one, a
// low-pass measure that passes on less of the noise than third differences do
// (docs/notes/hdr-merge.md, "The ripple settled by a polynomial").
// With f~(u) = f(u - p(u)) ~ f(u) - f'(u) p(u) on knots [first, last] and P the
// projection off the polynomials there, it minimises |P f~|^2: linear least squares in
// p's coefficients. Over a shorter range (a contrasty S-curve's, which spends the same
// codes on fewer stops) the polynomials come to hold much of the first harmonic,
// and the noise passed into it grows as one over what is left of it: the degree is the
// highest, up to kMaxRippleDegree, at which every direction of the ripple keeps
// kMinRippleSingularValue of its size; with none, the ripple is left as Debevec and
// Malik's curve had it. Moving each code's exposure by p then changes nothing the data
// see: every sample's codes are explained as well, its exposure moved by p too.
constexpr int kMaxRippleDegree = 8;
constexpr double kMinRippleSingularValue = 0.4;
Ripple settle_ripple(double period, const Eigen::VectorXd& f, const ForwardKnots& knots, int first, int last) {
  Ripple ripple;
  // As many harmonics as have three knots or more to the wavelength (4 for a bracket 2 EV
  // apart, 6 for 3 EV), on five knots more than unknowns (a line and the harmonics at
  // the least).
  const int harmonics = int(period / (3.0 * knots.step));
  const int rows = last - first + 1;
  if (!(period > 0.0) || harmonics < 1 || rows < 2 * harmonics + 7) return ripple;
  ripple.frequency = 2.0 * M_PI / period;
  // Each harmonic's shift of f~ (d f~ / d coefficient = -f'(u) harmonic(u)), in units of
  // its size on the knots.
  Eigen::MatrixXd shifts(rows, 2 * harmonics);
  for (int r = 0; r < rows; ++r) {
    const int k = first + r;
    const double slope = (f(k + 1) - f(k - 1)) / (2.0 * knots.step);
    for (int column = 0; column < 2 * harmonics; ++column)
      shifts(r, column) = -slope * ripple.harmonic(column, knots.start + k * knots.step);
  }
  const Eigen::VectorXd size = shifts.colwise().norm().transpose();
  if (!(size.minCoeff() > 0.0)) return ripple;
  shifts = shifts * size.cwiseInverse().asDiagonal();
  // The polynomials up to kMaxRippleDegree on the knots mapped to [-1, 1] (Legendre's, for
  // a well-conditioned start); those of a lower degree are the first columns.
  Eigen::MatrixXd polynomials(rows, kMaxRippleDegree + 1);
  for (int r = 0; r < rows; ++r) {
    const double x = 2.0 * r / (rows - 1) - 1.0;
    double previous = 1.0, current = x;
    polynomials(r, 0) = 1.0;
    polynomials(r, 1) = x;
    for (int n = 1; n < kMaxRippleDegree; ++n) {
      const double next = ((2 * n + 1) * x * current - n * previous) / (n + 1);
      previous = current, current = next;
      polynomials(r, n + 1) = next;
    }
  }
  for (int degree = kMaxRippleDegree; degree >= 1; --degree) {
    if (rows < 2 * harmonics + degree + 6) continue;
    // An orthonormal basis of the polynomials of `degree`.
    const Eigen::MatrixXd basis =
        Eigen::HouseholderQR<Eigen::MatrixXd>(polynomials.leftCols(degree + 1)).householderQ() *
        Eigen::MatrixXd::Identity(rows, degree + 1);
    const auto off_polynomials = [&](const Eigen::MatrixXd& y) -> Eigen::MatrixXd {
      return y - basis * (basis.transpose() * y);
    };
    const Eigen::MatrixXd a = off_polynomials(shifts);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
    if (svd.singularValues().minCoeff() < kMinRippleSingularValue) continue;
    const Eigen::VectorXd coefficients =
        svd.solve(Eigen::VectorXd(-off_polynomials(f.segment(first, rows)))).cwiseQuotient(size);
    if (!coefficients.allFinite()) return ripple;
    // u + p(u) must keep increasing, or the curve would fold back: |p'| under 1/2 by far,
    // as a ripple of a few tenths of a percent is (its slope is about 0.02).
    double steepest = 0.0;
    for (int h = 0; h < harmonics; ++h)
      steepest += (h + 1) * ripple.frequency * std::hypot(coefficients(2 * h), coefficients(2 * h + 1));
    if (steepest < 0.5) ripple.coefficients = coefficients;
    return ripple;
  }
  return ripple;
}

void refine_forward(std::span<const ResponseSamples> brackets, const CodeLimits& limits,
                    const std::vector<float>& weight, int c, const std::array<int, 2>& well_constrained,
                    double ripple_period, std::vector<double>& g) {
  // Each sample's ln exposure through g, and the (its ln exposure + ln t, code) pairs.
  std::vector<std::pair<double, int>> pairs;
  double lowest = INFINITY, highest = -INFINITY;
  for (const ResponseSamples& bracket : brackets) {
    const size_t exposures = bracket.exposures.size();
    const double longest = *std::max_element(bracket.exposures.begin(), bracket.exposures.end());
    for (size_t i = 0; i * exposures * 3 < bracket.codes.size(); ++i) {
      double sum = 0.0, total = 0.0;
      int used = 0;
      for (size_t j = 0; j < exposures; ++j) {
        const uint16_t* rgb = &bracket.codes[(i * exposures + j) * 3];
        if (limits.saturated(rgb) || weight[rgb[c]] <= 0.0f) continue;
        const double w = weight[rgb[c]] * bracket.exposures[j] / longest;
        sum += w * std::exp(g[rgb[c]]) / bracket.exposures[j], total += w;
        ++used;
      }
      if (used < 2) continue;  // one code alone is as noisy as the codes regressed on it
      const double log_exposure = std::log(sum / total);
      for (size_t j = 0; j < exposures; ++j) {
        const double x = log_exposure + std::log(bracket.exposures[j]);
        const int code = bracket.codes[(i * exposures + j) * 3 + c];
        pairs.emplace_back(x, code);
        if (code > limits.low && code < limits.high) lowest = std::min(lowest, x), highest = std::max(highest, x);
      }
    }
  }
  if (!(highest > lowest)) return;
  // f on knots over the exposures that gave unclipped codes, and one beyond each end; at
  // most kMaxKnots of them (the solve is dense), coarser for a range of exposure times
  // beyond a camera's (over 100 units of ln exposure: 43 decades).
  constexpr double kMaxKnots = 1000.0;
  const double step = std::max(1.0 / kKnotsPerUnit, (highest - lowest) / kMaxKnots), start = lowest - step;
  const ForwardKnots grid{start, step, int(std::ceil((highest - start) / step)) + 2};
  const int knots = grid.count;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(knots, knots);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(knots);
  size_t used = 0;
  for (const auto& [x, code] : pairs) {
    int k;
    Eigen::Vector2d basis;
    if (!grid.locate(x, k, basis)) continue;
    a.block<2, 2>(k, k) += basis * basis.transpose();
    b.segment<2>(k) += basis * code;
    ++used;
  }
  const double smoothness = kForwardSmoothness * double(used) / knots;
  add_difference_penalty(2, smoothness, a);
  Eigen::VectorXd f = a.ldlt().solve(b);
  for (int k = 1; k < knots; ++k) f(k) = std::max(f(k), f(k - 1));
  // The knots where the ripple is settled: inside the well-constrained codes, and off
  // the limits, where a curve's clip (a gamma's kink at 255) bends the mean of the codes
  // that f regresses and, through the settle, the ripple (docs/notes/hdr-merge.md).
  int first = 1, last = knots - 2;
  int low = well_constrained[0], high = well_constrained[1];
  while (low < high && weight[low] < kRippleWeight) ++low;
  while (high > low && weight[high] < kRippleWeight) --high;
  while (first < last && f(first) < low) ++first;
  while (last > first && f(last) > high) --last;
  const Ripple ripple = settle_ripple(ripple_period, f, grid, first, last);
  // g = f^-1 over the well-constrained codes, each moved by the ripple; the codes beyond
  // keep the curve's shape, moved to meet the refined ends.
  std::vector<double> refined = g;
  int k = 0;
  for (int z = well_constrained[0]; z <= well_constrained[1]; ++z) {
    while (k + 1 < knots && f(k + 1) < z) ++k;
    if (k + 1 >= knots || f(k) > z || !(f(k + 1) > f(k))) return;  // f does not reach z: keep g
    const double u = start + step * (k + (z - f(k)) / (f(k + 1) - f(k)));
    refined[z] = u + ripple.shift(u);
  }
  for (int z = 0; z < well_constrained[0]; ++z) refined[z] += refined[well_constrained[0]] - g[well_constrained[0]];
  for (int z = well_constrained[1] + 1; z < kCodes; ++z)
    refined[z] += refined[well_constrained[1]] - g[well_constrained[1]];
  g = std::move(refined);
  normalise(g);
}

}  // namespace

CodeLimits code_limits(int bits) {
  const int max = (1 << bits) - 1;
  return {int(std::lround(0.02 * max)), int(std::lround(0.98 * max)), max};
}

std::vector<float> hat_weights(const CodeLimits& limits) {
  std::vector<float> weight(size_t(limits.max) + 1, 0.0f);
  const double half = 0.5 * (limits.high - limits.low);
  for (int z = limits.low + 1; z < limits.high; ++z)
    weight[z] = float(std::min(z - limits.low, limits.high - z) / half);
  return weight;
}

std::string method_name(ResponseMethod method) {
  switch (method) {
    case ResponseMethod::kDebevec:
      return "debevec";
    case ResponseMethod::kLinear:
      return "linear";
  }
  return "linear";
}

std::array<std::vector<float>, 3> CameraResponse::linear_table() const {
  std::array<std::vector<float>, 3> table;
  const int codes = 1 << bits;
  for (int c = 0; c < 3; ++c) {
    table[c].resize(codes);
    for (int z = 0; z < codes; ++z)
      table[c][z] =
          method == ResponseMethod::kLinear ? float(z) / float(codes - 1) : float(std::exp(log_exposure[c][z]));
  }
  return table;
}

ResponseSamples sample_bracket(const BracketPhotos& photos, int max_samples) {
  ResponseSamples samples;
  for (const BracketExposure& exposure : photos.bracket.exposures) samples.exposures.push_back(exposure.exposure);
  const PhotoCodes& first = photos.photos.front();
  const size_t pixels = size_t(first.width) * first.height;
  const auto take = [&](size_t pixel) {
    for (const PhotoCodes& photo : photos.photos)
      samples.codes.insert(samples.codes.end(), &photo.codes[pixel * 3], &photo.codes[pixel * 3 + 3]);
  };
  if (pixels <= size_t(max_samples)) {
    for (size_t pixel = 0; pixel < pixels; ++pixel) take(pixel);
    return samples;
  }
  // Samples spread evenly over the scene's range of exposure, as Debevec and Malik ask.
  // With exposures in a constant ratio (a bracket 2 EV apart) the data leave the curve
  // free up to a component periodic in ln exposure with the bracket's step (Grossberg
  // and Nayar 2003, the "fractal" ambiguity); a smoothness settles that component
  // (settle_ripple), and samples massed at the few radiances of a backdrop let their
  // noise set it instead (9% off on a simulated shoot; docs/notes/hdr-merge.md). Per channel,
  // a pixel's place on the exposure axis is the exposure that sees it nearest the middle
  // code and that code's band of 16; each place keeps at most `cap` pixels, chosen at
  // random (a fixed seed) so that they do not alias with a regular structure, and each
  // channel chooses a third of the samples.
  constexpr int kBands = 16;
  const int max_code = (1 << first.bits) - 1;
  const size_t exposures = photos.photos.size(), places = exposures * kBands;
  if (places > 65536)  // a place is a 16-bit key
    throw Error(photos.bracket.folder.string() + ": " + std::to_string(exposures) +
                " exposures in one bracket; the camera response is recovered from at most 4096");
  // Every pixel's place in each channel, in one parallel pass over the photos (the
  // pass is a read of every code of the bracket; the counts are integers, so their sum
  // does not depend on how the pixels are split between threads).
  using Counts = std::array<std::vector<size_t>, 3>;
  std::vector<const uint16_t*> codes;
  for (const PhotoCodes& photo : photos.photos) codes.push_back(photo.codes.data());
  std::array<std::vector<uint16_t>, 3> place;
  for (std::vector<uint16_t>& channel : place) channel.resize(pixels);
  const Counts count = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, pixels, size_t(1) << 16), Counts{},
      [&](const tbb::blocked_range<size_t>& range, Counts counts) {
        for (std::vector<size_t>& channel : counts) channel.resize(places, 0);
        for (size_t pixel = range.begin(); pixel < range.end(); ++pixel) {
          std::array<int, 3> best = {max_code + 1, max_code + 1, max_code + 1};
          std::array<size_t, 3> key = {0, 0, 0};
          for (size_t j = 0; j < exposures; ++j) {
            const uint16_t* rgb = codes[j] + pixel * 3;
            for (int c = 0; c < 3; ++c) {
              const int distance = std::abs(2 * int(rgb[c]) - max_code);
              // The code's band: its top four bits (codes run to 2^bits - 1).
              if (distance < best[c])
                best[c] = distance, key[c] = j * kBands + ((size_t(rgb[c]) * kBands) >> first.bits);
            }
          }
          for (int c = 0; c < 3; ++c) {
            place[c][pixel] = uint16_t(key[c]);
            ++counts[c][key[c]];
          }
        }
        return counts;
      },
      [&](Counts a, const Counts& b) {
        for (int c = 0; c < 3; ++c) {
          a[c].resize(places, 0);
          for (size_t k = 0; k < b[c].size(); ++k) a[c][k] += b[c][k];
        }
        return a;
      });
  std::vector<bool> chosen(pixels, false);
  Pcg32 rng(0x5eed);
  for (int c = 0; c < 3; ++c) {
    const size_t budget = size_t(max_samples) / 3;
    const auto kept = [&](size_t cap) {
      size_t total = 0;
      for (size_t n : count[c]) total += std::min(n, cap);
      return total;
    };
    size_t cap = 1;
    while (kept(cap) < budget) ++cap;
    // Selection sampling (Knuth's algorithm S) per place: one pass, pixels in order.
    std::vector<size_t> wanted(places), left = count[c];
    for (size_t k = 0; k < places; ++k) wanted[k] = std::min(count[c][k], cap);
    for (size_t pixel = 0; pixel < pixels; ++pixel) {
      const size_t k = place[c][pixel];
      if (wanted[k] > 0 && double(rng.next_uint()) * double(left[k]) < double(wanted[k]) * 0x1p32) {
        chosen[pixel] = true;
        --wanted[k];
      }
      --left[k];
    }
  }
  for (size_t pixel = 0; pixel < pixels; ++pixel)
    if (chosen[pixel]) take(pixel);
  return samples;
}

CameraResponse recover_response(std::span<const ResponseSamples> brackets) {
  std::set<double> distinct;
  for (const ResponseSamples& bracket : brackets) distinct.insert(bracket.exposures.begin(), bracket.exposures.end());
  if (distinct.size() < 2)
    throw Error(
        "every photo of the brackets has the same exposure; recovering the camera response needs "
        "photos of the same view at different exposures");
  CameraResponse response;
  response.method = ResponseMethod::kDebevec;
  response.bits = 8;
  const CodeLimits limits = code_limits(8);
  const std::vector<float> weight = hat_weights(limits);
  const auto count = observations(brackets, limits, weight);
  const double ripple = free_ripple_period(brackets);
  for (const ResponseSamples& bracket : brackets)
    response.samples += bracket.codes.size() / 3 / bracket.exposures.size();
  for (int c = 0; c < 3; ++c) {
    response.log_exposure[c] = debevec(brackets, limits, weight, c);
    normalise(response.log_exposure[c]);
    int low = kCodes, high = -1;
    for (int z = 0; z < kCodes; ++z)
      if (count[c][z] >= kMinObservations && weight[z] >= kMinWeight) low = std::min(low, z), high = std::max(high, z);
    if (high < 0) throw Error(std::string("no sample constrains the camera response's ") + kChannels[c] + " channel");
    response.well_constrained[c] = {low, high};
    refine_forward(brackets, limits, weight, c, response.well_constrained[c], ripple, response.log_exposure[c]);
  }
  return response;
}

CameraResponse linear_response(int bits) {
  CameraResponse response;
  response.method = ResponseMethod::kLinear;
  response.bits = bits;
  const CodeLimits limits = code_limits(bits);
  for (auto& range : response.well_constrained) range = {limits.low + 1, limits.high - 1};
  return response;
}

nlohmann::json response_json(const CameraResponse& response) {
  const CodeLimits limits = code_limits(response.bits);
  nlohmann::json json = {{"method", method_name(response.method)},
                         {"bits", response.bits},
                         {"underexposed_at_or_below", limits.low},
                         {"saturated_at_or_above", limits.high},
                         {"samples", response.samples}};
  for (int c = 0; c < 3; ++c) {
    json["well_constrained"][kChannels[c]] = response.well_constrained[c];
    if (response.method != ResponseMethod::kLinear) json["log_exposure"][kChannels[c]] = response.log_exposure[c];
  }
  return json;
}

CameraResponse read_response(const std::string& path) {
  const nlohmann::json json = read_json_file(path, "camera response");
  auto fail = [&](const std::string& what) -> Error {
    return Error(path + ": " + what + "; expected a response.json as `glaze hdr-merge` writes it");
  };
  if (!json.is_object() || !json.contains("method") || !json["method"].is_string()) throw fail("no \"method\"");
  CameraResponse response;
  const std::string method = json["method"];
  if (method == "linear") return linear_response(json.value("bits", 16));
  if (method != "debevec") throw fail("unknown method \"" + method + "\"");
  response.method = ResponseMethod::kDebevec;
  response.bits = 8;
  for (int c = 0; c < 3; ++c) {
    const nlohmann::json curve =
        json.contains("log_exposure") ? json["log_exposure"].value(kChannels[c], nlohmann::json()) : nlohmann::json();
    if (!curve.is_array() || curve.size() != kCodes)
      throw fail(std::string("\"log_exposure\" has no list of 256 numbers for ") + kChannels[c]);
    for (const nlohmann::json& value : curve) {
      if (!value.is_number() || !std::isfinite(value.get<double>()))
        throw fail(std::string("\"log_exposure\" of ") + kChannels[c] + " holds " + json_excerpt(value));
      response.log_exposure[c].push_back(value.get<double>());
    }
    for (int z = 1; z < kCodes; ++z)
      if (response.log_exposure[c][z] < response.log_exposure[c][z - 1])
        throw fail(std::string("the ") + kChannels[c] + " curve decreases at code " + std::to_string(z));
    const nlohmann::json range = json.contains("well_constrained")
                                     ? json["well_constrained"].value(kChannels[c], nlohmann::json())
                                     : nlohmann::json();
    response.well_constrained[c] =
        range.is_array() && range.size() == 2 && range[0].is_number_integer() && range[1].is_number_integer()
            ? std::array<int, 2>{range[0].get<int>(), range[1].get<int>()}
            : std::array<int, 2>{0, kCodes - 1};
  }
  response.samples = json.value("samples", size_t(0));
  return response;
}

}  // namespace glaze
