// Frames tracked after a hole in the input (issue 41, docs/frontend.md "After a gap"): the frontend's
// chain (FrameProcessor) and its gap prediction, without DDS, on MH01 with frames dropped as a loaded
// real-time run misses or sheds them. Known answer: every frame has a pose near the ground truth's or
// none (lost); no step between consecutive poses of one map is wrong. Before the check after a gap,
// 10 frames dropped at frame 70 gave frame 80 a pose 153 mm off (51 inliers), at 115 frame 125 one 59 mm
// off (40 inliers), and each made a keyframe that carried the error into every later pose.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/frontend/frame_processor.hpp"
#include "components/frontend/load_shedding.hpp"
#include "runtime/config.hpp"
#include "test_support.hpp"
#include "tools/bench/frontend_offline/euroc_sequence.hpp"
#include "tools/synth/preset.hpp"
#include "tools/synth/sequence.hpp"
#include "tools/synth/writers.hpp"

namespace heslam::frontend {
namespace {

struct Hole {
  int first = 0;  // index of the first frame dropped
  int length = 0;
};

struct GapFrame {
  int index = 0;
  TrackingState state = TrackingState::kNotInitialized;
  TrackingMethod method = TrackingMethod::kNone;
  Pose3 T_wc = Pose3::Identity();
  Pose3 T_truth = Pose3::Identity();  // rectified left camera, ground-truth world
  int tracked_points = 0;
  bool keyframe = false;
  MapId map_id = kFirstMapId;
  GapCheck gap_check = GapCheck::kNoGap;
};

std::vector<GapFrame> run_with_holes(const bench::EurocSequence& sequence, const std::vector<Hole>& holes,
                                     bool predict_over_gaps, const std::string& config_yaml = "") {
  std::set<int> dropped;
  for (const Hole& hole : holes) {
    for (int k = hole.first; k < hole.first + hole.length; ++k) dropped.insert(k);
  }
  const runtime::Config config =
      config_yaml.empty() ? runtime::Config::empty() : runtime::Config::parse(config_yaml, "frontend.yaml");
  FrameProcessor processor(load_euroc_calibration(sequence.mav0_dir), FrontendOptions::from_config(config));
  GapPrediction gap_prediction;
  std::vector<GapFrame> frames;
  for (int k = 0; k < static_cast<int>(sequence.frames.size()); ++k) {
    if (dropped.count(k) != 0) continue;
    const bench::EurocFrame& input = sequence.frames[static_cast<std::size_t>(k)];
    const cv::Mat left = cv::imread(input.left_png.string(), cv::IMREAD_GRAYSCALE);
    const cv::Mat right = cv::imread(input.right_png.string(), cv::IMREAD_GRAYSCALE);
    const auto seq = static_cast<std::uint64_t>(k);
    if (predict_over_gaps) {
      Tracker& tracker = processor.tracker();
      if (const auto T_wc = gap_prediction.predict(seq, tracker.last_frame().T_wc)) tracker.set_prediction(*T_wc);
    }
    const FrameOutput output = processor.process(input.stamp_ns, seq, left, right);
    gap_prediction.record(seq, output.result.state == TrackingState::kOk, output.result.T_wc);
    GapFrame frame;
    frame.index = k;
    frame.state = output.result.state;
    frame.method = output.result.method;
    frame.T_wc = output.result.T_wc;
    if (input.T_WB_truth) frame.T_truth = *input.T_WB_truth * processor.rectifier().T_B_rect();
    frame.tracked_points = output.result.tracked_points;
    frame.keyframe = output.result.new_keyframe.has_value();
    frame.map_id = output.result.map_id;
    frame.gap_check = output.result.gap_check;
    frames.push_back(frame);
  }
  return frames;
}

// Translation error of the pose relative to the first frame (the tracker's world origin).
double position_error_m(const GapFrame& first, const GapFrame& frame) {
  const Pose3 truth = first.T_truth.inverse() * frame.T_truth;
  return (truth.translation() - frame.T_wc.translation()).norm();
}

double step_error_m(const GapFrame& a, const GapFrame& b) {
  const Pose3 truth = a.T_truth.inverse() * b.T_truth;
  const Pose3 estimate = a.T_wc.inverse() * b.T_wc;
  return (truth.translation() - estimate.translation()).norm();
}

struct GapFigures {
  int lost = 0;
  int maps = 1;
  int rechecked = 0;              // GapCheck::kChosen
  int refused = 0;                // GapCheck::kRefused
  int keyframes_after_gap = 0;    // keyframes made by a frame right after a gap
  double worst_position_m = 0.0;  // first map: against the ground truth, relative to the first frame
  int worst_position_at = -1;
  double worst_step_m = 0.0;  // consecutive poses of one map (lost frames and gaps between them skipped)
  int worst_step_at = -1;
};

GapFigures evaluate(const std::string& label, const std::vector<GapFrame>& frames) {
  GapFigures figures;
  const GapFrame* previous = nullptr;
  for (const GapFrame& f : frames) {
    figures.rechecked += f.gap_check == GapCheck::kChosen ? 1 : 0;
    figures.refused += f.gap_check == GapCheck::kRefused ? 1 : 0;
    figures.keyframes_after_gap += f.keyframe && f.gap_check != GapCheck::kNoGap ? 1 : 0;
    if (f.state != TrackingState::kOk) {
      ++figures.lost;
      continue;
    }
    figures.maps = std::max(figures.maps, static_cast<int>(f.map_id) + 1);
    // A new map (the atlas) starts at the last pose, not the ground truth's: only its steps count.
    if (f.map_id == kFirstMapId) {
      const double e = position_error_m(frames.front(), f);
      if (e > figures.worst_position_m) {
        figures.worst_position_m = e;
        figures.worst_position_at = f.index;
      }
    }
    if (previous != nullptr && previous->map_id == f.map_id) {
      const double step = step_error_m(*previous, f);
      if (step > figures.worst_step_m) {
        figures.worst_step_m = step;
        figures.worst_step_at = f.index;
      }
    }
    previous = &f;
  }
  std::printf(
      "[ figures  ] %-30s %zu frames, %d lost, %d maps; after a gap: %d rechecked, %d refused, %d keyframes; "
      "worst position %.1f mm (frame %d), worst step %.1f mm (frame %d)\n",
      label.c_str(), frames.size(), figures.lost, figures.maps, figures.rechecked, figures.refused,
      figures.keyframes_after_gap, figures.worst_position_m * 1e3, figures.worst_position_at,
      figures.worst_step_m * 1e3, figures.worst_step_at);
  if (std::getenv("GAP_VERBOSE") != nullptr) {
    previous = nullptr;
    for (const GapFrame& f : frames) {
      const double s = previous != nullptr && f.state == TrackingState::kOk ? step_error_m(*previous, f) : 0.0;
      std::printf("   %3d %-6s %-18s %-8s pts %4d kf %d map %u pos %.1f step %.1f\n", f.index, to_string(f.state),
                  to_string(f.method), to_string(f.gap_check), f.tracked_points, f.keyframe ? 1 : 0, f.map_id,
                  position_error_m(frames.front(), f) * 1e3, s * 1e3);
      if (f.state == TrackingState::kOk) previous = &f;
    }
  }
  return figures;
}

void report(const std::string& label, const std::vector<GapFrame>& frames) { evaluate(label, frames); }

std::string settings_yaml(const std::filesystem::path& settings) {
  return "%YAML:1.0\n---\nsettings:\n  file: " + settings.string() + "\n";
}

void sweep(const std::string& name, const bench::EurocSequence& sequence, const std::string& config,
           const std::vector<int>& lengths, const std::vector<int>& places) {
  report(name + " no hole", run_with_holes(sequence, {}, true, config));
  const char* only = std::getenv("GAP_ONLY");
  for (const int length : lengths) {
    for (const int first : places) {
      const std::string label = name + " hole " + std::to_string(length) + " at " + std::to_string(first);
      if (only != nullptr && label.find(only) == std::string::npos) continue;
      report(label + " pred", run_with_holes(sequence, {{first, length}}, true, config));
      if (std::getenv("GAP_NOPRED") != nullptr) {
        report(label + " nopred", run_with_holes(sequence, {{first, length}}, false, config));
      }
    }
  }
}

bench::EurocSequence render(const std::string& preset, int frames, const std::filesystem::path& dir) {
  synth::SequenceRenderer renderer(synth::load_preset(synth::find_preset(preset)),
                                   {.seed = 1, .frames = frames, .apply_distortion = false, .threads = 2});
  synth::write_sequence(renderer, synth::OutputFormat::kEuroc, dir);
  return bench::load_euroc_sequence(dir);
}

// The sweeps behind the tests below (run with --gtest_also_run_disabled_tests; GAP_ONLY="hole 10 at 70",
// GAP_PRESET=room, GAP_NOPRED=1, GAP_VERBOSE=1 narrow or widen them).
TEST(GapTracking, DISABLED_SweepSynthetic) {
  test::ScratchDir scratch("gap_tracking");
  const char* which = std::getenv("GAP_PRESET");
  const std::vector<std::pair<std::string, int>> presets = {{"room", 300}, {"corridor_loop", 400}, {"street", 300}};
  for (const auto& [preset, frames] : presets) {
    if (which != nullptr && preset != which) continue;
    const auto dir = scratch.path() / preset;
    const auto sequence = render(preset, frames, dir);
    sweep(preset, sequence, settings_yaml(dir / "orbslam2_settings.yaml"), {3, 5, 10, 20, 40},
          {frames / 5, 2 * frames / 5, 3 * frames / 5, 4 * frames / 5});
  }
}

TEST(GapTracking, DISABLED_SweepMh01Settings) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const auto sequence = bench::load_euroc_sequence(test::shared_dataset("euroc_mh01_handheld"));
  const std::filesystem::path settings = test::source_dir() / "config/camera/EuRoC.yaml";
  sweep("mh01s", sequence, settings_yaml(settings), {2, 3, 5, 10, 20, 40}, {20, 45, 70, 95, 115});
}

TEST(GapTracking, DISABLED_SweepMh01) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const auto sequence = bench::load_euroc_sequence(test::shared_dataset("euroc_mh01_handheld"));
  report("mh01 no hole", run_with_holes(sequence, {}, true));
  const char* only = std::getenv("GAP_ONLY");
  for (const int length : {5, 10, 20, 40}) {
    for (const int first : {20, 45, 70, 95, 115}) {
      const std::string label = "mh01 hole " + std::to_string(length) + " at " + std::to_string(first);
      if (only != nullptr && label.find(only) == std::string::npos) continue;
      report(label + " pred", run_with_holes(sequence, {{first, length}}, true));
      report(label + " nopred", run_with_holes(sequence, {{first, length}}, false));
    }
  }
}

