// Stereo-inertial heslam end to end (issue 34): config/pipelines/euroc_inertial.yaml and synth_inertial.yaml
// as real processes under heslam-supervisor, in lockstep, each run on its own domain. Known answers: the
// EuRoC ground truth of the shared MH01 clip (skipped when absent) and heslam-synth's exact trajectory.
// Blackouts are copies of the data made here: every file a symlink but the blackened frames' PNGs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "pipeline_runs.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"
#include "tools/eval/association.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

using test::ate_rmse_m;
using test::finish;
using test::lost_entries;
using test::start_pipeline;

// Bound of a hung pipeline run, not a performance assertion: lockstep runs on a loaded 2-core machine
// go at 1-2 frames/s (the 400-frame room took 289 s for 283 frames at load ~28).
constexpr std::chrono::seconds kRunTimeout{1200};

// The synthetic room with --imu: 20 s at 20 Hz, a 2 s blackout in the middle.
constexpr int kSynthFrames = 400;
constexpr int kSynthBlackFirst = 200;
constexpr int kSynthBlackFrames = 40;

// A copy of the EuRoC folder `source` in `dest`: symlinks, but frames [first, first + count) of cam0 and
// cam1 (in stamp order) written black, same size. Returns the number of frames of cam0.
std::size_t blackout_copy(const fs::path& source, const fs::path& dest, int first, int count) {
  fs::create_directories(dest / "mav0");
  std::size_t frames = 0;
  for (const auto& entry : fs::directory_iterator(source / "mav0")) {
    const std::string name = entry.path().filename().string();
    if (name != "cam0" && name != "cam1") {
      fs::create_symlink(fs::absolute(entry.path()), dest / "mav0" / name);
      continue;
    }
    const fs::path camera = dest / "mav0" / name;
    fs::create_directories(camera / "data");
    for (const auto& file : fs::directory_iterator(entry.path())) {
      if (file.path().filename() != "data")
        fs::create_symlink(fs::absolute(file.path()), camera / file.path().filename());
    }
    std::vector<fs::path> images;
    for (const auto& image : fs::directory_iterator(entry.path() / "data")) images.push_back(image.path());
    std::sort(images.begin(), images.end());
    for (std::size_t i = 0; i < images.size(); ++i) {
      const fs::path target = camera / "data" / images[i].filename();
      if (static_cast<int>(i) >= first && static_cast<int>(i) < first + count) {
        const cv::Mat original = cv::imread(images[i].string(), cv::IMREAD_GRAYSCALE);
        if (original.empty() || !cv::imwrite(target.string(), cv::Mat::zeros(original.size(), CV_8UC1))) {
          throw std::runtime_error("cannot blacken " + images[i].string() + " into " + target.string());
        }
      } else {
        fs::create_symlink(fs::absolute(images[i]), target);
      }
    }
    if (name == "cam0") frames = images.size();
  }
  return frames;
}

// The number in the first match of `pattern`'s group 1 in `text`, -1 when none.
long long first_number(const std::string& text, const std::string& pattern) {
  std::smatch match;
  return std::regex_search(text, match, std::regex(pattern)) ? std::stoll(match[1]) : -1;
}

std::size_t occurrences(const std::string& text, const std::string& needle) {
  std::size_t count = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++count;
  return count;
}

struct PipelineRun {
  int code = -1;
  std::string output;
  fs::path trajectory;
  fs::path lost;
};

PipelineRun run_pipeline(const std::string& pipeline, const fs::path& dataset, const fs::path& dir,
                         const std::string& label, const std::vector<std::string>& args = {},
                         std::chrono::seconds timeout = kRunTimeout) {
  auto supervisor = start_pipeline(pipeline, dataset, dir, label, test::exclusive_domain_id(), args);
  PipelineRun run;
  run.code = finish(*supervisor, timeout);
  run.output = supervisor->out() + supervisor->err();
  run.trajectory = dir / (label + ".txt");
  run.lost = dir / (label + ".lost.txt");
  return run;
}

std::size_t poses_in(const fs::path& trajectory) { return eval::read_trajectory(trajectory).size(); }

// The recorder's STEM.inertial.txt (docs/outputs.md): R_gw and the velocities by stamp (ns).
struct InertialFile {
  std::optional<Eigen::Quaterniond> R_gw;
  std::map<std::int64_t, Eigen::Vector3d> velocities;
};

