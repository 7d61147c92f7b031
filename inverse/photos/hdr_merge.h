// hdr_merge.h: a bracket merged into one linear HDR image.
//
// Each exposure j of a pixel gives, per channel, f^-1(Z_j) / t_j (camera_response.h); the
// merge is their mean weighted by t_j times the hat weight of Z_j: under shot noise the
// variance of f^-1(Z_j) / t_j falls as 1 / t_j (on the tests' brackets this takes the
// median error from 1.5% to 1.2% at 20000 electrons full well). An exposure in which any channel
// of the pixel is saturated is left out whole (a camera's colour processing spreads a
// clipped channel into the others), and codes near black weigh nothing. A pixel
// saturated in every exposure keeps its shortest exposure's value, a lower bound, with
// alpha 0 so that the fits leave it out; every other pixel has alpha 1. Rows merge in
// parallel, each pixel on its own: the result does not depend on the thread count.
#pragma once

#include "inverse/photos/bracket.h"
#include "inverse/photos/bracket_alignment.h"
#include "inverse/photos/camera_response.h"
#include "renderer/image.h"

#include <optional>
#include <span>
#include <string>
#include <vector>

namespace glaze {

struct HdrMerge {
  Image radiance;            // relative exposure per second: f^-1(code) / exposure
  std::vector<float> alpha;  // 0: saturated in every exposure, 1: measured
  size_t saturated = 0;      // pixels saturated in every exposure
  size_t underexposed = 0;   // pixels with no channel above the underexposed codes in any exposure
  double saturated_fraction() const { return double(saturated) / alpha.size(); }
  double underexposed_fraction() const { return double(underexposed) / alpha.size(); }
};

HdrMerge merge_bracket(const BracketPhotos& photos, const CameraResponse& response);

// Fractions of pixels above which warn_coverage says the bracket is too short.
inline constexpr double kCoverageWarningFraction = 0.001;

// Warns when more than kCoverageWarningFraction of the pixels are saturated in every
// exposure, or underexposed in every exposure, saying how many and which exposure to add.
void warn_coverage(const Bracket& bracket, const HdrMerge& merge);

// The response that merges `brackets`: read from `response_file` when given; linear for
// 16-bit and raw photos; else recovered (Debevec and Malik) from samples of every bracket
// at once, so that all of a shoot's HDR images share one curve and one unit. Reports on
// stderr what it reads. Throws glaze::Error for brackets that mix 8-bit and linear photos.
CameraResponse bracket_response(std::span<const Bracket> brackets, const std::optional<std::string>& response_file);

struct MergedBracket {
  HdrMerge merge;
  std::vector<ExposureShift> shifts;  // each exposure's offset from the first (bracket_alignment.h)
};

// Reads `bracket`, warns when the camera moved between its exposures or when it is too
// short at either end (warn_coverage), and merges it with `response`.
MergedBracket read_and_merge(const Bracket& bracket, const CameraResponse& response);

}  // namespace glaze