// MH01 without a hole: the bounds of the tests below. Measured: worst position 9.0 mm (frame 16's
// drift from the first frame included), worst step 4.1 mm; no frame is after a gap.
constexpr double kMh01NoHoleWorstPositionM = 0.0090;
// A frame after a hole is right when within twice the run without holes (wrong ones were 59-176 mm
// off); a step over a gap of up to 40 frames measured up to 8.5 mm.
constexpr double kPositionBoundM = 2.0 * kMh01NoHoleWorstPositionM + 0.002;
constexpr double kStepBoundM = 0.020;

const bench::EurocSequence& mh01() {
  static const bench::EurocSequence sequence = bench::load_euroc_sequence(test::shared_dataset("euroc_mh01_handheld"));
  return sequence;
}

std::string mh01_config() { return settings_yaml(test::source_dir() / "config/camera/EuRoC.yaml"); }

void expect_right_or_lost(const std::vector<Hole>& holes) {
  for (const Hole& hole : holes) {
    const std::string label = "mh01 " + std::to_string(hole.length) + " dropped at " + std::to_string(hole.first);
    const GapFigures figures = evaluate(label, run_with_holes(mh01(), {hole}, true, mh01_config()));
    EXPECT_LT(figures.worst_position_m, kPositionBoundM) << label << ": frame " << figures.worst_position_at;
    EXPECT_LT(figures.worst_step_m, kStepBoundM) << label << ": frame " << figures.worst_step_at;
  }
}