InertialFile read_inertial_file(const fs::path& path) {
  InertialFile file;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    if (line.rfind("R_gw ", 0) == 0) {
      std::string tag;
      double x, y, z, w;
      if (fields >> tag >> x >> y >> z >> w) file.R_gw = Eigen::Quaterniond(w, x, y, z);
      continue;
    }
    if (line.rfind("g_w ", 0) == 0) continue;
    std::uint64_t seq = 0;
    double stamp_s = 0.0;
    Eigen::Vector3d v;
    if (fields >> seq >> stamp_s >> v.x() >> v.y() >> v.z()) {
      file.velocities[static_cast<std::int64_t>(std::llround(stamp_s * 1e9))] = v;
    }
  }
  return file;
}

// The ground truth's velocities (the IMU body's, in its world) by stamp (ns): EuRoC's v_RS_R columns when
// the file has them (heslam-synth's), else central differences of its positions (the shared MH01 clip's
// ground truth has positions only: 20 Hz, so the difference spans 0.1 s).
std::map<std::int64_t, Eigen::Vector3d> ground_truth_velocities(const fs::path& dataset) {
  std::map<std::int64_t, Eigen::Vector3d> velocities;
  std::vector<std::pair<std::int64_t, Eigen::Vector3d>> positions;
  std::ifstream in(dataset / "mav0/state_groundtruth_estimate0/data.csv");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream fields(line);
    std::int64_t stamp = 0;
    Eigen::Vector3d p;
    double skip = 0.0;
    Eigen::Vector3d v;
    if (!(fields >> stamp >> p.x() >> p.y() >> p.z())) continue;
    positions.emplace_back(stamp, p);
    for (int k = 0; k < 4; ++k) fields >> skip;
    if (fields >> v.x() >> v.y() >> v.z()) velocities[stamp] = v;
  }
  if (!velocities.empty()) return velocities;
  for (std::size_t i = 1; i + 1 < positions.size(); ++i) {
    const double dt_s = static_cast<double>(positions[i + 1].first - positions[i - 1].first) * 1e-9;
    velocities[positions[i].first] = (positions[i + 1].second - positions[i - 1].second) / dt_s;
  }
  return velocities;
}

// The recorder's velocities against the ground truth's (within 3 ms of the frame): the rms error of the
// speed, which does not depend on the worlds' orientations.
struct VelocityCheck {
  double speed_rms_m_s = -1.0;
  std::size_t velocities = 0;
};

VelocityCheck check_velocities(const fs::path& dataset, const PipelineRun& run) {
  VelocityCheck check;
  const std::map<std::int64_t, Eigen::Vector3d> truth = ground_truth_velocities(dataset);
  double speed = 0.0;
  const fs::path file = fs::path(run.trajectory).replace_extension(".inertial.txt");
  for (const auto& [stamp, v] : read_inertial_file(file).velocities) {
    auto it = truth.lower_bound(stamp - 3'000'000);
    if (it == truth.end() || it->first > stamp + 3'000'000) continue;
    speed += (v.norm() - it->second.norm()) * (v.norm() - it->second.norm());
    ++check.velocities;
  }
  if (check.velocities > 0) check.speed_rms_m_s = std::sqrt(speed / static_cast<double>(check.velocities));
  return check;
}

// Per pose, the tilt between the recorder's world z and the ground truth's (z vertical): the recorder
// writes gravity-aligned files, so it is the pose's roll / pitch error (yaw does not tilt z). Sorted.
std::vector<double> world_tilts_deg(const fs::path& dataset, const PipelineRun& run) {
  const eval::Trajectory estimate = eval::read_trajectory(run.trajectory);
  const eval::AlignedPair pairs = eval::associate(test::ground_truth_for(dataset, estimate), estimate);
  std::vector<double> tilts;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const Eigen::Matrix3d R_rel = pairs.est.poses_wc[i].linear() * pairs.gt.poses_wc[i].linear().transpose();
    const Eigen::Vector3d z = R_rel * Eigen::Vector3d::UnitZ();
    tilts.push_back(std::atan2(z.head<2>().norm(), z.z()) * 180.0 / M_PI);
  }
  std::sort(tilts.begin(), tilts.end());
  return tilts;
}

double median_world_tilt_deg(const fs::path& dataset, const PipelineRun& run) {
  const std::vector<double> tilts = world_tilts_deg(dataset, run);
  return tilts.empty() ? 180.0 : tilts[tilts.size() / 2];
}

