#include "inverse/cross_view.h"

#include "renderer/error.h"
#include "renderer/latlong.h"
#include "renderer/material.h"
#include "renderer/math.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <climits>
#include <cmath>

namespace glaze {
namespace {

// Pairs are summed in fixed chunks added in order: the profile does not depend on the
// thread count.
constexpr size_t kChunk = 4096;

// Chunk `chunk` of `used` pairs: its first pair and its count.
std::pair<Eigen::Index, Eigen::Index> chunk_span(size_t chunk, size_t used) {
  const size_t first = chunk * kChunk;
  return {Eigen::Index(first), Eigen::Index(std::min(used, first + kChunk) - first)};
}

}  // namespace

// A view's samples as a triangle mesh over the directions they reflect: two triangles per
// 2 x 2 block of pixels whose samples all exist, binned in a lat-long grid of directions
// so that the triangle around a direction is found among a few.
class ReflectedMesh {
 public:
  ReflectedMesh(const LightingData& data, const PixelGrid& pixels) : data_(data), pixels_(pixels) {
    start_.assign(kRows * kColumns + 1, 0);
    for (int j = pixels.y0(); j + 1 < pixels.y0() + pixels.height(); ++j)
      for (int i = pixels.x0(); i + 1 < pixels.x0() + pixels.width(); ++i) {
        const int64_t a = pixels.sample_at(i, j), b = pixels.sample_at(i + 1, j);
        const int64_t c = pixels.sample_at(i + 1, j + 1), e = pixels.sample_at(i, j + 1);
        if (a >= 0 && b >= 0 && c >= 0) triangles_.push_back({uint32_t(a), uint32_t(b), uint32_t(c)});
        if (a >= 0 && c >= 0 && e >= 0) triangles_.push_back({uint32_t(a), uint32_t(c), uint32_t(e)});
      }
    // Bin each triangle into the cells its vertices' (u, v) box covers (u unwrapped
    // around the first vertex; a box wider than a quarter turn, or touching a pole row,
    // takes whole rows), padded by half a cell for the bulge of its great-circle edges.
    std::vector<std::pair<uint32_t, uint32_t>> entries;  // (cell, triangle)
    for (uint32_t t = 0; t < triangles_.size(); ++t) {
      float u_low = 0, u_high = 0, v_low = 1, v_high = 0, u_first = 0;
      for (int corner = 0; corner < 3; ++corner) {
        const Vec2 uv = direction_to_latlong(data_.reflected[triangles_[t][corner]]);
        float u = uv.x();
        if (corner == 0) u_first = u, u_low = u_high = u;
        if (u - u_first > 0.5f) u -= 1.0f;
        if (u_first - u > 0.5f) u += 1.0f;
        u_low = std::min(u_low, u), u_high = std::max(u_high, u);
        v_low = std::min(v_low, uv.y()), v_high = std::max(v_high, uv.y());
      }
      const int row_low = std::max(0, int(std::floor(v_low * kRows - 0.5f)));
      const int row_high = std::min(kRows - 1, int(std::floor(v_high * kRows + 0.5f)));
      const bool whole_rows = u_high - u_low > 0.25f || row_low == 0 || row_high == kRows - 1;
      const int column_low = int(std::floor(u_low * kColumns - 0.5f)),
                column_high = int(std::floor(u_high * kColumns + 0.5f));
      for (int row = row_low; row <= row_high; ++row) {
        if (whole_rows) {
          for (int column = 0; column < kColumns; ++column) entries.emplace_back(row * kColumns + column, t);
          continue;
        }
        for (int column = column_low; column <= column_high; ++column)
          entries.emplace_back(row * kColumns + ((column % kColumns) + kColumns) % kColumns, t);
      }
    }
    std::sort(entries.begin(), entries.end());
    for (const auto& [cell, triangle] : entries) ++start_[cell + 1];
    for (size_t cell = 0; cell < size_t(kRows) * kColumns; ++cell) start_[cell + 1] += start_[cell];
    members_.reserve(entries.size());
    for (const auto& entry : entries) members_.push_back(entry.second);
  }

  // The view's samples by pixel.
  const PixelGrid& pixels() const { return pixels_; }

