// Synthetic trajectories with known geometry for the evaluation tests.
#pragma once

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "tools/eval/trajectory.hpp"

namespace heslam::eval::test {

// A figure-eight drive with a slow climb, heading along the path, with small roll and pitch
// oscillations; 0.1 s between poses.
inline Trajectory figure_eight(std::size_t poses = 400) {
  Trajectory t;
  t.name = "figure_eight";
  for (std::size_t k = 0; k < poses; ++k) {
    const double a = 2.0 * M_PI * static_cast<double>(k) / static_cast<double>(poses);
    const Eigen::Vector3d p(20.0 * std::cos(a), 10.0 * std::sin(2.0 * a), 0.01 * static_cast<double>(k));
    const double yaw = std::atan2(20.0 * std::cos(2.0 * a), -20.0 * std::sin(a));
    const Eigen::Quaterniond q = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(0.05 * std::sin(3.0 * a), Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(0.03 * std::cos(5.0 * a), Eigen::Vector3d::UnitX());
    t.push_back(make_pose(p, q), static_cast<std::int64_t>(k), 100.0 + 0.1 * static_cast<double>(k));
  }
  return t;
}

// A straight drive along +z (the KITTI camera's forward axis), `step_m` between poses, no rotation.
inline Trajectory straight_line(std::size_t poses, double step_m) {
  Trajectory t;
  t.name = "straight_line";
  for (std::size_t k = 0; k < poses; ++k) {
    Pose3 T = Pose3::Identity();
    T.translation() = Eigen::Vector3d(0.0, 0.0, step_m * static_cast<double>(k));
    t.push_back(T, static_cast<std::int64_t>(k));
  }
  return t;
}

// A camera held still at (1, 2, 3): `poses` poses 0.05 s apart whose positions wobble by about
// `wobble_m` (deterministic, different per axis), with a slowly nodding heading.
inline Trajectory still_wobble(std::size_t poses, double wobble_m, double phase = 0.0) {
  Trajectory t;
  t.name = "still_wobble";
  for (std::size_t k = 0; k < poses; ++k) {
    const double a = 0.37 * static_cast<double>(k) + phase;
    const Eigen::Vector3d p =
        Eigen::Vector3d(1.0, 2.0, 3.0) + wobble_m * Eigen::Vector3d(std::sin(a), std::cos(1.7 * a), std::sin(2.3 * a));
    const Eigen::Quaterniond q(
        Eigen::AngleAxisd(0.02 * std::sin(0.1 * static_cast<double>(k)), Eigen::Vector3d::UnitZ()));
    t.push_back(make_pose(p, q), static_cast<std::int64_t>(k), 10.0 + 0.05 * static_cast<double>(k));
  }
  return t;
}

// A fresh, empty scratch folder for the current test.
inline std::filesystem::path scratch_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const auto dir = std::filesystem::path(::testing::TempDir()) / "heslam_eval" /
                   (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

}  // namespace heslam::eval::test