double max_world_tilt_deg(const fs::path& dataset, const PipelineRun& run) {
  const std::vector<double> tilts = world_tilts_deg(dataset, run);
  return tilts.empty() ? 180.0 : tilts.back();
}

TEST(InertialEndToEnd, EurocMh01InitializesWithin2sAndIsNoWorseThanStereoOnly) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("inertial_mh01");
  const PipelineRun inertial = run_pipeline("euroc_inertial", dataset, dir.path(), "inertial");
  ASSERT_EQ(inertial.code, 0) << inertial.output;
  const PipelineRun stereo = run_pipeline("euroc_inertial", dataset, dir.path(), "stereo", {"imu=none"});
  ASSERT_EQ(stereo.code, 0) << stereo.output;
  EXPECT_EQ(poses_in(inertial.trajectory), 160u);
  EXPECT_EQ(poses_in(stereo.trajectory), 160u);
  // Initialized from the keyframes of the first 2 s (40 frames at 20 Hz, frame 0 the first).
  const long long initialized_at = first_number(inertial.output, R"(IMU initialized at frame (\d+))");
  ASSERT_GE(initialized_at, 0) << inertial.output;
  EXPECT_LE(initialized_at, 40) << inertial.output;
  EXPECT_EQ(occurrences(stereo.output, "inertial tracking:"), 0u) << "--arg imu=none must be stereo-only";
  const double inertial_ate_m = ate_rmse_m(dataset, inertial.trajectory);
  const double stereo_ate_m = ate_rmse_m(dataset, stereo.trajectory);
  std::printf("MH01 ATE: stereo-inertial %.3f mm, stereo-only %.3f mm; IMU initialized at frame %lld\n",
              inertial_ate_m * 1e3, stereo_ate_m * 1e3, initialized_at);
  EXPECT_LE(inertial_ate_m, stereo_ate_m * 1.05);
  // The recorder writes the velocities (inertial runs only).
  const VelocityCheck velocity = check_velocities(dataset, inertial);
  std::printf("MH01 velocity: speed rms %.4f m/s over %zu frames\n", velocity.speed_rms_m_s, velocity.velocities);
  EXPECT_GE(velocity.velocities, 100u);
  EXPECT_LT(velocity.speed_rms_m_s, 0.015);  // 0.0073 (the ground truth's own differences limit it)
  const double tilt_deg = median_world_tilt_deg(dataset, inertial);
  std::printf("MH01 world tilt %.3f deg (median)\n", tilt_deg);
  // Measured 0.899 deg (2026-12-06) with the mapper's inertial local BA on (1.009 without it: the frontend's
  // gravity estimate, refined over the keyframes, is better on the poses the inertial BA refines). Issue 34's
  // bar: 1 deg. The initializer on the ground truth's own poses is 0.47 deg off (InertialInitialization.*).
  EXPECT_LT(tilt_deg, 1.0);
  EXPECT_FALSE(fs::exists(fs::path(stereo.trajectory).replace_extension(".inertial.txt")));
}

TEST(InertialEndToEnd, EurocMh01BlackFrames60To79CarriedByTheImu) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path source = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("inertial_blackout");
  const fs::path dataset = dir.path() / "mh01_black";
  ASSERT_EQ(blackout_copy(source, dataset, 60, 20), 160u);
  const PipelineRun inertial = run_pipeline("euroc_inertial", dataset, dir.path(), "inertial");
  ASSERT_EQ(inertial.code, 0) << inertial.output;
  EXPECT_EQ(poses_in(inertial.trajectory), 160u) << inertial.output;
  EXPECT_EQ(lost_entries(inertial.lost), 0) << inertial.output;
  EXPECT_NE(inertial.output.find("tracked 160/160 frames, 0 lost"), std::string::npos) << inertial.output;
  const long long inertial_only = first_number(inertial.output, R"(, (\d+) inertial-only frames)");
  EXPECT_GE(inertial_only, 20) << inertial.output;
  const double ate_m = ate_rmse_m(source, inertial.trajectory);
  // Stereo-only on the same copy has no pose for the black frames.
  const PipelineRun stereo = run_pipeline("euroc_inertial", dataset, dir.path(), "stereo", {"imu=none"});
  ASSERT_EQ(stereo.code, 0) << stereo.output;
  std::printf(
      "MH01 frames 60-79 black: stereo-inertial %zu poses, ATE %.3f mm (%lld inertial-only); stereo-only "
      "%zu poses\n",
      poses_in(inertial.trajectory), ate_m * 1e3, inertial_only, poses_in(stereo.trajectory));
  EXPECT_LE(poses_in(stereo.trajectory), 140u);
  EXPECT_LE(ate_m, 0.006);
}

