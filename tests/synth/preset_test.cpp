// Presets: every shipped preset loads and describes the trajectory it promises; bad files give one
// line naming file and field.
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>

#include "synth_test_util.hpp"
#include "tools/synth/scene_builders.hpp"
#include "tools/synth/trajectory.hpp"

namespace heslam::synth {
namespace {

namespace fs = std::filesystem;

struct Motion {
  double max_speed = 0, max_rate = 0, length = 0, t_max_rate = 0;
};

Motion motion(const Trajectory& traj, double duration_s) {
  Motion m;
  const double dt = 0.05;
  for (double t = 0; t + dt <= duration_s; t += dt) {
    const Pose3 a = traj.T_wb(t), b = traj.T_wb(t + dt);
    const double step = (b.translation() - a.translation()).norm();
    m.length += step;
    m.max_speed = std::max(m.max_speed, step / dt);
    const double rate = Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() / dt;
    if (rate > m.max_rate) m.max_rate = rate, m.t_max_rate = t;
  }
  return m;
}

TEST(SynthPresets, ShippedPresetsLoad) {
  for (const char* name : {"room", "room_exposure", "corridor_loop", "street"}) {
    EXPECT_NO_THROW(test::repo_preset(name)) << name;
  }
  const auto known = known_presets();
  EXPECT_NE(std::find(known.begin(), known.end(), "street"), known.end());
}

TEST(SynthPresets, TrajectoriesHaveRealisticSpeedsAndRates) {
  struct Case {
    const char* name;
    double max_speed_mps, max_rate_rad_s, min_length_m;
  };
  for (const Case& c : {Case{"room", 1.3, 2.0, 20.0}, Case{"corridor_loop", 1.5, 2.0, 40.0}, Case{"street", 11.0, 0.8, 500.0}}) {
    const Preset p = test::repo_preset(c.name);
    const BuiltScene scene = build_scene(p);
    const Trajectory traj(scene.path, p.trajectory, 1);
    const Motion m = motion(traj, p.frames / p.camera.rate_hz);
    EXPECT_LT(m.max_speed, c.max_speed_mps) << c.name;
    EXPECT_LT(m.max_rate, c.max_rate_rad_s) << c.name << " at t=" << m.t_max_rate;
    EXPECT_GT(m.length, c.min_length_m) << c.name;
  }
}

TEST(SynthPresets, CorridorLoopReturnsAndRevisitsInTheOppositeDirection) {
  const Preset p = test::repo_preset("corridor_loop");
  const BuiltScene scene = build_scene(p);
  const Trajectory traj(scene.path, p.trajectory, 1);
  const double duration = p.frames / p.camera.rate_hz;
  const Pose3 start = traj.T_wb(2.0);
  bool same_direction = false, opposite_direction = false;
  for (double t = 30.0; t < duration; t += 0.05) {
    const Pose3 T = traj.T_wb(t);
    if ((T.translation() - start.translation()).head<2>().norm() > 0.6) continue;
    const double cos_heading = T.linear().col(0).dot(start.linear().col(0));
    same_direction |= cos_heading > 0.8;
    opposite_direction |= cos_heading < -0.8;
  }
  EXPECT_TRUE(same_direction) << "closes the loop";
  EXPECT_TRUE(opposite_direction) << "passes the start again facing the other way";
}

TEST(SynthPresets, StreetClosesALoop) {
  const Preset p = test::repo_preset("street");
  const BuiltScene scene = build_scene(p);
  const Trajectory traj(scene.path, p.trajectory, 1);
  const Pose3 start = traj.T_wb(5.0);
  double closest = 1e9;
  for (double t = 40.0; t < p.frames / p.camera.rate_hz; t += 0.1)
    closest = std::min(closest, (traj.T_wb(t).translation() - start.translation()).norm());
  EXPECT_LT(closest, 1.0);
}

TEST(SynthPresets, BadFilesNameFileAndField) {
  const fs::path dir = fs::temp_directory_path() / "heslam_synth_bad_presets";
  fs::create_directories(dir);
  auto expect_error = [&](const std::string& body, const std::string& expected) {
    const fs::path f = dir / "bad.yaml";
    std::ofstream(f) << "%YAML:1.0\n---\n" << body;
    try {
      load_preset(f);
      ADD_FAILURE() << "no error for: " << body;
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(f.string()), std::string::npos) << what;
      EXPECT_NE(what.find(expected), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
    }
  };
  expect_error("frames: 3\n", "'scene' is missing");
  expect_error("scene: moon\n", "'scene' is 'moon'");
  expect_error("scene: room\ncamera:\n  fx: fast\n", "'camera.fx' expected a number");
  expect_error("scene: room\ncamera:\n  distortion: [1, 2]\n", "'camera.distortion'");
  expect_error("scene: room\nevents:\n  - type: fog\n    start_s: 1\n    end_s: 2\n", "'events[0].type'");
  expect_error("scene: room\nevents:\n  - type: haze\n    start_s: 3\n    end_s: 2\n", "'events[0].end_s'");
  EXPECT_THROW(find_preset("no_such_preset"), std::runtime_error);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace heslam::synth
