#include "renderer/text_file.h"

#include "renderer/error.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>

namespace glaze {
namespace {

std::string system_reason(int error) { return std::strerror(error); }

// GLAZE_FAULT_KILL_AFTER_COMMITS=N: the commit after which the process dies (0: never).
long kill_after_commits() {
  static const long n = [] {
    const char* value = std::getenv("GLAZE_FAULT_KILL_AFTER_COMMITS");
    return value ? std::strtol(value, nullptr, 10) : 0L;
  }();
  return n;
}

void count_commit() {
  static std::atomic<long> commits{0};
  const long limit = kill_after_commits();
  if (limit > 0 && ++commits == limit) std::raise(SIGKILL);
}

// .NAME.glaze-PID-RANDOM.EXT beside `target`: the extension last, so that image writers
// chosen by it still are.
std::filesystem::path temporary_name(const std::filesystem::path& target) {
  thread_local std::mt19937_64 random{std::random_device{}() ^ (uint64_t(std::random_device{}()) << 32)};
  char tag[64];
  std::snprintf(tag, sizeof tag, ".glaze-%ld-%016llx", long(::getpid()), static_cast<unsigned long long>(random()));
  std::string name = ".";
  name.append(target.stem().string()).append(tag).append(target.extension().string());
  return target.parent_path() / name;
}

}  // namespace

TemporaryOutput::TemporaryOutput(const std::filesystem::path& target) : target_(target) {
  if (target.filename().empty()) fail("no file name given");
  const std::filesystem::path folder = target.parent_path().empty() ? "." : target.parent_path();
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(folder, ec);
  if (!std::filesystem::exists(status)) fail("the folder " + folder.string() + " does not exist; create it first");
  if (!std::filesystem::is_directory(status)) fail(folder.string() + " is not a folder");
  if (std::filesystem::is_directory(target, ec)) fail("it is a folder; give a file name");
  for (int attempt = 0; fd_ < 0; ++attempt) {
    path_ = temporary_name(target);
    fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd_ < 0 && (errno != EEXIST || attempt == 16)) fail(system_reason(errno));
  }
}

TemporaryOutput::~TemporaryOutput() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_ && !path_.empty()) ::unlink(path_.c_str());
}

void TemporaryOutput::write(const std::string& text) {
  for (size_t done = 0; done < text.size();) {
    const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail(system_reason(errno));
    done += size_t(n);
  }
}

void TemporaryOutput::commit() {
  // fsync syncs the file, whichever descriptor wrote it; close reports late write errors.
  if (::fsync(fd_) != 0) fail(system_reason(errno));
  const int closed = ::close(fd_);
  fd_ = -1;
  if (closed != 0) fail(system_reason(errno));
  if (::rename(path_.c_str(), target_.c_str()) != 0) fail(system_reason(errno));
  committed_ = true;
  sync_folder(target_.parent_path());
  count_commit();
}

void TemporaryOutput::fail(const std::string& reason) const {
  throw Error(target_.string() + ": could not be written (" + reason + ")");
}

void write_text_atomically(const std::string& path, const std::string& text) {
  TemporaryOutput file(path);
  file.write(text);
  file.commit();
}

void create_output_folder(const std::filesystem::path& path, const std::string& what) {
  if (path.empty()) throw Error("no " + what + " folder given (an empty path)");
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  if (ec && !std::filesystem::is_directory(path))
    throw Error(path.string() + ": cannot create the " + what + " folder (" + ec.message() + ")");
  if (!std::filesystem::is_directory(path, ec))
    throw Error(path.string() + ": cannot be the " + what + " folder: it exists and is not a folder");
}

void sync_folder(const std::filesystem::path& folder) {
  const std::filesystem::path name = folder.empty() ? "." : folder;
  const int fd = ::open(name.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  const bool ok = fd >= 0 && ::fsync(fd) == 0;
  const int error = errno;
  if (fd >= 0) ::close(fd);
  if (!ok) throw Error(name.string() + ": could not be synced to disk (" + system_reason(error) + ")");
}

}  // namespace glaze
