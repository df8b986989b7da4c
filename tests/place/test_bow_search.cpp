// BoW matching (ORB-SLAM2 SearchByBoW) with a known answer: a keyframe's descriptors seen again in a
// frame with a few bits flipped and in another order must match their own copies only, keyframe
// features without a map point never match, and matches whose orientation disagrees are dropped.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "components/core/place/keyframe_database.hpp"
#include "components/core/tracking/bow_search.hpp"
#include "hand_built_vocabulary.hpp"

namespace heslam {
namespace {

using test::HandBuiltVocabulary;

constexpr int kFeatures = 300;
constexpr int kNoiseBits = 5;
// The tree has 2 levels: match at its first level (4 nodes), as kBowMatchLevelsUp does on 6 levels.
constexpr int kLevelsUp = 1;

PinholeStereo camera() { return test::synthetic_camera(); }

Descriptor with_flipped_bits(Descriptor d, std::mt19937_64& rng, int bits) {
  for (int b = 0; b < bits; ++b) {
    const std::uint64_t at = rng() % 256;
    d[at / 8] ^= static_cast<std::uint8_t>(1u << (at % 8));
  }
  return d;
}

struct Scene {
  Map map;
  Keyframe keyframe;
  StereoFeatures frame_features;
  std::vector<std::uint32_t> frame_index_of;  // keyframe feature i is frame feature frame_index_of[i]
};

// Keyframe features with map points (all but every 10th), the frame holding the same features with
// noise, shuffled, all rotated by 30 degrees (a consistent in-plane rotation).
Scene make_scene(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Scene scene;
  Keyframe& kf = scene.keyframe;
  kf.id = 1;
  std::vector<std::uint32_t> order(kFeatures);
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin(), order.end(), rng);
  scene.frame_index_of = order;
  scene.frame_features.keypoints.resize(kFeatures);
  scene.frame_features.descriptors.resize(kFeatures);
  scene.frame_features.u_right_px.assign(kFeatures, kNoStereo);
  scene.frame_features.depth_m.assign(kFeatures, kNoStereo);
  for (int i = 0; i < kFeatures; ++i) {
    const Descriptor d = HandBuiltVocabulary::random_descriptor(rng);
    Keypoint kp;
    kp.u_px = static_cast<float>(rng() % 640);
    kp.v_px = static_cast<float>(rng() % 480);
    kp.angle_deg = static_cast<float>(rng() % 300);
    kf.features.keypoints.push_back(kp);
    kf.features.descriptors.push_back(d);
    kf.features.u_right_px.push_back(kNoStereo);
    kf.features.depth_m.push_back(kNoStereo);
    const PointId point = i % 10 == 9 ? kNoId : static_cast<PointId>(100 + i);
    kf.point_ids.push_back(point);
    if (point != kNoId) scene.map.points[point].id = point;
    Keypoint seen = kp;
    seen.angle_deg = kp.angle_deg + 30.f;
    scene.frame_features.keypoints[order[static_cast<std::size_t>(i)]] = seen;
    scene.frame_features.descriptors[order[static_cast<std::size_t>(i)]] = with_flipped_bits(d, rng, kNoiseBits);
  }
  scene.map.keyframes[kf.id] = kf;
  return scene;
}

FeatureVector features_of(const Vocabulary& vocabulary, std::span<const Descriptor> descriptors) {
  BowVector bow;
  FeatureVector features;
  vocabulary.transform(descriptors, bow, &features, kLevelsUp);
  return features;
}

TEST(BowSearch, KeyframePointsMatchTheirOwnFeaturesInTheFrame) {
  const HandBuiltVocabulary v;
  const Scene scene = make_scene(11);
  Frame frame(0, 1, scene.frame_features, camera());
  const FeatureVector frame_fv = features_of(v.vocabulary(), frame.features.descriptors);
  const FeatureVector keyframe_fv = features_of(v.vocabulary(), scene.keyframe.features.descriptors);
  const int matches =
      search_keyframe_by_bow(frame, frame_fv, scene.keyframe, keyframe_fv, scene.map, BowSearchOptions{});

  int correct = 0;
  int with_point = 0;
  for (int i = 0; i < kFeatures; ++i) {
    const PointId point = scene.keyframe.point_ids[static_cast<std::size_t>(i)];
    const PointId matched = frame.point_ids[scene.frame_index_of[static_cast<std::size_t>(i)]];
    if (point == kNoId) {
      EXPECT_EQ(matched, kNoId) << "feature " << i << " has no map point and must not be matched";
      continue;
    }
    ++with_point;
    correct += matched == point ? 1 : 0;
  }
  int assigned = 0;
  for (const PointId id : frame.point_ids) assigned += id != kNoId ? 1 : 0;
  EXPECT_EQ(assigned, matches);
  EXPECT_EQ(correct, matches) << "every match is the feature's own copy";
  // A noisy copy can descend into another first-level node than the original (then it cannot match):
  // most stay.
  EXPECT_GE(matches, with_point * 8 / 10);
}

TEST(BowSearch, InconsistentOrientationIsRejected) {
  const HandBuiltVocabulary v;
  Scene scene = make_scene(12);
  // A fifth of the frame's features turned by 60-300 degrees more, each its own way: not the image's
  // rotation, and spread over many histogram bins.
  std::mt19937_64 rng(5);
  for (int i = 0; i < kFeatures; i += 5) {
    Keypoint& kp = scene.frame_features.keypoints[scene.frame_index_of[static_cast<std::size_t>(i)]];
    kp.angle_deg = std::fmod(kp.angle_deg + 60.f + static_cast<float>(rng() % 240), 360.f);
  }
  Frame frame(0, 1, scene.frame_features, camera());
  const FeatureVector frame_fv = features_of(v.vocabulary(), frame.features.descriptors);
  const FeatureVector keyframe_fv = features_of(v.vocabulary(), scene.keyframe.features.descriptors);
  search_keyframe_by_bow(frame, frame_fv, scene.keyframe, keyframe_fv, scene.map, BowSearchOptions{});
  for (int i = 0; i < kFeatures; i += 5) {
    EXPECT_EQ(frame.point_ids[scene.frame_index_of[static_cast<std::size_t>(i)]], kNoId) << "feature " << i;
  }
  BowSearchOptions no_check;
  no_check.check_orientation = false;
  Frame unchecked(0, 1, scene.frame_features, camera());
  int kept_turned = 0;
  search_keyframe_by_bow(unchecked, frame_fv, scene.keyframe, keyframe_fv, scene.map, no_check);
  for (int i = 0; i < kFeatures; i += 5) {
    kept_turned += unchecked.point_ids[scene.frame_index_of[static_cast<std::size_t>(i)]] != kNoId ? 1 : 0;
  }
  EXPECT_GT(kept_turned, 0) << "without the check the turned features match";
}

TEST(BowSearch, KeyframeAgainstKeyframeGivesIndexPairs) {
  const HandBuiltVocabulary v;
  const Scene scene = make_scene(13);
  Map map = scene.map;
  Keyframe other;
  other.id = 2;
  other.features = scene.frame_features;
  for (std::size_t k = 0; k < other.features.size(); ++k) {
    other.point_ids.push_back(500 + k);
    map.points[500 + k].id = 500 + k;
  }
  const auto pairs =
      match_keyframes_by_bow(scene.keyframe, features_of(v.vocabulary(), scene.keyframe.features.descriptors), other,
                             features_of(v.vocabulary(), other.features.descriptors), map, BowSearchOptions{});
  ASSERT_FALSE(pairs.empty());
  for (std::size_t m = 0; m < pairs.size(); ++m) {
    EXPECT_EQ(pairs[m].b, scene.frame_index_of[pairs[m].a]);
    EXPECT_NE(scene.keyframe.point_ids[pairs[m].a], kNoId);
    if (m > 0) {
      EXPECT_LT(pairs[m - 1].a, pairs[m].a);
    }
  }
  // A culled point on one side takes its feature out.
  map.points[scene.keyframe.point_ids[pairs[0].a]].culled = true;
  const auto fewer =
      match_keyframes_by_bow(scene.keyframe, features_of(v.vocabulary(), scene.keyframe.features.descriptors), other,
                             features_of(v.vocabulary(), other.features.descriptors), map, BowSearchOptions{});
  EXPECT_EQ(fewer.size() + 1, pairs.size());
}

}  // namespace
}  // namespace heslam
