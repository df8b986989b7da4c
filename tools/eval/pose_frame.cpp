// The `# heslam frame: NAME` header of heslam's trajectory files and the change of frame.
#include "tools/eval/pose_frame.hpp"

namespace heslam::eval {

namespace {
constexpr std::string_view kHeaderPrefix = "# heslam frame: ";
}  // namespace

std::optional<PoseFrame> parse_pose_frame(std::string_view name) {
  if (name == "body") return PoseFrame::body;
  if (name == "cam0") return PoseFrame::cam0;
  if (name == "rectified") return PoseFrame::rectified;
  return std::nullopt;
}

const char* pose_frame_name(PoseFrame frame) {
  switch (frame) {
    case PoseFrame::body: return "body";
    case PoseFrame::cam0: return "cam0";
    case PoseFrame::rectified: return "rectified";
  }
  return "?";
}

std::string pose_frame_header(PoseFrame frame) {
  std::string line(kHeaderPrefix);
  line += pose_frame_name(frame);
  switch (frame) {
    case PoseFrame::body:
      line += " (T_wb: the calibration's body frame (T_BS), world = the body at the first keyframe)";
      break;
    case PoseFrame::cam0: line += " (T_wc: the raw left camera, world = that camera at the first keyframe)"; break;
    case PoseFrame::rectified:
      line += " (T_wc: the rectified left camera, world = that camera at the first keyframe)";
      break;
  }
  return line;
}

std::optional<PoseFrame> pose_frame_from_header(std::string_view line) {
  if (!line.starts_with(kHeaderPrefix)) return std::nullopt;
  line.remove_prefix(kHeaderPrefix.size());
  return parse_pose_frame(line.substr(0, line.find_first_of(" \t\r")));
}

std::optional<PoseFrame> pose_frame_from_header(const std::vector<std::string>& lines) {
  for (const std::string& line : lines) {
    if (const std::optional<PoseFrame> frame = pose_frame_from_header(std::string_view(line))) return frame;
  }
  return std::nullopt;
}

Pose3 to_pose_frame(const Pose3& T_wr, const Pose3& T_x_r) { return T_x_r * T_wr * T_x_r.inverse(); }

}  // namespace heslam::eval
