// ORB-SLAM2's DetectLoop over the keyframe database: candidates that score at least as well as the
// query's worst covisible neighbour, kept only when their covisibility groups are consistent over
// consecutive keyframes.
#pragma once

#include <cstddef>
#include <map>
#include <memory>
#include <set>
#include <utility>
#include <vector>

#include "components/core/loop/loop_detector.hpp"
#include "components/core/place/keyframe_database.hpp"
#include "components/core/place/vocabulary.hpp"
#include "components/core/tracking/bow_search.hpp"

namespace heslam {

struct BowLoopDetectorOptions {
  // ORB-SLAM2 does not look for loops in a map of fewer than 10 keyframes, nor within 10 keyframes
  // after the last loop it closed.
  int min_keyframes_in_map = 10;
  int keyframes_after_loop = 10;
  // A candidate group must be consistent (share a keyframe) with groups of this many consecutive
  // queries before it is verified (ORB-SLAM2: 3).
  int consistency_threshold = 3;
  PlaceQueryOptions query;
  BowSearchOptions matching;  // ORB-SLAM2 ComputeSim3: ratio 0.75, TH_LOW, orientation check
};

class BowLoopDetector final : public LoopDetector {
 public:
  BowLoopDetector(std::shared_ptr<const Vocabulary> vocabulary, const BowLoopDetectorOptions& options);

  const char* name() const override { return "bow"; }
  LoopCandidates detect(const Map& map, KeyframeId query) override;
  void loop_closed(KeyframeId query) override;
  // The keyframe database's merge query with the loops' minimum score (none for a keyframe without
  // covisible keyframes: a new map's first) and consistency check, kept per active map; the candidates
  // not consistent yet come back as `unconfirmed` (the best 3).
  LoopCandidates detect_merge(const Map& map, KeyframeId query, const std::set<KeyframeId>& other_maps) override;
  void maps_merged(KeyframeId query) override;
  // ORB-SLAM2 SearchByBoW(KF, KF) with these options.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> match(const Map& map, KeyframeId query,
                                                             KeyframeId candidate) const override;

  const KeyframeDatabase& database() const { return database_; }

 private:
  struct ConsistentGroup {
    std::set<KeyframeId> keyframes;
    int consistency = 0;
  };

  // Consistency: keeps candidates whose group shares a keyframe with groups of `groups` over
  // consistency_threshold consecutive queries (ORB-SLAM2); updates `groups`.
  void consistent(const Map& map, const std::vector<PlaceCandidate>& candidates, std::vector<ConsistentGroup>& groups,
                  LoopCandidates& result) const;
  double covisible_min_score(const Map& map, const Keyframe& keyframe) const;

  BowLoopDetectorOptions options_;
  std::shared_ptr<const Vocabulary> vocabulary_;  // the database refers to it
  KeyframeDatabase database_;
  std::vector<ConsistentGroup> groups_;
  // The same, for candidates in other maps, per active map: the keyframes of two agents (two maps)
  // interleave, and one agent's queries must not reset the other's consistency.
  std::map<MapId, std::vector<ConsistentGroup>> merge_groups_;
  int keyframes_since_loop_;
};

}  // namespace heslam
