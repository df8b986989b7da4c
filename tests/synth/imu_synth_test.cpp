// heslam-synth --imu, the proof of issue 34's input: on a noise-free render, preintegrating the
// written imu0/ readings between consecutive frames reproduces the ground truth's relative rotation,
// velocity and position change (to the midpoint integrator's discretization error, ~1e-8 over a 50 ms
// frame interval at 200 Hz); the noisy render's readings carry the noise model's white noise and a
// random-walk bias that the ground truth's bias columns record.
#include <cmath>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "components/core/imu/imu_buffer.hpp"
#include "components/core/imu/so3.hpp"
#include "synth_test_util.hpp"
#include "tools/dataset/imu_reader.hpp"
#include "tools/synth/imu_synth.hpp"
#include "tools/synth/writers.hpp"

namespace heslam::synth {
namespace {

namespace fs = std::filesystem;

struct GroundTruthRow {
  std::int64_t stamp_ns = 0;
  NavState state;
  ImuBias bias;
};

std::vector<GroundTruthRow> read_ground_truth(const fs::path& file) {
  std::ifstream in(file);
  std::vector<GroundTruthRow> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream fields(line);
    GroundTruthRow row;
    double p[3], q[4], v[3], bw[3], ba[3];
    fields >> row.stamp_ns >> p[0] >> p[1] >> p[2] >> q[0] >> q[1] >> q[2] >> q[3] >> v[0] >> v[1] >> v[2] >> bw[0] >>
        bw[1] >> bw[2] >> ba[0] >> ba[1] >> ba[2];
    EXPECT_TRUE(fields) << line;
    row.state.p_wb = Eigen::Vector3d(p[0], p[1], p[2]);
    row.state.R_wb = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
    row.state.v_wb = Eigen::Vector3d(v[0], v[1], v[2]);
    row.bias.gyro_rad_s = Eigen::Vector3d(bw[0], bw[1], bw[2]);
    row.bias.accel_m_s2 = Eigen::Vector3d(ba[0], ba[1], ba[2]);
    rows.push_back(row);
  }
  return rows;
}

RenderOptions imu_options(bool noise_free, int frames) {
  RenderOptions options;
  options.frames = frames;
  options.imu = true;
  options.imu_noise_free = noise_free;
  options.events = false;
  return options;
}

const Eigen::Vector3d kGravity(0.0, 0.0, -kGravityMps2);

TEST(SynthImu, NoiseFreeReadingsPreintegrateToTheGroundTruthBetweenFrames) {
  ::heslam::test::ScratchDir dir("synth_imu");
  SequenceRenderer renderer(test::repo_preset("room"), imu_options(true, 41));
  write_sequence(renderer, OutputFormat::kEuroc, dir.path());
  const ImuRecording imu = read_euroc_imu(dir.path());
  EXPECT_EQ(imu.rate_hz, 200.0);
  EXPECT_TRUE(imu.T_BS.isApprox(Pose3::Identity()));
  // 2 s before the first frame to 2 s after the last, every 5 ms.
  EXPECT_EQ(imu.samples.front().stamp_ns, renderer.stamp_ns(0) - 2'000'000'000);
  EXPECT_EQ(imu.samples.back().stamp_ns, renderer.stamp_ns(40) + 2'000'000'000);
  EXPECT_EQ(imu.samples.size(), 1201u);
  const std::vector<GroundTruthRow> truth =
      read_ground_truth(dir.path() / "mav0" / "state_groundtruth_estimate0" / "data.csv");
  ASSERT_EQ(truth.size(), 41u);

  // The frontend's path: the buffer cuts each frame interval, preintegrate() integrates it.
  ImuBuffer buffer({.source = "imu0"});
  for (const ImuSample& sample : imu.samples) ASSERT_TRUE(buffer.add(sample).accepted());
  double worst_rotation_rad = 0.0, worst_velocity_mps = 0.0, worst_position_m = 0.0;
  for (std::size_t i = 0; i + 1 < truth.size(); ++i) {
    const ImuInterval interval = buffer.interval(truth[i].stamp_ns, truth[i + 1].stamp_ns);
    ASSERT_EQ(interval.coverage, ImuCoverage::kComplete) << interval.message;
    const ImuPreintegration pre = preintegrate(interval.samples, truth[i].stamp_ns, truth[i + 1].stamp_ns);
    const NavState predicted = pre.predict(truth[i].state, kGravity);
    const NavState& actual = truth[i + 1].state;
    worst_rotation_rad = std::max(worst_rotation_rad, so3::log(predicted.R_wb.transpose() * actual.R_wb).norm());
    worst_velocity_mps = std::max(worst_velocity_mps, (predicted.v_wb - actual.v_wb).norm());
    worst_position_m = std::max(worst_position_m, (predicted.p_wb - actual.p_wb).norm());
    EXPECT_EQ(truth[i].bias.gyro_rad_s, Eigen::Vector3d::Zero());
  }
  // The motion is not trivial: it moves and turns.
  EXPECT_GT((truth.back().state.p_wb - truth.front().state.p_wb).norm(), 0.5);
  EXPECT_LT(worst_rotation_rad, 1e-6);
  EXPECT_LT(worst_velocity_mps, 1e-6);
  EXPECT_LT(worst_position_m, 1e-6);
  std::printf("noise-free, 40 intervals of 50 ms: worst rotation %.3g rad, velocity %.3g m/s, position %.3g m\n",
              worst_rotation_rad, worst_velocity_mps, worst_position_m);

  // Over the whole 2 s at once the midpoint integrator's error grows (second order in the step).
  const ImuPreintegration whole = preintegrate(imu.samples, truth.front().stamp_ns, truth.back().stamp_ns);
  const NavState end = whole.predict(truth.front().state, kGravity);
  std::printf("noise-free, one 2 s interval: rotation %.3g rad, velocity %.3g m/s, position %.3g m\n",
              so3::log(end.R_wb.transpose() * truth.back().state.R_wb).norm(),
              (end.v_wb - truth.back().state.v_wb).norm(), (end.p_wb - truth.back().state.p_wb).norm());
  EXPECT_LT((end.p_wb - truth.back().state.p_wb).norm(), 1e-4);
}

TEST(SynthImu, NoisyReadingsCarryTheModelsWhiteNoiseAndBiasWalk) {
  const Preset preset = test::repo_preset("room");
  SequenceRenderer noisy(preset, imu_options(false, 201));
  SequenceRenderer exact(preset, imu_options(true, 201));
  const SynthImu measured = synthesize_imu(noisy);
  const SynthImu ideal = synthesize_imu(exact);
  ASSERT_EQ(measured.samples.size(), ideal.samples.size());
  const ImuNoise noise;  // EuRoC's ADIS16448, the default
  const double dt = 0.005;
  double gyro_sq = 0.0, accel_sq = 0.0;
  const std::size_t n = measured.samples.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d gyro_noise =
        measured.samples[i].gyro_rad_s - ideal.samples[i].gyro_rad_s - measured.biases[i].gyro_rad_s;
    const Eigen::Vector3d accel_noise =
        measured.samples[i].accel_m_s2 - ideal.samples[i].accel_m_s2 - measured.biases[i].accel_m_s2;
    gyro_sq += gyro_noise.squaredNorm();
    accel_sq += accel_noise.squaredNorm();
  }
  // 3 axes x 2801 readings: the sample deviation is within 5 % of sigma / sqrt(dt).
  EXPECT_NEAR(std::sqrt(gyro_sq / (3.0 * n)), noise.gyro_noise_density / std::sqrt(dt),
              0.05 * noise.gyro_noise_density / std::sqrt(dt));
  EXPECT_NEAR(std::sqrt(accel_sq / (3.0 * n)), noise.accel_noise_density / std::sqrt(dt),
              0.05 * noise.accel_noise_density / std::sqrt(dt));
  // The bias starts at zero and walks: after T seconds its spread is sigma_rw sqrt(T) per axis.
  EXPECT_EQ(measured.biases.front().accel_m_s2, Eigen::Vector3d::Zero());
  const double T = static_cast<double>(n - 1) * dt;
  EXPECT_LT(measured.biases.back().accel_m_s2.norm(), 5.0 * noise.accel_random_walk * std::sqrt(3.0 * T));
  EXPECT_GT(measured.biases.back().accel_m_s2.norm(), 0.0);
  // Seeded: the same render gives the same readings.
  SequenceRenderer again(preset, imu_options(false, 201));
  EXPECT_EQ(synthesize_imu(again).samples.back().accel_m_s2, measured.samples.back().accel_m_s2);
}

TEST(SynthImu, WithoutImuTheMotionIsTheOriginal) {
  const Preset preset = test::repo_preset("room");
  RenderOptions plain;
  plain.frames = 5;
  SequenceRenderer renderer(preset, plain);
  EXPECT_FALSE(renderer.trajectory().smooth());
  EXPECT_THROW(synthesize_imu(renderer), std::runtime_error);
  EXPECT_THROW(renderer.trajectory().acceleration_w(0.1), std::logic_error);
}

}  // namespace
}  // namespace heslam::synth
