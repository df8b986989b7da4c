// Rendering a heslam-synth sequence from a test: the real renderer process (build/bin), bounded.
#pragma once

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include "child_process.hpp"
#include "test_support.hpp"

namespace heslam::test {

// Renders the first `frames` frames of `preset` (EuRoC layout, 2 threads, without photometric
// events) to `out`; the renderer's output goes to `log_dir`. Empty on success, else why not
// (exit code and the renderer's stderr). The timeout bounds a hung renderer (~8 frame pairs/s on
// 2 loaded cores), it is no performance assertion.
inline std::string render_synth(const std::string& preset, int frames, const std::filesystem::path& out,
                                const std::filesystem::path& log_dir,
                                std::chrono::seconds timeout = std::chrono::seconds(300),
                                const std::string& format = "euroc") {
  ChildProcess synth(bin_dir() / "heslam-synth",
                     {"--preset", preset, "--frames", std::to_string(frames), "--threads", "2", "--no-events",
                      "--format", format, "--out", out.string()},
                     log_dir, "synth_" + preset);
  const int code = synth.wait(timeout).value_or(-1);
  return code == 0 ? std::string{} : "heslam-synth exited " + std::to_string(code) + ": " + synth.err();
}

// The same rendering, done once per build for every test process that asks for it: the sequence is
// kept under build/test-data/PRESET_FRAMES and reused while the heslam-synth binary is unchanged
// (its size and modification time are the key). Concurrent callers wait on a lock file. Sets
// `dataset` to the folder; returns as render_synth. `format` kitti: the KITTI layout
// (build/test-data/PRESET_FRAMES_kitti).
inline std::string cached_synth(const std::string& preset, int frames, std::filesystem::path& dataset,
                                const std::string& format = "euroc") {
  namespace fs = std::filesystem;
  const fs::path root = bin_dir().parent_path() / "test-data";
  fs::create_directories(root);
  const std::string name = preset + "_" + std::to_string(frames) + (format == "euroc" ? "" : "_" + format);
  dataset = root / name;
  const fs::path renderer = bin_dir() / "heslam-synth";
  std::error_code error;
  const std::string key = std::to_string(fs::file_size(renderer, error)) + " " +
                          std::to_string(fs::last_write_time(renderer, error).time_since_epoch().count());
  const fs::path marker = root / (name + ".complete");
  const int fd = ::open((root / (name + ".lock")).c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0666);
  if (fd < 0 || ::flock(fd, LOCK_EX) != 0) return "cannot lock " + (root / (name + ".lock")).string();
  std::string result;
  std::string done;
  std::ifstream marker_in(marker);
  std::getline(marker_in, done);
  if (done != key) {
    fs::remove(marker, error);
    fs::remove_all(dataset, error);
    result = render_synth(preset, frames, dataset, root, std::chrono::seconds(300), format);
    if (result.empty()) std::ofstream(marker) << key << "\n";
  }
  ::close(fd);  // releases the lock
  return result;
}

}  // namespace heslam::test