  // The triangle whose directions contain `r`, and r's barycentric weights in it (the
  // central projection onto its plane); false when no triangle of this view does.
  bool locate(const Vec3& r, std::array<uint32_t, 3>& corners, std::array<float, 3>& weights,
              double* area = nullptr) const {
    const Vec2 uv = direction_to_latlong(r);
    const int cell = texel_of(uv, kColumns, kRows);
    for (uint32_t i = start_[cell]; i < start_[cell + 1]; ++i) {
      const std::array<uint32_t, 3>& t = triangles_[members_[i]];
      const Eigen::Vector3d A = data_.reflected[t[0]].cast<double>(), B = data_.reflected[t[1]].cast<double>(),
                            C = data_.reflected[t[2]].cast<double>(), R = r.cast<double>();
      const double det = A.dot(B.cross(C));
      if (!(std::abs(det) > 1e-18)) continue;
      const double a = R.dot(B.cross(C)) / det, b = A.dot(R.cross(C)) / det, c = A.dot(B.cross(R)) / det;
      constexpr double kSlack = -1e-7;
      if (a < kSlack || b < kSlack || c < kSlack) continue;
      const double sum = a + b + c;
      if (!(sum > 0.0)) continue;
      corners = t;
      weights = {float(a / sum), float(b / sum), float(c / sum)};
      if (area) *area = 0.5 * (B - A).cross(C - A).norm();
      return true;
    }
    return false;
  }

