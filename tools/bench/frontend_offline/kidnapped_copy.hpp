// A "kidnapped camera" copy of an EuRoC folder for relocalization tests and benchmarks: some frames
// replaced by black images (the camera sees nothing), the frames after them by the clip's own earlier
// frames played again under the later stamps (the camera reappears at a place it saw before; time
// stays monotonic). Images are symlinks to the source, black images are written once per camera.
#pragma once

#include <filesystem>

namespace heslam::bench {

struct KidnapPlan {
  int black_first = 60;   // frames [black_first, replay_first) become black
  int replay_first = 80;  // frames [replay_first, end) show the source's frames from replay_source on
  int replay_source = 0;
};

// Writes DEST/mav0/cam{0,1}/{data.csv,data/,sensor.yaml} and body.yaml (no ground truth: at the
// replayed stamps it would be wrong). Throws std::runtime_error naming the file on a bad source or
// an unwritable destination. Returns the number of frames written.
int write_kidnapped_copy(const std::filesystem::path& source_dataset, const std::filesystem::path& dest_dataset,
                         const KidnapPlan& plan = {});

}  // namespace heslam::bench
