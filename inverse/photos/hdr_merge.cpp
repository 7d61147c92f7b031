#include "inverse/photos/hdr_merge.h"

#include "renderer/error.h"
#include "renderer/memory_budget.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <cstdio>
#include <iostream>

namespace glaze {
namespace {

struct Counts {
  size_t saturated = 0, underexposed = 0;
};

std::string seconds_text(double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", seconds);
  return text;
}

std::string percent_text(double fraction) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f%%", 100.0 * fraction);
  return text;
}

}  // namespace

HdrMerge merge_bracket(const BracketPhotos& photos, const CameraResponse& response) {
  const PhotoCodes& first = photos.photos.front();
  if (first.bits != response.bits)
    throw Error(photos.bracket.folder.string() + ": the photos are " + std::to_string(first.bits) +
                "-bit, the camera response is for " + std::to_string(response.bits) + "-bit codes");
  const size_t pixels = size_t(first.width) * first.height;
  require_memory(pixels * 16, "merging the bracket " + photos.bracket.folder.string());
  const CodeLimits limits = code_limits(response.bits);
  const std::vector<float> weight = hat_weights(limits);
  const std::array<std::vector<float>, 3> table = response.linear_table();
  const size_t exposures = photos.photos.size();
  std::vector<float> inverse_exposure(exposures), exposure_weight(exposures);
  for (size_t j = 0; j < exposures; ++j) {
    inverse_exposure[j] = float(1.0 / photos.bracket.exposures[j].exposure);
    exposure_weight[j] = float(photos.bracket.exposures[j].exposure / photos.bracket.exposures.back().exposure);
  }

  HdrMerge merge;
  merge.radiance = Image(first.width, first.height);
  merge.alpha.assign(pixels, 1.0f);
  const Counts counts = tbb::parallel_reduce(
      tbb::blocked_range<int>(0, first.height), Counts{},
      [&](const tbb::blocked_range<int>& rows, Counts counts) {
        for (int y = rows.begin(); y < rows.end(); ++y)
          for (size_t p = size_t(y) * first.width; p < size_t(y + 1) * first.width; ++p) {
            float sum[3] = {0, 0, 0}, total[3] = {0, 0, 0};
            int longest = -1;  // the longest exposure with no channel saturated
            for (size_t j = 0; j < exposures; ++j) {
              const uint16_t* rgb = &photos.photos[j].codes[p * 3];
              if (limits.saturated(rgb)) continue;
              longest = int(j);
              for (int c = 0; c < 3; ++c) {
                const float w = weight[rgb[c]] * exposure_weight[j];
                sum[c] += w * table[c][rgb[c]] * inverse_exposure[j];
                total[c] += w;
              }
            }
            float* out = &merge.radiance.pixels[p * 3];
            if (longest < 0) {  // saturated everywhere: the shortest exposure bounds it from below
              const uint16_t* rgb = &photos.photos[0].codes[p * 3];
              for (int c = 0; c < 3; ++c) out[c] = table[c][rgb[c]] * inverse_exposure[0];
              merge.alpha[p] = 0.0f;
              ++counts.saturated;
              continue;
            }
            // A channel dark in every exposure: the longest unsaturated exposure's value,
            // the best there is (noisy, and counted when the whole pixel is dark).
            const uint16_t* rgb = &photos.photos[longest].codes[p * 3];
            for (int c = 0; c < 3; ++c)
              out[c] = total[c] > 0.0f ? sum[c] / total[c] : table[c][rgb[c]] * inverse_exposure[longest];
            counts.underexposed += total[0] == 0.0f && total[1] == 0.0f && total[2] == 0.0f;
          }
        return counts;
      },
      [](Counts a, const Counts& b) {
        a.saturated += b.saturated, a.underexposed += b.underexposed;
        return a;
      });
  merge.saturated = counts.saturated;
  merge.underexposed = counts.underexposed;
  return merge;
}