 private:
  static constexpr int kColumns = 256, kRows = 128;
  const LightingData& data_;
  const PixelGrid& pixels_;
  std::vector<std::array<uint32_t, 3>> triangles_;
  std::vector<uint32_t> start_, members_;
};

namespace {

// The stencils' test of fit on captures with noise (quadratic_weights): the misfit's
// chi-square may exceed its degrees of freedom by this many of its standard deviations
// (10: a chi-square about four times its mean through 25 pixels, nine times through 9,
// which the noise alone exceeds about once in 10^5). It is there to catch detail far
// above the noise: a small lamp's reflection fails it at any width from 3 to 30, while at
// 3 the blue room's lamps fail it too at low resolutions, where the wider stencil's
// averaging is what holds R0 (docs/notes/studio-lamps.md, "The test's width").
constexpr double kGoodness = 10.0;

}  // namespace

CrossViewSystem::~CrossViewSystem() = default;

CrossViewSystem::CrossViewSystem(const LightingData& data, const SampleSet& samples, bool trim)
    : data_(data), n_(int(data.cc.rows())), trim_(trim) {
  if (!samples.pixels)
    throw Error("the joint fit compares views on their pixel grids: use pixel samples (drop --points)");
  const size_t count = samples.samples.size();
  if (data.noise.size() != count) throw Error("the views' comparison needs the captures' noise model (estimate_noise)");
  const int views = int(samples.per_frame.size());
  grids_ = pixel_grids(samples);
  meshes_.reserve(views);
  for (int f = 0; f < views; ++f) meshes_.emplace_back(data, grids_[f]);
  // Per sample, the change of its reflected direction per pixel along the film's x and y
  // (central differences where both neighbours exist): its footprint's shape.
  std::vector<std::array<Vec3, 2>> steps(count, {Vec3::Zero(), Vec3::Zero()});
  tbb::parallel_for(size_t(0), count, [&](size_t k) {
    const Sample& s = samples.samples[k];
    const PixelGrid& grid = grids_[s.frame];
    const int i = int(s.film.x()), j = int(s.film.y());
    for (int axis = 0; axis < 2; ++axis) {
      const int64_t plus = grid.sample_at(i + (axis == 0), j + (axis == 1));
      const int64_t minus = grid.sample_at(i - (axis == 0), j - (axis == 1));
      if (plus >= 0 && minus >= 0)
        steps[k][axis] = 0.5f * (data.reflected[plus] - data.reflected[minus]);
      else if (plus >= 0)
        steps[k][axis] = data.reflected[plus] - data.reflected[k];
      else if (minus >= 0)
        steps[k][axis] = data.reflected[k] - data.reflected[minus];
    }
  });
  // Per sample, its pairs with every other view, found in parallel a block of samples at
  // a time (which bounds the full-width stencils held at once) and kept in sample order.
  constexpr size_t kBlock = size_t(1) << 16;
  for (size_t begin = 0; begin < count; begin += kBlock) {
    const size_t end = std::min(count, begin + kBlock);
    std::vector<std::vector<Stencil>> found(end - begin);
    tbb::parallel_for(begin, end, [&](size_t k) {
      const int own = samples.samples[k].frame;
      for (int f = 0; f < views; ++f) {
        if (f == own) continue;
        Stencil s{};
        std::array<uint32_t, 3> corners;
        std::array<float, 3> weights;
        if (!meshes_[f].locate(data.reflected[k], corners, weights)) continue;
        s.count = 3;
        std::copy(corners.begin(), corners.end(), s.member.begin());
        std::copy(weights.begin(), weights.end(), s.weight.begin());
        if (interpolate_quadratically(meshes_[f], samples, steps, uint32_t(k), !data.noise_free, s))
          found[k - begin].push_back(s);
      }
    });
    for (size_t k = begin; k < end; ++k)
      for (const Stencil& s : found[k - begin]) {
        pairs_.push_back({uint32_t(k), s.count, members_.size()});
        members_.insert(members_.end(), s.member.begin(), s.member.begin() + s.count);
        weights_.insert(weights_.end(), s.weight.begin(), s.weight.begin() + s.count);
      }
  }
  if (pairs_.empty())
    throw Error(
        "no direction is reflected towards two views: material and lighting cannot be separated; the joint "
        "fit needs views from several directions");
}

bool CrossViewSystem::interpolate_quadratically(const ReflectedMesh& mesh, const SampleSet& samples,
                                                const std::vector<std::array<Vec3, 2>>& steps, uint32_t sample,
                                                bool with_noise, Stencil& s) const {
  // Around the corner nearest r: where the captures have noise and the other view sees r
  // nearer its normal than the sample does (F smaller there, whatever R0 is: the header
  // says why), 5 x 5 pixels, and where that fails 3 x 3; where it sees r nearer grazing,
  // 3 x 3 pixels that must pass the test of fit, or the pair is left out.
  const int nearest = int(std::max_element(s.weight.begin(), s.weight.begin() + 3) - s.weight.begin());
  const uint32_t corner = s.member[nearest];
  const bool finer = data_.mu[corner] > data_.mu[sample];
  if (with_noise && finer && quadratic_weights(mesh, samples, steps, sample, corner, 2, true, s) == StencilFit::fitted)
    return true;
  return quadratic_weights(mesh, samples, steps, sample, corner, 1, with_noise && !finer, s) != StencilFit::unresolved;
}

CrossViewSystem::StencilFit CrossViewSystem::quadratic_weights(const ReflectedMesh& mesh, const SampleSet& samples,
                                                               const std::vector<std::array<Vec3, 2>>& steps,
                                                               uint32_t sample, uint32_t corner, int reach,
                                                               bool test_fit, Stencil& s) const {
  // All the pixels but at most one: six unknowns, and some to spare against a degenerate
  // layout at the object's edge.
  const Vec2& film = samples.samples[corner].film;
  std::array<uint32_t, kWidestStencil> members;
  int n = 0;
  for (int dj = -reach; dj <= reach; ++dj)
    for (int di = -reach; di <= reach; ++di)
      if (const int64_t k = mesh.pixels().sample_at(int(film.x()) + di, int(film.y()) + dj); k >= 0)
        members[n++] = uint32_t(k);
  if (n < (2 * reach + 1) * (2 * reach + 1) - 1) return StencilFit::degenerate;
  // Coordinates on the plane tangent at r (the central projection, as the triangles'
  // barycentric weights use). A pixel modelled by K x K rays at the centres of its K x K
  // cells (footprint.h) has a footprint of (K^2 - 1) / (12 K^2) pixels^2 per film axis;
  // J maps the film's axes to the plane.
  const Frame plane = Frame::from_normal(data_.reflected[sample].normalized());
  const Eigen::Vector3d r = plane.n.cast<double>(), e1 = plane.s.cast<double>(), e2 = plane.t.cast<double>();
  const double K = data_.footprint, per_axis = (K * K - 1.0) / (12.0 * K * K);
  auto covariance = [&](uint32_t k) {
    Eigen::Matrix2d J;
    for (int axis = 0; axis < 2; ++axis) {
      const Eigen::Vector3d step = steps[k][axis].cast<double>();
      J(0, axis) = step.dot(e1), J(1, axis) = step.dot(e2);
    }
    return Eigen::Matrix2d(per_axis * J * J.transpose());
  };
  // Row j: pixel j's record of L0 + g.u + u^T H u / 2 in the unknowns (L0, g, H_uu, H_uv,
  // H_vv); the target: sample a's record, at u = 0 with its own footprint.
  Eigen::Matrix<double, Eigen::Dynamic, 6> A(n, 6);
  for (int m = 0; m < n; ++m) {
    const Eigen::Vector3d q = data_.reflected[members[m]].cast<double>();
    const double along = q.dot(r);
    if (!(along > 0.5)) return StencilFit::degenerate;
    const double u = q.dot(e1) / along, v = q.dot(e2) / along;
    const Eigen::Matrix2d S = covariance(members[m]);
    A.row(m) << 1.0, u, v, 0.5 * (u * u + S(0, 0)), u * v + S(0, 1), 0.5 * (v * v + S(1, 1));
  }
  const Eigen::Matrix2d Sa = covariance(sample);
  Eigen::Matrix<double, 6, 1> target;
  target << 1.0, 0.0, 0.0, 0.5 * Sa(0, 0), Sa(0, 1), 0.5 * Sa(1, 1);
  // The weights are A (A^T A)^-1 target, the quadratic's value through the records; the
  // columns scaled to unit norm so that the conditioning test means something.
  const Eigen::Matrix<double, 6, 1> norms = A.colwise().norm().transpose();
  if (!(norms.minCoeff() > 0.0)) return StencilFit::degenerate;
  const Eigen::Matrix<double, Eigen::Dynamic, 6> scaled = A * norms.cwiseInverse().asDiagonal();
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> normal(scaled.transpose() * scaled);
  if (normal.info() != Eigen::Success || !(normal.vectorD().minCoeff() > 1e-8 * normal.vectorD().maxCoeff()))
    return StencilFit::degenerate;
  const Eigen::VectorXd weights = scaled * normal.solve(target.cwiseQuotient(norms));
  if (!weights.allFinite()) return StencilFit::degenerate;
  // The quadratic stands for the lighting only where its misfit through the records is
  // the noise's (chi-square with n - 6 degrees of freedom, in units of the noise model;
  // kGoodness standard deviations above its mean). Where the lighting has detail the
  // pixels do not resolve, the quadratic smooths it by an amount that changes with n.v
  // as F does (a grazing view's pixels span more of it) and biases R0: a 5 x 5 stencil
  // then gives way to the 3 x 3, which follows the detail closer, and where the other
  // view's pixels are the coarser ones a 3 x 3 that fails leaves the pair out
  // (interpolate_quadratically).
  if (test_fit) {
    Eigen::Matrix<double, Eigen::Dynamic, 3> records(n, 3);
    for (int m = 0; m < n; ++m) records.row(m) = data_.observed[members[m]].cast<double>().matrix().transpose();
    const Eigen::Matrix<double, Eigen::Dynamic, 3> misfit =
        records - scaled * normal.solve(scaled.transpose() * records);
    const double dof = n - 6.0, bound = dof + kGoodness * std::sqrt(2.0 * dof);
    for (int c = 0; c < 3; ++c) {
      double chi2 = 0.0;
      for (int m = 0; m < n; ++m) chi2 += misfit(m, c) * misfit(m, c) / double(data_.noise[members[m]][c]);
      if (!(chi2 < bound)) return StencilFit::unresolved;
    }
  }
  s.count = uint32_t(n);
  for (int m = 0; m < n; ++m) s.member[m] = members[m], s.weight[m] = float(weights(m));
  return StencilFit::fitted;
}

std::vector<double> CrossViewSystem::inverse_fresnel(double R0) const {
  std::vector<double> inverse(data_.mu.size());
  tbb::parallel_for(size_t(0), inverse.size(),
                    [&](size_t k) { inverse[k] = 1.0 / std::max(schlick_fresnel(R0, double(data_.mu[k])), 1e-30); });
  return inverse;
}

void CrossViewSystem::pair_terms(const Pair& p, const std::vector<double>& inverse_F, Eigen::Ref<Eigen::VectorXd> x,
                                 Eigen::Ref<Eigen::Vector3d> y, Eigen::Ref<Eigen::Vector3d> weight) const {
  // o_a - c_a.d - F_a sum_j w_j (o_j - c_j.d) / F_j = y - x.d: its noise variance is
  // v_a + sum_j (F_a w_j / F_j)^2 v_j (the lighting eliminated between two independent
  // observations), and its weight the inverse of that.
  const double Fa = 1.0 / inverse_F[p.sample];
  x = data_.c_row(p.sample).cast<double>();
  y = data_.observed[p.sample].cast<double>().matrix();
  Eigen::Vector3d variance = data_.noise[p.sample].cast<double>().matrix();
  for (size_t i = p.first; i < p.first + p.count; ++i) {
    const uint32_t j = members_[i];
    const double ratio = Fa * weights_[i] * inverse_F[j];
    x -= ratio * data_.c_row(j).cast<double>();
    y -= ratio * data_.observed[j].cast<double>().matrix();
    variance += ratio * ratio * data_.noise[j].cast<double>().matrix();
  }
  weight = variance.cwiseInverse();
}

CrossViewSystem::PairTerms CrossViewSystem::pair_terms(double R0) const {
  const std::vector<double> inverse_F = inverse_fresnel(R0);
  const size_t used = (pairs_.size() + stride_ - 1) / stride_;
  PairTerms terms;
  terms.x.resize(n_, Eigen::Index(used));
  terms.y.resize(Eigen::Index(used), 3);
  terms.weight.resize(Eigen::Index(used), 3);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, used, kChunk), [&](const tbb::blocked_range<size_t>& range) {
    Eigen::VectorXd x(n_);
    Eigen::Vector3d y, weight;
    for (size_t p = range.begin(); p < range.end(); ++p) {
      pair_terms(pairs_[p * stride_], inverse_F, x, y, weight);
      terms.x.col(Eigen::Index(p)) = x.cast<float>();
      terms.y.row(Eigen::Index(p)) = y.transpose();
      terms.weight.row(Eigen::Index(p)) = weight.transpose();
    }
  });
  return terms;
}

