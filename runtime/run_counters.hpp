// Names of the counters a run's verdict is made of (heslam-supervisor, runtime/supervisor/run_verdict.hpp):
// each program counts its part in its Stats, and reports the final values to the supervisor as it ends.
#pragma once

namespace heslam::runtime {

// The source (heslam-replay): frames written on camera/stereo, frames per pass of the recording,
// pairs it skipped (a missing or corrupt image).
inline constexpr const char* kFramesPublished = "frames_published";
inline constexpr const char* kFramesTotal = "frames_total";
inline constexpr const char* kImagesSkipped = "images_skipped";
// A source with a finite input (a recording) that was stopped before its end: the frames it did not
// play. The outputs then hold only a beginning of the run, so the run fails (a Ctrl-C included).
inline constexpr const char* kFramesNotPlayed = "frames_not_played";
// The frontend: frames it published odometry for, those of its journal included (the same frames
// again after a restart count once).
inline constexpr const char* kOdometryFrames = "odometry_frames";
// The recorder, counted once at its end: frames in its outputs (a pose, or in the lost list), of
// them with a pose, and the frames its summary accounts for ("tracked N/M": M).
inline constexpr const char* kFramesRecorded = "frames_recorded";
inline constexpr const char* kFramesWithPose = "frames_with_pose";
inline constexpr const char* kFramesAccounted = "frames_accounted";
// Any program: two live writers claimed one role at once (runtime/role_binding.hpp, CheckedReader):
// a forged participant that copies the run id, or a second copy of a component. Counted in total
// and per topic (kWriterConflictsOn + topic name); the run fails and its last line names the topic.
inline constexpr const char* kWriterConflicts = "writer_conflicts";
inline constexpr const char* kWriterConflictsOn = "writer_conflicts@";

}  // namespace heslam::runtime
