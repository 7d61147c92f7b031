// bracket_alignment.h: whether the camera moved between a bracket's exposures.
//
// A bracket is merged pixel by pixel, so it must be shot from a tripod without touching
// the camera. Each exposure is compared with the one before it in linear units (the
// camera response applied, divided by the exposure): over sample pixels well exposed in
// both, the integer shift within kMaxShift pixels that minimises the mean absolute
// difference of log exposure is the camera's motion. Exposure-invariant comparisons
// of the codes themselves failed on the tests' brackets, whose clipping edges move from
// one exposure to the next: OpenCV's AlignMTB (median threshold bitmaps) and
// phaseCorrelate both found shifts of 5 to 60 pixels between aligned exposures.
#pragma once

#include "inverse/photos/bracket.h"
#include "inverse/photos/camera_response.h"

#include <vector>

namespace glaze {

inline constexpr int kMaxShift = 8;

struct ExposureShift {
  int dx = 0, dy = 0;  // pixels the scene moved in this exposure against the bracket's first
};

// One shift per exposure (the first's is zero).
std::vector<ExposureShift> bracket_shifts(const BracketPhotos& photos, const CameraResponse& response);

// Warns, naming the files, when an exposure is shifted against the one before it.
void warn_misaligned(const BracketPhotos& photos, const std::vector<ExposureShift>& shifts);

}  // namespace glaze
