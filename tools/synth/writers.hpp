// Writes a rendered sequence to disk in the EuRoC ASL layout or the KITTI odometry layout, plus
// synth.yaml (preset, seed, events with their time ranges) and an ORB-SLAM2 stereo settings file.
#pragma once

#include <filesystem>
#include <functional>

#include "tools/synth/sequence.hpp"

namespace heslam::synth {

enum class OutputFormat { kEuroc, kKitti };

// Called after each frame with (frames done, total).
using Progress = std::function<void(int, int)>;

// EuRoC: out/mav0/cam{0,1}/{data/<stamp>.png, data.csv, sensor.yaml}, out/mav0/body.yaml,
// out/mav0/state_groundtruth_estimate0/data.csv (body poses, 17 columns), out/timestamps.txt
// (ORB-SLAM2's EuRoC_TimeStamps format). KITTI: out/image_{0,1}/NNNNNN.png, times.txt, calib.txt,
// poses.txt (left camera in the first left camera's frame); KITTI images are rectified, so the
// renderer must have been created with apply_distortion = false.
// Both write out/synth.yaml and out/orbslam2_settings.yaml. Throws std::runtime_error on I/O errors.
void write_sequence(SequenceRenderer& renderer, OutputFormat format, const std::filesystem::path& out_dir,
                    const Progress& progress = {});

}  // namespace heslam::synth
