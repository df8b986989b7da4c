// replace_file: write a temporary file beside the target, optionally fsync it, rename it over.
#include "runtime/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>
#include <system_error>

namespace heslam::runtime {
namespace {

// Closes a POSIX file descriptor when it goes out of scope.
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

std::runtime_error system_error(const std::filesystem::path& file, const std::string& what) {
  return std::runtime_error(file.string() + ": " + what + ": " + std::strerror(errno));
}

void sync_path(const std::filesystem::path& path, int flags) {
  const FileDescriptor fd(::open(path.c_str(), flags | O_CLOEXEC));
  if (fd.get() < 0 || ::fsync(fd.get()) != 0) throw system_error(path, "cannot fsync");
}

}  // namespace

std::filesystem::path replacement_temp_path(const std::filesystem::path& path) {
  std::filesystem::path temp = path;
  temp += ".tmp";
  return temp;
}

void replace_file(const std::filesystem::path& path,
                  const std::function<void(const std::filesystem::path& temp)>& write, bool sync) {
  const std::filesystem::path temp = replacement_temp_path(path);
  try {
    write(temp);
    if (sync) sync_path(temp, O_RDONLY);
    std::filesystem::rename(temp, path);
  } catch (const std::exception& failure) {
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    throw std::runtime_error(path.string() + ": cannot replace the file (" + failure.what() + ")");
  }
  // The rename is durable only once the folder's entry is: after it, so a failure here leaves the
  // new file in place (it is complete) and only reports that it may not survive a power loss.
  if (sync) sync_path(path.has_parent_path() ? path.parent_path() : ".", O_RDONLY | O_DIRECTORY);
}

void replace_file_contents(const std::filesystem::path& path, std::string_view bytes, bool sync) {
  replace_file(
      path,
      [&](const std::filesystem::path& temp) {
        const FileDescriptor fd(::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
        if (fd.get() < 0) throw system_error(temp, "cannot create");
        for (std::size_t written = 0; written < bytes.size();) {
          const ssize_t n = ::write(fd.get(), bytes.data() + written, bytes.size() - written);
          if (n < 0 && errno == EINTR) continue;
          if (n <= 0) throw system_error(temp, "write failed");
          written += static_cast<std::size_t>(n);
        }
      },
      sync);
}

}  // namespace heslam::runtime