TEST(GapTracking, Mh01WithoutHolesIsTheBound) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const std::vector<GapFrame> frames = run_with_holes(mh01(), {}, true, mh01_config());
  const GapFigures figures = evaluate("mh01 no hole", frames);
  EXPECT_EQ(figures.lost, 0);
  EXPECT_EQ(figures.rechecked + figures.refused, 0);
  for (const GapFrame& f : frames) EXPECT_EQ(f.gap_check, GapCheck::kNoGap) << "frame " << f.index;
  EXPECT_LT(figures.worst_position_m, kMh01NoHoleWorstPositionM + 0.0005);
  EXPECT_LT(figures.worst_step_m, 0.005);
}

// The two holes that gave a wrong pose before the check: the doubtful first pose (40-51 inliers against
// 219-275 for the frame before) loses to the one-frame motion model's start (238 inliers) and the last
// pose's (318), and the frame makes no keyframe.
TEST(GapTracking, Mh01TenFramesDroppedWhereTheFirstPoseWasWrong) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  for (const Hole hole : {Hole{70, 10}, Hole{115, 10}}) {
    const std::vector<GapFrame> frames = run_with_holes(mh01(), {hole}, true, mh01_config());
    const GapFigures figures = evaluate("mh01 10 dropped at " + std::to_string(hole.first), frames);
    const auto after = std::find_if(frames.begin(), frames.end(),
                                    [&](const GapFrame& f) { return f.index == hole.first + hole.length; });
    ASSERT_NE(after, frames.end());
    EXPECT_EQ(after->gap_check, GapCheck::kChosen);
    EXPECT_FALSE(after->keyframe);
    EXPECT_EQ(after->state, TrackingState::kOk);
    EXPECT_LT(figures.worst_position_m, kPositionBoundM) << "frame " << figures.worst_position_at;
    EXPECT_LT(figures.worst_step_m, kStepBoundM) << "frame " << figures.worst_step_at;
  }
}