Eigen::MatrixXd CrossViewSystem::solve(const PairTerms& terms, const Eigen::MatrixXd* reweight_at, double c2,
                                       bool trim) const {
  const size_t used = size_t(terms.y.rows());
  const size_t chunks = (used + kChunk - 1) / kChunk;
  struct Sums {
    std::array<Eigen::MatrixXd, 3> xx;
    Eigen::MatrixXd xy;
  };
  std::vector<Sums> partial(chunks);
  tbb::parallel_for(size_t(0), chunks, [&](size_t chunk) {
    const auto [first, rows] = chunk_span(chunk, used);
    const Eigen::MatrixXd X = terms.x.middleCols(first, rows).cast<double>();
    const auto Y = terms.y.middleRows(first, rows);
    Eigen::MatrixXd W = terms.weight.middleRows(first, rows);
    if (reweight_at) {
      const Eigen::ArrayXd z = normalised_residuals(terms, first, X, *reweight_at) / c2;
      if (trim)
        W.array().colwise() *= (-z).exp();
      else
        W.array().colwise() /= 1.0 + z;
    }
    Sums& s = partial[chunk];
    s.xy.resize(n_, 3);
    // X W X^T is symmetric: a rank update of its lower triangle by X sqrt(W) does half
    // the arithmetic of the general product.
    for (int c = 0; c < 3; ++c) {
      s.xx[c].setZero(n_, n_);
      s.xx[c].selfadjointView<Eigen::Lower>().rankUpdate(X * W.col(c).cwiseSqrt().asDiagonal());
      s.xy.col(c).noalias() = X * W.col(c).cwiseProduct(Y.col(c));
    }
  });
  Eigen::MatrixXd d(n_, 3);
  for (int c = 0; c < 3; ++c) {
    Eigen::MatrixXd xx = Eigen::MatrixXd::Zero(n_, n_);
    Eigen::VectorXd xy = Eigen::VectorXd::Zero(n_);
    for (const Sums& s : partial) xx += s.xx[c], xy += s.xy.col(c);
    // A whisper of ridge keeps d finite for views that leave part of it unseen.
    xx.diagonal().array() += 1e-9 * std::max(xx.diagonal().mean(), 1e-300);
    d.col(c) = xx.ldlt().solve(xy);  // LDLT reads the lower triangle only
  }
  return d;
}

