// Visual-inertial initialization (inertial_initialization.hpp). STUB: not implemented yet.
#include "components/core/imu/inertial_initialization.hpp"

#include <stdexcept>

namespace heslam {

InertialInitResult initialize_inertial(const InertialInitInput&, const InertialInitOptions&) {
  throw std::logic_error("initialize_inertial: not implemented");
}

const char* to_string(InertialInitStatus status) {
  switch (status) {
    case InertialInitStatus::kOk: return "ok";
    case InertialInitStatus::kTooShort: return "too_short";
    case InertialInitStatus::kTooLittleExcitation: return "too_little_excitation";
    case InertialInitStatus::kNotConverged: return "not_converged";
    case InertialInitStatus::kResidualTooHigh: return "residual_too_high";
  }
  return "unknown";
}

}  // namespace heslam