TEST(GapTracking, Mh01ShortHolesRightOrLost) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  expect_right_or_lost({{20, 2}, {45, 3}, {95, 5}, {20, 10}, {45, 10}});
}

TEST(GapTracking, Mh01LongHolesRightOrLost) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  expect_right_or_lost({{45, 20}, {95, 20}, {20, 40}, {70, 40}});
}

// Without the gap prediction (realtime.predict_over_gaps off) the first start is the one-frame motion
// model; 5 frames dropped at 95: frame 100 is refused, the next 19 are lost and frame 120 starts a new
// map (the atlas's 1 s), whose steps only are checked.
TEST(GapTracking, Mh01HolesWithoutGapPredictionRightOrLost) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  for (const Hole hole : {Hole{95, 5}, Hole{70, 10}, Hole{115, 10}}) {
    const std::string label =
        "mh01 nopred " + std::to_string(hole.length) + " dropped at " + std::to_string(hole.first);
    const GapFigures figures = evaluate(label, run_with_holes(mh01(), {hole}, false, mh01_config()));
    EXPECT_LT(figures.worst_position_m, kPositionBoundM) << label << ": frame " << figures.worst_position_at;
    EXPECT_LT(figures.worst_step_m, kStepBoundM) << label << ": frame " << figures.worst_step_at;
  }
}

}  // namespace
}  // namespace heslam::frontend
