// Reading FrontendOptions from the component's YAML config; defaults are the core structs' own.
#include "components/frontend/frontend_options.hpp"

#include <climits>
#include <stdexcept>

#include "components/core/place/vocabulary_setting.hpp"

namespace heslam::frontend {
namespace {

// Upper bounds that only catch typos (a value beyond them is certainly a mistake).
constexpr int kMaxFeatures = 100000;
constexpr int kMaxPyramidLevels = 16;
constexpr int kMaxPixels = 1000;
constexpr int kMaxCount = 100000;
constexpr double kMaxTimeoutS = 3600.0;

void read(const runtime::Config& c, const char* key, int& value, int min = 0, int max = kMaxCount) {
  value = c.get_int(key, value, min, max);
}
void read(const runtime::Config& c, const char* key, float& value, double min, double max) {
  value = static_cast<float>(c.get_double(key, value, min, max));
}
void read(const runtime::Config& c, const char* key, double& value, double min, double max) {
  value = c.get_double(key, value, min, max);
}
void read(const runtime::Config& c, const char* key, bool& value) { value = c.get_bool(key, value); }

void read_features(const runtime::Config& c, StereoFeaturePipelineOptions& o) {
  HistogramEqualizerOptions& he = o.he;
  he.mode = parse_he_mode(c.get_choice("he.mode", to_string(he.mode), {"none", "global", "clipped", "clahe", "adaptive"}));
  read(c, "he.global_clip_limit", he.global_clip_limit, 0.01, 1000.0);
  read(c, "he.clahe_clip_limit", he.clahe_clip_limit, 0.0, 1000.0);
  read(c, "he.clahe_tiles_x", he.clahe_tiles_x, 1, 64);
  read(c, "he.clahe_tiles_y", he.clahe_tiles_y, 1, 64);
  read(c, "he.adaptive_on_below", he.adaptive_on_below, 0.0, 255.0);
  read(c, "he.adaptive_off_above", he.adaptive_off_above, 0.0, 255.0);
  he.stereo = parse_stereo_photometry(c.get_choice("he.stereo", to_string(he.stereo), {"shared", "matched", "separate"}));
  read(c, "he.saturation_excess", he.saturation_excess, 0.001, 1.0);
  read(c, "he.match_shift_from", he.match_shift_from, 0.0, 255.0);
  // Above match_shift_from: the fade-in needs a positive width.
  read(c, "he.match_shift_full", he.match_shift_full, he.match_shift_from + 0.01, 255.0);
  read(c, "he.match_gain_from", he.match_gain_from, 1.0001, 1000.0);
  read(c, "he.tone_from_matches", o.tone_from_matches);

  OrbOptions& orb = o.orb;
  read(c, "orb.features", orb.features, 1, kMaxFeatures);
  read(c, "orb.scale_factor", orb.scale_factor, 1.01, 4.0);
  read(c, "orb.levels", orb.levels, 1, kMaxPyramidLevels);
  read(c, "orb.fast_threshold_initial", orb.fast_threshold_initial, 1, 255);
  read(c, "orb.fast_threshold_min", orb.fast_threshold_min, 1, 255);
  read(c, "orb.cell_size_px", orb.cell_size_px, 8.0, kMaxPixels);
  read(c, "orb.features_by_area", orb.features_by_area);

  StereoMatcherOptions& stereo = o.stereo;
  read(c, "stereo.max_distance", stereo.max_distance, 0, 256);
  read(c, "stereo.row_band_px", stereo.row_band_px, 0.0, kMaxPixels);
  read(c, "stereo.sad_half_window_px", stereo.sad_half_window_px, 1, 32);
  read(c, "stereo.sad_search_px", stereo.sad_search_px, 0, 64);
  read(c, "stereo.min_depth_baselines", stereo.min_depth_baselines, 0.01, 1000.0);
  read(c, "stereo.sad_outlier_factor", stereo.sad_outlier_factor, 0.0, 1000.0);
  read(c, "stereo.clip_masked_sad", stereo.clip_masked_sad);
  {
    using Cost = StereoMatcherOptions::MatchCost;
    const char* current = stereo.cost == Cost::kZncc ? "zncc" : stereo.cost == Cost::kCensus ? "census" : "sad";
    const std::string cost = c.get_choice("stereo.cost", current, {"sad", "zncc", "census"});
    stereo.cost = cost == "zncc" ? Cost::kZncc : cost == "census" ? Cost::kCensus : Cost::kSad;
  }

  read(c, "pipeline.parallel", o.parallel);
  read(c, "pipeline.pin_threads", o.pin_threads);
  read(c, "pipeline.left_only_features", o.left_only_features, 0.0f, 4.0f);
}

void read_tracker(const runtime::Config& c, TrackerOptions& t) {
  read(c, "tracker.min_stereo_points_to_initialize", t.min_stereo_points_to_initialize);
  read(c, "tracker.close_depth_baselines", t.close_depth_baselines, 1.0, 1000.0);
  read(c, "tracker.descriptor_threshold_high", t.descriptor_threshold_high, 0, 256);
  read(c, "tracker.descriptor_threshold_low", t.descriptor_threshold_low, 0, 256);
  read(c, "tracker.check_orientation", t.check_orientation);
  read(c, "tracker.motion_search_radius_px", t.motion_search_radius_px, 0.5, kMaxPixels);
  read(c, "tracker.min_motion_matches", t.min_motion_matches);
  read(c, "tracker.reference_search_radius_px", t.reference_search_radius_px, 0.5, kMaxPixels);
  read(c, "tracker.reference_ratio", t.reference_ratio, 0.0, 1.0);
  read(c, "tracker.min_reference_matches", t.min_reference_matches);
  read(c, "tracker.min_pose_inliers", t.min_pose_inliers);
  read(c, "tracker.local_search_radius_px", t.local_search_radius_px, 0.5, kMaxPixels);
  read(c, "tracker.local_search_radius_relocalized_px", t.local_search_radius_relocalized_px, 0.5, kMaxPixels);
  read(c, "tracker.local_ratio", t.local_ratio, 0.0, 1.0);
  read(c, "tracker.min_view_cosine", t.min_view_cosine, -1.0, 1.0);
  read(c, "tracker.local_map_max_keyframes", t.local_map_max_keyframes, 1);
  read(c, "tracker.local_map_neighbours_per_keyframe", t.local_map_neighbours_per_keyframe);
  read(c, "tracker.min_local_map_inliers", t.min_local_map_inliers);
  read(c, "tracker.min_local_map_inliers_after_relocalization", t.min_local_map_inliers_after_relocalization);
  read(c, "tracker.pose_optimization_rounds", t.pose_optimization_rounds, 1, 100);
  read(c, "tracker.pose_optimization_iterations", t.pose_optimization_iterations, 1, 1000);
  read(c, "tracker.disparity_sigma_ratio", t.disparity_sigma_ratio, 0.01, 100.0);
  read(c, "tracker.near_clip_disparity_sigma_factor", t.near_clip_disparity_sigma_factor, 0.0, 1000.0);
  read(c, "tracker.stationary_test_chi2", t.stationary_test_chi2, 0.0, 1e6);
  read(c, "tracker.rotation_only_test_chi2", t.rotation_only_test_chi2, 0.0, 1e6);
  read(c, "tracker.max_frames_between_keyframes", t.max_frames_between_keyframes, 1);
  read(c, "tracker.min_frames_between_keyframes", t.min_frames_between_keyframes);
  read(c, "tracker.close_tracked_needed", t.close_tracked_needed);
  read(c, "tracker.close_untracked_enough", t.close_untracked_enough);
  read(c, "tracker.close_untracked_near_clip_weight", t.close_untracked_near_clip_weight, 0.0, 1.0);
  read(c, "tracker.reference_ratio_stereo", t.reference_ratio_stereo, 0.0, 1.0);
  read(c, "tracker.reference_near_clip_weight", t.reference_near_clip_weight, 0.0, 1.0);
  read(c, "tracker.reference_ratio_single_keyframe", t.reference_ratio_single_keyframe, 0.0, 1.0);
  read(c, "tracker.min_keyframe_inliers", t.min_keyframe_inliers);
  read(c, "tracker.new_keyframe_min_points", t.new_keyframe_min_points);
  read(c, "tracker.relocalization_keyframes", t.relocalization_keyframes, 1);
  read(c, "tracker.relocalization_ratio", t.relocalization_ratio, 0.0, 1.0);
  read(c, "tracker.min_relocalization_matches", t.min_relocalization_matches);
  read(c, "tracker.min_relocalization_inliers", t.min_relocalization_inliers);
  t.ransac_seed = static_cast<std::uint64_t>(c.get_int("tracker.ransac_seed", static_cast<int>(t.ransac_seed), 0, INT_MAX));
}

}  // namespace

FrontendOptions FrontendOptions::from_config(const runtime::Config& config, const std::vector<std::string>& rest) {
  FrontendOptions options;
  read_features(config, options.features);
  read_tracker(config, options.tracker);
  read(config, "lockstep.wait_for_mapper", options.wait_for_mapper);
  options.mapper_enabled = config.get_bool("mapper.enabled", options.wait_for_mapper);
  options.wait_for_mapper = options.wait_for_mapper && options.mapper_enabled;
  double timeout_s = std::chrono::duration<double>(options.mapper_timeout).count();
  read(config, "lockstep.mapper_timeout_s", timeout_s, 0.1, kMaxTimeoutS);
  options.mapper_timeout = std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000.0));
  read(config, "frames.max_pending", options.max_pending_frames, 1, 1000);
  options.vocabulary_file = config.get_string("vocabulary.file", "");
  options.vocabulary = load_vocabulary_setting(options.vocabulary_file);
  options.mapper_map_file = config.get_string("mapper.map_file", "");
  options.journal_file = config.get_string("journal.file", "");
  std::string loop_closer = config.get_string("lockstep.loop_closer", "none");
  const std::string loop_closer_name = config.get_string("lockstep.loop_closer_name", "loop_closer");
  for (std::size_t i = 0; i < rest.size(); ++i) {
    if (rest[i] == "--mapper-map-file" && i + 1 < rest.size()) {
      options.mapper_map_file = rest[++i];
    } else if (rest[i] == "--journal" && i + 1 < rest.size()) {
      options.journal_file = rest[++i];
    } else if (rest[i] == "--loop-closer" && i + 1 < rest.size()) {
      loop_closer = rest[++i];
    } else if (rest[i] == "--localize") {
      options.localize = true;
    } else {
      throw std::runtime_error("unknown argument '" + rest[i] +
                               "' (expected --mapper-map-file FILE, --journal FILE, --loop-closer EXECUTABLE|none or --localize)");
    }
  }
  if (options.localize && (options.mapper_map_file.empty() || !options.mapper_enabled)) {
    throw std::runtime_error("--localize: needs the local mapper (mapper.enabled) and its map file (--mapper-map-file FILE)");
  }
  if (!loop_closer.empty() && loop_closer != "none" && options.wait_for_mapper) {
    options.loop_closers.push_back(loop_closer_name);
  }

  // With a mapper the frontend mirrors the map instead of maintaining it; its ids stay the frontend's.
  options.tracker.maintain_map = !options.mapper_enabled;
  options.tracker.id_tag = kFrontendTag;
  return options;
}

}  // namespace heslam::frontend
