// LoopClosing end to end on the synthetic ring (loop_world.hpp) with a detector that knows the truth:
// the revisit is verified and corrected; the drift gate turns away a loop that would need more drift
// than odometry makes (perceptual aliasing), with the reason.
#include <gtest/gtest.h>

#include <map>
#include <memory>

#include "components/core/loop/loop_closing.hpp"
#include "tests/loop/loop_world.hpp"

namespace heslam {
namespace {

// Offers one fixed candidate and matches keypoints by their true world point.
class TruthDetector final : public LoopDetector {
 public:
  TruthDetector(const test::LoopWorld& world, KeyframeId candidate) : world_(world), candidate_(candidate) {}
  const char* name() const override { return "truth"; }
  LoopCandidates detect(const Map&, KeyframeId) override { return {{candidate_}, "", {}}; }
  void loop_closed(KeyframeId) override {}
  std::vector<std::pair<std::uint32_t, std::uint32_t>> match(const Map& map, KeyframeId query,
                                                             KeyframeId candidate) const override {
    std::map<int, std::uint32_t> in_candidate;
    const std::vector<int>& truth_c = world_.truth_of_keypoint.at(candidate);
    const Keyframe& kf_c = *map.keyframe(candidate);
    for (std::uint32_t j = 0; j < truth_c.size(); ++j) {
      if (truth_c[j] >= 0 && kf_c.point_ids[j] != kNoId) in_candidate[truth_c[j]] = j;
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    const std::vector<int>& truth_q = world_.truth_of_keypoint.at(query);
    const Keyframe& kf_q = *map.keyframe(query);
    for (std::uint32_t i = 0; i < truth_q.size(); ++i) {
      const auto j = in_candidate.find(truth_q[i]);
      if (truth_q[i] >= 0 && kf_q.point_ids[i] != kNoId && j != in_candidate.end()) pairs.emplace_back(i, j->second);
    }
    return pairs;
  }

 private:
  const test::LoopWorld& world_;
  KeyframeId candidate_;
};

// Keyframe 36 (0-based) is back at keyframe 0's place after 12.6 m round the ring.
constexpr int kQuery = 36;

TEST(LoopClosingTest, TheRevisitIsVerifiedAndCorrected) {
  const test::LoopWorld w = test::make_loop_world();
  LoopClosing closing(w.world.camera, std::make_unique<TruthDetector>(w, test::loop_kf_id(0)), {});
  const LoopClosingResult result = closing.process_keyframe(w.map, test::loop_kf_id(kQuery));
  ASSERT_TRUE(result.correction) << (result.rejected.empty() ? "" : result.rejected.front().reason);
  EXPECT_EQ(result.correction->matched_kf, test::loop_kf_id(0));
  EXPECT_GE(result.loop_matches, 40);
}

TEST(LoopClosingTest, DriftGateRejectsALoopThatNeedsMoreDriftThanOdometryMakes) {
  const test::LoopWorld w = test::make_loop_world();
  LoopClosingOptions options;
  options.max_drift_fraction = 0.0;  // no drift allowed but 1 cm: the ring's odometry drifted more
  options.min_drift_allowance_m = 0.01;
  LoopClosing closing(w.world.camera, std::make_unique<TruthDetector>(w, test::loop_kf_id(0)), options);
  const LoopClosingResult result = closing.process_keyframe(w.map, test::loop_kf_id(kQuery));
  EXPECT_FALSE(result.correction);
  ASSERT_EQ(result.rejected.size(), 1u);
  EXPECT_NE(result.rejected.front().reason.find("drift gate: implies"), std::string::npos)
      << result.rejected.front().reason;
  EXPECT_NE(result.rejected.front().reason.find("m travelled"), std::string::npos) << result.rejected.front().reason;
}

}  // namespace
}  // namespace heslam
