// Keyframes that reach the mapper after a loop correction they predate (real time: the frontend
// tracked them against its uncorrected mirror) are moved with their reference keyframe, exactly
// T_new(ref) T_old(ref)^-1, with the points they create; later keyframes are left alone; several
// corrections compose; a global BA after a loop correction moves each keyframe once; the record
// survives a map file round trip.
#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>

#include "components/core/mapping/local_mapper.hpp"
#include "tests/mapping/correction_test_util.hpp"
#include "tests/mapping/mapping_test_util.hpp"

namespace heslam {
namespace {

using test::insertion_only;
using test::motion;

class LocalMapperLateKeyframes : public ::testing::Test {
 protected:
  LocalMapperLateKeyframes() : world_(test::make_room(2500, 57)), frontend_(world_) {}

  // Keyframe `id` (1-based) at the k-th circle pose, as the frontend estimated it (= truth here).
  std::pair<Keyframe, std::vector<MapPoint>> make(const LocalMapper& mapper, KeyframeId id) {
    const Pose3 T_wc = test::circle_pose(static_cast<int>(id) - 1, 0.05);
    auto view = test::make_view(world_, id, T_wc, 300 + static_cast<unsigned>(id));
    return frontend_.keyframe(mapper.map(), view, T_wc);
  }

  // Inserts keyframe `id` tracked against `reference` at `version`; returns its pose as sent and
  // its new points' positions as sent.
  struct Sent {
    Pose3 T_wc;
    std::map<PointId, Eigen::Vector3d> points;
  };
  Sent insert(LocalMapper& mapper, KeyframeId id, KeyframeId reference, std::uint64_t version,
              MapId map_id = kFirstMapId) {
    auto [kf, points] = make(mapper, id);
    kf.map_id = map_id;
    Sent sent{kf.T_wc, {}};
    for (const MapPoint& point : points) sent.points[point.id] = point.p_w;
    mapper.process_keyframe(std::move(kf), std::move(points), TrackedAgainst{reference, version});
    return sent;
  }

  // Moves keyframes 3 and 4 by `T` (1 and 2 stay): a loop correction computed on the current map.
  static LoopCorrection correct_3_and_4(const LocalMapper& mapper, const Pose3& T, std::uint64_t id) {
    LoopCorrection correction;
    correction.id = id;
    correction.map_version = mapper.map().version;
    for (const KeyframeId k : {KeyframeId{3}, KeyframeId{4}}) {
      correction.corrected_T_wc.emplace_back(k, T * mapper.map().keyframes.at(k).T_wc);
    }
    return correction;
  }

  static void expect_moved(const LocalMapper& mapper, KeyframeId id, const Sent& sent, const Pose3& expected_motion) {
    const Keyframe& kf = mapper.map().keyframes.at(id);
    EXPECT_LT(test::max_abs_difference(kf.T_wc, expected_motion * sent.T_wc), 1e-12) << "keyframe " << id;
    int checked = 0;
    for (const auto& [point_id, p_w] : sent.points) {
      const MapPoint* point = mapper.map().point(point_id);
      if (point == nullptr) continue;  // unreferenced, dropped at insertion
      EXPECT_LT((point->p_w - expected_motion * p_w).norm(), 1e-12) << "point " << point_id;
      ++checked;
    }
    EXPECT_GT(checked, 0) << "keyframe " << id << " should create points";
  }

