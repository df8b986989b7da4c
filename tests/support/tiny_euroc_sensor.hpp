// The sensor.yaml of a tiny EuRoC camera (40x30 pinhole, no distortion), for tests that write a
// small EuRoC folder of their own: the camera sits tx_m along the body's x axis.
#pragma once
#include <string>

namespace heslam::test {

inline constexpr int kTinyEurocWidth = 40;
inline constexpr int kTinyEurocHeight = 30;

inline std::string tiny_euroc_sensor_yaml(double tx_m) {
  return "%YAML:1.0\n"
         "sensor_type: camera\n"
         "T_BS:\n  cols: 4\n  rows: 4\n"
         "  data: [1.0, 0.0, 0.0, " +
         std::to_string(tx_m) +
         ",\n"
         "         0.0, 1.0, 0.0, 0.0,\n         0.0, 0.0, 1.0, 0.0,\n         0.0, 0.0, 0.0, 1.0]\n"
         "rate_hz: 20\nresolution: [40, 30]\ncamera_model: pinhole\n"
         "intrinsics: [50.0, 51.0, 20.0, 15.0]\n"
         "distortion_model: radial-tangential\n"
         "distortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n";
}

}  // namespace heslam::test
