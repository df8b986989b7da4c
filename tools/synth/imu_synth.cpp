// Synthetic IMU readings (imu_synth.hpp).
#include "tools/synth/imu_synth.hpp"

#include <cmath>
#include <random>
#include <stdexcept>

namespace heslam::synth {
namespace {

// Platform-independent standard normal (std::normal_distribution differs between standard libraries):
// Box-Muller on 53-bit uniforms.
class Gaussian {
 public:
  explicit Gaussian(std::uint64_t seed) : rng_(seed * 0xD1B54A32D192ED03ull + 0x1A2B) {}
  double operator()() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = (static_cast<double>(rng_() >> 11) + 1.0) * 0x1.0p-53;  // (0, 1]
    const double u2 = static_cast<double>(rng_() >> 11) * 0x1.0p-53;
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * M_PI * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * M_PI * u2);
  }
  Eigen::Vector3d vector() {
    const double x = (*this)();
    const double y = (*this)();
    const double z = (*this)();
    return {x, y, z};
  }

 private:
  std::mt19937_64 rng_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace

ImuSample ideal_imu_reading(const Trajectory& trajectory, double t_s, std::int64_t stamp_ns) {
  ImuSample sample;
  sample.stamp_ns = stamp_ns;
  const Eigen::Matrix3d R_wb = trajectory.T_wb(t_s).linear();
  sample.gyro_rad_s = trajectory.angular_velocity_b(t_s);
  sample.accel_m_s2 = R_wb.transpose() * (trajectory.acceleration_w(t_s) + Eigen::Vector3d(0.0, 0.0, kGravityMps2));
  return sample;
}

SynthImu synthesize_imu(const SequenceRenderer& renderer) {
  const RenderOptions& options = renderer.options();
  if (!options.imu || !renderer.trajectory().smooth()) {
    throw std::runtime_error("synthesize_imu: the renderer was made without options.imu (no smooth motion)");
  }
  if (!(options.imu_rate_hz > 0.0)) throw std::runtime_error("synthesize_imu: expected a positive IMU rate");
  const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / options.imu_rate_hz));
  const double dt_s = static_cast<double>(period_ns) * 1e-9;
  const auto margin_ns = static_cast<std::int64_t>(kImuMarginS * 1e9);
  const std::int64_t first_ns = renderer.stamp_ns(0) - margin_ns;
  const std::int64_t last_ns = renderer.stamp_ns(std::max(0, renderer.num_frames() - 1)) + margin_ns;
  Gaussian gaussian(options.seed);
  const ImuNoise& noise = options.imu_noise;
  ImuBias bias;
  SynthImu imu;
  for (std::int64_t stamp = first_ns; stamp <= last_ns; stamp += period_ns) {
    const double t_s = static_cast<double>(stamp - renderer.stamp_ns(0)) * 1e-9;
    ImuSample sample = ideal_imu_reading(renderer.trajectory(), t_s, stamp);
    if (!options.imu_noise_free) {
      sample.gyro_rad_s += bias.gyro_rad_s + gaussian.vector() * (noise.gyro_noise_density / std::sqrt(dt_s));
      sample.accel_m_s2 += bias.accel_m_s2 + gaussian.vector() * (noise.accel_noise_density / std::sqrt(dt_s));
    }
    imu.samples.push_back(sample);
    imu.biases.push_back(bias);
    if (!options.imu_noise_free) {
      bias.gyro_rad_s += gaussian.vector() * (noise.gyro_random_walk * std::sqrt(dt_s));
      bias.accel_m_s2 += gaussian.vector() * (noise.accel_random_walk * std::sqrt(dt_s));
    }
  }
  return imu;
}

}  // namespace heslam::synth
