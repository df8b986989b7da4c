// The frontend's journal: every frame it has finished (tracked, published, acknowledged) appended
// to a file, so a frontend killed mid-run and restarted by the supervisor knows where it stopped
// (frames at or below the last seq are acknowledged, not tracked again, even when the replay died too
// and starts again at seq 0) and can publish its odometry again for a recorder that was down when it
// first went out (the frontend's transient-local history died with the old process). A run file
// (runtime/run_journal.hpp) of one odometry record per line.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "runtime/messages.hpp"
#include "runtime/run_journal.hpp"

namespace heslam::frontend {

class OdometryJournal {
 public:
  struct Opened {
    // Of this run, from before a restart, in seq order, the last line of a seq winning (stage times
    // are not kept); empty on a fresh run. Includes a frame published but not finished.
    std::vector<msg::Odometry> frames;
    std::optional<std::uint64_t> last_seq;  // the largest finished seq
    int torn_lines = 0;                     // a torn last line (a kill mid-write) or a line that is no frame, skipped
    int dropped_lines = 0;                  // failing their checksum or out of sequence, never resumed from
    std::string dropped_report;             // one line naming the file and the dropped lines; empty when none
  };

  explicit OdometryJournal(std::filesystem::path path);

  // Reads the frames of run `run_id` if the file is that run's, then keeps the file open for
  // append; a file of another run (or none) is replaced by an empty journal. Throws
  // std::runtime_error naming the file when it cannot be written.
  Opened open_for_run(const std::string& run_id);

  // Appends one frame and flushes it to the kernel: a kill -9 of this process loses nothing written.
  // `finished`: about to be acknowledged (a restart does not track it again). A keyframe's frame is
  // also appended unfinished when published, before the wait for the mapper: killed during that
  // wait, the frame is tracked again, but its odometry still names the keyframe it made, which the
  // mapper may have stored (a recorder restarted meanwhile learns its stamp from it).
  void append(const msg::Odometry& odometry, bool finished);

  // Closes and deletes the journal (a frontend that stopped cleanly: the run is over).
  void remove() { journal_.remove(); }

  const std::filesystem::path& path() const { return journal_.path(); }

 private:
  runtime::RunJournal journal_;
};

}  // namespace heslam::frontend
