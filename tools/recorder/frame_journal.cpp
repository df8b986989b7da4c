// FrameJournal: one text line per frame, %.17g so poses round-trip exactly.
#include "tools/recorder/frame_journal.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include <Eigen/Geometry>

namespace heslam::recorder {
namespace {

constexpr const char* kHeader = "heslam-recorder-journal 1";

void write_pose(std::FILE* file, const Pose3& T) {
  const Eigen::Quaterniond q(T.linear());
  const Eigen::Vector3d t = T.translation();
  std::fprintf(file, " %.17g %.17g %.17g %.17g %.17g %.17g %.17g", t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
}

bool read_pose(std::istringstream& in, Pose3& T) {
  double tx, ty, tz, qx, qy, qz, qw;
  if (!(in >> tx >> ty >> tz >> qx >> qy >> qz >> qw)) return false;
  T = Pose3::Identity();
  T.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(tx, ty, tz);
  return true;
}

}  // namespace

FrameJournal::Opened FrameJournal::open_for_run(const std::string& run_id) {
  Opened opened;
  const std::string header = std::string(kHeader) + " " + run_id;
  bool same_run = false;
  {
    std::ifstream in(path_);
    std::string line;
    same_run = std::getline(in, line) && line == header;
    while (same_run && std::getline(in, line)) {
      std::istringstream fields(line);
      RecordedFrame frame;
      int tracked = 0;
      std::string end;
      if (fields >> frame.seq >> frame.stamp_ns >> tracked >> frame.state >> frame.reference &&
          read_pose(fields, frame.T_ref_c) && read_pose(fields, frame.T_wc) && fields >> end && end == ";") {
        frame.tracked = tracked != 0;
        opened.frames.push_back(frame);
      } else {
        ++opened.torn_lines;
      }
    }
  }
  if (path_.has_parent_path()) std::filesystem::create_directories(path_.parent_path());
  file_.reset(std::fopen(path_.c_str(), same_run ? "a" : "w"));
  if (!file_) throw std::runtime_error(path_.string() + ": cannot open the recorder journal for writing");
  if (!same_run) {
    std::fprintf(file_.get(), "%s\n", header.c_str());
    std::fflush(file_.get());
  }
  return opened;
}

void FrameJournal::append(const RecordedFrame& frame) {
  if (!file_) return;
  std::FILE* file = file_.get();
  std::fprintf(file, "%llu %lld %d %s %llu", static_cast<unsigned long long>(frame.seq),
               static_cast<long long>(frame.stamp_ns), frame.tracked ? 1 : 0,
               frame.state.empty() ? "-" : frame.state.c_str(), static_cast<unsigned long long>(frame.reference));
  write_pose(file, frame.T_ref_c);
  write_pose(file, frame.T_wc);
  // The terminator marks a complete line: a kill mid-write leaves a line without it, which the next
  // open skips and counts.
  std::fprintf(file, " ;\n");
  std::fflush(file);
}

void FrameJournal::remove() {
  file_.reset();
  std::error_code ignored;
  std::filesystem::remove(path_, ignored);
}

}  // namespace heslam::recorder