TEST(InertialEndToEnd, EurocMh01ImuStoppingMidRunFallsBackToStereoOnlyWithOneWarning) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path source = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("inertial_imu_stops");
  // The copy's imu0/data.csv ends 4 s into the clip (frame 80 of 160).
  const fs::path dataset = dir.path() / "mh01_imu_stops";
  fs::create_directories(dataset / "mav0" / "imu0");
  for (const auto& entry : fs::directory_iterator(source / "mav0")) {
    if (entry.path().filename() != "imu0") fs::create_symlink(entry.path(), dataset / "mav0" / entry.path().filename());
  }
  fs::create_symlink(source / "mav0/imu0/sensor.yaml", dataset / "mav0/imu0/sensor.yaml");
  std::vector<fs::path> images;
  for (const auto& image : fs::directory_iterator(source / "mav0/cam0/data")) images.push_back(image.path());
  std::sort(images.begin(), images.end());
  const long long stop_ns = std::stoll(images[80].stem().string());
  std::ifstream in(source / "mav0/imu0/data.csv");
  std::ofstream out(dataset / "mav0/imu0/data.csv");
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#' && std::stoll(line.substr(0, line.find(','))) > stop_ns) break;
    out << line << "\n";
  }
  out.close();
  const PipelineRun run = run_pipeline("euroc_inertial", dataset, dir.path(), "stops");
  ASSERT_EQ(run.code, 0) << run.output;
  EXPECT_EQ(occurrences(run.output, "IMU off:"), 1u) << run.output;
  EXPECT_EQ(poses_in(run.trajectory), 160u) << run.output;
  const double ate_m = ate_rmse_m(source, run.trajectory);
  std::printf("MH01, IMU stops at frame 80: ATE %.3f mm\n", ate_m * 1e3);
  EXPECT_LE(ate_m, 0.0045);
}

TEST(InertialEndToEnd, SynthRoomTracksEveryFrameAndA2sBlackoutKeepsEveryPose) {
  const test::ScratchDir dir("inertial_synth");
  const fs::path rendered = dir.path() / "room_imu";
  test::ChildProcess synth(test::bin_dir() / "heslam-synth",
                           {"--preset", "room", "--frames", std::to_string(kSynthFrames), "--threads", "2",
                            "--no-events", "--imu", "--out", rendered.string()},
                           dir.path(), "synth");
  ASSERT_EQ(synth.wait(std::chrono::seconds(600)).value_or(-1), 0) << synth.err();
  const PipelineRun clear = run_pipeline("synth_inertial", rendered, dir.path(), "clear", {"loop_closer=none"});
  ASSERT_EQ(clear.code, 0) << clear.output;
  EXPECT_EQ(poses_in(clear.trajectory), static_cast<std::size_t>(kSynthFrames)) << clear.output;
  EXPECT_EQ(first_number(clear.output, R"(, (\d+) inertial-only frames)"), 0) << clear.output;
  const VelocityCheck velocity = check_velocities(rendered, clear);
  std::printf("synthetic room velocity: speed rms %.4f m/s over %zu frames\n", velocity.speed_rms_m_s,
              velocity.velocities);
  EXPECT_GE(velocity.velocities, 300u);
  EXPECT_LT(velocity.speed_rms_m_s, 0.02);
  const double tilt_deg = median_world_tilt_deg(rendered, clear);
  std::printf("synthetic room world tilt %.3f deg (median)\n", tilt_deg);
  EXPECT_LT(tilt_deg, 0.5);  // exact gravity

  const fs::path black = dir.path() / "room_imu_black";
  ASSERT_EQ(blackout_copy(rendered, black, kSynthBlackFirst, kSynthBlackFrames),
            static_cast<std::size_t>(kSynthFrames));
  const PipelineRun blackout = run_pipeline("synth_inertial", black, dir.path(), "blackout", {"loop_closer=none"});
  ASSERT_EQ(blackout.code, 0) << blackout.output;
  EXPECT_EQ(poses_in(blackout.trajectory), static_cast<std::size_t>(kSynthFrames)) << blackout.output;
  EXPECT_EQ(lost_entries(blackout.lost), 0) << blackout.output;
  EXPECT_GE(first_number(blackout.output, R"(, (\d+) inertial-only frames)"), kSynthBlackFrames) << blackout.output;
  const double clear_ate_m = ate_rmse_m(rendered, clear.trajectory);
  const double blackout_ate_m = ate_rmse_m(rendered, blackout.trajectory);
  std::printf("synthetic room with --imu, %d frames: ATE %.3f mm; with a 2 s blackout %.3f mm\n", kSynthFrames,
              clear_ate_m * 1e3, blackout_ate_m * 1e3);
  EXPECT_LE(blackout_ate_m, 2.0 * clear_ate_m);
}

