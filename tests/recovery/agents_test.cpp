// Several agents (docs/agents.md), the parts that need no process: ids that carry their agent
// (components/core/map/ids.hpp), what a keyframe reader refuses (AgentKeyframeGuard) and the topic names
// of an agent namespace (runtime/topics.hpp). Known answers: agent 0's ids and maps are those of before.
#include <gtest/gtest.h>

#include <set>

#include "components/core/map/agent_guard.hpp"
#include "components/core/map/ids.hpp"
#include "runtime/topics.hpp"

namespace heslam {
namespace {

TEST(AgentIds, AgentZeroKeepsTheIdsOfASingleFrontend) {
  EXPECT_EQ(frontend_tag(0), kFrontendTag);
  EXPECT_EQ(first_map_id(0), 0u);
  EXPECT_EQ(agent_of(make_id(kFrontendTag, 17)), 0);
  EXPECT_EQ(format_id(make_id(frontend_tag(0), 17)), "fe:17");
}

TEST(AgentIds, EveryAgentHasItsOwnTagAndMapsAndIsReadBackFromAnyId) {
  std::set<std::uint8_t> tags{kMapperTag, kLoopCloserTag};
  for (int agent = 0; agent <= kMaxAgentId; ++agent) {
    EXPECT_TRUE(tags.insert(frontend_tag(agent)).second) << "agent " << agent << " shares a creator tag";
    EXPECT_EQ(agent_of(make_id(frontend_tag(agent), 123456789)), agent);
    EXPECT_EQ(agent_of_map(first_map_id(agent) + 5), agent);
  }
  EXPECT_EQ(format_id(make_id(frontend_tag(2), 17)), "fe2:17");
  EXPECT_EQ(agent_of(make_id(kMapperTag, 1)), -1);
  EXPECT_EQ(agent_of(make_id(kLoopCloserTag, 1)), -1);
  EXPECT_EQ(agent_of(5), -1);  // a creator-less id
}

TEST(AgentKeyframeGuard, AcceptsEachAgentsOwnIdsAndMaps) {
  AgentKeyframeGuard guard(2);
  const auto none = [](std::uint32_t) { return false; };
  EXPECT_FALSE(guard.check(/*writer=*/10, make_id(frontend_tag(0), 1), first_map_id(0), none));
  EXPECT_FALSE(guard.check(/*writer=*/11, make_id(frontend_tag(1), 1), first_map_id(1), none));
  EXPECT_FALSE(guard.check(11, make_id(frontend_tag(1), 2), first_map_id(1) + 1, none));  // its new map
  // After a merge agent 1 goes on in agent 0's map, which exists.
  const auto merged = [](std::uint32_t map_id) { return map_id == first_map_id(0); };
  EXPECT_FALSE(guard.check(11, make_id(frontend_tag(1), 3), first_map_id(0), merged));
}

TEST(AgentKeyframeGuard, RefusesAnotherAgentsIdsAMapThatDoesNotExistAndUnknownAgents) {
  AgentKeyframeGuard guard(2);
  const auto none = [](std::uint32_t) { return false; };
  ASSERT_FALSE(guard.check(10, make_id(frontend_tag(0), 1), first_map_id(0), none));
  const std::optional<std::string> forged = guard.check(10, make_id(frontend_tag(1), 1), first_map_id(1), none);
  ASSERT_TRUE(forged);
  EXPECT_NE(forged->find("ids of another agent"), std::string::npos) << *forged;
  const std::optional<std::string> no_map = guard.check(11, make_id(frontend_tag(1), 1), first_map_id(0) + 3, none);
  ASSERT_TRUE(no_map);
  EXPECT_NE(no_map->find("does not exist"), std::string::npos) << *no_map;
  EXPECT_TRUE(guard.check(12, make_id(frontend_tag(2), 1), first_map_id(2), none));  // only agents 0 and 1
  EXPECT_TRUE(guard.check(13, make_id(kMapperTag, 1), first_map_id(0), none));       // no frontend's id
}

TEST(AgentTopics, AnAgentsOwnTopicsGoUnderItsNamespaceTheMapStaysShared) {
  const runtime::Topics single;
  EXPECT_EQ(single.stereo().name, "heslam/camera/stereo");
  EXPECT_EQ(single.frame_done().name, "heslam/lockstep/frame_done");
  const runtime::Topics b("heslam", "b");
  EXPECT_EQ(b.stereo().name, "heslam/b/camera/stereo");
  EXPECT_EQ(b.calibration().name, "heslam/b/camera/calibration");
  EXPECT_EQ(b.imu().name, "heslam/b/imu/readings");
  EXPECT_EQ(b.imu_calibration().name, "heslam/b/imu/calibration");
  EXPECT_EQ(b.odometry().name, "heslam/b/odometry");
  EXPECT_EQ(b.frame_done().name, "heslam/b/lockstep/frame_done");
  EXPECT_EQ(b.keyframes().name, "heslam/map/keyframes");
  EXPECT_EQ(b.keyframe_states().name, "heslam/map/keyframe_states");
  EXPECT_EQ(b.map_points().name, "heslam/map/points");
  EXPECT_EQ(b.loop_corrections().name, "heslam/loop/corrections");
  EXPECT_EQ(b.keyframe_done().name, "heslam/lockstep/keyframe_done");
  EXPECT_EQ(b.turns().name, "heslam/lockstep/turns");
  EXPECT_EQ(b.status().name, "heslam/system/status");
  EXPECT_THROW(runtime::Topics("heslam", "/b"), std::runtime_error);
}

}  // namespace
}  // namespace heslam
