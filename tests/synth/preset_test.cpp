// Presets: every shipped preset loads and describes the trajectory it promises; bad files give one
// line naming file and field.
#include <algorithm>
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
  for (const char* name : {"room", "room_exposure", "corridor_loop", "street", "town"}) {
    EXPECT_NO_THROW(test::repo_preset(name)) << name;
    EXPECT_FALSE(load_preset(find_preset(name)).purpose.empty()) << name << ": heslam-synth --list shows it";
  }
  const auto known = known_presets();
  EXPECT_NE(std::find(known.begin(), known.end(), "street"), known.end());
}

TEST(SynthPresets, TrajectoriesHaveRealisticSpeedsAndRates) {
  struct Case {
    const char* name;
    double max_speed_mps, max_rate_rad_s, min_length_m;
  };
  for (const Case& c : {Case{"room", 1.3, 2.0, 20.0}, Case{"corridor_loop", 1.5, 2.0, 40.0},
                        Case{"street", 11.0, 0.8, 500.0}, Case{"town", 11.0, 0.8, 500.0}}) {
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

// Street buildings are 7-20 m high, parked cars 1.45 m.
constexpr double kFacadeMinHeightM = 5.0;

// Distance from p to the nearest point of a quad's rectangle.
double distance_to_quad(const Eigen::Vector3d& p, const Quad& q) {
  const Eigen::Vector3d d = p - q.origin_w;
  const double u = std::clamp(d.dot(q.axis_u_w), 0.0, q.size_u_m);
  const double v = std::clamp(d.dot(q.axis_v_w), 0.0, q.size_v_m);
  return (p - q.point(u, v)).norm();
}

// The street drive started in front of a facade that stood across the road and drove
// through it. At every frame of a driving preset the camera (on the car's centre line, half a car
// width = 0.9 m from its side) stays 3 m from facades and 1.2 m from anything else (parked cars).
TEST(SynthPresets, DrivesStayOnTheRoad) {
  for (const char* name : {"street", "town"}) {
    const Preset p = test::repo_preset(name);
    const BuiltScene scene = build_scene(p);
    const Trajectory traj(scene.path, p.trajectory, 1);
    double closest_facade_m = 1e9, closest_other_m = 1e9;
    for (int k = 0; k < p.frames; ++k) {
      const Eigen::Vector3d c = traj.T_wb(k / p.camera.rate_hz).translation();
      for (const Quad& q : scene.scene.quads) {
        if (std::abs(q.normal_w().z()) > 0.5) continue;  // ground, sidewalks, markings, roofs
        double& closest = q.size_v_m > kFacadeMinHeightM ? closest_facade_m : closest_other_m;
        closest = std::min(closest, distance_to_quad(c, q));
      }
    }
    EXPECT_GT(closest_facade_m, 3.0) << name;
    EXPECT_GT(closest_other_m, 1.2) << name;
  }
}

// The second driving preset: a stop at the crossroads, turns both ways, braking to rest at the end.
TEST(SynthPresets, TownStopsAtTheCrossroadsAndTurnsBothWays) {
  const Preset p = test::repo_preset("town");
  ASSERT_EQ(p.trajectory.stops.size(), 1u);
  const BuiltScene scene = build_scene(p);
  const Trajectory traj(scene.path, p.trajectory, 1);
  const double duration = p.frames / p.camera.rate_hz;
  const double dt = 1.0 / p.camera.rate_hz;
  double at_rest_s = 0.0, max_left_rad_s = 0.0, max_right_rad_s = 0.0;
  Eigen::Vector3d rest_position = Eigen::Vector3d::Zero();
  for (double t = 5.0; t + dt < duration - 10.0; t += dt) {
    if (traj.velocity_w(t).norm() < 1e-6) {
      at_rest_s += dt;
      rest_position = traj.T_wb(t).translation();
    }
    const Eigen::Vector3d x0 = traj.T_wb(t).linear().col(0), x1 = traj.T_wb(t + dt).linear().col(0);
    const double yaw_rate = std::atan2(x0.x() * x1.y() - x0.y() * x1.x(), x0.dot(x1)) / dt;
    max_left_rad_s = std::max(max_left_rad_s, yaw_rate);
    max_right_rad_s = std::max(max_right_rad_s, -yaw_rate);
  }
  EXPECT_NEAR(at_rest_s, p.trajectory.stops[0].wait_s, 2 * dt);
  // The stop line before the crossroads at (100, 80), on the right-hand lane going north.
  EXPECT_NEAR(rest_position.x(), 101.8, 0.5);
  EXPECT_NEAR(rest_position.y(), 67.0, 1.0);
  EXPECT_GT(max_left_rad_s, 0.3);
  EXPECT_GT(max_right_rad_s, 0.3);
  // Braked to rest at the end, not stopped dead: the last second is still, the one before slows down.
  EXPECT_LT(traj.velocity_w(duration - 1.0).norm(), 1e-6);
  const double v_before = traj.velocity_w(duration - 3.0).norm();
  EXPECT_GT(v_before, 0.1);
  EXPECT_LT(v_before, p.trajectory.speed_mps);
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
  expect_error("scene: room\nevents:\n  - type: stereo_gain\n    start_s: 1\n    end_s: 2\n", "'events[0].left'");
  expect_error("scene: room\nevents:\n  - type: stereo_gain\n    start_s: 1\n    end_s: 2\n    left: 1\n    right: 0\n",
               "'events[0].right'");
  expect_error("scene: room\nevents:\n  - type: darkness\n    start_s: 1\n    end_s: 2\n    left: 2\n",
               "'events[0].left'");
  expect_error("scene: town\ntrajectory:\n  stops:\n    - {at_m: 50, wait_s: 1}\n    - {at_m: 20, wait_s: 1}\n",
               "'trajectory.stops[1].at_m'");
  EXPECT_THROW(find_preset("no_such_preset"), std::runtime_error);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace heslam::synth
