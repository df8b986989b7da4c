// The keyframe database: an inverted index word -> keyframes over the BoW vectors of a map's
// keyframes, answering ORB-SLAM2's two place queries (loop candidates for a keyframe, relocalization
// candidates for a lost frame). Holds each keyframe's BoW and feature vector so matchers can use them.
//
// Not thread-safe; one owner (the frontend's tracker, a loop closer). Results are ordered (score
// descending, then id) so lockstep runs stay bit-identical.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <span>
#include <vector>

#include "components/core/feature/features.hpp"
#include "components/core/map/map.hpp"
#include "components/core/place/bow_vector.hpp"
#include "components/core/place/vocabulary.hpp"

namespace heslam {

struct PlaceCandidate {
  KeyframeId id = kNoId;
  double score = 0.0;              // vocabulary score against the query
  double accumulated_score = 0.0;  // summed over its covisible group (ORB-SLAM2)
  int common_words = 0;
};

struct PlaceQueryOptions {
  // ORB-SLAM2: candidates need at least 0.8 x the largest number of words any keyframe shares.
  float min_common_words_ratio = 0.8f;
  // Candidates' groups are their best covisible keyframes (ORB-SLAM2: 10).
  int group_size = 10;
  // Groups kept: accumulated score above this ratio of the best group's (ORB-SLAM2: 0.75).
  float retain_ratio = 0.75f;
};

struct DatabaseSync {
  int added = 0;
  int erased = 0;
};

class KeyframeDatabase {
 public:
  // The vocabulary must outlive the database.
  explicit KeyframeDatabase(const Vocabulary& vocabulary);

  const Vocabulary& vocabulary() const { return *vocabulary_; }

  // Adds (or replaces) a keyframe, transforming its descriptors (feature vector at
  // `levels_up` = 4 levels above the leaves, as ORB-SLAM2).
  void add(KeyframeId id, std::span<const Descriptor> descriptors);
  void add(KeyframeId id, BowVector bow, FeatureVector features);
  void erase(KeyframeId id);
  void clear();

  // Makes the database hold exactly the map's keyframes that are not culled: transforms new ones,
  // erases culled or vanished ones. Cheap when nothing changed (one pass over ids).
  DatabaseSync sync(const Map& map);

  bool contains(KeyframeId id) const { return entries_.count(id) != 0; }
  std::size_t size() const { return entries_.size(); }
  const BowVector* bow(KeyframeId id) const;
  const FeatureVector* features(KeyframeId id) const;

  // ORB-SLAM2 DetectLoopCandidates: keyframes sharing words with `query` (which must be in the
  // database), excluding the query and its covisible keyframes in `map`, scoring at least
  // `min_score`, grouped with their covisible neighbours; the best of each retained group.
  std::vector<PlaceCandidate> loop_candidates(KeyframeId query, const Map& map, double min_score,
                                              const PlaceQueryOptions& options = {}) const;

  // The atlas's merge query (ORB-SLAM3 DetectCommonRegions' BoW step): as loop_candidates, but only
  // keyframes in `among` answer (the keyframes of the maps other than the query's); the query's own
  // map cannot crowd them out of the ranking.
  std::vector<PlaceCandidate> merge_candidates(KeyframeId query, const std::set<KeyframeId>& among, const Map& map,
                                               double min_score, const PlaceQueryOptions& options = {}) const;

  // ORB-SLAM2 DetectRelocalizationCandidates for a frame's BoW vector (all keyframes may answer).
  std::vector<PlaceCandidate> relocalization_candidates(const BowVector& bow, const Map& map,
                                                        const PlaceQueryOptions& options = {}) const;

 private:
  struct Entry {
    BowVector bow;
    FeatureVector features;
  };

  const Vocabulary* vocabulary_;
  std::map<KeyframeId, Entry> entries_;
  std::vector<std::vector<KeyframeId>> inverted_;  // per word: keyframes containing it, ascending
};

// ORB-SLAM2's feature-vector level for matching keyframes by BoW.
inline constexpr int kBowMatchLevelsUp = 4;

}  // namespace heslam
