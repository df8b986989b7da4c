// The readings of an IMU riding on a synthetic trajectory (heslam-synth --imu): exact angular velocity
// and specific force of the body (the IMU is the body, T_BS = identity, as EuRoC's imu0), plus the
// noise of a Kalibr / EuRoC noise model: white noise of density sigma (sigma / sqrt(dt) per reading)
// and a bias that random-walks from zero (sigma_rw sqrt(dt) per reading). Seeded, so a render repeats.
#pragma once

#include <cstdint>
#include <vector>

#include "components/core/imu/preintegration.hpp"
#include "tools/synth/sequence.hpp"

namespace heslam::synth {

// Standard gravity in the synthetic world (z up): what the accelerometer feels at rest is +kGravity on z.
inline constexpr double kGravityMps2 = 9.81;
// Readings start this long before the first frame and end this long after the last (EuRoC's clip: 2 s).
inline constexpr double kImuMarginS = 2.0;

struct SynthImu {
  std::vector<ImuSample> samples;  // what the sensor reports (noise included unless noise-free)
  std::vector<ImuBias> biases;     // the true bias at each reading
};

// Requires a renderer made with options.imu (a smooth trajectory); throws std::runtime_error otherwise.
SynthImu synthesize_imu(const SequenceRenderer& renderer);

// The ideal (noise-free) reading at time t_s of the trajectory: body angular velocity and specific force.
ImuSample ideal_imu_reading(const Trajectory& trajectory, double t_s, std::int64_t stamp_ns);

}  // namespace heslam::synth
