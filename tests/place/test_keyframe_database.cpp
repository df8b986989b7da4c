// The keyframe database on a hand-built vocabulary with known words: inverted index add / erase /
// sync, ORB-SLAM2's loop and relocalization queries (exclusions, min score, group accumulation), and
// deterministic results.
#include <gtest/gtest.h>

#include <algorithm>

#include "components/core/place/keyframe_database.hpp"
#include "hand_built_vocabulary.hpp"

namespace heslam {
namespace {

using test::HandBuiltVocabulary;

// A map keyframe holding these words (features carry the descriptors only).
Keyframe keyframe_with(KeyframeId id, const HandBuiltVocabulary& vocabulary, const std::vector<WordId>& words) {
  Keyframe keyframe;
  keyframe.id = id;
  keyframe.features.descriptors = vocabulary.image(words);
  keyframe.features.keypoints.resize(words.size());
  keyframe.point_ids.assign(words.size(), kNoId);
  return keyframe;
}

void link(Map& map, KeyframeId a, KeyframeId b, int weight) {
  map.keyframe(a)->covisible.emplace_back(b, weight);
  map.keyframe(b)->covisible.emplace_back(a, weight);
}

std::vector<KeyframeId> ids(const std::vector<PlaceCandidate>& candidates) {
  std::vector<KeyframeId> out;
  for (const auto& c : candidates) out.push_back(c.id);
  return out;
}

BowVector bow_of(const HandBuiltVocabulary& v, const std::vector<WordId>& words) {
  BowVector bow;
  v.vocabulary().transform(v.image(words), bow, nullptr, 0);
  return bow;
}

TEST(KeyframeDatabase, AddFindsAndEraseForgets) {
  const HandBuiltVocabulary v;
  KeyframeDatabase database(v.vocabulary());
  database.add(5, v.image({0, 1, 2, 3}));
  database.add(6, v.image({8, 9, 10}));
  EXPECT_EQ(database.size(), 2u);
  ASSERT_NE(database.bow(5), nullptr);
  EXPECT_EQ(database.bow(5)->size(), 4u);
  ASSERT_NE(database.features(6), nullptr);
  const Map map;
  EXPECT_EQ(ids(database.relocalization_candidates(bow_of(v, {0, 1, 2}), map)), std::vector<KeyframeId>{5});
  EXPECT_EQ(ids(database.relocalization_candidates(bow_of(v, {8, 9}), map)), std::vector<KeyframeId>{6});
  database.erase(5);
  EXPECT_FALSE(database.contains(5));
  EXPECT_TRUE(database.relocalization_candidates(bow_of(v, {0, 1, 2}), map).empty());
  // Adding again replaces: the old words are gone from the index.
  database.add(6, v.image({0, 1}));
  EXPECT_TRUE(database.relocalization_candidates(bow_of(v, {8, 9}), map).empty());
  EXPECT_EQ(ids(database.relocalization_candidates(bow_of(v, {0}), map)), std::vector<KeyframeId>{6});
  database.clear();
  EXPECT_EQ(database.size(), 0u);
  EXPECT_TRUE(database.relocalization_candidates(bow_of(v, {0}), map).empty());
}

TEST(KeyframeDatabase, SyncHoldsExactlyTheMapsLiveKeyframes) {
  const HandBuiltVocabulary v;
  KeyframeDatabase database(v.vocabulary());
  Map map;
  for (KeyframeId id : {1, 2, 3}) map.keyframes[id] = keyframe_with(id, v, {static_cast<WordId>(id), 5});
  map.keyframes[2].culled = true;
  DatabaseSync changes = database.sync(map);
  EXPECT_EQ(changes.added, 2);
  EXPECT_EQ(changes.erased, 0);
  EXPECT_TRUE(database.contains(1));
  EXPECT_FALSE(database.contains(2));
  EXPECT_TRUE(database.contains(3));

  changes = database.sync(map);  // nothing changed: nothing transformed
  EXPECT_EQ(changes.added, 0);
  EXPECT_EQ(changes.erased, 0);

  map.keyframes[4] = keyframe_with(4, v, {4, 5});
  map.keyframes[3].culled = true;
  map.keyframes.erase(1);  // vanished (e.g. a map replaced by a loaded one)
  changes = database.sync(map);
  EXPECT_EQ(changes.added, 1);
  EXPECT_EQ(changes.erased, 2);
  EXPECT_EQ(database.size(), 1u);
  EXPECT_TRUE(database.contains(4));
  // The erased keyframes are gone from the inverted index too.
  EXPECT_EQ(ids(database.relocalization_candidates(bow_of(v, {5}), map)), std::vector<KeyframeId>{4});
}

TEST(KeyframeDatabase, LoopCandidatesExcludeTheQueryAndItsCovisibleKeyframes) {
  const HandBuiltVocabulary v;
  Map map;
  map.keyframes[1] = keyframe_with(1, v, {0, 1, 2, 3, 4});  // the place, long ago
  map.keyframes[2] = keyframe_with(2, v, {9, 10, 11});      // elsewhere
  map.keyframes[8] = keyframe_with(8, v, {0, 1, 2, 3, 4});  // the same place, seen just now
  map.keyframes[9] = keyframe_with(9, v, {0, 1, 2, 3, 4});  // the query
  link(map, 8, 9, 100);
  KeyframeDatabase database(v.vocabulary());
  database.sync(map);
  EXPECT_EQ(ids(database.loop_candidates(9, map, 0.0)), std::vector<KeyframeId>{1});
  // min_score: a keyframe sharing one word of five scores 0.2 here.
  map.keyframes[1] = keyframe_with(1, v, {0, 12, 13, 14, 15});
  database.sync(map);
  database.add(1, map.keyframes[1].features.descriptors);
  const auto low = database.loop_candidates(9, map, 0.0);
  ASSERT_EQ(low.size(), 1u);
  EXPECT_NEAR(low[0].score, 0.2, 1e-6);
  EXPECT_EQ(low[0].common_words, 1);
  EXPECT_TRUE(database.loop_candidates(9, map, 0.3).empty());
  EXPECT_TRUE(database.loop_candidates(77, map, 0.0).empty());  // not in the database
}

TEST(KeyframeDatabase, MergeCandidatesComeOnlyFromTheOtherMaps) {
  const HandBuiltVocabulary v;
  Map map;
  map.keyframes[1] = keyframe_with(1, v, {0, 1, 2, 3});     // another map: the place, a bit different
  map.keyframes[2] = keyframe_with(2, v, {9, 10, 11});      // another map: elsewhere
  map.keyframes[8] = keyframe_with(8, v, {0, 1, 2, 3, 4});  // the query's own map: the same place
  map.keyframes[9] = keyframe_with(9, v, {0, 1, 2, 3, 4});  // the query
  KeyframeDatabase database(v.vocabulary());
  database.sync(map);
  // A loop query answers with the own map's keyframe 8 first (it scores best), the merge query with 1 only.
  EXPECT_EQ(ids(database.loop_candidates(9, map, 0.0)).front(), 8u);
  const auto merge = database.merge_candidates(9, {1, 2}, map, 0.0);
  ASSERT_EQ(ids(merge), std::vector<KeyframeId>{1});
  EXPECT_NEAR(merge[0].score, 0.8, 1e-6);
  EXPECT_TRUE(database.merge_candidates(9, {1, 2}, map, 0.9).empty());  // min_score
  EXPECT_TRUE(database.merge_candidates(9, {}, map, 0.0).empty());      // no other map
}

TEST(KeyframeDatabase, GroupAccumulationAnswersWithTheBestOfAGroup) {
  const HandBuiltVocabulary v;
  Map map;
  // A group of three covisible keyframes that each resemble the query, and a lone keyframe that
  // resembles it a bit more than any one of them but has no neighbours to back it up.
  map.keyframes[10] = keyframe_with(10, v, {0, 1, 2, 12, 13});  // 3 of 5 words
  map.keyframes[11] = keyframe_with(11, v, {0, 1, 2, 3, 14});   // 4 of 5: the group's best
  map.keyframes[12] = keyframe_with(12, v, {0, 1, 2, 13, 14});  // 3 of 5
  map.keyframes[20] = keyframe_with(20, v, {0, 1, 2, 3, 15});   // 4 of 5, alone
  link(map, 10, 11, 50);
  link(map, 11, 12, 40);
  link(map, 10, 12, 30);
  KeyframeDatabase database(v.vocabulary());
  database.sync(map);
  const BowVector query = bow_of(v, {0, 1, 2, 3, 4});
  PlaceQueryOptions options;
  options.min_common_words_ratio = 0.5f;  // let the 3-word keyframes take part
  const auto candidates = database.relocalization_candidates(query, map, options);
  // Group {10, 11, 12}: 0.6 + 0.8 + 0.6 = 2.0; keyframe 20 alone: 0.8 < 0.75 x 2.0.
  ASSERT_EQ(ids(candidates), std::vector<KeyframeId>{11});
  EXPECT_NEAR(candidates[0].score, 0.8, 1e-6);
  EXPECT_NEAR(candidates[0].accumulated_score, 2.0, 1e-6);

  // With the default 0.8 ratio only 4-word keyframes count: 11 and 20 tie (0.8 each), both answer,
  // ordered by id.
  EXPECT_EQ(ids(database.relocalization_candidates(query, map)), (std::vector<KeyframeId>{11, 20}));
}

TEST(KeyframeDatabase, RelocalizationCandidatesRankTheSamePlaceFirst) {
  const HandBuiltVocabulary v;
  Map map;
  for (KeyframeId id = 1; id <= 12; ++id) {
    // Keyframe id holds words id-1 .. id+2 (mod 16): neighbours in id share words.
    std::vector<WordId> words;
    for (int w = -1; w <= 2; ++w) words.push_back(static_cast<WordId>((static_cast<int>(id) + w + 16) % 16));
    map.keyframes[id] = keyframe_with(id, v, words);
  }
  KeyframeDatabase database(v.vocabulary());
  database.sync(map);
  const auto candidates = database.relocalization_candidates(bow_of(v, {6, 7, 8, 9}), map);
  ASSERT_FALSE(candidates.empty());
  EXPECT_EQ(candidates.front().id, 7u);
  EXPECT_NEAR(candidates.front().score, 1.0, 1e-6);
  for (std::size_t i = 1; i < candidates.size(); ++i) EXPECT_LE(candidates[i].score, candidates[i - 1].score);
}

TEST(KeyframeDatabase, ResultsDoNotDependOnInsertionOrder) {
  const HandBuiltVocabulary v;
  Map map;
  std::mt19937_64 rng(3);
  for (KeyframeId id = 1; id <= 40; ++id) {
    std::vector<WordId> words;
    for (int k = 0; k < 6; ++k) words.push_back(static_cast<WordId>(rng() % 16));
    map.keyframes[id] = keyframe_with(id, v, words);
    if (id > 1) link(map, id, id - 1, 20 + static_cast<int>(rng() % 20));
  }
  for (auto& [id, keyframe] : map.keyframes) {
    std::stable_sort(keyframe.covisible.begin(), keyframe.covisible.end(),
                     [](const auto& a, const auto& b) { return a.second > b.second; });
  }
  KeyframeDatabase forward(v.vocabulary());
  forward.sync(map);
  KeyframeDatabase backward(v.vocabulary());
  for (auto it = map.keyframes.rbegin(); it != map.keyframes.rend(); ++it)
    backward.add(it->first, it->second.features.descriptors);
  const BowVector query = bow_of(v, {1, 2, 3, 5, 8, 13});
  const auto a = forward.relocalization_candidates(query, map);
  const auto b = backward.relocalization_candidates(query, map);
  ASSERT_EQ(ids(a), ids(b));
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].score, b[i].score);
    EXPECT_EQ(a[i].accumulated_score, b[i].accumulated_score);
  }
  EXPECT_EQ(ids(forward.loop_candidates(20, map, 0.0)), ids(backward.loop_candidates(20, map, 0.0)));
}

}  // namespace
}  // namespace heslam