void warn_coverage(const Bracket& bracket, const HdrMerge& merge) {
  const BracketExposure& shortest = bracket.exposures.front();
  const BracketExposure& longest = bracket.exposures.back();
  if (merge.saturated_fraction() > kCoverageWarningFraction)
    warn(bracket.folder.string() + ": " + percent_text(merge.saturated_fraction()) +
         " of the pixels are saturated in every exposure, even the shortest (" + shortest.file.filename().string() +
         ", " + seconds_text(shortest.exposure) + " s): the bracket is too short for the highlights. Add an exposure " +
         "at least 2 stops shorter (" + seconds_text(shortest.exposure / 4) +
         " s or less); these pixels have alpha 0 and hold a lower bound");
  if (merge.underexposed_fraction() > kCoverageWarningFraction)
    warn(bracket.folder.string() + ": " + percent_text(merge.underexposed_fraction()) +
         " of the pixels are underexposed in every exposure, even the longest (" + longest.file.filename().string() +
         ", " + seconds_text(longest.exposure) + " s): the bracket is too short for the shadows. Add an exposure " +
         "at least 2 stops longer (" + seconds_text(longest.exposure * 4) + " s or more)");
}

namespace {

// JPEG codes a photo's colour as luma and two chroma planes, quantised in 8 x 8 blocks
// and the chroma (usually) at half resolution, so a channel's code is no longer the tone
// curve of that channel's exposure alone: on simulated shoots the recovered response,
// the ball's reflectance and a saturated colour's Rd came out several times as far off
// as from PNGs (docs/notes/photo-shoots.md, "JPEG photos"). Said once, for the first
// JPEG bracket.
void warn_jpeg(std::span<const Bracket> brackets) {
  for (const Bracket& bracket : brackets)
    for (const BracketExposure& exposure : bracket.exposures) {
      if (!is_jpeg_file(exposure.file)) continue;
      warn(bracket.folder.string() + ": holds JPEG photos (" + exposure.file.filename().string() +
           "); JPEG's compression mixes the colour channels, so the merged radiance (and the camera response " +
           "recovered from it) is less accurate than from raw, 16-bit TIFF or PNG photos; shoot those where the " +
           "camera can");
      return;
    }
}

}  // namespace

CameraResponse bracket_response(std::span<const Bracket> brackets, const std::optional<std::string>& response_file) {
  warn_jpeg(brackets);
  if (response_file) return read_response(*response_file);
  std::vector<ResponseSamples> samples;
  for (const Bracket& bracket : brackets) {
    std::cerr << "reading " << bracket.folder.string() << " (" << bracket.exposures.size() << " exposures, "
              << bracket.exposures.front().exposure << " to " << bracket.exposures.back().exposure << " s)\n";
    const BracketPhotos photos = read_bracket(bracket);
    const PhotoCodes& photo = photos.photos.front();
    if (!photo.linear) {
      samples.push_back(sample_bracket(photos));
      continue;
    }
    if (!samples.empty())
      throw Error(bracket.folder.string() + ": holds linear " + std::to_string(photo.bits) +
                  "-bit photos, the brackets before it 8-bit ones; merge them separately");
    return linear_response(photo.bits);  // merge_bracket refuses a bracket stored otherwise
  }
  const CameraResponse response = recover_response(samples);
  std::cerr << "camera response recovered (Debevec and Malik) from " << response.samples << " sample pixels of "
            << samples.size() << " bracket(s); well constrained from code " << response.well_constrained[1][0] << " to "
            << response.well_constrained[1][1] << " (green)\n";
  return response;
}

MergedBracket read_and_merge(const Bracket& bracket, const CameraResponse& response) {
  const BracketPhotos photos = read_bracket(bracket);
  MergedBracket merged;
  merged.shifts = bracket_shifts(photos, response);
  warn_misaligned(photos, merged.shifts);
  merged.merge = merge_bracket(photos, response);
  warn_coverage(bracket, merged.merge);
  return merged;
}

}  // namespace glaze
