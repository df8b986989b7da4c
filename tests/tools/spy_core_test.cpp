// heslam-spy's DDS-free parts: rate/bandwidth statistics on exact stamps, QoS matching rules,
// message text, option parsing and topic resolution.
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "components/core/map/ids.hpp"

#include "runtime/sequence.hpp"
#include "runtime/wire_enum.hpp"
#include "tools/spy/arrival_window.hpp"
#include "tools/spy/endpoint_qos.hpp"
#include "tools/spy/message_format.hpp"
#include "tools/spy/spy_options.hpp"
#include "tools/spy/spy_topic.hpp"

namespace heslam {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(ArrivalWindow, RateAndPeriodSpread) {
  ArrivalWindow window(10);
  // Periods 40, 60, 40, 60 ms: mean 50 ms -> 20 Hz, std 10 ms.
  const std::int64_t arrivals[] = {0, 40, 100, 140, 200};
  for (const std::int64_t t : arrivals) window.add(t * kMs, 1000);
  const RateStats stats = window.rate();
  EXPECT_EQ(stats.periods, 4u);
  EXPECT_NEAR(stats.rate_hz, 20.0, 1e-9);
  EXPECT_NEAR(stats.min_period_s, 0.040, 1e-12);
  EXPECT_NEAR(stats.max_period_s, 0.060, 1e-12);
  EXPECT_NEAR(stats.std_period_s, 0.010, 1e-9);
}

TEST(ArrivalWindow, KeepsOnlyTheLastNArrivals) {
  ArrivalWindow window(3);
  window.add(0, 1);
  window.add(1000 * kMs, 1);  // a long gap that must fall out of the window
  window.add(1100 * kMs, 1);
  window.add(1200 * kMs, 1);
  EXPECT_EQ(window.size(), 3u);
  EXPECT_NEAR(window.rate().rate_hz, 10.0, 1e-9);
  EXPECT_THROW(ArrivalWindow(1), std::runtime_error);
}

TEST(ArrivalWindow, Bandwidth) {
  ArrivalWindow window(100);
  // 722 KB stereo frames at 20 Hz: 14.44 MB/s.
  for (int i = 0; i <= 20; ++i) window.add(i * 50 * kMs, 722'000);
  const BandwidthStats stats = window.bandwidth();
  EXPECT_EQ(stats.samples, 21u);
  EXPECT_NEAR(stats.bytes_per_s, 14.44e6, 1e-3);
  EXPECT_DOUBLE_EQ(stats.mean_bytes, 722'000.0);
  EXPECT_EQ(stats.min_bytes, 722'000u);
  EXPECT_EQ(stats.max_bytes, 722'000u);
}

TEST(EndpointQos, RequestedVersusOffered) {
  EndpointQos writer;
  writer.reliable = false;
  writer.durability = 0;
  EndpointQos reader;
  reader.reliable = true;
  reader.durability = 1;
  const std::vector<std::string> reasons = incompatibilities(writer, reader);
  ASSERT_EQ(reasons.size(), 2u);
  EXPECT_EQ(reasons[0], "RELIABILITY: reader requests RELIABLE, writer offers BEST_EFFORT");
  EXPECT_EQ(reasons[1], "DURABILITY: reader requests TRANSIENT_LOCAL, writer offers VOLATILE");
  // The spy's best-effort volatile tap matches a reliable transient-local writer.
  EXPECT_TRUE(incompatibilities(reader, writer).empty());
  EndpointQos other_partition = reader;
  other_partition.partitions = {"robot2"};
  EXPECT_EQ(incompatibilities(reader, other_partition), std::vector<std::string>{"PARTITION: no common partition"});
  EndpointQos deadline_reader = writer;
  deadline_reader.deadline_ns = 100 * kMs;
  EXPECT_EQ(incompatibilities(writer, deadline_reader).size(), 1u);
}

TEST(EndpointQos, ReadsAndDescribesARealQosObject) {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 4);
  dds_qset_durability_service(qos, 0, DDS_HISTORY_KEEP_LAST, 16, -1, -1, -1);
  dds_qset_liveliness(qos, DDS_LIVELINESS_AUTOMATIC, DDS_SECS(2));
  const EndpointQos read = read_endpoint_qos(qos, true);
  dds_delete_qos(qos);
  EXPECT_TRUE(read.reliable);
  EXPECT_EQ(read.durability, 1);
  EXPECT_EQ(read.depth, 4);
  EXPECT_EQ(read.service_depth, 16);
  EXPECT_EQ(describe(read, true),
            "RELIABLE(max_blocking 100 ms) TRANSIENT_LOCAL(late joiners get KEEP_LAST(16)) KEEP_LAST(4) "
            "liveliness AUTOMATIC(2 s)");
}

TEST(MessageFormat, StereoFrameIsSummarised) {
  std::vector<std::uint8_t> left(8 * 4, 10);
  std::vector<std::uint8_t> right(8 * 4, 30);
  right[0] = 62;  // mean 31
  msg::StereoFrame frame{};
  frame.seq = 7;
  frame.stamp_ns = 1403715273262142976;
  frame.stamp_right_ns = frame.stamp_ns;
  frame.width_px = 8;
  frame.height_px = 4;
  frame.encoding = heslam_msg_ENCODING_MONO8;
  runtime::borrow(frame.left, left);
  runtime::borrow(frame.right, right);
  EXPECT_DOUBLE_EQ(mean_intensity(frame, true), 31.0);
  const std::string text = format_message(frame, {});
  EXPECT_NE(text.find("seq: 7\n"), std::string::npos) << text;
  EXPECT_NE(text.find("stamp_ns: 1403715273262142976\n"), std::string::npos);
  EXPECT_NE(text.find("size: 8x4 mono8\n"), std::string::npos);
  EXPECT_NE(text.find("mean_intensity_left_right: 10.00 / 31.00\n"), std::string::npos);
  EXPECT_EQ(text.find("0a0a0a"), std::string::npos);  // no pixel bytes in the summary
  EXPECT_NE(format_message(frame, {.full = true}).find("0a0a0a0a"), std::string::npos);
}

// Enum fields holding a value of no enumerator (a hostile or newer writer) are shown as unknown,
// read as their wire integers (runtime/wire_enum.hpp), never loaded as the enum.
TEST(MessageFormat, UnknownEnumValuesAreShownAsUnknown) {
  msg::Odometry odometry{};
  odometry.T_wc.orientation_xyzw[3] = odometry.T_ref_c.orientation_xyzw[3] = 1.0;
  odometry.state = heslam_msg_TRACKING_LOST;
  EXPECT_NE(format_message(odometry, {}).find("state: LOST\n"), std::string::npos);
  runtime::set_wire_value(odometry.state, 7);
  EXPECT_NE(format_message(odometry, {}).find("state: unknown\n"), std::string::npos);
  msg::ComponentStatus status{};
  runtime::set_wire_value(status.state, 9);
  EXPECT_NE(format_message(status, {}).find("state: unknown\n"), std::string::npos);
  msg::StereoFrame frame{};
  runtime::set_wire_value(frame.encoding, 3);
  EXPECT_NE(format_message(frame, {}).find("size: 0x0 unknown\n"), std::string::npos);
}

// Odometry shows the continuous pose, the covariance's diagonal and the velocity, or says they are unknown.
TEST(MessageFormat, OdometryShowsContinuousPoseCovarianceAndVelocity) {
  msg::Odometry odometry{};
  odometry.T_wc.orientation_xyzw[3] = odometry.T_ref_c.orientation_xyzw[3] = odometry.T_oc.orientation_xyzw[3] = 1.0;
  odometry.T_oc.position_m[2] = 2.5;
  std::string text = format_message(odometry, {});
  EXPECT_NE(text.find("T_oc: {position_m: [0, 0, 2.5], orientation_xyzw: [0, 0, 0, 1]}\n"), std::string::npos) << text;
  EXPECT_NE(text.find("T_wc_covariance_diagonal: unknown\nv_w: unknown\n"), std::string::npos) << text;
  // Upper triangle row by row: diagonal entries at 0, 6, 11, 15, 18, 20.
  const int diagonal[6] = {0, 6, 11, 15, 18, 20};
  for (int row = 0; row < 6; ++row) odometry.T_wc_covariance[diagonal[row]] = row + 1;
  odometry.T_wc_covariance[1] = 0.5;  // off the diagonal: not shown
  odometry.velocity_valid = true;
  odometry.v_w[0] = 0.25;
  text = format_message(odometry, {});
  EXPECT_NE(text.find("T_wc_covariance_diagonal: [1, 2, 3, 4, 5, 6]\nv_w: [0.25, 0, 0]\n"), std::string::npos) << text;
}

TEST(MessageFormat, KeyframeShowsIdPoseAndKeypointCount) {
  std::vector<msg::KeyframeKeypoint> keypoints(5);
  keypoints[0].u_px = 12.5f;
  std::vector<std::uint64_t> point_ids = {0, 42, 0, 43, 44};
  msg::Keyframe keyframe{};
  keyframe.id = 72057594037927939ULL;  // the frontend's (tag 1) third keyframe
  keyframe.T_wc.position_m[0] = 1.5;
  keyframe.T_wc.orientation_xyzw[3] = 1.0;
  keyframe.reference_keyframe_id = 72057594037927938ULL;
  keyframe.tracked_map_version = 7;
  runtime::borrow(keyframe.keypoints, keypoints);
  runtime::borrow(keyframe.point_ids, point_ids);
  const std::string text = format_message(keyframe, {});
  EXPECT_NE(text.find("id: fe:3\n"), std::string::npos) << text;
  EXPECT_NE(text.find("T_wc: {position_m: [1.5, 0, 0], orientation_xyzw: [0, 0, 0, 1]}"), std::string::npos);
  EXPECT_NE(text.find("reference_keyframe_id: fe:2\ntracked_map_version: 7\n"), std::string::npos) << text;
  EXPECT_NE(text.find("keypoints_count: 5\n"), std::string::npos);
  EXPECT_NE(text.find("... (2 more, --full)"), std::string::npos);
  EXPECT_NE(text.find("observed_points: 3\n"), std::string::npos);
  EXPECT_EQ(format_message(keyframe, {.full = true}).find("more, --full"), std::string::npos);
}

// Ids show their creator and counter; an unknown creator stays visible in hex; 0 is "no id".
TEST(MessageFormat, IdsShowCreatorAndCounter) {
  EXPECT_EQ(format_id(72057594037927937ULL), "fe:1");
  EXPECT_EQ(format_id(make_id(kMapperTag, 12345)), "lm:12345");
  EXPECT_EQ(format_id(make_id(kLoopCloserTag, 2)), "lc:2");
  EXPECT_EQ(format_id(make_id(7, 5)), "0x0700000000000005");
  EXPECT_EQ(format_id(0), "0");
  EXPECT_EQ(format_id(42), "42");  // no creator tag (the ids of tests): the plain number
  msg::KeyframeState state{};
  state.id = make_id(kFrontendTag, 9);
  state.parent_id = make_id(kFrontendTag, 8);
  state.map_id = 2;
  const std::string text = format_message(state, {});
  EXPECT_NE(text.find("id: fe:9\nmap_version: 0\nmap_id: 2\nT_wc: "), std::string::npos) << text;
  EXPECT_NE(text.find("parent_id: fe:8\n"), std::string::npos) << text;
}

// The issue's ids: the log lines and the spy print the same short form (format_id, ids.hpp).
TEST(MessageFormat, TheIdsOfTheIssueReadAsCreatorAndCounter) {
  EXPECT_EQ(format_id(72057594037928006ULL), "fe:70");
  EXPECT_EQ(format_id(72057594037927938ULL), "fe:2");
  EXPECT_EQ(format_id(216174495068772617ULL), "lc:1712954988809");
}

// The mapper's end-of-batch marker (id 0) is labelled as such, not shown as a keyframe or point of
// id 0 with a zero pose.
TEST(MessageFormat, VersionMarkersAreLabelled) {
  msg::KeyframeState marker{};
  marker.map_version = 12;
  const std::string text = format_message(marker, {});
  EXPECT_EQ(text,
            "version_marker: end of the local mapper's batch of map version 12 (id 0: no keyframe or point)\n"
            "map_version: 12\n");
  msg::MapPointState point_marker{};
  point_marker.map_version = 12;
  EXPECT_EQ(format_message(point_marker, {}), text);
}

// A dispose names the instance by its key; odometry says the frame of its pose.
TEST(MessageFormat, DisposalsPrintTheirKeyAndOdometryItsFrame) {
  msg::KeyframeState culled{};
  culled.id = make_id(kFrontendTag, 41);
  EXPECT_EQ(format_instance_end(culled, true), "# disposed: id fe:41\n");
  msg::MapPointState point{};
  point.id = make_id(kMapperTag, 7);
  EXPECT_EQ(format_instance_end(point, false), "# no writers any more: id lm:7\n");
  msg::ComponentStatus status{};
  char name[] = "frontend";
  status.name = name;
  EXPECT_EQ(format_instance_end(status, false), "# no writers any more: name frontend\n");
  msg::Odometry odometry{};
  EXPECT_EQ(format_instance_end(odometry, true), "# disposed\n");
  const std::string text = format_message(odometry, {});
  EXPECT_NE(text.find("T_wc_frame: rectified left camera (optical: x right, y down, z forward)"), std::string::npos)
      << text;
}

std::string spy_error(const std::vector<std::string>& args) {
  try {
    parse_spy_options(args);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(SpyOptions, CommandsAndErrors) {
  const SpyOptions hz = parse_spy_options({"hz", "camera/stereo", "--window", "40", "--count", "60"});
  EXPECT_EQ(hz.command, SpyCommand::kHz);
  EXPECT_EQ(hz.topic, "camera/stereo");
  EXPECT_EQ(hz.window, 40u);
  EXPECT_EQ(hz.count, 60u);
  const SpyOptions echo = parse_spy_options({"echo", "odometry", "--once", "--full"});
  EXPECT_EQ(echo.count, 1u);
  EXPECT_TRUE(echo.full);
  EXPECT_EQ(parse_spy_options({"list"}).command, SpyCommand::kList);
  EXPECT_EQ(spy_error({}), "missing command: list, echo, hz, bw or info (see --help)");
  EXPECT_EQ(spy_error({"tail"}), "'tail': unknown command (expected list, echo, hz, bw or info)");
  EXPECT_EQ(spy_error({"echo"}), "echo: missing TOPIC argument");
  EXPECT_EQ(spy_error({"hz", "odometry", "--window", "1"}), "--window: expected an integer >= 2, got '1'");
  EXPECT_EQ(spy_error({"list", "extra"}), "'extra': unexpected argument");
}

TEST(SpyTopic, ResolvesRelativeAndFullNames) {
  const ResolvedTopic relative = resolve_topic("camera/stereo", "heslam");
  EXPECT_EQ(relative.full_name, "heslam/camera/stereo");
  EXPECT_EQ(relative.type_name, "StereoFrame");
  EXPECT_EQ(relative.role, runtime::QosRole::kImages);
  const ResolvedTopic full = resolve_topic("/robot2/map/keyframes", "heslam");
  EXPECT_EQ(full.full_name, "robot2/map/keyframes");
  EXPECT_EQ(full.type_name, "Keyframe");
  EXPECT_THROW(resolve_topic("camera/mono", "heslam"), std::runtime_error);
  std::string visited;
  with_message_type("FrameDone",
                    [&]<typename T>(std::type_identity<T>) { visited = runtime::MessageTraits<T>::name(); });
  EXPECT_EQ(visited, "FrameDone");
  EXPECT_THROW(with_message_type("Image", [](auto) {}), std::runtime_error);
}

// Every topic of the table can be echoed: its type is compiled into the spy.
TEST(SpyTopic, EveryTopicOfTheTableHasItsTypeInTheSpy) {
  for (const runtime::TopicEntry& entry : runtime::all_topics()) {
    std::string visited;
    EXPECT_NO_THROW(with_message_type(std::string(entry.type_name), [&]<typename T>(std::type_identity<T>) {
      visited = runtime::MessageTraits<T>::name();
    })) << entry.relative_name;
    EXPECT_EQ(visited, entry.type_name) << entry.relative_name;
  }
  const ResolvedTopic reply = resolve_topic("map/occupancy_save_reply", "heslam");
  EXPECT_EQ(reply.type_name, "OccupancySaveReply");
  EXPECT_EQ(reply.role, runtime::QosRole::kLockstep);
}

TEST(MessageFormat, OccupancySaveReplyShowsWhatWasWritten) {
  msg::OccupancySaveReply reply{};
  reply.request_id = 7;
  reply.ok = true;
  std::string stem = "/tmp/run/now", empty;
  reply.output_stem = stem.data();
  reply.message = empty.data();
  reply.keyframes = 8;
  reply.occupied_cells = 120;
  reply.free_cells = 900;
  reply.points = 4321;
  const std::string text = format_message(reply, {});
  EXPECT_NE(text.find("request_id: 7"), std::string::npos) << text;
  EXPECT_NE(text.find("ok: true"), std::string::npos) << text;
  EXPECT_NE(text.find("output_stem: /tmp/run/now"), std::string::npos) << text;
  EXPECT_NE(text.find("120 occupied, 900 free"), std::string::npos) << text;
  EXPECT_NE(text.find("points: 4321"), std::string::npos) << text;
}

}  // namespace
}  // namespace heslam
