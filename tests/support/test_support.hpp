// Helpers every test may use: where the shared real data is, and a skip when it is absent.
#pragma once

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace heslam::test {

// The build's paths, compiled into one file (test_paths.cpp) so that no other test object depends on
// where the checkout is: a second checkout's build reuses the compiler cache for every test.
std::filesystem::path shared_data();
std::filesystem::path bin_dir();
std::filesystem::path source_dir();

// The folder of a shared data set, e.g. "euroc_mh01_handheld", or empty when it is not there.
inline std::filesystem::path shared_dataset(const std::string& name) {
  const auto dir = shared_data() / name;
  return std::filesystem::exists(dir) ? dir : std::filesystem::path{};
}

// The last non-empty line of a process's output: where heslam's tools say what happened.
inline std::string last_line(const std::string& text) {
  std::string last;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (!line.empty()) last = line;
  }
  return last;
}

// A scratch folder per test process, removed when the test passes (kept for a look when it fails).
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& label)
      : path_(std::filesystem::temp_directory_path() / ("heslam_test_" + label + "_" + std::to_string(getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    if (!::testing::Test::HasFailure()) std::filesystem::remove_all(path_);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// Whether a heslam-supervisor of this host runs on `domain_id` (in any namespace): it holds a
// claim file under $TMPDIR/heslam-domains for its life (runtime/supervisor/domain_check.hpp).
inline bool supervisor_on_domain(int domain_id) {
  std::error_code error;
  const std::string prefix = std::to_string(domain_id) + "-";
  for (const auto& entry :
       std::filesystem::directory_iterator(std::filesystem::temp_directory_path() / "heslam-domains", error)) {
    if (entry.path().filename().string().rfind(prefix, 0) != 0) continue;
    const int fd = ::open(entry.path().c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) continue;
    const bool held = ::flock(fd, LOCK_SH | LOCK_NB) != 0;
    ::close(fd);
    if (held) return true;
  }
  return false;
}

// A DDS domain id in 1..last_id (at most 230), tried from `first` on, reserved for this process: a lock
// on it and on the next id (a pipeline's image domain with image_transport shm) under
// $TMPDIR/heslam-test-domains, held until the process exits, and no supervisor of this host on either (a
// pipeline started by hand without those locks). Throws when every id is taken.
inline int reserve_test_domain(int first, int last_id = 230) {
  constexpr int kFirstDomain = 1;
  const int kDomainCount = std::min(last_id, 230);  // Cyclone allows up to 232; 0 is left to interactive runs
  const std::filesystem::path lock_dir = std::filesystem::temp_directory_path() / "heslam-test-domains";
  std::filesystem::create_directories(lock_dir);
  const auto lock = [&](int id) {
    const auto lock_file = lock_dir / (std::to_string(id) + ".lock");
    const int fd = ::open(lock_file.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0666);
    if (fd >= 0 && ::flock(fd, LOCK_EX | LOCK_NB) == 0) return fd;  // fd stays open: the lock lives with us
    if (fd >= 0) ::close(fd);
    return -1;
  };
  for (int i = 0; i < kDomainCount; ++i) {
    const int id = kFirstDomain + (first + i) % kDomainCount;
    const int fd = lock(id);
    if (fd < 0) continue;
    const int image_fd = lock(id + 1);
    if (image_fd >= 0 && !supervisor_on_domain(id) && !supervisor_on_domain(id + 1)) return id;
    ::close(fd);
    if (image_fd >= 0) ::close(image_fd);
  }
  throw std::runtime_error("no free DDS test domain in 1.." + std::to_string(kDomainCount) + " (all locked under " +
                           lock_dir.string() + " or used by a heslam run)");
}

// This process's test domain (reserve_test_domain from a pid-derived id: ctest runs tests in
// parallel); the same id for every call within one process.
inline int exclusive_domain_id() {
  static const int domain_id = reserve_test_domain(static_cast<int>(getpid() % 230));
  return domain_id;
}

// The frames listed in a recorder's FILE.lost.txt (rows that are not comments); 0 when it is absent.
inline int lost_entries(const std::filesystem::path& lost) {
  std::ifstream in(lost);
  int count = 0;
  for (std::string line; std::getline(in, line);) count += (!line.empty() && line[0] != '#') ? 1 : 0;
  return count;
}

}  // namespace heslam::test

// Skips the current test with a clear message when a shared data set is absent.
#define HESLAM_REQUIRE_SHARED_DATA(name)                                                                 \
  do {                                                                                                   \
    if (::heslam::test::shared_dataset(name).empty()) {                                                  \
      GTEST_SKIP() << "shared data '" << (name) << "' not found under " << ::heslam::test::shared_data() \
                   << " (tests on real images are skipped)";                                             \
    }                                                                                                    \
  } while (0)
