// bracket.h: an exposure bracket as a photographer leaves it in a folder (docs/design.md
// §7): every photograph in the folder but the board photo (board.*), all taken from one
// tripod position at different exposures, with each one's exposure from exposures.json
// ({"FILE": seconds}) when the folder has one, else from the photo's EXIF metadata.
#pragma once

#include "renderer/image.h"

#include <filesystem>
#include <string>
#include <vector>

namespace glaze {

struct BracketExposure {
  std::filesystem::path file;
  // Relative exposure: the exposure time in seconds, times ISO and 1 / f-number^2
  // relative to the first photo's when those vary across the bracket.
  double exposure = 0.0;
};

struct Bracket {
  std::filesystem::path folder;
  std::vector<BracketExposure> exposures;  // sorted by exposure, shortest first
  std::string name() const { return folder.filename().string(); }
};

// `text` in ASCII lower case: file names and extensions are matched case-blind.
std::string lowercase(std::string text);

// Whether `file` is a photograph glaze reads by its extension (JPEG, PNG, TIFF, camera raw).
bool is_photo_file(const std::filesystem::path& file);
// Whether `file` is a JPEG by its extension (.jpg, .jpeg).
bool is_jpeg_file(const std::filesystem::path& file);

// The bracket of `folder`. Throws glaze::Error naming the file when a photo's exposure is
// neither in exposures.json nor in its EXIF ExposureTime, when exposures.json is invalid
// or names a file that is not there, and when the folder holds fewer than two exposures.
Bracket find_bracket(const std::filesystem::path& folder);

// The brackets of `folder`: those of its view_*/ and probe_*/ folders when it is a
// shoot, else its own.
std::vector<Bracket> find_brackets(const std::filesystem::path& folder);

// A bracket's photos, decoded (image.h: read_photo_codes), one per exposure.
struct BracketPhotos {
  Bracket bracket;
  std::vector<PhotoCodes> photos;
};

// Decodes every photo of `bracket`. Throws glaze::Error naming the file when the photos
// differ in size, bit depth or encoding.
BracketPhotos read_bracket(const Bracket& bracket);

}  // namespace glaze
