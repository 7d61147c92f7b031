#include "inverse/photos/bracket_alignment.h"

#include "renderer/error.h"
#include "renderer/rng.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace glaze {
namespace {

constexpr int kSamples = 65536;  // pixels compared per pair of exposures

// The shift of `next` against `previous` (photos.photos indices).
ExposureShift pair_shift(const BracketPhotos& photos, size_t previous, size_t next, const std::vector<float>& log_green,
                         const CodeLimits& limits) {
  const PhotoCodes& a = photos.photos[previous];
  const PhotoCodes& b = photos.photos[next];
  const float offset_a = float(std::log(photos.bracket.exposures[previous].exposure));
  const float offset_b = float(std::log(photos.bracket.exposures[next].exposure));
  // Well exposed: not saturated, and green above the toe, whose codes are mostly noise in
  // the darkest exposures (a shortest exposure shows a few highlights in the read noise,
  // and their noise alone picked a shift of several pixels in a still bracket).
  const int toe = limits.low + (limits.high - limits.low) / 16;
  auto usable = [&](const PhotoCodes& photo, size_t pixel) {
    const uint16_t* rgb = &photo.codes[pixel * 3];
    return !limits.saturated(rgb) && rgb[1] > toe;
  };
  // Sample pixels away from the border, well exposed in `previous`.
  std::vector<size_t> pixels;
  Pcg32 rng(0xa11e, next);
  const int width = a.width - 2 * kMaxShift, height = a.height - 2 * kMaxShift;
  if (width <= 0 || height <= 0) return {};
  const int samples = int(std::min<int64_t>(kSamples, int64_t(width) * height));
  for (int k = 0; k < samples; ++k) {
    const size_t pixel = size_t(kMaxShift + rng.next_uint() % height) * a.width + kMaxShift + rng.next_uint() % width;
    if (usable(a, pixel)) pixels.push_back(pixel);
  }
  constexpr int kSide = 2 * kMaxShift + 1;
  std::vector<double> cost(kSide * kSide, std::numeric_limits<double>::infinity());
  tbb::parallel_for(0, kSide * kSide, [&](int s) {
    const int dx = s % kSide - kMaxShift, dy = s / kSide - kMaxShift;
    double sum = 0.0;
    size_t count = 0;
    for (size_t pixel : pixels) {
      const size_t moved = size_t(int64_t(pixel) + int64_t(dy) * a.width + dx);
      if (!usable(b, moved)) continue;
      sum += std::abs((log_green[a.codes[pixel * 3 + 1]] - offset_a) - (log_green[b.codes[moved * 3 + 1]] - offset_b));
      ++count;
    }
    if (count >= pixels.size() / 4 && count >= 100) cost[s] = sum / count;
  });
  // No shift, unless another fits clearly better: a moved camera misaligns every edge, so
  // the right shift takes far more than a tenth off the unshifted cost.
  constexpr double kClearlyBetter = 0.9;
  const int still = kMaxShift * kSide + kMaxShift;
  int best = still;
  for (int s = 0; s < kSide * kSide; ++s)
    if (cost[s] < cost[best]) best = s;
  if (!(cost[best] < kClearlyBetter * cost[still]) && std::isfinite(cost[still])) best = still;
  return {best % kSide - kMaxShift, best / kSide - kMaxShift};
}

}  // namespace

std::vector<ExposureShift> bracket_shifts(const BracketPhotos& photos, const CameraResponse& response) {
  const std::array<std::vector<float>, 3> table = response.linear_table();
  std::vector<float> log_green(table[1].size());
  for (size_t z = 0; z < log_green.size(); ++z) log_green[z] = std::log(std::max(table[1][z], 1e-30f));
  const CodeLimits limits = code_limits(response.bits);
  std::vector<ExposureShift> shifts(photos.photos.size());
  for (size_t j = 1; j < photos.photos.size(); ++j) {
    const ExposureShift shift = pair_shift(photos, j - 1, j, log_green, limits);
    shifts[j] = {shifts[j - 1].dx + shift.dx, shifts[j - 1].dy + shift.dy};
  }
  return shifts;
}

void warn_misaligned(const BracketPhotos& photos, const std::vector<ExposureShift>& shifts) {
  for (size_t j = 1; j < shifts.size(); ++j) {
    const int dx = shifts[j].dx - shifts[j - 1].dx, dy = shifts[j].dy - shifts[j - 1].dy;
    if (dx == 0 && dy == 0) continue;
    warn(photos.bracket.exposures[j].file.string() + " is shifted by (" + std::to_string(dx) + ", " +
         std::to_string(dy) + ") pixels against " + photos.bracket.exposures[j - 1].file.filename().string() +
         (std::abs(dx) == kMaxShift || std::abs(dy) == kMaxShift ? " or more" : "") +
         ": the camera moved during the bracket, and the merge blurs or doubles edges there. Shoot from a tripod "
         "with a remote release (or the self-timer) and without touching the camera");
  }
}

}  // namespace glaze
