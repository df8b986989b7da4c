// Map merging on exact synthetic geometry: one ring scene (loop_world.hpp) mapped twice, map B in the
// world frame and map A (started later, the same place seen again further round) in a frame turned
// and shifted by a known T_AW. Noise-free: the shared SE(3) verification recovers T_BA = T_AW^-1 to
// 1e-6, the merge puts every keyframe of A at its true pose in B's frame, fuses A's duplicates of B's
// points into B's, and the gate rejects a merge that implies impossible unobserved motion.
#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <set>

#include "components/core/loop/loop_closing.hpp"
#include "components/core/loop/map_merge.hpp"
#include "components/core/loop/proximity_loop_detector.hpp"
#include "components/core/mapping/correction_application.hpp"
#include "tests/loop/loop_world.hpp"

namespace heslam {
namespace {

constexpr int kPerTurn = 36;  // 10 deg between keyframes
constexpr int kFirstOfB = 0;  // map B: ring keyframes 0..14
constexpr int kLastOfB = 14;
constexpr int kFirstOfA = 10;  // map A: ring keyframes 10..24, 5 cm further out (same place, other views)
constexpr int kLastOfA = 24;
constexpr KeyframeId kIdOffsetA = 100;
constexpr MapId kMapB = 3;  // the older map
constexpr MapId kMapA = 5;  // the active one
constexpr double kExact = 1e-6;
// Points are triangulated from float keypoints and depths (ulp 6e-5 px at u = 700, on a 6 px
// disparity at 8 m: up to 1e-4 m).
constexpr double kPointExact = 1e-4;

struct TwoMaps {
  test::SyntheticWorld world;
  Map map;
  std::set<KeyframeId> map_a;
  std::set<KeyframeId> map_b;
  std::map<KeyframeId, Pose3> true_T_wc;  // world = B's frame
  std::map<PointId, int> truth_of_point;
  std::map<KeyframeId, std::vector<int>> truth_of_keypoint;
  Pose3 T_AW = Pose3::Identity();
};

Pose3 known_T_AW() {
  Pose3 T = Pose3::Identity();
  T.linear() = (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(3.0, -0.5, 12.0);
  return T;
}

// Keyframes observe every point of their own map they see; points never cross maps.
TwoMaps make_two_maps(std::int64_t gap_ns) {
  test::LoopWorldOptions ring;
  TwoMaps result;
  result.T_AW = known_T_AW();
  // The ring's points, descriptors and octaves (make_loop_world's scene; its map is not used).
  result.world = test::make_loop_world(ring).world;
  test::ViewOptions view_options;
  view_options.clutter = 20;
  view_options.pixel_noise_px = 0.0;
  std::uint64_t counter = 0;
  std::int64_t last_b_stamp_ns = 0;
  const auto build = [&](int first, int last, KeyframeId offset, double radius_m, const Pose3& T_frame_w,
                         std::set<KeyframeId>& members, std::int64_t stamp_offset_ns, MapId map_id) {
    std::map<int, PointId> point_of_truth;
    for (int k = first; k <= last; ++k) {
      const KeyframeId id = offset + static_cast<KeyframeId>(k + 1);
      const Pose3 T_true = test::ring_pose(k, kPerTurn, radius_m);
      test::SyntheticView view =
          test::make_view(result.world, id, T_true, 900 + static_cast<unsigned>(id), view_options);
      view.kf.T_wc = T_frame_w * T_true;
      view.kf.stamp_ns = stamp_offset_ns + (k - first) * 50'000'000;
      view.kf.parent = k > first ? id - 1 : kNoId;
      view.kf.map_id = map_id;
      result.true_T_wc[id] = T_true;
      result.truth_of_keypoint[id] = view.truth;
      result.map.keyframes.emplace(id, view.kf);
      members.insert(id);
      const Keyframe& kf = result.map.keyframes.at(id);
      for (std::size_t i = 0; i < view.truth.size(); ++i) {
        const int t = view.truth[i];
        if (t < 0) continue;
        if (const auto tracked = point_of_truth.find(t); tracked != point_of_truth.end()) {
          add_observation(result.map, tracked->second, id, static_cast<int>(i));
          continue;
        }
        if (!kf.features.has_stereo(i)) continue;
        MapPoint point;
        point.id = make_id(kFrontendTag, ++counter);
        const Keypoint& kp = kf.features.keypoints[i];
        point.p_w = kf.T_wc * result.world.camera.unproject(kp.u_px, kp.v_px, kf.features.depth_m[i]);
        point.reference_kf = id;
        point.map_id = map_id;
        result.map.points.emplace(point.id, point);
        add_observation(result.map, point.id, id, static_cast<int>(i));
        point_of_truth[t] = point.id;
        result.truth_of_point[point.id] = t;
      }
      last_b_stamp_ns = std::max(last_b_stamp_ns, view.kf.stamp_ns);
    }
  };
  build(kFirstOfB, kLastOfB, 0, 2.0, Pose3::Identity(), result.map_b, 0, kMapB);
  build(kFirstOfA, kLastOfA, kIdOffsetA, 2.05, result.T_AW, result.map_a, last_b_stamp_ns + gap_ns, kMapA);
  for (const auto& [id, point] : result.map.points) update_point_statistics(result.map, id);
  for (const auto& [id, kf] : result.map.keyframes) update_connections(result.map, id, CovisibilityOptions{});
  result.map.version = 9;
  return result;
}

KeyframeId id_of_a(int k) { return kIdOffsetA + static_cast<KeyframeId>(k + 1); }
KeyframeId id_of_b(int k) { return static_cast<KeyframeId>(k + 1); }

// Offers nothing; matches keypoints by their true world point (the verification under test is the
// shared one; detection has its own tests).
class TruthMatcher final : public LoopDetector {
 public:
  explicit TruthMatcher(const TwoMaps& maps, KeyframeId loop_candidate = kNoId)
      : maps_(maps), loop_candidate_(loop_candidate) {}
  const char* name() const override { return "truth"; }
  LoopCandidates detect(const Map&, KeyframeId) override {
    if (loop_candidate_ == kNoId) return {};
    return {{loop_candidate_}, "", {}};
  }
  void loop_closed(KeyframeId) override {}
  std::vector<std::pair<std::uint32_t, std::uint32_t>> match(const Map& map, KeyframeId query,
                                                             KeyframeId candidate) const override {
    std::map<int, std::uint32_t> in_candidate;
    const std::vector<int>& truth_c = maps_.truth_of_keypoint.at(candidate);
    for (std::uint32_t j = 0; j < truth_c.size(); ++j) {
      if (truth_c[j] >= 0 && map.keyframe(candidate)->point_ids[j] != kNoId) in_candidate[truth_c[j]] = j;
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    const std::vector<int>& truth_q = maps_.truth_of_keypoint.at(query);
    for (std::uint32_t i = 0; i < truth_q.size(); ++i) {
      const auto j = in_candidate.find(truth_q[i]);
      if (truth_q[i] >= 0 && map.keyframe(query)->point_ids[i] != kNoId && j != in_candidate.end()) {
        pairs.emplace_back(i, j->second);
      }
    }
    return pairs;
  }

 private:
  const TwoMaps& maps_;
  KeyframeId loop_candidate_;
};

double rotation_error_rad(const Pose3& a, const Pose3& b) {
  return Eigen::AngleAxisd(a.rotation().transpose() * b.rotation()).angle();
}

MapMergeRequest request_for(const TwoMaps& maps, const VerifiedPlace& place, KeyframeId active, KeyframeId matched) {
  MapMergeRequest request;
  request.active_kf = active;
  request.matched_kf = matched;
  request.T_matched_active = place.T_matched_loop;
  request.matched_points = place.matched_points;
  request.active_map = maps.map_a;
  request.matched_map = maps.map_b;
  return request;
}

constexpr std::int64_t kLongGapNs = 60'000'000'000;  // a minute unobserved: any jump is possible

TEST(MapMergeTest, TheSharedVerificationRecoversTheMapsRelativeTransformExactly) {
  const TwoMaps maps = make_two_maps(kLongGapNs);
  const LoopClosing closing(maps.world.camera, std::make_unique<TruthMatcher>(maps), {});
  std::string why;
  const auto place = closing.verify_place(maps.map, id_of_a(12), id_of_b(12), /*drift_gate=*/false, why);
  ASSERT_TRUE(place) << why;
  const Pose3 T_BA =
      maps.map.keyframe(id_of_b(12))->T_wc * place->T_matched_loop * maps.map.keyframe(id_of_a(12))->T_wc.inverse();
  const Pose3 expected = maps.T_AW.inverse();
  EXPECT_LT((T_BA.translation() - expected.translation()).norm(), kExact);
  EXPECT_LT(rotation_error_rad(T_BA, expected), kExact);
  // The loops' drift gate would see 12 m of "drift" on no path travelled: it must not judge merges.
  EXPECT_FALSE(closing.verify_place(maps.map, id_of_a(12), id_of_b(12), /*drift_gate=*/true, why));
  EXPECT_NE(why.find("drift gate"), std::string::npos) << why;
}

TEST(MapMergeTest, TheActiveMapIsWeldedIntoTheOlderMapsFrame) {
  const TwoMaps maps = make_two_maps(kLongGapNs);
  const LoopClosing closing(maps.world.camera, std::make_unique<TruthMatcher>(maps), {});
  std::string why;
  const auto place = closing.verify_place(maps.map, id_of_a(12), id_of_b(12), false, why);
  ASSERT_TRUE(place) << why;
  const MapMergeOutput merged =
      MapMerge().compute(maps.map, maps.world.camera, request_for(maps, *place, id_of_a(12), id_of_b(12)), {});
  ASSERT_TRUE(merged.error.empty()) << merged.error;
  EXPECT_EQ(merged.correction.kind, CorrectionKind::kMerge);
  EXPECT_EQ(merged.stats.moved_keyframes, kLastOfA - kFirstOfA + 1);
  EXPECT_GT(merged.stats.seam_connections, 0);
  EXPECT_GT(merged.stats.seam_ba.free_keyframes, 0);

  // Every keyframe of both maps, at its true pose in B's (= the world) frame.
  ASSERT_EQ(merged.correction.corrected_T_wc.size(), maps.map_a.size() + maps.map_b.size());
  for (const auto& [id, T_wc] : merged.correction.corrected_T_wc) {
    const Pose3& truth = maps.true_T_wc.at(id);
    EXPECT_LT((T_wc.translation() - truth.translation()).norm(), kExact) << format_id(id);
    EXPECT_LT(rotation_error_rad(T_wc, truth), kExact) << format_id(id);
  }

  // Applied as the mapper applies it: A's duplicates of B's points are gone into B's, every point is at
  // its true position, and no world point seen by both maps' seam keyframes is held twice.
  // A keyframe the mapper made in A after the merge's map version (unknown to the loop closer) follows
  // its parent into B's frame and map.
  Map after = maps.map;
  const KeyframeId late = id_of_a(kLastOfA) + 1;
  const Pose3 T_parent_late =
      test::ring_pose(kLastOfA, kPerTurn, 2.05).inverse() * test::ring_pose(kLastOfA + 1, kPerTurn, 2.05);
  Keyframe& late_kf = after.keyframes[late];
  late_kf.id = late;
  late_kf.map_id = kMapA;
  late_kf.parent = id_of_a(kLastOfA);
  late_kf.T_wc = after.keyframes.at(id_of_a(kLastOfA)).T_wc * T_parent_late;
  MapChanges changes;
  EXPECT_EQ(apply_loop_correction(after, merged.correction, {{late, maps.map.version + 1}}, changes), 0);
  EXPECT_EQ(after.keyframes.at(late).map_id, kMapB);
  EXPECT_LT((after.keyframes.at(late).T_wc.translation() - test::ring_pose(kLastOfA + 1, kPerTurn, 2.05).translation())
                .norm(),
            kExact);
  after.keyframes.erase(late);
  ASSERT_GT(merged.stats.point_merges, 100);
  for (const auto& [from, into] : merged.correction.point_merges) {
    EXPECT_EQ(maps.truth_of_point.at(from), maps.truth_of_point.at(into));
    EXPECT_EQ(maps.map_a.count(maps.map.point(from)->reference_kf), 1u) << "the newer map's point is replaced";
    EXPECT_EQ(maps.map_b.count(maps.map.point(into)->reference_kf), 1u) << "the older map's point survives";
  }
  // The input's own error (points triangulated from float keypoints and disparities), A's taken in
  // B's frame through the true T_AW: the merge adds nothing to it.
  const auto error_m = [&maps](PointId id, const Eigen::Vector3d& p_w) {
    return (p_w - maps.world.points_w[static_cast<std::size_t>(maps.truth_of_point.at(id))]).norm();
  };
  double input_error_m = 0.0;
  for (const auto& [id, point] : maps.map.points) {
    const bool of_a = maps.map_a.count(point.reference_kf) != 0;
    input_error_m = std::max(input_error_m, error_m(id, of_a ? maps.T_AW.inverse() * point.p_w : point.p_w));
  }
  EXPECT_LT(input_error_m, kPointExact);
  for (const auto& [id, point] : after.points) {
    EXPECT_LE(error_m(id, point.p_w), input_error_m + kExact) << format_id(id);
  }
  // One map: every keyframe and point of A now carries B's map id.
  for (const auto& [id, kf] : after.keyframes) EXPECT_EQ(kf.map_id, kMapB) << format_id(id);
  for (const auto& [id, point] : after.points) EXPECT_EQ(point.map_id, kMapB) << format_id(id);
  std::map<int, int> holders;
  for (const PointId id : after.keyframe(id_of_a(12))->point_ids) {
    if (id != kNoId) ++holders[maps.truth_of_point.at(id)];
  }
  for (const auto& [truth, count] : holders) EXPECT_EQ(count, 1) << "world point " << truth;
}

TEST(MapMergeTest, TheGateRejectsAMergeThatImpliesImpossibleUnobservedMotion) {
  // A starts 0.1 s after B's last keyframe, but the merge puts A's first keyframe (ring keyframe 10)
  // 1.39 m away from B's last (ring keyframe 14): 13 m/s, more than a walking camera can do.
  const TwoMaps maps = make_two_maps(100'000'000);
  const LoopClosing closing(maps.world.camera, std::make_unique<TruthMatcher>(maps), {});
  std::string why;
  const auto place = closing.verify_place(maps.map, id_of_a(12), id_of_b(12), false, why);
  ASSERT_TRUE(place) << why;
  MapMergeOptions options;
  options.max_unobserved_speed_mps = 2.0;
  options.min_drift_allowance_m = 0.1;
  options.max_drift_fraction = 0.0;
  const MapMergeOutput merged =
      MapMerge(options).compute(maps.map, maps.world.camera, request_for(maps, *place, id_of_a(12), id_of_b(12)), {});
  EXPECT_TRUE(merged.gate_rejected);
  EXPECT_NE(merged.error.find("merge gate: implies 1.39 m"), std::string::npos) << merged.error;
  EXPECT_NE(merged.error.find("travelled unobserved in 0.10 s"), std::string::npos) << merged.error;
  EXPECT_TRUE(merged.correction.corrected_T_wc.empty());

  // The default (10 m/s) allows it.
  EXPECT_TRUE(MapMerge()
                  .compute(maps.map, maps.world.camera, request_for(maps, *place, id_of_a(12), id_of_b(12)), {})
                  .error.empty());
}

TEST(MapMergeTest, TheProximityDetectorFindsTheOtherMapsPlaceByAppearanceAlone) {
  // A's frame is 12 m and 40 deg away from B's: poses say nothing, descriptors do.
  const TwoMaps maps = make_two_maps(kLongGapNs);
  ProximityLoopDetectorOptions options;
  options.merge_keyframes_per_query = 6;  // B has 15 keyframes: three queries cover them
  ProximityLoopDetector detector(options);
  std::set<KeyframeId> found;
  for (int k = 12; k <= 14; ++k) {
    const LoopCandidates candidates = detector.detect_merge(maps.map, id_of_a(k), maps.map_b);
    for (const KeyframeId id : candidates.keyframes) {
      EXPECT_EQ(maps.map_b.count(id), 1u);
      found.insert(id);
    }
  }
  // Ring keyframes 10..14 of B see what A's 12..14 see; 0..5 look elsewhere.
  EXPECT_FALSE(found.empty());
  for (const KeyframeId id : found) EXPECT_GE(id, id_of_b(6)) << format_id(id);
  EXPECT_NE(detector.detect_merge(maps.map, id_of_a(12), {}).reason.find("no other map"), std::string::npos);
}

TEST(MapMergeTest, LoopClosingFindsVerifiesAndMergesAnotherMapsPlace) {
  // The proximity closer's path end to end: detection by descriptors, the shared verification, the
  // merge gate (a minute apart: passes), the weld.
  const TwoMaps maps = make_two_maps(kLongGapNs);
  LoopClosing closing(maps.world.camera, std::make_unique<ProximityLoopDetector>(ProximityLoopDetectorOptions{}), {});
  const LoopClosingResult result = closing.process_merge(maps.map, id_of_a(12));
  ASSERT_TRUE(result.correction) << (result.rejected.empty() ? result.candidates.reason
                                                             : result.rejected.front().reason);
  EXPECT_EQ(result.correction->kind, CorrectionKind::kMerge);
  EXPECT_EQ(result.merged_map, kMapA);
  EXPECT_EQ(result.into_map, kMapB);
  EXPECT_EQ(maps.map_b.count(result.correction->matched_kf), 1u);
  for (const auto& [id, T_wc] : result.correction->corrected_T_wc) {
    EXPECT_LT((T_wc.translation() - maps.true_T_wc.at(id).translation()).norm(), kExact) << format_id(id);
  }

  // One map only: no merge search at all.
  Map only_b = maps.map;
  for (const KeyframeId id : maps.map_a) only_b.keyframes.at(id).map_id = kMapB;
  const LoopClosingResult alone = closing.process_merge(only_b, id_of_a(13));
  EXPECT_FALSE(alone.correction);
  EXPECT_TRUE(alone.candidates.keyframes.empty());
}

// Every keyframe and point of map `from` relabelled `to`.
void relabel_map(Map& map, MapId from, MapId to) {
  for (auto& [id, kf] : map.keyframes) {
    if (kf.map_id == from) kf.map_id = to;
  }
  for (auto& [id, point] : map.points) {
    if (point.map_id == from) point.map_id = to;
  }
}

// Whichever keyframe is the query, the older map stays and the newer one moves into it: one agent's maps
// by id (creation order), two agents' by their first keyframe's stamp.
void expect_newer_moves_into_older(const TwoMaps& maps, const Map& map, KeyframeId query, MapId newer, MapId older) {
  LoopClosing closing(maps.world.camera, std::make_unique<ProximityLoopDetector>(ProximityLoopDetectorOptions{}), {});
  const LoopClosingResult result = closing.process_merge(map, query);
  ASSERT_TRUE(result.correction) << format_id(query) << ": "
                                 << (result.rejected.empty() ? result.candidates.reason
                                                             : result.rejected.front().reason);
  EXPECT_EQ(result.merged_map, newer) << format_id(query);
  EXPECT_EQ(result.into_map, older) << format_id(query);
  // The correction's loop keyframe is in the map that moves, its matched keyframe in the one that stays
  // (the mapper renumbers the loop keyframe's map: correction_application.hpp).
  EXPECT_EQ(maps.map_a.count(result.correction->loop_kf), 1u) << format_id(query);
  EXPECT_EQ(maps.map_b.count(result.correction->matched_kf), 1u) << format_id(query);
  // Every keyframe of both maps at its true pose in the older map's frame (B's: the world).
  EXPECT_EQ(result.correction->corrected_T_wc.size(), maps.map_a.size() + maps.map_b.size());
  for (const auto& [id, T_wc] : result.correction->corrected_T_wc) {
    EXPECT_LT((T_wc.translation() - maps.true_T_wc.at(id).translation()).norm(), kExact) << format_id(id);
    EXPECT_LT(rotation_error_rad(T_wc, maps.true_T_wc.at(id)), kExact) << format_id(id);
  }
  // The seam's duplicates: the newer map's point replaced by the older map's, each by its own world point.
  ASSERT_GT(result.correction->point_merges.size(), 100u) << format_id(query);
  for (const auto& [from, into] : result.correction->point_merges) {
    EXPECT_EQ(maps.truth_of_point.at(from), maps.truth_of_point.at(into));
    EXPECT_EQ(maps.map_a.count(map.point(from)->reference_kf), 1u) << "the newer map's point is replaced";
    EXPECT_EQ(maps.map_b.count(map.point(into)->reference_kf), 1u) << "the older map's point survives";
  }
  Map applied = map;
  MapChanges changes;
  EXPECT_EQ(apply_loop_correction(applied, *result.correction, {}, changes), 0);
  for (const auto& [id, kf] : applied.keyframes) EXPECT_EQ(kf.map_id, older) << format_id(id);
}

TEST(MapMergeTest, TheOlderMapStaysWhicheverKeyframeRecognisesTheOther) {
  const TwoMaps maps = make_two_maps(kLongGapNs);
  // One agent: A (map 5) was made after B (map 3). A query in A moves A into B, and so does a query in B
  // (a frame relocalized back into B recognising A): the place is verified from B's keyframe, and the
  // request is turned round (transform inverted, point pairs swapped).
  expect_newer_moves_into_older(maps, maps.map, id_of_a(12), kMapA, kMapB);
  expect_newer_moves_into_older(maps, maps.map, id_of_b(12), kMapA, kMapB);
  // Two agents: B is agent 1's map, A agent 0's (a smaller id), but B's first keyframe is older: B stays.
  Map agents = maps.map;
  relabel_map(agents, kMapB, first_map_id(1));
  relabel_map(agents, kMapA, first_map_id(0));
  expect_newer_moves_into_older(maps, agents, id_of_a(12), first_map_id(0), first_map_id(1));
  expect_newer_moves_into_older(maps, agents, id_of_b(12), first_map_id(0), first_map_id(1));
}

TEST(MapMergeTest, APlaceOfAnotherMapIsNoLoop) {
  const TwoMaps maps = make_two_maps(kLongGapNs);
  LoopClosing closing(maps.world.camera, std::make_unique<TruthMatcher>(maps, id_of_b(12)), {});
  const LoopClosingResult result = closing.process_keyframe(maps.map, id_of_a(12));
  EXPECT_FALSE(result.correction);
  ASSERT_EQ(result.rejected.size(), 1u);
  EXPECT_EQ(result.rejected.front().reason, "in map 3, not in map 5 (a merge, not a loop)");
}

TEST(MapMergeTest, ARequestAcrossTheWrongMapsIsRefusedWithItsReason) {
  const TwoMaps maps = make_two_maps(kLongGapNs);
  MapMergeRequest request;
  request.active_kf = id_of_b(3);  // a keyframe of B named as A's
  request.matched_kf = id_of_b(12);
  request.active_map = maps.map_a;
  request.matched_map = maps.map_b;
  const MapMergeOutput merged = MapMerge().compute(maps.map, maps.world.camera, request, {});
  EXPECT_NE(merged.error.find("must be live keyframes of the active and the matched map"), std::string::npos)
      << merged.error;
  EXPECT_FALSE(merged.gate_rejected);
}

}  // namespace
}  // namespace heslam
