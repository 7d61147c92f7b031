// noise_model.cpp: the captures' noise per sample, from the pixels' residuals.
#include "inverse/noise_model.h"

#include "renderer/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <experimental/simd>
#include <limits>
#include <optional>

namespace glaze {
namespace {

// The window whose residuals estimate a sample's noise: (2 kNoiseReach + 1)^2 pixels less
// the 3 x 3 around the sample, widened (doubled) while it holds fewer than kNoiseValues.
constexpr int kNoiseReach = 4;
constexpr size_t kNoiseValues = 8;

// The median of e^2 / var(e) for Gaussian e (of a chi-square variable with one degree of
// freedom): the window's median residual over this is the noise's variance.
constexpr double kMedianOfChiSquare1 = 0.45493642311957;

using Lanes = std::experimental::native_simd<double>;
static_assert(Lanes::size() <= kMedianPadding);
constexpr size_t kWalkRanks = 32;

// The nearest value beyond `bound` in v[0 .. padded - 1] (above it, or at or above it
// where `inclusive`, for kUpwards; below it otherwise) and how many values equal it; a
// count of 0 where there is none.
template <bool kUpwards>
std::pair<double, size_t> nearest_beyond(const double* v, size_t padded, double bound, bool inclusive) {
  constexpr double kNone =
      kUpwards ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
  auto load = [&](size_t i) { return Lanes(v + i, std::experimental::element_aligned); };
  Lanes nearest(kNone);
  for (size_t i = 0; i < padded; i += Lanes::size()) {
    Lanes x = load(i);
    where(!(kUpwards ? (inclusive ? x >= bound : x > bound) : x < bound), x) = kNone;
    nearest = kUpwards ? std::experimental::min(nearest, x) : std::experimental::max(nearest, x);
  }
  const double value = kUpwards ? std::experimental::hmin(nearest) : std::experimental::hmax(nearest);
  if (value == kNone) return {value, 0};
  size_t ties = 0;
  for (size_t i = 0; i < padded; i += Lanes::size()) ties += size_t(std::experimental::popcount(load(i) == value));
  return {value, ties};
}

// The k-th value (from 0) outwards from `bound`: upwards the k-th least of those >= bound,
// downwards the k-th greatest of those < bound; nothing where that takes over kWalkRanks
// passes.
template <bool kUpwards>
std::optional<double> walk(const double* v, size_t padded, double bound, size_t k) {
  for (bool first = true; k < kWalkRanks; first = false) {  // each pass takes one rank or more
    const auto [value, ties] = nearest_beyond<kUpwards>(v, padded, bound, first);
    if (ties == 0) return std::nullopt;
    if (k < ties) return value;
    k -= ties, bound = value;
  }
  return std::nullopt;
}

}  // namespace

// How: `guess` is first ranked by counting the values below it; the median is then a
// few ranks from it, reached by as many passes for the nearest value beyond the
// last one found, each a vectorised scan of v, and one more that counts that value's
// ties. Neighbouring windows share most of their values, so nearly all medians are within
// a few ranks of the last one's, and a few branch-free scans beat selection
// (std::nth_element), which mispredicts about half its branches on 72 values in random
// order (docs/notes/fit-timings.md). Medians further away (the first window of a thread,
// wider windows) take the selection.
double median_near(const double* v, size_t n, double guess) {
  if (n == 0) throw Error("the median of no values");
  const size_t padded = (n + Lanes::size() - 1) / Lanes::size() * Lanes::size();
  size_t below = 0;
  for (size_t i = 0; i < padded; i += Lanes::size())
    below += size_t(std::experimental::popcount(Lanes(v + i, std::experimental::element_aligned) < guess));
  const size_t rank = n / 2;
  const std::optional<double> found =
      rank < below ? walk<false>(v, padded, guess, below - 1 - rank) : walk<true>(v, padded, guess, rank - below);
  if (found) return *found;
  thread_local std::vector<double> values;
  values.assign(v, v + n);
  std::nth_element(values.begin(), values.begin() + ptrdiff_t(rank), values.end());
  return values[rank];
}

PixelGrid::PixelGrid(const SampleSet& set, const std::vector<uint32_t>& members) {
  if (members.empty()) return;  // a view that does not see the object
  int x0 = INT32_MAX, y0 = INT32_MAX, x1 = INT32_MIN, y1 = INT32_MIN;
  for (uint32_t k : members) {
    const Vec2& film = set.samples[k].film;
    x0 = std::min(x0, int(film.x())), y0 = std::min(y0, int(film.y()));
    x1 = std::max(x1, int(film.x())), y1 = std::max(y1, int(film.y()));
  }
  x0_ = x0, y0_ = y0, width_ = x1 - x0 + 1, height_ = y1 - y0 + 1;
  grid_.assign(size_t(width_) * height_, -1);
  for (uint32_t k : members) {
    const Vec2& film = set.samples[k].film;
    grid_[size_t(int(film.y()) - y0) * width_ + (int(film.x()) - x0)] = k;
  }
}

std::vector<PixelGrid> pixel_grids(const SampleSet& samples) {
  const int views = int(samples.per_frame.size());
  std::vector<std::vector<uint32_t>> members(views);
  for (uint32_t k = 0; k < samples.samples.size(); ++k) members[samples.samples[k].frame].push_back(k);
  std::vector<PixelGrid> grids;
  grids.reserve(views);
  for (int f = 0; f < views; ++f) grids.emplace_back(samples, members[f]);
  return grids;
}

// Per sample and channel, the variance of the captures' noise around it, estimated from
// the data. A pixel's noise is what its neighbours do not predict: the residual
//   e = o - (sum of the 4 edge neighbours) / 2 + (sum of the 4 corner neighbours) / 4
// vanishes for any cubic in the film's coordinates, so smooth shading and the mirrored
// lighting's gradients and curvature leave it, and for independent pixel noise of
// variance v it has variance (1 + 4/4 + 4/16) v = 2.25 v. The median of e^2 / 2.25 over
// the window around the sample, divided by kMedianOfChiSquare1, is its noise variance; the
// window leaves out the sample and its 8 neighbours, whose residuals contain the sample's
// own noise, so that a sample's noise does not set its weight. With a floor of
// kNoiseFloor times the level (the four neighbours' mean, plus 1% of the
// mean observation).
//
// The median, not the mean: where the lighting has detail the pixels do not resolve (a
// small lamp's reflection, a window's edge) e is that detail, large in a few pixels of
// the window, and the mean counts it as noise. The pairs there then carry a variance that
// makes their misfit (the interpolation's, not the noise's) look like noise, and the
// robust loss keeps them; with the median they stay outliers, and the 5 x 5 stencils'
// test of fit (quadratic_weights) sees the detail (docs/notes/studio-lamps.md, "The fix:
// lamps are not noise").
//
// Why from the data: a path tracer's noise is its diffuse estimate's (the coat's mirror
// is traced exactly), so it is not proportional to the pixel's level. Measured on 256 spp
// captures of the white sphere in the blue room, it is 4% of the level near the normal and
// 1.5% at n.v = 0.2-0.3, where the mirror carries much of the level; weighting by the
// level instead misweighs the grazing pairs that fix R0, and biases it for every seed
// (docs/notes/noise-model.md, "Why the noise is estimated from the data"). Photographs'
// noise (shot and read noise) is not proportional to the level either.
//
// `noise_free` captures (glaze's sh integrator, which is deterministic) take the floor
// everywhere. Their residuals e are the signal's detail, not noise: in a channel that
// only the mirror lights (the red sphere's green and blue) they are the reflected map's
// texture, 4-9% of the level under St Fagans at one ray per pixel, which would
// down-weight the detailed pairs for noise they do not have.
std::vector<RGB> estimate_noise(const std::vector<RGB>& observed, const SampleSet& samples, bool noise_free) {
  const size_t count = samples.samples.size();
  if (observed.size() != count) throw Error("the noise model needs one observation per sample");
  // Point samples are read between pixels: they have no grid, and take the floor.
  noise_free = noise_free || !samples.pixels;
  const std::vector<PixelGrid> grids = samples.pixels ? pixel_grids(samples) : std::vector<PixelGrid>{};
  // Per view, the residuals e^2 / 2.25 on its pixel box (-1: no sample there, or a
  // neighbour missing), so that a window's are read row by row; none where unread.
  std::vector<std::vector<RGBd>> residual(grids.size());
  if (!noise_free)
    for (size_t f = 0; f < grids.size(); ++f)
      residual[f].assign(size_t(grids[f].width()) * grids[f].height(), RGBd::Constant(-1.0));
  auto pixel_of = [&](size_t k) {
    return std::pair(int(samples.samples[k].film.x()), int(samples.samples[k].film.y()));
  };
  if (!noise_free)
    tbb::parallel_for(size_t(0), count, [&](size_t k) {
      const PixelGrid& grid = grids[samples.samples[k].frame];
      const auto [i, j] = pixel_of(k);
      RGBd edges = RGBd::Zero(), corners = RGBd::Zero();
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          if (di == 0 && dj == 0) continue;
          const int64_t m = grid.sample_at(i + di, j + dj);
          if (m < 0) return;
          (di == 0 || dj == 0 ? edges : corners) += observed[m].cast<double>();
        }
      // Left -1 (no residual) unless finite in every channel: a window's median counts it
      // in all three.
      if (const RGBd e = (observed[k].cast<double>() - edges / 2.0 + corners / 4.0).square() / 2.25; e.allFinite())
        residual[samples.samples[k].frame][size_t(j - grid.y0()) * grid.width() + (i - grid.x0())] = e;
    });
  RGBd mean = RGBd::Zero();
  for (const RGB& o : observed) mean += o.cast<double>();
  const RGBd offset = (0.01 * mean / double(count)).max(1e-12);
  std::vector<RGB> variance(count);
  tbb::parallel_for(size_t(0), count, [&](size_t k) {
    RGBd level = RGBd::Zero();
    int neighbours = 0;
    // The window's residuals, per channel; kept per thread, their room reused.
    thread_local std::array<std::vector<double>, 3> values;
    size_t n = 0;
    if (samples.pixels) {
      const int frame = samples.samples[k].frame;
      const PixelGrid& grid = grids[frame];
      grid.for_each_neighbour(samples.samples[k].film, [&](uint32_t m) {
        level += observed[m].cast<double>();
        ++neighbours;
      });
      const auto [i, j] = pixel_of(k);
      for (int reach = kNoiseReach; !noise_free && n < kNoiseValues && reach <= 4 * kNoiseReach; reach *= 2) {
        n = 0;
        // Room for the window and median_near's padding.
        for (auto& v : values) v.resize(size_t(2 * reach + 1) * size_t(2 * reach + 1) + kMedianPadding);
        const int x0 = std::max(i - reach, grid.x0()), x1 = std::min(i + reach, grid.x0() + grid.width() - 1);
        for (int y = std::max(j - reach, grid.y0()); y <= std::min(j + reach, grid.y0() + grid.height() - 1); ++y) {
          const RGBd* row = residual[frame].data() + size_t(y - grid.y0()) * grid.width();
          const bool near_row = std::abs(y - j) <= 1;
          for (int x = x0; x <= x1; ++x) {  // written always, kept where counted (no branch)
            const RGBd& e = row[x - grid.x0()];
            values[0][n] = e[0], values[1][n] = e[1], values[2][n] = e[2];
            n += size_t((!near_row || std::abs(x - i) > 1) && e[0] >= 0.0);
          }
        }
      }
    }
    level = neighbours > 0 ? RGBd(level / neighbours) : observed[k].cast<double>();
    const RGBd floor = (kNoiseFloor * (level.abs() + offset)).square();
    RGBd estimate = floor;
    thread_local RGBd last_median = RGBd::Constant(-1.0);
    if (n > 0)
      for (int c = 0; c < 3; ++c) {
        std::fill_n(values[c].begin() + ptrdiff_t(n), kMedianPadding, NAN);
        const double median = median_near(values[c].data(), n, last_median[c]);
        last_median[c] = median;
        estimate[c] = std::max(median / kMedianOfChiSquare1, floor[c]);
      }
    variance[k] = estimate.cast<float>();
  });
  return variance;
}

}  // namespace glaze
