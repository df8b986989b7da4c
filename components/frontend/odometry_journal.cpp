// OdometryJournal: one record per frame, %.17g so poses round-trip exactly.
#include "components/frontend/odometry_journal.hpp"

#include <algorithm>
#include <map>
#include <sstream>

namespace heslam::frontend {
namespace {

// What the records hold; a journal of another format is not resumed from.
// 3: the map id (the atlas) after the finished flag.
constexpr const char* kFormat = "heslam-frontend-journal 3";

void write_pose(std::ostringstream& record, const msg::Pose& pose) {
  for (const double value : pose.position_m) record << ' ' << value;
  for (const double value : pose.orientation_xyzw) record << ' ' << value;
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

bool read_record(const std::string& record, msg::Odometry& odometry, bool& finished) {
  std::istringstream fields(record);
  unsigned long long seq = 0, reference = 0;
  long long stamp_ns = 0;
  int state = 0, keyframe_created = 0, finished_flag = 0;
  unsigned keypoints = 0, tracked_points = 0, map_id = 0;
  std::string rest;
  if (!(fields >> seq >> stamp_ns >> state >> reference) || !read_pose(fields, odometry.T_wc) ||
      !read_pose(fields, odometry.T_ref_c) ||
      !(fields >> keypoints >> tracked_points >> keyframe_created >> finished_flag >> map_id) || fields >> rest) {
    return false;
  }
  // A state that is no TrackingState is a damaged line (casting it to the enum would be undefined).
  if (state != heslam_msg_TRACKING_NOT_INITIALIZED && state != heslam_msg_TRACKING_OK &&
      state != heslam_msg_TRACKING_LOST && state != heslam_msg_TRACKING_INERTIAL_ONLY) {
    return false;
  }
  odometry.T_oc = odometry.T_wc;  // not journaled: a restarted frontend's odom starts again at the world
  odometry.seq = seq;
  odometry.stamp_ns = stamp_ns;
  odometry.state = static_cast<heslam_msg_TrackingState>(state);
  odometry.reference_keyframe_id = reference;
  odometry.map_id = map_id;
  odometry.keypoints = keypoints;
  odometry.tracked_points = tracked_points;
  odometry.keyframe_created = keyframe_created != 0;
  finished = finished_flag != 0;
  return true;
}

}  // namespace

OdometryJournal::OdometryJournal(std::filesystem::path path) : journal_(std::move(path), kFormat) {}

OdometryJournal::Opened OdometryJournal::open_for_run(const std::string& run_id) {
  const runtime::RunJournal::Contents contents = journal_.open_for_run(run_id);
  Opened opened;
  opened.torn_lines = contents.torn_lines;
  opened.dropped_lines = contents.dropped_lines();
  opened.dropped_report = contents.dropped_report(journal_.path());
  std::map<std::uint64_t, msg::Odometry> by_seq;
  for (const std::string& record : contents.records) {
    msg::Odometry odometry{};
    bool finished = false;
    if (!read_record(record, odometry, finished)) {
      ++opened.torn_lines;
      continue;
    }
    if (finished) opened.last_seq = std::max(opened.last_seq.value_or(0), odometry.seq);
    by_seq[odometry.seq] = odometry;
  }
  for (const auto& [seq, odometry] : by_seq) opened.frames.push_back(odometry);
  return opened;
}

void OdometryJournal::append(const msg::Odometry& odometry, bool finished) {
  std::ostringstream record;
  record.precision(17);  // as %.17g: every double comes back bit for bit
  record << odometry.seq << ' ' << odometry.stamp_ns << ' ' << static_cast<int>(odometry.state) << ' '
         << odometry.reference_keyframe_id;
  write_pose(record, odometry.T_wc);
  write_pose(record, odometry.T_ref_c);
  record << ' ' << odometry.keypoints << ' ' << odometry.tracked_points << ' ' << (odometry.keyframe_created ? 1 : 0)
         << ' ' << (finished ? 1 : 0) << ' ' << odometry.map_id;
  journal_.append(record.str());
}

}  // namespace heslam::frontend
