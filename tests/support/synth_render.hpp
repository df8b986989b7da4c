// Rendering a heslam-synth sequence from a test: the real renderer process (build/bin), bounded.
#pragma once

#include <chrono>
#include <filesystem>
#include <string>

#include "child_process.hpp"
#include "test_support.hpp"

namespace heslam::test {

// Renders the first `frames` frames of `preset` (EuRoC layout, 2 threads, without photometric
// events) to `out`; the renderer's output goes to `log_dir`. Empty on success, else why not
// (exit code and the renderer's stderr). The timeout bounds a hung renderer (~8 frame pairs/s on
// 2 loaded cores), it is no performance assertion.
inline std::string render_synth(const std::string& preset, int frames, const std::filesystem::path& out,
                                const std::filesystem::path& log_dir,
                                std::chrono::seconds timeout = std::chrono::seconds(300)) {
  ChildProcess synth(bin_dir() / "heslam-synth",
                     {"--preset", preset, "--frames", std::to_string(frames), "--threads", "2", "--no-events", "--out",
                      out.string()},
                     log_dir, "synth_" + preset);
  const int code = synth.wait(timeout).value_or(-1);
  return code == 0 ? std::string{} : "heslam-synth exited " + std::to_string(code) + ": " + synth.err();
}

}  // namespace heslam::test
