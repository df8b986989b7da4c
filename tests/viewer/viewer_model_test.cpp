// The viewer's model with hand-made samples: points are categorised as the docs say (map, recent,
// merged by a loop closure, culled = disposed but remembered), a correction flashes, frames replaced
// before a drawing are counted, and odometry poses follow their reference keyframe.
#include <gtest/gtest.h>

#include <vector>

#include "runtime/sequence.hpp"
#include "tools/viewer/viewer_model.hpp"

namespace heslam::viewer {
namespace {

using Clock = ViewerModel::Clock;

msg::MapPointState point_state(PointId id, double x, KeyframeId reference = kNoId) {
  msg::MapPointState state{};
  state.id = id;
  state.schema_version = msg::kSchemaVersion;
  state.map_version = 1;
  state.position_w_m[0] = x;
  state.position_w_m[2] = 2.0;
  state.reference_keyframe_id = reference;
  return state;
}

int count(const Scene& scene, PointCategory category) {
  int n = 0;
  for (const ScenePoint& point : scene.points) n += point.category == category ? 1 : 0;
  return n;
}

TEST(ViewerModel, CategorisesPointsAsMapLoopMergedAndCulled) {
  ViewerModel model{ViewerModelOptions{}};
  for (PointId id = 1; id <= 4; ++id) model.apply_point_state(point_state(id, static_cast<double>(id)));
  // Point 4 is culled (disposed); it stays in the picture, greyed.
  model.point_disposed(4);
  // A loop correction merges 3 into 2.
  std::vector<msg::PointMerge> merges{{3, 2}};
  msg::LoopCorrection correction{};
  correction.id = 7;
  runtime::borrow(correction.point_merges, merges);
  model.apply_point_state(point_state(3, 3.0));
  const auto now = Clock::now();
  model.apply_correction(correction, now);
  model.point_disposed(3);  // the mapper disposes the merged point after its last state
  // The mapper's own fusion: a last state naming the point it merged into, then the dispose.
  model.apply_point_state(point_state(5, 5.0));
  msg::MapPointState merged = point_state(5, 5.0);
  merged.merged_into = 1;
  model.apply_point_state(merged);
  model.point_disposed(5);

  const Scene scene = model.scene(now);
  EXPECT_EQ(count(scene, PointCategory::kMap), 1);         // point 1
  EXPECT_EQ(count(scene, PointCategory::kLoopMerged), 1);  // point 2
  EXPECT_EQ(count(scene, PointCategory::kCulled), 1);      // point 4 (3 was merged, not culled)
  EXPECT_EQ(scene.map_points, 2u);
  EXPECT_EQ(scene.loop_corrections, 1u);
  EXPECT_TRUE(scene.loop_flash);
  EXPECT_FALSE(model.scene(now + std::chrono::seconds(10)).loop_flash);
}

TEST(ViewerModel, CountsFramesReplacedBeforeTheyWereDrawnAndSeqGaps) {
  ViewerModel model{ViewerModelOptions{}};
  std::vector<std::uint8_t> pixels(8 * 6, 100);
  auto frame = [&](std::uint64_t seq) {
    msg::StereoFrame message{};
    message.schema_version = msg::kSchemaVersion;
    message.seq = seq;
    message.stamp_ns = static_cast<std::int64_t>(seq) * 50000000;
    message.width_px = 8;
    message.height_px = 6;
    message.encoding = heslam_msg_ENCODING_MONO8;
    runtime::borrow(message.left, pixels);
    runtime::borrow(message.right, pixels);
    model.add_frame(message);
  };
  frame(0);
  frame(1);
  frame(2);
  Scene scene = model.scene(Clock::now());
  ASSERT_TRUE(scene.has_frame);
  EXPECT_EQ(scene.frame_seq, 2u);
  frame(5);  // 3 and 4 never arrived
  scene = model.scene(Clock::now());
  EXPECT_EQ(scene.frame_seq, 5u);
  EXPECT_EQ(model.frame_counts().received, 4u);
  EXPECT_EQ(model.frame_counts().drawn, 2u);
  EXPECT_EQ(model.frame_counts().not_drawn(), 2u);
  EXPECT_EQ(model.frame_counts().missed, 2u);
}

TEST(ViewerModel, BadFrameIsRejectedWithItsSeq) {
  ViewerModel model{ViewerModelOptions{}};
  std::vector<std::uint8_t> pixels(10, 0);
  msg::StereoFrame message{};
  message.seq = 42;
  message.width_px = 8;
  message.height_px = 6;
  message.encoding = heslam_msg_ENCODING_MONO8;
  runtime::borrow(message.left, pixels);
  runtime::borrow(message.right, pixels);
  try {
    model.add_frame(message);
    FAIL() << "a truncated image was accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("42"), std::string::npos) << error.what();
  }
  EXPECT_EQ(model.frame_counts().received, 0u);
}

}  // namespace
}  // namespace heslam::viewer
