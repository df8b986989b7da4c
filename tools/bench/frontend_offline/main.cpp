// heslam-frontend-offline: runs rectification, HE, ORB, stereo matching and tracking over an EuRoC
// folder in one thread (no DDS), writes the TUM trajectory of the rectified left camera, prints the
// per-stage time breakdown (median / p90) and, when the folder has ground truth, the SE(3) ATE.
// `heslam-frontend-offline --help` lists the flags.
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "components/core/place/vocabulary_setting.hpp"
#include "components/core/tracking/settings_file.hpp"
#include "runtime/flags.hpp"
#include "runtime/quote_value.hpp"
#include "tools/bench/bench_util.hpp"
#include "tools/bench/frontend_offline/kidnapped_copy.hpp"
#include "tools/bench/frontend_offline/offline_run.hpp"

namespace {

using heslam::bench::percentile;

using heslam::bench::FrameRecord;

void print_stage(const char* name, const std::vector<FrameRecord>& frames, double FrameRecord::*field) {
  std::vector<double> values;
  for (const FrameRecord& f : frames) values.push_back(f.*field);
  std::printf("  %-10s median %7.2f ms   p90 %7.2f ms\n", name, percentile(values, 0.5), percentile(values, 0.9));
}

// Frames lost (not tracked after the map started) and what relocalizing took: the tracker's wall
// time of every lost frame (each tried a relocalization and failed) and of each relocalized one.
void print_relocalization_summary(const heslam::bench::OfflineRun& run) {
  int lost = 0;
  std::vector<double> lost_ms;
  std::vector<double> relocalized_ms;
  std::vector<double> relocalized_cpu_ms;
  std::string relocalized_at;
  for (std::size_t k = 0; k < run.frames.size(); ++k) {
    const FrameRecord& f = run.frames[k];
    if (f.state == heslam::TrackingState::kLost) {
      ++lost;
      lost_ms.push_back(f.tracking_ms);
    }
    if (f.method == heslam::TrackingMethod::kRelocalization) {
      relocalized_ms.push_back(f.tracking_ms);
      relocalized_cpu_ms.push_back(f.tracking_cpu_ms);
      relocalized_at += (relocalized_at.empty() ? "" : ", ") + std::to_string(k);
    }
  }
  if (lost == 0 && relocalized_ms.empty()) return;
  std::printf(
      "relocalization: %d frames lost (tracking median %.2f ms, max %.2f ms); relocalized at frame %s "
      "(tracking median %.2f ms, max %.2f ms; CPU median %.2f ms)\n",
      lost, percentile(lost_ms, 0.5), lost_ms.empty() ? 0.0 : *std::max_element(lost_ms.begin(), lost_ms.end()),
      relocalized_at.empty() ? "none" : relocalized_at.c_str(), percentile(relocalized_ms, 0.5),
      relocalized_ms.empty() ? 0.0 : *std::max_element(relocalized_ms.begin(), relocalized_ms.end()),
      percentile(relocalized_cpu_ms, 0.5));
}

// "B,R,S" or "B,R,S,N" (KidnapPlan's black_first, replay_first, replay_source, replay_frames).
heslam::bench::KidnapPlan parse_kidnap_plan(const std::string& flag, const std::string& value) {
  std::vector<int> numbers;
  std::size_t begin = 0;
  while (begin <= value.size()) {
    const std::size_t comma = std::min(value.find(',', begin), value.size());
    std::int64_t number = 0;
    if (!heslam::runtime::parse_whole_integer(value.substr(begin, comma - begin), number) || number < INT_MIN ||
        number > INT_MAX) {
      heslam::runtime::throw_bad_flag_value(flag, "B,R,S or B,R,S,N (integers)", value);
    }
    numbers.push_back(static_cast<int>(number));
    begin = comma + 1;
  }
  if (numbers.size() != 3 && numbers.size() != 4)
    heslam::runtime::throw_bad_flag_value(flag, "B,R,S or B,R,S,N", value);
  return heslam::bench::KidnapPlan{numbers[0], numbers[1], numbers[2], numbers.size() == 4 ? numbers[3] : -1};
}

// The command line, declared once for the parser and the usage.
struct Arguments {
  std::string dataset;
  std::string output;
  std::string settings;
  heslam::bench::OfflineRunOptions options;
  std::string he_mode;
  std::string he_stereo;
  std::optional<bool> pin_threads;  // --pin-threads: overrides the settings' Pipeline.pinThreads
  std::string kidnap_dir;
  heslam::bench::KidnapPlan kidnap_plan;
  std::string vocabulary;
  bool help = false;
};

heslam::runtime::Flags offline_flags(Arguments& a) {
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  heslam::runtime::Flags flags("heslam-frontend-offline DATASET [options]");
  flags.text("--output", "FILE.tum", &a.output, "the trajectory of the rectified left camera")
      .text("--settings", "SETTINGS.yaml", &a.settings,
            "ORB-SLAM2 settings: HE.*, ORBextractor.*, Stereo.*, and Camera.fps / ThDepth for the tracker")
      .text("--he", "none|global|clipped|clahe|adaptive", &a.he_mode, "the histogram equalization")
      .text("--he-stereo", "shared|matched|separate", &a.he_stereo, "how the two images are equalized")
      .custom("--variant", "none|dark|low_contrast", "a photometric variant of the images",
              [&a](const std::string& value) { a.options.variant = heslam::bench::parse_photometric_variant(value); })
      .custom(
          "--stereo-gain", "L,R[/L,R...]",
          "left image x L, right x R, saturated to 8 bit: cameras exposed\n"
          "differently; several: the run split into equal blocks",
          [&a](const std::string& value) { a.options.stereo_gain = heslam::bench::parse_stereo_gain_schedule(value); })
      .number("--disparity-noise", "SIGMA", &a.options.disparity_noise_px, 0.0, kInfinity,
              "Gaussian noise of SIGMA px added to every stereo disparity, seeded per\n"
              "frame: what stereo noise alone costs the trajectory")
      .integer("--drop-stereo-right-above", "LEVEL", &a.options.drop_stereo_right_above, 0, 254,
               "no stereo match where the right pixel matched is above LEVEL,\n"
               "0-254: the stereo set of a brighter right camera, no pixel changed")
      .number("--k1-offset", "DK", &a.options.k1_offset,
              "DK added to both cameras' k1 before rectification: how much the trajectory\n"
              "depends on the lens model at the image's edges")
      .integer("--first-frame", "K", &a.options.first_frame, "start at frame K of the sequence")
      .integer("--frames", "N", &a.options.max_frames, "at most N frames")
      .number("--period-ms", "P", &a.options.period_ms, 0.0, kInfinity,
              "start a frame every P ms, idle in between, as a camera: 50 for EuRoC's 20 Hz")
      .custom("--pin-threads", "on|off", "the pipeline's two threads on two CPUs, Pipeline.pinThreads; default on",
              [&a](const std::string& value) {
                if (value != "on" && value != "off")
                  heslam::runtime::throw_bad_flag_value("--pin-threads", "on or off", value);
                a.pin_threads = value == "on";
              })
      .number("--close-untracked-near-clip-weight", "W", &a.options.tracker.close_untracked_near_clip_weight, 0.0, 1.0,
              "tracker.close_untracked_near_clip_weight, 0-1; default 0.9")
      .number("--reference-near-clip-weight", "W", &a.options.tracker.reference_near_clip_weight, 0.0, 1.0,
              "tracker.reference_near_clip_weight, 0-1; default 1")
      .number("--stationary-chi2", "X", &a.options.tracker.stationary_test_chi2, "tracker.stationary_test_chi2; 0: off")
      .number("--rotation-chi2", "X", &a.options.tracker.rotation_only_test_chi2,
              "tracker.rotation_only_test_chi2; 0: off")
      .text("--kidnap", "DIR", &a.kidnap_dir,
            "run on a kidnapped-camera copy written to DIR: frames 60-79 black, 80-159 = 0-79")
      .custom("--kidnap-plan", "B,R,S[,N]",
              "the copy's plan: frames B..R-1 black, from R on the source's frames\n"
              "S.. (N of them; default: to the source's end); B = R: a teleport",
              [&a](const std::string& value) { a.kidnap_plan = parse_kidnap_plan("--kidnap-plan", value); })
      .text("--vocabulary", "FILE|none", &a.vocabulary,
            "keyframe database for relocalization; default: the build's vocabulary")
      .toggle("--help", &a.help, "this help")
      .alias("-h")
      .positional("DATASET", "", [&a](const std::string& arg) {
        if (!a.dataset.empty()) {
          throw std::runtime_error("'" + heslam::runtime::quote_value(arg) +
                                   "': unexpected second DATASET (see --help)");
        }
        a.dataset = arg;
      });
  return flags;
}

int run(int argc, char** argv) {
  Arguments arguments;
  heslam::runtime::Flags flags = offline_flags(arguments);
  flags.parse(argc, argv);
  if (arguments.help) {
    std::fputs(flags.usage().c_str(), stdout);
    return 0;
  }
  if (arguments.dataset.empty()) throw std::runtime_error("missing DATASET\n" + flags.usage());
  std::string dataset = arguments.dataset;
  const std::string& output = arguments.output;
  const std::string& settings = arguments.settings;
  heslam::bench::OfflineRunOptions& options = arguments.options;
  const std::string& he_mode = arguments.he_mode;
  const std::string& he_stereo = arguments.he_stereo;
  const std::optional<bool>& pin_threads = arguments.pin_threads;
  const std::string& kidnap_dir = arguments.kidnap_dir;
  const heslam::bench::KidnapPlan& kidnap_plan = arguments.kidnap_plan;
  const bool kidnap_plan_given = flags.given("--kidnap-plan");
  const std::string& vocabulary = arguments.vocabulary;
  if (!settings.empty()) {
    // The frontend's reader: the same keys mean the same options here (docs/configuration.md).
    heslam::SettingsFile file = heslam::load_settings_file(settings, options.tracker);
    options.pipeline = file.pipeline;
    options.tracker = file.tracker;
    for (const std::string& key : file.unused_keys)
      std::fprintf(stderr, "%s: %s: not used by heslam\n", settings.c_str(), key.c_str());
  }
  if (pin_threads) options.pipeline.pin_threads = *pin_threads;
  if (!he_mode.empty()) {
    try {
      options.pipeline.he.mode = heslam::parse_he_mode(he_mode);
    } catch (const std::invalid_argument&) {
      throw std::runtime_error("--he: expected none, global, clipped, clahe or adaptive, got '" + he_mode + "'");
    }
  }
  if (!he_stereo.empty()) {
    try {
      options.pipeline.he.stereo = heslam::parse_stereo_photometry(he_stereo);
    } catch (const std::invalid_argument&) {
      throw std::runtime_error("--he-stereo: expected shared, matched or separate, got '" + he_stereo + "'");
    }
  }

  options.vocabulary = heslam::load_vocabulary_setting(vocabulary);
  if (options.vocabulary) {
    std::printf("vocabulary %s: %zu words\n", heslam::describe_vocabulary_setting(vocabulary).c_str(),
                options.vocabulary->word_count());
  } else {
    std::printf("warning: --vocabulary none: a lost frame is relocalized against the newest keyframes only\n");
  }
  if (kidnap_dir.empty() && kidnap_plan_given) throw std::runtime_error("--kidnap-plan: needs --kidnap DIR");
  if (!kidnap_dir.empty()) {
    heslam::bench::write_kidnapped_copy(dataset, kidnap_dir, kidnap_plan);
    std::printf("kidnapped copy of %s written to %s\n", dataset.c_str(), kidnap_dir.c_str());
    dataset = kidnap_dir;
  }
  const auto sequence = heslam::bench::load_euroc_sequence(dataset);
  const auto result = heslam::bench::run_offline(sequence, options);
  if (!output.empty()) heslam::bench::write_tum_trajectory(output, result);

  std::string noise_note;
  if (options.disparity_noise_px > 0.0) {
    char text[64];
    std::snprintf(text, sizeof text, ", disparity noise %g px", options.disparity_noise_px);
    noise_note = text;
  }
  if (options.k1_offset != 0.0) {
    char text[48];
    std::snprintf(text, sizeof text, ", k1 %+g", options.k1_offset);
    noise_note += text;
  }
  if (options.drop_stereo_right_above >= 0) {
    noise_note += ", stereo dropped where the right is above " + std::to_string(options.drop_stereo_right_above);
  }
  std::printf(
      "dataset %s: %zu frames, %d tracked, %d keyframes, %d map points (HE %s %s, variant %s, stereo gain %s%s)\n",
      dataset.c_str(), result.frames.size(), result.tracked_frames(), result.keyframes, result.map_points,
      heslam::to_string(options.pipeline.he.mode), heslam::to_string(options.pipeline.he.stereo),
      heslam::bench::to_string(options.variant), heslam::bench::describe(options.stereo_gain).c_str(),
      noise_note.c_str());
  std::vector<double> features;
  std::vector<double> stereo;
  std::vector<double> near_clip;
  int still = 0;
  int rotating = 0;
  for (const FrameRecord& f : result.frames) {
    features.push_back(f.features);
    stereo.push_back(f.stereo_features);
    near_clip.push_back(f.near_clip_features);
    still += f.motion == heslam::FrameMotion::kStill ? 1 : 0;
    rotating += f.motion == heslam::FrameMotion::kRotatingInPlace ? 1 : 0;
  }
  std::printf("features per frame: median %.0f (stereo %.0f, near a clip edge %.0f)\n", percentile(features, 0.5),
              percentile(stereo, 0.5), percentile(near_clip, 0.5));
  std::printf("stationary test: %d frames still (last pose kept), %d rotating in place (last centre kept)\n", still,
              rotating);
  print_relocalization_summary(result);
  std::printf("per-frame time (image decoding excluded):\n");
  print_stage("rectify", result.frames, &FrameRecord::rectify_ms);
  print_stage("rect cpu", result.frames, &FrameRecord::rectify_cpu_ms);
  print_stage("he", result.frames, &FrameRecord::he_ms);
  print_stage("extract", result.frames, &FrameRecord::extract_ms);
  print_stage("stereo", result.frames, &FrameRecord::stereo_ms);
  print_stage("tracking", result.frames, &FrameRecord::tracking_ms);
  print_stage("track cpu", result.frames, &FrameRecord::tracking_cpu_ms);
  print_stage("track pcpu", result.frames, &FrameRecord::tracking_process_cpu_ms);
  print_stage("total", result.frames, &FrameRecord::total_ms);
  print_stage("total cpu", result.frames, &FrameRecord::cpu_ms);
  if (!result.frames.empty()) {
    const double frames = static_cast<double>(result.frames.size());
    std::printf(
        "hand-offs between the pipeline's two threads: %.1f per frame, %.1f of them to a sleeping thread; "
        "threads %s\n",
        static_cast<double>(result.hand_offs) / frames, static_cast<double>(result.sleeping_hand_offs) / frames,
        result.threads_pinned ? "pinned to two CPUs" : "not pinned");
  }
  if (std::getenv("HESLAM_FRONTEND_OFFLINE_PER_FRAME") != nullptr) {
    for (std::size_t k = 0; k < result.frames.size(); ++k) {
      const FrameRecord& f = result.frames[k];
      std::printf("frame %3zu %-8s %-18s tracked %4d features %4d stereo %4d%s %s\n", k, heslam::to_string(f.state),
                  heslam::to_string(f.method), f.tracked_points, f.features, f.stereo_features,
                  f.keyframe ? " keyframe" : "",
                  f.motion != heslam::FrameMotion::kMoving ? heslam::to_string(f.motion) : "");
    }
  }
  if (const auto ate = heslam::bench::compute_ate_se3(result)) {
    std::printf("ATE (SE3 Umeyama, %d poses): rmse %.5f m, max %.4f m; path length %.3f m\n", ate->pairs, ate->rmse_m,
                ate->max_m, heslam::bench::tracked_path_length_m(result));
  } else {
    std::printf("path length %.3f m (no ground truth)\n", heslam::bench::tracked_path_length_m(result));
  }
  if (const auto drift = heslam::bench::compute_kitti_drift(result)) {
    std::printf("KITTI drift (devkit, %zu sub-sequences of 100-800 m): translation %.2f %%, rotation %.4f deg/100 m\n",
                drift->segments.size(), drift->translation_error_percent, drift->rotation_error_deg_per_100m);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return heslam::bench::bench_main("heslam-frontend-offline", argc, argv, run); }
