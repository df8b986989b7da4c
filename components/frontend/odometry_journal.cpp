// OdometryJournal: one text line per frame, %.17g so poses round-trip exactly.
#include "components/frontend/odometry_journal.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace heslam::frontend {
namespace {

constexpr const char* kHeader = "heslam-frontend-journal 1";  // + the run id

void write_pose(std::FILE* file, const msg::Pose& pose) {
  for (const double value : pose.position_m) std::fprintf(file, " %.17g", value);
  for (const double value : pose.orientation_xyzw) std::fprintf(file, " %.17g", value);
}

bool read_pose(std::istringstream& in, msg::Pose& pose) {
  for (double& value : pose.position_m) {
    if (!(in >> value)) return false;
  }
  for (double& value : pose.orientation_xyzw) {
    if (!(in >> value)) return false;
  }
  return true;
}

bool read_line(const std::string& line, msg::Odometry& odometry, bool& finished) {
  std::istringstream fields(line);
  unsigned long long seq = 0, reference = 0;
  long long stamp_ns = 0;
  int state = 0, keyframe_created = 0, finished_flag = 0;
  unsigned keypoints = 0, tracked_points = 0;
  std::string end;
  if (!(fields >> seq >> stamp_ns >> state >> reference) || !read_pose(fields, odometry.T_wc) ||
      !read_pose(fields, odometry.T_ref_c) || !(fields >> keypoints >> tracked_points >> keyframe_created >> finished_flag >> end) ||
      end != ";") {
    return false;
  }
  // A state that is no TrackingState is a damaged line (casting it to the enum would be undefined).
  if (state != heslam_msg_TRACKING_NOT_INITIALIZED && state != heslam_msg_TRACKING_OK && state != heslam_msg_TRACKING_LOST) {
    return false;
  }
  odometry.seq = seq;
  odometry.stamp_ns = stamp_ns;
  odometry.state = static_cast<heslam_msg_TrackingState>(state);
  odometry.reference_keyframe_id = reference;
  odometry.keypoints = keypoints;
  odometry.tracked_points = tracked_points;
  odometry.keyframe_created = keyframe_created != 0;
  finished = finished_flag != 0;
  return true;
}

}  // namespace

OdometryJournal::Opened OdometryJournal::open_for_run(const std::string& run_id) {
  Opened opened;
  const std::string header = std::string(kHeader) + " " + run_id;
  bool same_run = false;
  bool ends_with_newline = true;
  {
    std::ifstream in(path_, std::ios::binary);
    if (in.seekg(-1, std::ios::end)) ends_with_newline = in.get() == '\n';
    in.clear();
    in.seekg(0);
    std::string line;
    same_run = std::getline(in, line) && line == header;
    std::map<std::uint64_t, msg::Odometry> by_seq;
    while (same_run && std::getline(in, line)) {
      msg::Odometry odometry{};
      bool finished = false;
      if (read_line(line, odometry, finished)) {
        if (finished) opened.last_seq = std::max(opened.last_seq.value_or(0), odometry.seq);
        by_seq[odometry.seq] = odometry;
      } else {
        ++opened.torn_lines;
      }
    }
    for (const auto& [seq, odometry] : by_seq) opened.frames.push_back(odometry);
  }
  std::error_code ignored;  // an uncreatable folder fails the fopen below, with our message
  if (path_.has_parent_path()) std::filesystem::create_directories(path_.parent_path(), ignored);
  file_.reset(std::fopen(path_.c_str(), same_run ? "a" : "w"));
  if (!file_) throw std::runtime_error(path_.string() + ": cannot open the frontend journal for writing");
  if (!same_run) {
    std::fprintf(file_.get(), "%s\n", header.c_str());
  } else if (!ends_with_newline) {
    std::fprintf(file_.get(), "\n");  // after a torn last line, so the next one is not glued to it
  }
  std::fflush(file_.get());
  return opened;
}

void OdometryJournal::append(const msg::Odometry& odometry, bool finished) {
  if (!file_) return;
  std::FILE* file = file_.get();
  std::fprintf(file, "%llu %lld %d %llu", static_cast<unsigned long long>(odometry.seq),
               static_cast<long long>(odometry.stamp_ns), static_cast<int>(odometry.state),
               static_cast<unsigned long long>(odometry.reference_keyframe_id));
  write_pose(file, odometry.T_wc);
  write_pose(file, odometry.T_ref_c);
  // The terminator marks a complete line: a kill mid-write leaves a line without it, which the next
  // open skips and counts.
  std::fprintf(file, " %u %u %d %d ;\n", odometry.keypoints, odometry.tracked_points, odometry.keyframe_created ? 1 : 0,
               finished ? 1 : 0);
  std::fflush(file);
}

void OdometryJournal::remove() {
  file_.reset();
  std::error_code ignored;
  std::filesystem::remove(path_, ignored);
}

}  // namespace heslam::frontend
