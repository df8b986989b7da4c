// Load shedding of a real-time frontend (issue 41, docs/frontend.md "Behind the camera"): when frames
// come faster than the machine lets it track them, the frontend skips stale frames (counted, never
// silent) instead of tracking each one later and later, and the frame after a gap is predicted over
// the gap's length, so that skipped and missed frames do not cost the tracking its motion model.
// Lockstep runs never have a newer frame waiting nor a gap: nothing here changes them.
#pragma once

#include <cstdint>
#include <optional>

#include "components/core/geometry/pose.hpp"
#include "runtime/config.hpp"

namespace heslam::frontend {

struct LoadSheddingOptions {
  // realtime.shed_frames_after_ms: a frame at least this old (from its publication) when a newer one
  // is already waiting is skipped: counted as shed (and missed: it gets no pose). 0: off, every frame
  // is tracked in order however late (the reader's keep-last queue still drops the oldest).
  double shed_after_ms = 0.0;
  // realtime.predict_over_gaps: the frame after a gap (missed or shed frames) starts from the last
  // motion scaled to the gap's length in frames instead of the one-frame motion model. A run without
  // gaps (lockstep) is not touched.
  bool predict_over_gaps = false;
  // debug.frame_delay_ms: sleep this long before tracking each frame: a slow machine on demand, for
  // tests of the shedding (deterministic: any delay above the frame period makes the frontend behind).
  double frame_delay_ms = 0.0;

  // Throws std::runtime_error (one line: field, expectation) on a bad field, or on shedding asked
  // of a lockstep frontend (`lockstep`: lockstep.wait_for_mapper), which is never behind.
  static LoadSheddingOptions from_config(const runtime::Config& config, bool lockstep);
};

// Whether a frame `age_ms` after its publication is skipped, a newer frame waiting or not.
bool shed_frame(const LoadSheddingOptions& options, double age_ms, bool newer_frame_waiting);

// The motion between the last two tracked frames, per frame of the replay's numbering (seq), for the
// prediction of a frame after a gap.
class GapPrediction {
 public:
  // After each tracked (tracked = true, with its pose) or untracked frame the frontend processed.
  void record(std::uint64_t seq, bool tracked, const Pose3& T_wc);
  // The starting pose of frame `seq` from `T_wc_last` (the tracker's last frame, which follows loop
  // corrections): the last motion scaled from its seq gap to this one's. None when the gaps are equal
  // (the tracker's own motion model is exactly that) or no motion is known (the last two frames
  // processed were not both tracked).
  std::optional<Pose3> predict(std::uint64_t seq, const Pose3& T_wc_last) const;

 private:
  std::optional<std::uint64_t> last_seq_;
  std::optional<Pose3> last_T_wc_;
  std::optional<Pose3> motion_;   // T_last_prev^-1 ... : T_wc(prev)^-1 T_wc(last)
  std::uint64_t motion_gap_ = 0;  // seq(last) - seq(prev)
};

// The rigid motion `motion` scaled by `factor`: its rotation angle and its translation, each (constant
// velocity in the camera's frame, to first order: exact enough over the few frames of a gap).
Pose3 scale_motion(const Pose3& motion, double factor);

}  // namespace heslam::frontend
