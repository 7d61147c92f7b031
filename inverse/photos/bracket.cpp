#include "inverse/photos/bracket.h"

#include "renderer/error.h"
#include "renderer/json_input.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <optional>
#include <set>

namespace glaze {
namespace {

namespace fs = std::filesystem;

// The first of `keys` that the photo's metadata has.
std::optional<double> first_attribute(const fs::path& file, std::initializer_list<const char*> keys) {
  for (const char* key : keys)
    if (const std::optional<double> value = photo_number_attribute(file.string(), key)) return value;
  return std::nullopt;
}

// exposures.json: {"FILE": seconds, ...}, every value a positive number.
std::map<std::string, double> read_exposures_json(const fs::path& path) {
  const nlohmann::json json = read_json_file(path.string(), "exposures");
  if (!json.is_object())
    throw Error(path.string() + ": expected an object {\"FILE\": seconds, ...}, found " + json_excerpt(json));
  std::map<std::string, double> exposures;
  for (const auto& [file, seconds] : json.items()) {
    if (!seconds.is_number() || !(seconds.get<double>() > 0.0) || !std::isfinite(seconds.get<double>()))
      throw Error(path.string() + ": the exposure of \"" + file + "\" is " + json_excerpt(seconds) +
                  "; expected a positive number of seconds");
    exposures[file] = seconds.get<double>();
  }
  return exposures;
}

// From EXIF: ExposureTime, times ISO and 1 / FNumber^2 (relative to the first photo's)
// where those vary across the bracket; a photo that lacks one that varies is an error.
void exposures_from_exif(std::vector<BracketExposure>& photos, const fs::path& folder) {
  std::vector<std::optional<double>> iso, f_number;
  for (BracketExposure& photo : photos) {
    const std::optional<double> seconds = first_attribute(photo.file, {"ExposureTime", "Exif:ExposureTime"});
    if (!seconds || !(*seconds > 0.0))
      throw Error(photo.file.string() + ": has no EXIF ExposureTime and the folder has no exposures.json; write " +
                  (folder / "exposures.json").string() + " as {\"" + photo.file.filename().string() +
                  "\": seconds, ...} for every photo of the bracket");
    photo.exposure = *seconds;
    iso.push_back(first_attribute(photo.file, {"Exif:PhotographicSensitivity", "Exif:ISOSpeedRatings", "ISO"}));
    f_number.push_back(first_attribute(photo.file, {"FNumber", "Exif:FNumber"}));
  }
  auto apply = [&](const std::vector<std::optional<double>>& values, const char* what, auto factor) {
    std::set<double> distinct;
    for (const auto& value : values)
      if (value) distinct.insert(*value);
    if (distinct.size() < 2) return;  // constant (or absent): the exposure time alone orders the bracket
    for (size_t i = 0; i < photos.size(); ++i) {
      if (!values[i] || !(*values[i] > 0.0))
        throw Error(photos[i].file.string() + ": has no EXIF " + what + " although it varies across the bracket in " +
                    folder.string() + "; give the exposures in exposures.json instead");
      photos[i].exposure *= factor(*values[i], *values[0]);
    }
  };
  apply(iso, "ISO", [](double value, double first) { return value / first; });
  apply(f_number, "FNumber", [](double value, double first) { return (first * first) / (value * value); });
}

}  // namespace

std::string lowercase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return text;
}

bool is_photo_file(const fs::path& file) {
  static const std::set<std::string> kExtensions = {".jpg", ".jpeg", ".png", ".tif", ".tiff", ".dng", ".cr2",
                                                    ".cr3", ".nef",  ".nrw", ".arw", ".orf",  ".rw2", ".raf",
                                                    ".pef", ".srw",  ".x3f", ".3fr", ".iiq",  ".erf"};
  return kExtensions.count(lowercase(file.extension().string())) > 0;
}

bool is_jpeg_file(const fs::path& file) {
  const std::string extension = lowercase(file.extension().string());
  return extension == ".jpg" || extension == ".jpeg";
}

Bracket find_bracket(const fs::path& folder) {
  if (!fs::is_directory(folder)) throw Error(folder.string() + ": is not a folder (a bracket is a folder of photos)");
  Bracket bracket{folder, {}};
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file() || name.starts_with(".") || !is_photo_file(entry.path())) continue;
    if (lowercase(entry.path().stem().string()) == "board") continue;  // the registration photo
    bracket.exposures.push_back({entry.path(), 0.0});
  }
  std::sort(bracket.exposures.begin(), bracket.exposures.end(),
            [](const BracketExposure& a, const BracketExposure& b) { return a.file < b.file; });
  if (bracket.exposures.size() < 2)
    throw Error(folder.string() + ": holds " + std::to_string(bracket.exposures.size()) +
                " exposure(s); a bracket needs at least two photos of the same view at different exposures "
                "(JPEG, PNG, TIFF or camera raw; board.* is the registration photo and does not count)");

  const fs::path json_path = folder / "exposures.json";
  if (fs::exists(json_path)) {
    std::map<std::string, double> seconds = read_exposures_json(json_path);
    for (BracketExposure& photo : bracket.exposures) {
      const auto found = seconds.find(photo.file.filename().string());
      if (found == seconds.end())
        throw Error(json_path.string() + ": has no exposure for " + photo.file.filename().string() + "; add \"" +
                    photo.file.filename().string() + "\": seconds");
      photo.exposure = found->second;
      seconds.erase(found);
    }
    if (!seconds.empty())
      throw Error(json_path.string() + ": names \"" + seconds.begin()->first +
                  "\", which is not a photo of the bracket in " + folder.string());
  } else {
    exposures_from_exif(bracket.exposures, folder);
  }
  std::stable_sort(bracket.exposures.begin(), bracket.exposures.end(),
                   [](const BracketExposure& a, const BracketExposure& b) { return a.exposure < b.exposure; });
  return bracket;
}

std::vector<Bracket> find_brackets(const fs::path& folder) {
  if (!fs::is_directory(folder)) throw Error(folder.string() + ": is not a folder (a shoot or a bracket)");
  std::vector<fs::path> views;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_directory() && (name.starts_with("view_") || name.starts_with("probe_")))
      views.push_back(entry.path());
  }
  if (views.empty()) return {find_bracket(folder)};
  std::sort(views.begin(), views.end());
  std::vector<Bracket> brackets;
  for (const fs::path& view : views) brackets.push_back(find_bracket(view));
  return brackets;
}

BracketPhotos read_bracket(const Bracket& bracket) {
  BracketPhotos result{bracket, {}};
  for (const BracketExposure& exposure : bracket.exposures) {
    PhotoCodes photo = read_photo_codes(exposure.file.string());
    if (!result.photos.empty()) {
      const PhotoCodes& first = result.photos.front();
      const std::string first_name = bracket.exposures.front().file.string();
      if (photo.width != first.width || photo.height != first.height)
        throw Error(exposure.file.string() + ": is " + std::to_string(photo.width) + "x" +
                    std::to_string(photo.height) + ", " + first_name + " is " + std::to_string(first.width) + "x" +
                    std::to_string(first.height) + "; a bracket's photos must be the same size (same camera, no crop)");
      if (photo.bits != first.bits || photo.linear != first.linear)
        throw Error(exposure.file.string() + ": is " + std::to_string(photo.bits) + "-bit" +
                    (photo.linear ? " linear" : "") + ", " + first_name + " is " + std::to_string(first.bits) + "-bit" +
                    (first.linear ? " linear" : "") + "; a bracket's photos must be stored alike");
    }
    result.photos.push_back(std::move(photo));
  }
  return result;
}

}  // namespace glaze
