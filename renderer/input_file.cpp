#include "renderer/input_file.h"

#include "renderer/error.h"
#include "renderer/memory_budget.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace glaze {
namespace {

// Closes the descriptor on every way out.
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileDescriptor(FileDescriptor&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a file";
}

// Opens without blocking (O_NONBLOCK: a FIFO without a writer would block open() itself)
// and checks the kind on the descriptor, so that nothing can swap the file in between.
FileDescriptor open_regular(const std::string& path, const std::string& what, uint64_t* size) {
  FileDescriptor file(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
  if (file.get() < 0) {
    const int error = errno;
    if (error == ENOENT) throw Error(path + ": " + what + " not found (no such file)");
    throw Error(path + ": " + what + " cannot be opened (" + std::strerror(error) + ")");
  }
  struct stat status {};
  if (::fstat(file.get(), &status) != 0)
    throw Error(path + ": " + what + " cannot be read (" + std::strerror(errno) + ")");
  if (!S_ISREG(status.st_mode))
    throw Error(path + ": " + what + " is " + kind_of(status.st_mode) + ", not a regular file; give a file");
  *size = uint64_t(status.st_size);
  return file;
}

}  // namespace

uint64_t require_regular_file(const std::string& path, const std::string& what) {
  uint64_t size = 0;
  open_regular(path, what, &size);
  return size;
}

std::string read_whole_file(const std::string& path, const std::string& what) {
  uint64_t size = 0;
  const FileDescriptor file = open_regular(path, what, &size);
  require_memory(size, "reading " + path);
  std::string bytes(size, '\0');
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t got = ::read(file.get(), bytes.data() + done, bytes.size() - done);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw Error(path + ": " + what + " cannot be read (" + std::strerror(errno) + ")");
    if (got == 0) break;  // the file shrank while being read: take what is there
    done += size_t(got);
  }
  bytes.resize(done);
  return bytes;
}

}  // namespace glaze
