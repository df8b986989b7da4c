// Which rigid frame a trajectory's poses are of, as heslam-recorder writes it in a header line of
// its TUM / EuRoC files (`# heslam frame: body ...`), so heslam-eval compares like with like.
//
//   body       the body frame of the calibration (EuRoC T_BS: sensor -> body), as EuRoC's ground truth
//   cam0       the raw (unrectified) left camera
//   rectified  the rectified left camera the tracker works in (differs from cam0 by the rectifying
//              rotation, ~1-2 deg on EuRoC)
// In every case the world is that frame at the first keyframe: T_w_x(t) = T_x_r T_wr(t) T_x_r^-1.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "components/core/geometry/pose.hpp"

namespace heslam::eval {

enum class PoseFrame { body, cam0, rectified };

// "body", "cam0", "rectified"; nullopt otherwise.
std::optional<PoseFrame> parse_pose_frame(std::string_view name);
const char* pose_frame_name(PoseFrame frame);

// The header line (with '#', without the newline) that names the frame.
std::string pose_frame_header(PoseFrame frame);
// The frame a header line names, nullopt for any other line.
std::optional<PoseFrame> pose_frame_from_header(std::string_view line);
// The frame the first such line among a file's header comments names.
std::optional<PoseFrame> pose_frame_from_header(const std::vector<std::string>& lines);

// A pose T_wr of the rectified camera (world: the rectified camera at the first keyframe) as a pose
// of frame x (world: x at the first keyframe), given T_x_r (rectified camera -> x).
Pose3 to_pose_frame(const Pose3& T_wr, const Pose3& T_x_r);

}  // namespace heslam::eval
