// The recorder's journal: every recorded frame appended to a file as it arrives, so a recorder
// killed mid-run and restarted by the supervisor resumes with every frame it had (the trajectory
// is otherwise held in memory until the end of the run).
#pragma once

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "tools/recorder/trajectory_recorder.hpp"

namespace heslam::recorder {

class FrameJournal {
 public:
  struct Opened {
    std::vector<RecordedFrame> frames;  // of this run, from before a restart; empty on a fresh run
    int torn_lines = 0;                 // unreadable lines (a kill mid-write), skipped
  };

  explicit FrameJournal(std::filesystem::path path) : path_(std::move(path)) {}

  // Reads the frames of run `run_id` if the file is that run's, then keeps the file open for
  // append; a file of another run (or none) is replaced by an empty journal. Throws
  // std::runtime_error naming the file when it cannot be written.
  Opened open_for_run(const std::string& run_id);

  // Appends one frame and flushes it to the kernel: a kill -9 of this process loses nothing written.
  void append(const RecordedFrame& frame);

  // Closes and deletes the journal (after the outputs are written).
  void remove();

  const std::filesystem::path& path() const { return path_; }

 private:
  struct Close {
    void operator()(std::FILE* file) const { std::fclose(file); }
  };
  std::filesystem::path path_;
  std::unique_ptr<std::FILE, Close> file_;
};

}  // namespace heslam::recorder