// Loop closing in an inertial run (issue 34): corridor_loop (42 m round a ring of corridors, back past the
// start, docs/tools/synth.md) rendered with --imu, through synth_inertial with heslam-loop-closer. The
// loop closer takes gravity from the odometry and corrects the loop with the 4-DoF pose graph (yaw and
// translation only); the same run with pose_graph.gravity_from_odometry: false corrects it in 6 DoF.
// Known answers: heslam-synth's exact trajectory (z vertical) against the recorder's gravity-aligned files.
constexpr int kCorridorFrames = 960;

TEST(InertialEndToEnd, CorridorLoopClosedWithTheFourDofPoseGraphKeepsRollAndPitch) {
  const test::ScratchDir dir("inertial_loop");
  const fs::path rendered = dir.path() / "corridor_imu";
  test::ChildProcess synth(test::bin_dir() / "heslam-synth",
                           {"--preset", "corridor_loop", "--frames", std::to_string(kCorridorFrames), "--threads", "2",
                            "--imu", "--out", rendered.string()},
                           dir.path(), "synth");
  ASSERT_EQ(synth.wait(kRunTimeout).value_or(-1), 0) << synth.err();
  const fs::path six_dof_config = dir.path() / "six_dof.yaml";
  std::ofstream(six_dof_config) << "%YAML:1.0\n---\npose_graph:\n  gravity_from_odometry: false\n";
  const auto loops = [](const std::string& output) { return first_number(output, R"((\d+) loops accepted)"); };

  const PipelineRun four =
      run_pipeline("synth_inertial", rendered, dir.path(), "four_dof", {"loop_closer=heslam-loop-closer"});
  ASSERT_EQ(four.code, 0) << four.output;
  const PipelineRun six =
      run_pipeline("synth_inertial", rendered, dir.path(), "six_dof",
                   {"loop_closer=heslam-loop-closer", "loop_closer_config=" + six_dof_config.string()});
  ASSERT_EQ(six.code, 0) << six.output;

  EXPECT_EQ(poses_in(four.trajectory), static_cast<std::size_t>(kCorridorFrames)) << four.output;
  EXPECT_GE(loops(four.output), 1) << four.output;
  EXPECT_GE(loops(six.output), 1) << six.output;
  EXPECT_NE(four.output.find("loop corrections use the 4-DoF pose graph about the odometry's gravity"),
            std::string::npos)
      << four.output;
  EXPECT_GE(first_number(four.output, R"((\d+) of the loops corrected with the 4-DoF pose graph)"), 1) << four.output;
  EXPECT_EQ(six.output.find("4-DoF pose graph about"), std::string::npos) << six.output;

  const double four_ate_m = ate_rmse_m(rendered, four.trajectory);
  const double six_ate_m = ate_rmse_m(rendered, six.trajectory);
  const double four_tilt_deg = max_world_tilt_deg(rendered, four);
  const double six_tilt_deg = max_world_tilt_deg(rendered, six);
  std::printf(
      "corridor_loop with --imu, %d frames: 4-DoF ATE %.3f mm, roll/pitch error max %.3f deg (median %.3f); "
      "6-DoF ATE %.3f mm, max %.3f deg (median %.3f)\n",
      kCorridorFrames, four_ate_m * 1e3, four_tilt_deg, median_world_tilt_deg(rendered, four), six_ate_m * 1e3,
      six_tilt_deg, median_world_tilt_deg(rendered, six));
  EXPECT_LT(four_tilt_deg, 0.5);
  EXPECT_LE(four_ate_m, six_ate_m * 1.05);  // not worse than 6-DoF (5 %: the runs differ after the loop)
}

}  // namespace
}  // namespace heslam
