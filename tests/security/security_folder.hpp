// The DDS Security material of a test: `heslam-security init DIR` (build/bin), bounded.
#pragma once

#include <chrono>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "test_support.hpp"

namespace heslam::test {

// Runs heslam-security init `dir` [options] (its output in log_dir); returns dir, throws with its
// stderr on failure.
inline std::filesystem::path make_security_folder(const std::filesystem::path& dir,
                                                  const std::filesystem::path& log_dir,
                                                  const std::vector<std::string>& options = {}) {
  std::vector<std::string> args{"init", dir.string()};
  args.insert(args.end(), options.begin(), options.end());
  ChildProcess init(bin_dir() / "heslam-security", args, log_dir, "security_init_" + dir.filename().string());
  // openssl makes 2 CAs and 8 identities in about a second; the bound is for a hung machine.
  const int code = init.wait(std::chrono::seconds(120)).value_or(-1);
  if (code != 0) throw std::runtime_error("heslam-security init exited " + std::to_string(code) + ": " + init.err());
  return dir;
}

}  // namespace heslam::test
