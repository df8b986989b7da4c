// Helpers every test may use: where the shared real data is, and a skip when it is absent.
#pragma once

#include <filesystem>
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

}  // namespace heslam::test

// Skips the current test with a clear message when a shared data set is absent.
#define HESLAM_REQUIRE_SHARED_DATA(name)                                                     \
  do {                                                                                       \
    if (::heslam::test::shared_dataset(name).empty()) {                                      \
      GTEST_SKIP() << "shared data '" << (name) << "' not found under "                      \
                   << ::heslam::test::shared_data() << " (tests on real images are skipped)"; \
    }                                                                                        \
  } while (0)