Eigen::ArrayXd CrossViewSystem::normalised_residuals(const PairTerms& terms, Eigen::Index first,
                                                     const Eigen::MatrixXd& X, const Eigen::MatrixXd& d) {
  // The chunk's residuals in one product: per pair, a 3 x n product is too small for
  // Eigen's kernels, and their dispatch costs more than the arithmetic.
  const Eigen::Index rows = X.cols();
  return ((terms.y.middleRows(first, rows) - X.transpose() * d).array().square() *
          terms.weight.middleRows(first, rows).array())
             .rowwise()
             .sum() /
         3.0;
}

std::vector<double> CrossViewSystem::normalised_residuals(const PairTerms& terms, const Eigen::MatrixXd& d) const {
  const size_t used = size_t(terms.y.rows());
  std::vector<double> squared(used);
  tbb::parallel_for(size_t(0), (used + kChunk - 1) / kChunk, [&](size_t chunk) {
    const auto [first, rows] = chunk_span(chunk, used);
    Eigen::Map<Eigen::ArrayXd>(squared.data() + first, rows) =
        normalised_residuals(terms, first, terms.x.middleCols(first, rows).cast<double>(), d);
  });
  return squared;
}

// Cauchy's loss at 2.385 robust standard deviations (95% efficiency for Gaussian noise).
constexpr double kCauchy = 2.385;
// The robust scale's floor, in units of the noise model: 0.1% of the pixel's level (the
// model's own floor is kNoiseFloor of it). Noise-free captures leave residuals of a few
// 1e-5 of the level (the pixel grids' interpolation error), and a scale that small makes
// the Cauchy weights swing by orders of magnitude between neighbouring R0: the misfit
// turns rough at the 1e-4 level and the search stops in a spurious minimum (measured: R0
// off by 2.6e-4, Rd by 0.0026 on three 512x512 views; with the floor 1e-6 and 1.5e-4
// of the level). Real noise (1-9% of the level at 256 spp) is far above it.
constexpr double kMinimumScale = 1e-3 / kNoiseFloor;

