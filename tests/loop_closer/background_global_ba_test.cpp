// The loop closer's global BA thread: the same correction as the inline adjustment, tagged with its
// loop; abort drops a running one; a second start replaces the first (a newer loop).
#include <gtest/gtest.h>

#include <memory>

#include "components/core/loop/proximity_loop_detector.hpp"
#include "components/loop_closer/background_global_ba.hpp"
#include "tests/loop/loop_world.hpp"

namespace heslam::loop_closer {
namespace {

test::LoopWorld drifted_world() {
  test::LoopWorldOptions options;
  options.keyframes = 14;
  options.points = 800;
  return test::make_loop_world(options);
}

LoopClosing make_closing(const test::LoopWorld& w) {
  return LoopClosing(w.world.camera, std::make_unique<ProximityLoopDetector>(ProximityLoopDetectorOptions{}), {});
}

TEST(LoopCloserGlobalBa, CollectGivesTheInlineResultForItsLoop) {
  const test::LoopWorld w = drifted_world();
  const LoopClosing closing = make_closing(w);
  const std::optional<LoopCorrection> inline_result = closing.global_bundle_adjustment(w.map, nullptr);
  ASSERT_TRUE(inline_result);

  BackgroundGlobalBa global_ba;
  global_ba.start(closing, w.map, test::loop_kf_id(13));
  EXPECT_TRUE(global_ba.running());
  const BackgroundGlobalBa::Outcome outcome = global_ba.collect();
  EXPECT_FALSE(global_ba.running());
  ASSERT_TRUE(outcome.correction);
  EXPECT_EQ(outcome.correction->loop_kf, test::loop_kf_id(13));
  EXPECT_EQ(outcome.correction->kind, CorrectionKind::kGlobalBundleAdjustment);
  EXPECT_EQ(outcome.correction->map_version, w.map.version);
  ASSERT_EQ(outcome.correction->corrected_T_wc.size(), inline_result->corrected_T_wc.size());
  for (std::size_t i = 0; i < inline_result->corrected_T_wc.size(); ++i) {
    EXPECT_EQ(outcome.correction->corrected_T_wc[i].first, inline_result->corrected_T_wc[i].first);
    EXPECT_EQ(outcome.correction->corrected_T_wc[i].second.matrix(), inline_result->corrected_T_wc[i].second.matrix());
  }
  EXPECT_EQ(outcome.correction->corrected_points.size(), inline_result->corrected_points.size());
}

TEST(LoopCloserGlobalBa, AbortDropsTheRunningAdjustment) {
  const test::LoopWorld w = drifted_world();
  const LoopClosing closing = make_closing(w);
  BackgroundGlobalBa global_ba;
  EXPECT_FALSE(global_ba.abort());  // nothing running
  global_ba.start(closing, w.map, test::loop_kf_id(13));
  EXPECT_TRUE(global_ba.abort());
  EXPECT_FALSE(global_ba.running());
  EXPECT_FALSE(global_ba.collect().correction);
}

TEST(LoopCloserGlobalBa, ANewerStartReplacesTheRunningOne) {
  const test::LoopWorld w = drifted_world();
  const LoopClosing closing = make_closing(w);
  BackgroundGlobalBa global_ba;
  global_ba.start(closing, w.map, test::loop_kf_id(12));
  global_ba.start(closing, w.map, test::loop_kf_id(13));
  const BackgroundGlobalBa::Outcome outcome = global_ba.collect();
  ASSERT_TRUE(outcome.correction);
  EXPECT_EQ(outcome.correction->loop_kf, test::loop_kf_id(13));
}

}  // namespace
}  // namespace heslam::loop_closer
