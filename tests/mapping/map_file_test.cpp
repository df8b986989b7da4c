// Map persistence: exact round trip, resume equivalence, and clear errors on damaged files.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "components/core/mapping/local_mapper.hpp"
#include "components/core/mapping/map_file.hpp"
#include "tests/mapping/synthetic_world.hpp"

namespace heslam {
namespace {

std::filesystem::path temp_path(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("heslam_mapping_" + std::to_string(::getpid()) + "_" + name);
}

void expect_maps_equal(const Map& a, const Map& b) {
  ASSERT_EQ(a.version, b.version);
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  ASSERT_EQ(a.points.size(), b.points.size());
  for (const auto& [id, ka] : a.keyframes) {
    const Keyframe& kb = b.keyframes.at(id);
    EXPECT_EQ(ka.stamp_ns, kb.stamp_ns);
    EXPECT_EQ(ka.map_id, kb.map_id) << "keyframe " << id;
    EXPECT_EQ(ka.T_wc.matrix(), kb.T_wc.matrix()) << "keyframe " << id;
    EXPECT_EQ(ka.parent, kb.parent);
    EXPECT_EQ(ka.covisible, kb.covisible);
    EXPECT_EQ(ka.culled, kb.culled);
    EXPECT_EQ(ka.point_ids, kb.point_ids);
    ASSERT_EQ(ka.features.size(), kb.features.size());
    EXPECT_EQ(ka.features.descriptors, kb.features.descriptors);
    EXPECT_EQ(ka.features.u_right_px, kb.features.u_right_px);
    EXPECT_EQ(ka.features.depth_m, kb.features.depth_m);
    EXPECT_EQ(ka.features.pyramid.levels, kb.features.pyramid.levels);
    for (std::size_t i = 0; i < ka.features.size(); ++i) {
      EXPECT_EQ(ka.features.keypoints[i].u_px, kb.features.keypoints[i].u_px);
      EXPECT_EQ(ka.features.keypoints[i].octave, kb.features.keypoints[i].octave);
      EXPECT_EQ(ka.features.keypoints[i].angle_deg, kb.features.keypoints[i].angle_deg);
    }
  }
  for (const auto& [id, pa] : a.points) {
    const MapPoint& pb = b.points.at(id);
    EXPECT_EQ(pa.p_w, pb.p_w) << "point " << id;
    EXPECT_EQ(pa.map_id, pb.map_id) << "point " << id;
    EXPECT_EQ(pa.descriptor, pb.descriptor);
    EXPECT_EQ(pa.normal, pb.normal);
    EXPECT_EQ(pa.min_distance_m, pb.min_distance_m);
    EXPECT_EQ(pa.max_distance_m, pb.max_distance_m);
    EXPECT_EQ(pa.reference_kf, pb.reference_kf);
    EXPECT_EQ(pa.observations, pb.observations);
    EXPECT_EQ(pa.visible, pb.visible);
    EXPECT_EQ(pa.found, pb.found);
  }
}

// Runs the mapper over keyframes [first, last] of the synthetic circle.
void run(LocalMapper& mapper, test::FrontendEmulator& frontend, const test::SyntheticWorld& world, int first,
         int last) {
  for (int k = first; k <= last; ++k) {
    auto view =
        test::make_view(world, static_cast<KeyframeId>(k + 1), test::circle_pose(k), 1000 + static_cast<unsigned>(k));
    auto [kf, points] = frontend.keyframe(mapper.map(), view, view.kf.T_wc);
    mapper.process_keyframe(std::move(kf), std::move(points));
  }
}

class MapFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    run(mapper_, frontend_, world_, 0, 5);
    path_ = temp_path("map.bin");
    mapper_.save(path_);
  }
  void TearDown() override {
    std::filesystem::remove(path_);
    std::filesystem::remove(temp_path("damaged.bin"));
  }
  std::filesystem::path damaged(const std::function<void(std::vector<char>&)>& edit) {
    std::ifstream in(path_, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    edit(bytes);
    const auto out_path = temp_path("damaged.bin");
    std::ofstream out(out_path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return out_path;
  }
  static std::string load_error(const std::filesystem::path& path) {
    try {
      load_map_file(path);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }

  test::SyntheticWorld world_ = test::make_room(1500, 81);
  LocalMapper mapper_{world_.camera, LocalMapperOptions{}};
  test::FrontendEmulator frontend_{world_};
  std::filesystem::path path_;
};

TEST_F(MapFileTest, RoundTripIsExact) {
  const MapSnapshot loaded = load_map_file(path_);
  expect_maps_equal(mapper_.map(), loaded.map);
  const MapperState& a = mapper_.state();
  const MapperState& b = loaded.state;
  EXPECT_EQ(a.next_point_counter, b.next_point_counter);
  EXPECT_EQ(a.keyframes_processed, b.keyframes_processed);
  EXPECT_EQ(a.last_keyframe, b.last_keyframe);
  EXPECT_EQ(a.created_version, b.created_version);
  EXPECT_EQ(a.recent_points, b.recent_points);
  EXPECT_EQ(a.merged_into, b.merged_into);
  EXPECT_EQ(a.culled_T_pc.size(), b.culled_T_pc.size());
}

// A mapper restarted from its file continues exactly as one that never stopped (kill -9 + restart).
TEST_F(MapFileTest, ResumedMapperMatchesUninterruptedRun) {
  LocalMapper resumed(world_.camera, LocalMapperOptions{}, load_map_file(path_));
  test::FrontendEmulator frontend_copy = frontend_;
  run(mapper_, frontend_, world_, 6, 9);
  run(resumed, frontend_copy, world_, 6, 9);
  expect_maps_equal(mapper_.map(), resumed.map());
}

TEST_F(MapFileTest, TruncatedFileGivesOneLineError) {
  const auto size = std::filesystem::file_size(path_);
  for (const std::size_t keep : {std::size_t{0}, std::size_t{5}, std::size_t{23}, std::size_t{100},
                                 static_cast<std::size_t>(size / 2), static_cast<std::size_t>(size - 1)}) {
    const auto path = damaged([keep](std::vector<char>& bytes) { bytes.resize(keep); });
    const std::string error = load_error(path);
    EXPECT_NE(error.find("map file " + path.string()), std::string::npos) << error;
    EXPECT_EQ(error.find('\n'), std::string::npos);
  }
}

TEST_F(MapFileTest, CorruptByteIsDetected) {
  const auto path = damaged([](std::vector<char>& bytes) { bytes[bytes.size() / 2] ^= 0x5a; });
  EXPECT_NE(load_error(path).find("checksum mismatch"), std::string::npos);
}

TEST_F(MapFileTest, WrongMagicAndVersionAreNamed) {
  EXPECT_NE(load_error(damaged([](std::vector<char>& bytes) { bytes[0] = 'X'; })).find("not a heslam map file"),
            std::string::npos);
  EXPECT_NE(load_error(damaged([](std::vector<char>& bytes) { bytes[8] = 99; })).find("format version 99"),
            std::string::npos);
  EXPECT_NE(load_error(temp_path("missing.bin")).find("cannot open"), std::string::npos);
}

// The atlas: keyframes and points of a second map keep their map id through save and load (a restarted
// mapper, save_map / load).
TEST_F(MapFileTest, MapIdsSurviveTheRoundTrip) {
  Map map = mapper_.map();
  ASSERT_GE(map.keyframes.size(), 2u);
  const KeyframeId second_map_keyframe = map.keyframes.rbegin()->first;
  map.keyframes.at(second_map_keyframe).map_id = 3;
  map.points.begin()->second.map_id = 3;
  const auto path = temp_path("atlas.bin");
  save_map_file(path, map, mapper_.state());
  const MapSnapshot loaded = load_map_file(path);
  std::filesystem::remove(path);
  expect_maps_equal(map, loaded.map);
  EXPECT_EQ(loaded.map.keyframes.at(second_map_keyframe).map_id, 3u);
  EXPECT_EQ(loaded.map.keyframes.begin()->second.map_id, kFirstMapId);
  EXPECT_EQ(loaded.map.points.begin()->second.map_id, 3u);
}

TEST_F(MapFileTest, SaveLeavesNoTemporaryFile) {
  EXPECT_FALSE(std::filesystem::exists(path_.string() + ".tmp"));
  EXPECT_GT(std::filesystem::file_size(path_), 1000u);
}

}  // namespace
}  // namespace heslam