  test::SyntheticWorld world_;
  test::FrontendEmulator frontend_;
};

TEST_F(LocalMapperLateKeyframes, KeyframeTrackedBeforeACorrectionMovesWithItsReference) {
  LocalMapper mapper(world_.camera, insertion_only());
  for (KeyframeId k = 1; k <= 4; ++k) insert(mapper, k, k - 1, mapper.map().version);
  const std::uint64_t tracked = mapper.map().version;  // the frontend's mirror when it made kf 5, 6
  const Pose3 old4 = mapper.map().keyframes.at(4).T_wc;
  const Pose3 A = motion(0.07, Eigen::Vector3d(0.2, 1.0, 0.1), Eigen::Vector3d(0.3, -0.05, 0.2));
  mapper.apply_correction(correct_3_and_4(mapper, A, 1));
  const Pose3 new4 = mapper.map().keyframes.at(4).T_wc;

  const Sent five = insert(mapper, 5, 4, tracked);  // tracked against kf 4, before the correction
  expect_moved(mapper, 5, five, new4 * old4.inverse());
  expect_moved(mapper, 5, five, A);  // the same motion: kf 4 was moved by A
  // Tracked against kf 1 (not moved by the correction): stays as it came.
  const Sent six = insert(mapper, 6, 1, tracked);
  expect_moved(mapper, 6, six, Pose3::Identity());
  // Tracked after the correction (the mirror had it): stays as it came.
  const Sent seven = insert(mapper, 7, 4, mapper.map().version);
  expect_moved(mapper, 7, seven, Pose3::Identity());
}

TEST_F(LocalMapperLateKeyframes, TwoCorrectionsComposeAndChainsOfLateKeyframesFollow) {
  LocalMapper mapper(world_.camera, insertion_only());
  for (KeyframeId k = 1; k <= 4; ++k) insert(mapper, k, k - 1, mapper.map().version);
  const std::uint64_t before_both = mapper.map().version;
  const Pose3 A = motion(0.05, Eigen::Vector3d(0.0, 1.0, 0.0), Eigen::Vector3d(0.2, 0.0, -0.1));
  const Pose3 B = motion(-0.03, Eigen::Vector3d(1.0, 0.2, 0.0), Eigen::Vector3d(-0.1, 0.05, 0.3));
  mapper.apply_correction(correct_3_and_4(mapper, A, 1));
  const std::uint64_t between = mapper.map().version;
  mapper.apply_correction(correct_3_and_4(mapper, B, 2));

  // kf 5: tracked against kf 4 before both corrections; kf 6 against kf 5 (also in flight then).
  const Sent five = insert(mapper, 5, 4, before_both);
  expect_moved(mapper, 5, five, B * A);
  const Sent six = insert(mapper, 6, 5, before_both);
  expect_moved(mapper, 6, six, B * A);
  // kf 7: tracked after the first correction, before the second.
  const Sent seven = insert(mapper, 7, 4, between);
  expect_moved(mapper, 7, seven, B);
}

TEST_F(LocalMapperLateKeyframes, GlobalBaAfterALoopCorrectionMovesEveryKeyframeOnce) {
  // Real time: a loop correction (A, computed at version v) applied after keyframe 5 was tracked;
  // a global BA computed at version g, after 5 arrived (moved by A), moving the whole map by B;
  // keyframe 6 inserted between g and the global BA's application, keyframe 7 in flight across it.
  LocalMapper mapper(world_.camera, insertion_only());
  for (KeyframeId k = 1; k <= 4; ++k) insert(mapper, k, k - 1, mapper.map().version);
  const std::uint64_t before_loop = mapper.map().version;
  const Pose3 A = motion(0.05, Eigen::Vector3d(0.0, 1.0, 0.2), Eigen::Vector3d(0.3, 0.0, -0.1));
  mapper.apply_correction(correct_3_and_4(mapper, A, 1));
  const Sent five = insert(mapper, 5, 4, before_loop);
  expect_moved(mapper, 5, five, A);

  const Pose3 B = motion(-0.02, Eigen::Vector3d(1.0, 0.1, 0.0), Eigen::Vector3d(-0.05, 0.02, 0.1));
  LoopCorrection global_ba;
  global_ba.id = 2;
  global_ba.kind = CorrectionKind::kGlobalBundleAdjustment;
  global_ba.map_version = mapper.map().version;
  std::map<KeyframeId, Pose3> at_g;
  for (const auto& [id, kf] : mapper.map().keyframes) {
    at_g[id] = kf.T_wc;
    global_ba.corrected_T_wc.emplace_back(id, B * kf.T_wc);
  }
  const std::uint64_t g = mapper.map().version;
  const Sent six = insert(mapper, 6, 5, g);  // mapped before the global BA lands: follows its parent
  mapper.apply_correction(global_ba);
  const Sent seven = insert(mapper, 7, 5, g);  // tracked before it landed: moved with keyframe 5

  for (KeyframeId k = 1; k <= 5; ++k) {
    EXPECT_LT(test::max_abs_difference(mapper.map().keyframes.at(k).T_wc, B * at_g.at(k)), 1e-12) << "keyframe " << k;
  }
  expect_moved(mapper, 5, five, B * A);  // once by each correction, not twice by either
  EXPECT_LT(test::max_abs_difference(mapper.map().keyframes.at(6).T_wc, B * six.T_wc), 1e-12);
  expect_moved(mapper, 7, seven, B);
}

// A keyframe made in a map that a merge folded into another before it arrived (agent b's frontend, in real
// time, had not heard of the merge yet): it joins the map its reference keyframe went into, moved with it;
// one made in the map that stays keeps it.
TEST_F(LocalMapperLateKeyframes, KeyframeOfAMergedAwayMapJoinsTheMapItsReferenceWentInto) {
  constexpr MapId kSecondMap = 7;
  LocalMapper mapper(world_.camera, insertion_only());
  insert(mapper, 1, kNoId, mapper.map().version);
  insert(mapper, 2, 1, mapper.map().version);
  insert(mapper, 3, kNoId, mapper.map().version, kSecondMap);  // the second map's first keyframe
  insert(mapper, 4, 3, mapper.map().version, kSecondMap);
  const std::uint64_t before_merge = mapper.map().version;
  const Pose3 A = motion(0.04, Eigen::Vector3d(0.0, 1.0, 0.0), Eigen::Vector3d(0.1, 0.0, 0.05));
  LoopCorrection merge = correct_3_and_4(mapper, A, 1);
  merge.kind = CorrectionKind::kMerge;
  merge.loop_kf = 3;
  merge.matched_kf = 2;
  mapper.apply_correction(merge);
  ASSERT_EQ(mapper.map().keyframes.at(4).map_id, kFirstMapId);

  const Sent five = insert(mapper, 5, 4, before_merge, kSecondMap);  // tracked before the merge
  EXPECT_EQ(mapper.map().keyframes.at(5).map_id, kFirstMapId);
  expect_moved(mapper, 5, five, A);
  insert(mapper, 6, 2, mapper.map().version);  // the map that stayed
  EXPECT_EQ(mapper.map().keyframes.at(6).map_id, kFirstMapId);
}

TEST_F(LocalMapperLateKeyframes, RememberedCorrectionsSurviveAMapFileRoundTrip) {
  LocalMapper mapper(world_.camera, insertion_only());
  for (KeyframeId k = 1; k <= 4; ++k) insert(mapper, k, k - 1, mapper.map().version);
  const std::uint64_t tracked = mapper.map().version;
  const Pose3 A = motion(0.04, Eigen::Vector3d(0.3, 1.0, 0.0), Eigen::Vector3d(0.1, 0.1, -0.2));
  mapper.apply_correction(correct_3_and_4(mapper, A, 1));
  const auto path =
      std::filesystem::temp_directory_path() / ("heslam_late_keyframe_" + std::to_string(::getpid()) + ".map");
  mapper.save(path);
  LocalMapper restarted(world_.camera, insertion_only(), load_map_file(path));
  std::filesystem::remove(path);
  ASSERT_EQ(restarted.state().correction_motions.size(), 1u);
  const Sent five = insert(restarted, 5, 4, tracked);
  expect_moved(restarted, 5, five, A);
  // Once a keyframe tracked after the correction arrived, nothing older can come: forgotten.
  insert(restarted, 6, 5, restarted.map().version);
  EXPECT_TRUE(restarted.state().correction_motions.empty());
}

}  // namespace
}  // namespace heslam
