// A "kidnapped camera" copy of an EuRoC folder for relocalization tests and benchmarks: some frames
// replaced by black images (the camera sees nothing), the frames after them by the clip's own earlier
// frames played again under later stamps (the camera reappears at a place it saw before; time stays
// monotonic). With no black frames it is a teleport: the image jumps from one frame to the next, as
// if the camera were carried to an earlier place between two shots. Images are symlinks to the
// source, black images are written once per camera.
#pragma once

#include <filesystem>

namespace heslam::bench {

struct KidnapPlan {
  int black_first = 60;   // frames [black_first, replay_first) become black (none when equal)
  int replay_first = 80;  // frames [replay_first, ...) show the source's frames from replay_source on
  int replay_source = 0;
  // How many frames are replayed; -1: up to the end of the source's frames. Stamps past the source's
  // last one continue at its mean frame period, so the copy may be longer than the source.
  int replay_frames = -1;
};

// Writes DEST/mav0/cam{0,1}/{data.csv,data/,sensor.yaml}, body.yaml and, when the source has one,
// the ground truth: each shown image's pose under the stamp it is shown at (black frames have none),
// so the teleport is in the ground truth too. Throws std::runtime_error naming the file on a bad
// source, a plan outside the source or an unwritable destination. Returns the number of frames
// written.
int write_kidnapped_copy(const std::filesystem::path& source_dataset, const std::filesystem::path& dest_dataset,
                         const KidnapPlan& plan = {});

}  // namespace heslam::bench
