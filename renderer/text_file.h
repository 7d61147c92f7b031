// text_file.h: output files written whole or not at all. Every file glaze writes goes
// first to a hidden temporary file beside its target, with a name no other run can pick
// (.NAME.glaze-PID-RANDOM.EXT), and is renamed over the target only once it is complete
// and on disk (fsync of the file, then of the folder). A run that dies leaves at worst
// such a temporary file; the target is either the old file or the new one. image.h
// writes images through the same TemporaryOutput.
#pragma once

#include <filesystem>
#include <string>

namespace glaze {

// A hidden temporary file beside `target`, created (O_EXCL) when constructed and renamed
// over `target` by commit(). Deleted by the destructor unless committed. Errors throw
// glaze::Error "TARGET: could not be written (REASON)" with the system's reason.
//
// For tests: GLAZE_FAULT_KILL_AFTER_COMMITS=N kills the process (SIGKILL) right after
// its N-th commit (every file counts, output_folder.h's marker too), as a crash or
// `kill -9` would at that point.
class TemporaryOutput {
 public:
  explicit TemporaryOutput(const std::filesystem::path& target);
  ~TemporaryOutput();
  TemporaryOutput(const TemporaryOutput&) = delete;
  TemporaryOutput& operator=(const TemporaryOutput&) = delete;

  // The temporary file: writers may open and rewrite it by name (OpenImageIO does).
  const std::filesystem::path& path() const { return path_; }
  // Writes `text` at the file's current end.
  void write(const std::string& text);
  // Syncs the file, renames it over the target and syncs the folder.
  void commit();
  // Throws "TARGET: could not be written (REASON)".
  [[noreturn]] void fail(const std::string& reason) const;

 private:
  std::filesystem::path target_, path_;
  int fd_ = -1;
  bool committed_ = false;
};

// Writes `text` to `path` atomically. Throws glaze::Error naming the file on failure.
void write_text_atomically(const std::string& path, const std::string& text);

// Creates the folder `path` and its parents unless they exist; `what` says what it is
// for ("output", "capture set"). Throws glaze::Error naming the path and the reason, also
// when it exists as something other than a folder.
void create_output_folder(const std::filesystem::path& path, const std::string& what);

// Makes the entries of `folder` (a rename, a new or removed file) durable. Throws
// glaze::Error naming it.
void sync_folder(const std::filesystem::path& folder);

}  // namespace glaze
