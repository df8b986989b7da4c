// FrameJournal: one record per frame, %.17g so poses round-trip exactly.
#include "tools/recorder/frame_journal.hpp"

#include <sstream>

#include <Eigen/Geometry>

namespace heslam::recorder {
namespace {

// What the records hold; a journal of another format is not resumed from.
constexpr const char* kFormat = "heslam-recorder-journal 2";

void write_pose(std::ostringstream& record, const Pose3& T) {
  const Eigen::Quaterniond q(T.linear());
  const Eigen::Vector3d t = T.translation();
  record << ' ' << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' '
         << q.w();
}

bool read_pose(std::istringstream& in, Pose3& T) {
  double tx, ty, tz, qx, qy, qz, qw;
  if (!(in >> tx >> ty >> tz >> qx >> qy >> qz >> qw)) return false;
  T = Pose3::Identity();
  T.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(tx, ty, tz);
  return true;
}

bool read_record(const std::string& record, RecordedFrame& frame) {
  std::istringstream fields(record);
  int tracked = 0;
  std::string rest;
  if (!(fields >> frame.seq >> frame.stamp_ns >> tracked >> frame.state >> frame.reference) ||
      !read_pose(fields, frame.T_ref_c) || !read_pose(fields, frame.T_wc)) {
    return false;
  }
  // Inertial runs: optional "v x y z" (velocity) and "g x y z" (gravity) after the poses; a frame
  // of a map other than the first (the atlas): "m MAP_ID".
  while (fields >> rest) {
    if (rest == "m") {
      if (!(fields >> frame.map_id)) return false;
      continue;
    }
    Eigen::Vector3d value;
    if ((rest != "v" && rest != "g") || !(fields >> value.x() >> value.y() >> value.z())) return false;
    (rest == "v" ? frame.v_w : frame.g_w) = value;
  }
  frame.tracked = tracked != 0;
  return true;
}

}  // namespace

FrameJournal::FrameJournal(std::filesystem::path path) : journal_(std::move(path), kFormat) {}

FrameJournal::Opened FrameJournal::open_for_run(const std::string& run_id) {
  const runtime::RunJournal::Contents contents = journal_.open_for_run(run_id);
  Opened opened;
  opened.torn_lines = contents.torn_lines;
  opened.dropped_lines = contents.dropped_lines();
  opened.dropped_report = contents.dropped_report(journal_.path());
  for (const std::string& record : contents.records) {
    RecordedFrame frame;
    if (read_record(record, frame)) {
      opened.frames.push_back(frame);
    } else {
      ++opened.torn_lines;
    }
  }
  return opened;
}

void FrameJournal::append(const RecordedFrame& frame) {
  std::ostringstream record;
  record.precision(17);  // as %.17g: every double comes back bit for bit
  record << frame.seq << ' ' << frame.stamp_ns << ' ' << (frame.tracked ? 1 : 0) << ' '
         << (frame.state.empty() ? "-" : frame.state) << ' ' << frame.reference;
  write_pose(record, frame.T_ref_c);
  write_pose(record, frame.T_wc);
  if (frame.v_w) record << " v " << frame.v_w->x() << ' ' << frame.v_w->y() << ' ' << frame.v_w->z();
  if (frame.g_w) record << " g " << frame.g_w->x() << ' ' << frame.g_w->y() << ' ' << frame.g_w->z();
  if (frame.map_id != kFirstMapId) record << " m " << frame.map_id;
  journal_.append(record.str());
}

}  // namespace heslam::recorder
