// Poses on the wire: msg::Pose (position and unit quaternion) <-> Pose3. Every topic that carries a
// pose converts it here, so writers and readers agree on the quaternion order and normalisation.
#pragma once

#include "components/core/geometry/pose.hpp"
#include "runtime/messages.hpp"

namespace heslam::messages {

msg::Pose to_message(const Pose3& T_ab);
Pose3 to_pose(const msg::Pose& pose);  // the quaternion is normalised (it crossed a wire)

}  // namespace heslam::messages
