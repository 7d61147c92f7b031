#include "renderer/output_folder.h"

#include "renderer/error.h"
#include "renderer/text_file.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>

namespace glaze {
namespace {

constexpr const char* kLock = ".glaze-lock";

std::string random_run_id() {
  std::random_device device;
  std::string id;
  for (int i = 0; i < 4; ++i) {
    char word[9];
    std::snprintf(word, sizeof word, "%08x", unsigned(device()));
    id += word;
  }
  return id;
}

std::string file_text(const std::filesystem::path& file) {
  std::ifstream stream(file);
  std::ostringstream text;
  text << stream.rdbuf();
  return text.str();
}

}  // namespace

OutputFolder::OutputFolder(const std::filesystem::path& folder, const std::string& final_file, const std::string& what)
    : folder_(folder), final_file_(final_file), run_(random_run_id()) {
  create_output_folder(folder, what);
  const std::filesystem::path lock_file = folder / kLock;
  lock_ = ::open(lock_file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (lock_ < 0)
    throw Error(lock_file.string() + ": cannot be created (" + std::strerror(errno) + "); is " + folder.string() +
                " writable?");
  if (::flock(lock_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    ::close(lock_);
    lock_ = -1;
    if (error != EWOULDBLOCK) throw Error(lock_file.string() + ": cannot be locked (" + std::strerror(error) + ")");
    std::string pid = file_text(lock_file);
    while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
    throw Error(folder.string() + " is being written by another glaze run (pid " + (pid.empty() ? "unknown" : pid) +
                "); wait for it to end, or give another folder");
  }
  // Who holds the lock, for the message above.
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(lock_, 0) != 0 || ::pwrite(lock_, pid.data(), pid.size(), 0) != ssize_t(pid.size())) {
    const int error = errno;
    ::close(lock_);
    throw Error(lock_file.string() + ": cannot be written (" + std::strerror(error) + ")");
  }
}

void OutputFolder::mark_incomplete() {
  if (marked_) return;
  marked_ = true;
  // The marker first, then the old final file goes: at no moment does the folder look
  // whole while old and new files mix.
  const auto now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  char time[64];
  std::strftime(time, sizeof time, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  write_text_atomically(file(kIncompleteMarker).string(), "run " + run_ + " (pid " + std::to_string(::getpid()) +
                                                              ") started " + time + " and has not finished\n");
  std::error_code ec;
  std::filesystem::remove(file(final_file_), ec);
  if (ec) throw Error(file(final_file_).string() + ": cannot be removed (" + ec.message() + ")");
  sync_folder(folder_);
}

OutputFolder::~OutputFolder() {
  if (lock_ >= 0) ::close(lock_);
}

void OutputFolder::tag(std::map<std::string, std::string>& metadata) {
  mark_incomplete();
  metadata["glaze:run"] = run_;
}

std::string OutputFolder::write_image(const std::string& name, const Image& image,
                                      std::map<std::string, std::string> metadata, std::span<const float> alpha) {
  const std::string path = file(name).string();
  tag(metadata);
  glaze::write_image(path, image, metadata, alpha);
  return path;
}

std::string OutputFolder::write_text(const std::string& name, const std::string& text) {
  mark_incomplete();
  const std::string path = file(name).string();
  write_text_atomically(path, text);
  return path;
}

void OutputFolder::finish(const std::string& text) {
  mark_incomplete();
  write_text_atomically(file(final_file_).string(), text);
  std::error_code ec;
  std::filesystem::remove(file(kIncompleteMarker), ec);
  if (ec) throw Error(file(kIncompleteMarker).string() + ": cannot be removed (" + ec.message() + ")");
  sync_folder(folder_);
}

bool interrupted_run(const std::filesystem::path& folder) {
  std::error_code ec;
  return std::filesystem::exists(folder / kIncompleteMarker, ec);
}

}  // namespace glaze