// Noise-free, band-limited captures: the Cauchy fit's d is trimmed by kTrimmings more solves with
// Welsch's weight exp(-(e / (kTrim scale))^2), which keeps the pairs that fit to about the
// robust scale (a pair at the median residual weighs 0.28) and drops the rest. Their
// residuals are no noise but the interpolation's error, heavy-tailed under small bright
// sources: a pair near a lamp misfits by many scales (the quadratic through the other
// view's pixels cannot follow the lamp's edge), and Cauchy's influence, which falls off
// only as 1 / e, lets such pairs pull d together, and with it the views' mirror estimates.
// Trimming less (fewer solves) or narrower (kTrim 0.3, too few pairs kept) holds less of
// that back; on smooth lighting it changes little (docs/notes/small-sources.md, "Small bright
// sources and the trimmed diffuse field"). Captures with noise keep the Cauchy fit: there
// the residuals are the noise, for which Cauchy's loss is 95% efficient. So do noise-free
// captures with a full-band diffuse term: until the later passes predict its bands above
// lmax, those bands are a model error that all pairs share, not a tail, and trimming keeps
// the pairs that happen to fit it, which can run R0 away (same note).
constexpr int kTrimmings = 4;
constexpr double kTrim = 0.6;

CrossViewSystem::Fit CrossViewSystem::fit(double R0) const { return fit(pair_terms(R0)); }

CrossViewSystem::Fit CrossViewSystem::fit(const PairTerms& terms) const {
  Fit result;
  if (!std::isfinite(scale_)) {  // not calibrated yet: plain least squares
    result.d = solve(terms, nullptr, 0.0);
    for (double z : normalised_residuals(terms, result.d)) result.cost += z;
    return result;
  }
  const double c2 = kCauchy * kCauchy * scale_ * scale_;
  // Iteratively reweighted: each solve weighs the pairs by the residuals of the last.
  constexpr int kReweightings = 3;
  result.d = solve(terms, nullptr, c2);
  for (int iteration = 1; iteration < kReweightings; ++iteration) result.d = solve(terms, &result.d, c2);
  if (trim_) {
    const double w2 = kTrim * kTrim * scale_ * scale_;
    for (int iteration = 0; iteration < kTrimmings; ++iteration) result.d = solve(terms, &result.d, w2, true);
  }
  const std::vector<double> squared = normalised_residuals(terms, result.d);
  for (double z : squared) result.cost += 0.5 * c2 * std::log1p(z / c2);
  return result;
}

