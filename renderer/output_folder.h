// output_folder.h: a folder that one glaze run fills with many files and then one final
// file that says the set is whole (a capture set's transforms.json, a fit's fit.json).
//
// The run locks the folder when it starts: .glaze-lock is locked (flock) for as long as
// the run lives, so a second run into the folder stops with an error instead of mixing
// its files in (the kernel drops the lock when the process dies, even by kill -9; the
// file stays). Before its first file, the run writes the marker .glaze-incomplete and
// removes the old final file; after the final file, it removes the marker. Every image
// the run writes carries its run id (metadata "glaze:run"), and so does the final file
// ("run"), so a reader can tell files of one run from those of another. A run that dies
// leaves the marker and no final file: readers refuse such a folder (capture_set.h). A
// run that fails before writing anything leaves the folder as it was.
#pragma once

#include "renderer/image.h"

#include <filesystem>
#include <map>
#include <span>
#include <string>

namespace glaze {

inline constexpr const char* kIncompleteMarker = ".glaze-incomplete";

class OutputFolder {
 public:
  // Creates `folder` if needed and locks it; `final_file` is the file finish() writes.
  // `what` names the folder in messages ("capture set", "fit output"). Throws
  // glaze::Error when another run holds the folder, or it cannot be written.
  OutputFolder(const std::filesystem::path& folder, const std::string& final_file, const std::string& what);
  ~OutputFolder();  // releases the lock (the marker stays unless finish() ran)
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  const std::filesystem::path& path() const { return folder_; }
  std::filesystem::path file(const std::string& name) const { return folder_ / name; }
  // 128 random bits, in hex.
  const std::string& run() const { return run_; }

  // Adds the run id to the metadata of an image about to be written into the folder
  // (which is then marked incomplete, if it was not yet).
  void tag(std::map<std::string, std::string>& metadata);
  // write_image (image.h) into the folder, tagged. Returns the file's path.
  std::string write_image(const std::string& name, const Image& image, std::map<std::string, std::string> metadata = {},
                          std::span<const float> alpha = {});
  // write_text_atomically (text_file.h) into the folder. Returns the file's path.
  std::string write_text(const std::string& name, const std::string& text);
  // Writes the final file (`text`, which should carry run()), then removes the marker.
  void finish(const std::string& text);

 private:
  std::filesystem::path folder_;
  std::string final_file_;
  std::string run_;
  int lock_ = -1;
  bool marked_ = false;  // incomplete: the marker is written and the old final file gone

  void mark_incomplete();
};

// Whether `folder` holds the marker of a run that did not finish.
bool interrupted_run(const std::filesystem::path& folder);

}  // namespace glaze
