// Loop candidate detection: which old keyframes might show the place a new keyframe sees. The part a
// loop closer swaps (bag of words, proximity, ...); geometric verification and correction are shared
// (se3_ransac.hpp, loop_correction_builder.hpp).
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "components/core/map/map.hpp"

namespace heslam {

struct LoopCandidates {
  std::vector<KeyframeId> keyframes;  // to verify geometrically, best first
  std::string reason;                 // when empty: why not (for the debug log), e.g. "too few keyframes"
  // detect_merge only: places found but not yet confirmed by the detector's own consistency over
  // successive queries (best first, at most 3). A merge may confirm them spatially instead: the query's
  // covisible keyframes see the matched place where its transform puts them (LoopClosing::process_merge).
  std::vector<KeyframeId> unconfirmed;
};

class LoopDetector {
 public:
  virtual ~LoopDetector() = default;
  virtual const char* name() const = 0;
  // Called once per new keyframe `query` (in keyframe order) after the local mapper processed it;
  // `map` is the loop closer's mirror and holds it. Detectors may keep state across calls (the
  // consistency groups of ORB-SLAM2), which is why a rejected loop is reported back.
  virtual LoopCandidates detect(const Map& map, KeyframeId query) = 0;
  // A loop was closed at `query`: detectors typically wait some keyframes before the next one.
  virtual void loop_closed(KeyframeId query) = 0;
  // The atlas: keyframes of OTHER maps (`other_maps`: their live keyframes) that might show the place
  // `query` of the active map sees, best first; verified as loops are, merged when accepted
  // (map_merge.hpp). Poses of two maps are not comparable, so detectors must not use them here.
  // Called after detect() for the same query. The default finds none (say why).
  virtual LoopCandidates detect_merge(const Map& /*map*/, KeyframeId /*query*/,
                                      const std::set<KeyframeId>& /*other_maps*/) {
    return {{}, std::string(name()) + " detector does not look for merges", {}};
  }
  // Two maps were merged at `query`.
  virtual void maps_merged(KeyframeId query) { loop_closed(query); }
  // Keypoint pairs (query keypoint, candidate keypoint), both observing live map points, that likely
  // show the same point: the input of the shared geometric check. Each detector matches the way
  // its candidates allow (words of a vocabulary, plain descriptors, ...).
  virtual std::vector<std::pair<std::uint32_t, std::uint32_t>> match(const Map& map, KeyframeId query,
                                                                     KeyframeId candidate) const = 0;
};

}  // namespace heslam
