// Loop candidates without a vocabulary: old keyframes near the query's current pose estimate, within a
// radius that grows with the path travelled since them (the drift odometry may have built up), looking
// the same way, and not already covisible with the query. Matched by plain descriptors. The second,
// swappable loop detector (heslam-loop-closer-proximity); for data a vocabulary fits poorly.
#pragma once

#include "components/core/loop/loop_detector.hpp"

namespace heslam {

struct ProximityLoopDetectorOptions {
  double base_radius_m = 1.0;  // search radius around the query's camera centre ...
  double drift_ratio = 0.05;   // ... plus this fraction of the path travelled since the candidate
  double max_radius_m = 30.0;
  double max_view_angle_deg = 45.0;  // optical axes of query and candidate at most this far apart
  double min_path_since_m = 5.0;     // candidates are at least this far back along the path
  int max_candidates = 3;            // nearest first
  int min_keyframes_in_map = 10;     // as the BoW detector (ORB-SLAM2)
  int keyframes_after_loop = 10;
  // Merges (the atlas): poses of two maps are not comparable, so merge candidates are found by
  // appearance alone: the query's map-point keypoints matched by descriptor (below) against keyframes
  // of the other maps, candidates with at least merge_min_matches matches, most matches first. At most
  // merge_keyframes_per_query keyframes are scanned per query (a round robin over the other maps'
  // keyframes, so the cost per keyframe stays bounded while successive keyframes cover them all).
  int merge_min_matches = 30;
  int merge_keyframes_per_query = 40;
  // Descriptor matching of the two keyframes' map-point keypoints.
  int max_descriptor_distance = 50;  // ORB-SLAM2 TH_LOW
  float ratio = 0.8f;                // best < ratio x second best
};

class ProximityLoopDetector final : public LoopDetector {
 public:
  explicit ProximityLoopDetector(const ProximityLoopDetectorOptions& options) : options_(options) {}

  const char* name() const override { return "proximity"; }
  LoopCandidates detect(const Map& map, KeyframeId query) override;
  void loop_closed(KeyframeId query) override;
  LoopCandidates detect_merge(const Map& map, KeyframeId query, const std::set<KeyframeId>& other_maps) override;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> match(const Map& map, KeyframeId query,
                                                             KeyframeId candidate) const override;

 private:
  ProximityLoopDetectorOptions options_;
  int keyframes_since_loop_ = 1 << 30;
  KeyframeId merge_cursor_ = kNoId;  // the last other-map keyframe scanned
};

}  // namespace heslam