void CrossViewSystem::calibrate(double R0) {
  // The scale from the least-squares residuals, then again from the robust fit's.
  const PairTerms terms = pair_terms(R0);
  auto median_magnitude = [&](const Eigen::MatrixXd& fitted) {
    std::vector<double> magnitude = normalised_residuals(terms, fitted);
    for (double& z : magnitude) z = std::sqrt(z);
    std::nth_element(magnitude.begin(), magnitude.begin() + magnitude.size() / 2, magnitude.end());
    return std::max(1.4826 * magnitude[magnitude.size() / 2], 1e-30);
  };
  scale_ = INFINITY;
  scale_ = std::max(median_magnitude(fit(terms).d), kMinimumScale);
  scale_ = std::max(median_magnitude(fit(terms).d), kMinimumScale);
}

Eigen::MatrixXd CrossViewSystem::lighting(double R0, const Eigen::MatrixXd& d, int width, int height,
                                          double* seen) const {
  const int lmax = data_.lmax;
  std::vector<Eigen::MatrixXd> rows(height);
  std::vector<Eigen::MatrixXd> unseen_rows(height);
  std::vector<double> seen_area(height, 0.0);
  tbb::parallel_for(0, height, [&](int j) {
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n_, 3), unseen = Eigen::MatrixXd::Zero(n_, n_);
    std::vector<float> basis(n_);
    const double solid_angle = latlong_texel_solid_angle(j, width, height);
    for (int i = 0; i < width; ++i) {
      const Vec3 direction = latlong_to_direction(Vec2((i + 0.5f) / width, (j + 0.5f) / height));
      Eigen::Vector3d estimate = Eigen::Vector3d::Zero();
      double total = 0.0;
      std::array<uint32_t, 3> near;
      std::array<float, 3> weight;
      for (const ReflectedMesh& mesh : meshes_) {
        double area = 0.0;
        if (!mesh.locate(direction, near, weight, &area)) continue;
        Eigen::Vector3d light = Eigen::Vector3d::Zero();
        double F = 0.0;
        for (int k = 0; k < 3; ++k) {
          const uint32_t s = near[k];
          const double Fs = std::max(schlick_fresnel(R0, double(data_.mu[s])), 1e-30);
          const Eigen::VectorXd c = data_.c_row(s).cast<double>();
          light += weight[k] * (data_.observed[s].cast<double>().matrix() - d.transpose() * c) / Fs;
          F += weight[k] * Fs;
        }
        // As in the lighting fit's map: where the mirror reflects under 1% (a matte coat
        // seen near the normal) (o - c.d) / F is the diffuse model's error amplified a
        // hundredfold, not the lighting.
        if (F < 0.01) continue;
        // Views combine by how finely they sample the direction: the interpolation error
        // grows with the triangle, and a grazing view's triangles are large.
        estimate += light / std::max(area, 1e-12);
        total += 1.0 / std::max(area, 1e-12);
      }
      sh_eval<float>(lmax, direction, basis);
      const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXf>(basis.data(), n_).cast<double>();
      if (total > 0.0) {
        sum += solid_angle * y * (estimate / total).transpose();
        seen_area[j] += solid_angle;
      } else {
        unseen += solid_angle * y * y.transpose();
      }
    }
    rows[j] = sum, unseen_rows[j] = unseen;
  });
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n_, 3), unseen = Eigen::MatrixXd::Zero(n_, n_);
  double area = 0.0;
  for (int j = 0; j < height; ++j) sum += rows[j], unseen += unseen_rows[j], area += seen_area[j];
  if (seen) *seen = area / (4.0 * kPiD);
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n_, n_);
  return (I - unseen + 1e-9 * I).ldlt().solve(sum);
}

}  // namespace glaze
