// The recorder's journal: every recorded frame appended to a file as it arrives, so a recorder
// killed mid-run and restarted by the supervisor resumes with every frame it had (the trajectory
// is otherwise held in memory until the end of the run). A run file (runtime/run_journal.hpp) of one
// frame record per line.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "runtime/run_journal.hpp"
#include "tools/recorder/trajectory_recorder.hpp"

namespace heslam::recorder {

class FrameJournal {
 public:
  struct Opened {
    std::vector<RecordedFrame> frames;  // of this run, from before a restart; empty on a fresh run
    int torn_lines = 0;                 // a torn last line (a kill mid-write) or a line that is no frame, skipped
    int dropped_lines = 0;              // failing their checksum or out of sequence, never resumed from
    std::string dropped_report;         // one line naming the file and the dropped lines; empty when none
  };

  explicit FrameJournal(std::filesystem::path path);

  // Reads the frames of run `run_id` if the file is that run's, then keeps the file open for
  // append; a file of another run (or none) is replaced by an empty journal. Throws
  // std::runtime_error naming the file when it cannot be written.
  Opened open_for_run(const std::string& run_id);

  // Appends one frame and flushes it to the kernel: a kill -9 of this process loses nothing written.
  void append(const RecordedFrame& frame);

  // Closes and deletes the journal (after the outputs are written).
  void remove() { journal_.remove(); }

  const std::filesystem::path& path() const { return journal_.path(); }

 private:
  runtime::RunJournal journal_;
};

}  // namespace heslam::recorder
