// The keyframe database: inverted index maintenance and ORB-SLAM2's loop / relocalization queries.
#include "components/core/place/keyframe_database.hpp"

#include <algorithm>
#include <unordered_map>

namespace heslam {
namespace {

// What the first pass of a query learns about one keyframe sharing words with the query.
struct Sharing {
  int common_words = 0;
  double score = 0.0;
  bool scored = false;  // shares enough words (the common-words threshold) to be scored
};
using SharingTable = std::unordered_map<KeyframeId, Sharing>;

// Keyframes whose neighbourhoods are compared: best-first, score then id (deterministic).
bool ranks_before(const PlaceCandidate& a, const PlaceCandidate& b) {
  if (a.score != b.score) return a.score > b.score;
  return a.id < b.id;
}

// Steps 3-5 of both ORB-SLAM2 queries, once the words are counted: keyframes with enough common
// words are scored; each one above `min_score` forms a group with its best covisible keyframes that
// were scored too; the group's accumulated score decides, and the best keyframe of each retained
// group answers. `table` holds every keyframe sharing at least one word (query and excluded ones
// already left out).
std::vector<PlaceCandidate> rank_groups(const BowVector& query, SharingTable& table, const KeyframeDatabase& database,
                                        const Map& map, double min_score, const PlaceQueryOptions& options) {
  if (table.empty()) return {};
  int max_common = 0;
  for (const auto& [id, sharing] : table) max_common = std::max(max_common, sharing.common_words);
  const double min_common = options.min_common_words_ratio * static_cast<double>(max_common);

  std::vector<PlaceCandidate> scored;
  for (auto& [id, sharing] : table) {
    if (static_cast<double>(sharing.common_words) < min_common) continue;
    sharing.score = database.vocabulary().score(query, *database.bow(id));
    sharing.scored = true;
    if (sharing.score >= min_score) scored.push_back({id, sharing.score, 0.0, sharing.common_words});
  }
  if (scored.empty()) return {};
  std::sort(scored.begin(), scored.end(), ranks_before);

  // Accumulate over each candidate's group; remember the group's best member.
  std::vector<PlaceCandidate> best_of_group;
  best_of_group.reserve(scored.size());
  double best_accumulated = 0.0;
  for (const PlaceCandidate& candidate : scored) {
    PlaceCandidate best = candidate;
    double accumulated = candidate.score;
    if (const Keyframe* keyframe = map.keyframe(candidate.id)) {
      const std::size_t group =
          std::min(keyframe->covisible.size(), static_cast<std::size_t>(std::max(options.group_size, 0)));
      for (std::size_t n = 0; n < group; ++n) {
        const KeyframeId neighbour = keyframe->covisible[n].first;
        const auto it = table.find(neighbour);
        if (it == table.end() || !it->second.scored) continue;
        accumulated += it->second.score;
        const PlaceCandidate member{neighbour, it->second.score, 0.0, it->second.common_words};
        if (ranks_before(member, best)) best = member;
      }
    }
    best.accumulated_score = accumulated;
    best_accumulated = std::max(best_accumulated, accumulated);
    best_of_group.push_back(best);
  }

  // Groups close to the best one; a keyframe that is the best of several groups answers once, with
  // its largest group score.
  const double retain = options.retain_ratio * best_accumulated;
  std::map<KeyframeId, PlaceCandidate> retained;
  for (const PlaceCandidate& candidate : best_of_group) {
    if (candidate.accumulated_score <= retain && candidate.accumulated_score < best_accumulated) continue;
    auto [it, inserted] = retained.emplace(candidate.id, candidate);
    if (!inserted) it->second.accumulated_score = std::max(it->second.accumulated_score, candidate.accumulated_score);
  }
  std::vector<PlaceCandidate> out;
  out.reserve(retained.size());
  for (const auto& [id, candidate] : retained) out.push_back(candidate);
  std::sort(out.begin(), out.end(), ranks_before);
  return out;
}

}  // namespace

KeyframeDatabase::KeyframeDatabase(const Vocabulary& vocabulary)
    : vocabulary_(&vocabulary), inverted_(vocabulary.word_count()) {}

void KeyframeDatabase::add(KeyframeId id, std::span<const Descriptor> descriptors) {
  BowVector bow;
  FeatureVector features;
  vocabulary_->transform(descriptors, bow, &features, kBowMatchLevelsUp);
  add(id, std::move(bow), std::move(features));
}

void KeyframeDatabase::add(KeyframeId id, BowVector bow, FeatureVector features) {
  erase(id);
  for (const auto& [word, weight] : bow.entries) {
    if (word >= inverted_.size()) continue;  // not this vocabulary's word: nothing to index
    std::vector<KeyframeId>& list = inverted_[word];
    // Ids usually grow, so this is an append; an older id is placed in order.
    list.insert(std::upper_bound(list.begin(), list.end(), id), id);
  }
  entries_[id] = Entry{std::move(bow), std::move(features)};
}

void KeyframeDatabase::erase(KeyframeId id) {
  const auto it = entries_.find(id);
  if (it == entries_.end()) return;
  for (const auto& [word, weight] : it->second.bow.entries) {
    if (word >= inverted_.size()) continue;
    std::vector<KeyframeId>& list = inverted_[word];
    const auto at = std::lower_bound(list.begin(), list.end(), id);
    if (at != list.end() && *at == id) list.erase(at);
  }
  entries_.erase(it);
}

void KeyframeDatabase::clear() {
  entries_.clear();
  for (auto& list : inverted_) list.clear();
}

DatabaseSync KeyframeDatabase::sync(const Map& map) {
  // One merge pass over the two id-ordered containers.
  DatabaseSync changes;
  std::vector<KeyframeId> stale;
  auto entry = entries_.begin();
  for (const auto& [id, keyframe] : map.keyframes) {
    while (entry != entries_.end() && entry->first < id) stale.push_back((entry++)->first);
    const bool held = entry != entries_.end() && entry->first == id;
    if (held) ++entry;
    if (keyframe.culled) {
      if (held) stale.push_back(id);
    } else if (!held) {
      add(id, keyframe.features.descriptors);  // entries_ grows behind `entry`: ids above stay valid
      ++changes.added;
    }
  }
  while (entry != entries_.end()) stale.push_back((entry++)->first);
  for (const KeyframeId id : stale) erase(id);
  changes.erased = static_cast<int>(stale.size());
  return changes;
}

const BowVector* KeyframeDatabase::bow(KeyframeId id) const {
  const auto it = entries_.find(id);
  return it == entries_.end() ? nullptr : &it->second.bow;
}

const FeatureVector* KeyframeDatabase::features(KeyframeId id) const {
  const auto it = entries_.find(id);
  return it == entries_.end() ? nullptr : &it->second.features;
}

std::vector<PlaceCandidate> KeyframeDatabase::loop_candidates(KeyframeId query, const Map& map, double min_score,
                                                              const PlaceQueryOptions& options) const {
  const BowVector* query_bow = bow(query);
  if (query_bow == nullptr) return {};
  // The query's covisible keyframes see the same place now; a loop is a place seen long ago.
  std::vector<KeyframeId> excluded{query};
  if (const Keyframe* keyframe = map.keyframe(query)) {
    for (const auto& [neighbour, weight] : keyframe->covisible) excluded.push_back(neighbour);
  }
  std::sort(excluded.begin(), excluded.end());

  SharingTable table;
  for (const auto& [word, weight] : query_bow->entries) {
    if (word >= inverted_.size()) continue;
    for (const KeyframeId id : inverted_[word]) {
      if (std::binary_search(excluded.begin(), excluded.end(), id)) continue;
      ++table[id].common_words;
    }
  }
  return rank_groups(*query_bow, table, *this, map, min_score, options);
}

std::vector<PlaceCandidate> KeyframeDatabase::merge_candidates(KeyframeId query, const std::set<KeyframeId>& among,
                                                               const Map& map, double min_score,
                                                               const PlaceQueryOptions& options) const {
  const BowVector* query_bow = bow(query);
  if (query_bow == nullptr || among.empty()) return {};
  SharingTable table;
  for (const auto& [word, weight] : query_bow->entries) {
    if (word >= inverted_.size()) continue;
    for (const KeyframeId id : inverted_[word]) {
      if (id != query && among.count(id) != 0) ++table[id].common_words;
    }
  }
  return rank_groups(*query_bow, table, *this, map, min_score, options);
}

std::vector<PlaceCandidate> KeyframeDatabase::relocalization_candidates(const BowVector& query, const Map& map,
                                                                        const PlaceQueryOptions& options) const {
  SharingTable table;
  for (const auto& [word, weight] : query.entries) {
    if (word >= inverted_.size()) continue;
    for (const KeyframeId id : inverted_[word]) ++table[id].common_words;
  }
  return rank_groups(query, table, *this, map, /*min_score=*/0.0, options);
}

}  // namespace heslam
