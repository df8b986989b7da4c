// Helpers every test may use: where the shared real data is, and a skip when it is absent.
#pragma once

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace heslam::test {

inline std::filesystem::path shared_data() { return HESLAM_SHARED_DATA; }
inline std::filesystem::path bin_dir() { return HESLAM_BIN_DIR; }
inline std::filesystem::path source_dir() { return HESLAM_SOURCE_DIR; }

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

// A DDS domain id (1..230) that no other test process on this machine holds. ctest runs tests in
// parallel and a pid-derived id alone can collide; a lock per id, held until this process exits,
// makes the choice exclusive. The same id is returned for every call within one process.
inline int exclusive_domain_id() {
  static const int domain_id = [] {
    constexpr int kFirstDomain = 1;
    constexpr int kDomainCount = 230;  // Cyclone allows up to 232; 0 is left to interactive runs
    const std::filesystem::path lock_dir = std::filesystem::temp_directory_path() / "heslam-test-domains";
    std::filesystem::create_directories(lock_dir);
    const int start = static_cast<int>(getpid() % kDomainCount);
    for (int i = 0; i < kDomainCount; ++i) {
      const int id = kFirstDomain + (start + i) % kDomainCount;
      const auto lock_file = lock_dir / (std::to_string(id) + ".lock");
      const int fd = ::open(lock_file.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0666);
      if (fd < 0) continue;
      if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return id;  // fd stays open: the lock lives with us
      ::close(fd);
    }
    throw std::runtime_error("no free DDS test domain in 1..230 (all locked under " + lock_dir.string() + ")");
  }();
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
#define HESLAM_REQUIRE_SHARED_DATA(name)                                                     \
  do {                                                                                       \
    if (::heslam::test::shared_dataset(name).empty()) {                                      \
      GTEST_SKIP() << "shared data '" << (name) << "' not found under "                      \
                   << ::heslam::test::shared_data() << " (tests on real images are skipped)"; \
    }                                                                                        \
  } while (0)
