// The topic table's namespace check and the list of all topics.
#include "runtime/topics.hpp"

#include <array>
#include <stdexcept>

namespace heslam::runtime {
namespace {

bool valid_namespace_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' || c == '/';
}

constexpr std::array kAllTopics{
    TopicEntry{topic_names::kStereo, "StereoFrame", QosRole::kImages},
    TopicEntry{topic_names::kCalibration, "StereoCalibration", QosRole::kCalibration},
    TopicEntry{topic_names::kImu, "ImuBatch", QosRole::kImu},
    TopicEntry{topic_names::kImuCalibration, "ImuCalibration", QosRole::kCalibration},
    TopicEntry{topic_names::kOdometry, "Odometry", QosRole::kOdometry},
    TopicEntry{topic_names::kKeyframes, "Keyframe", QosRole::kKeyframes},
    TopicEntry{topic_names::kKeyframeStates, "KeyframeState", QosRole::kMapState},
    TopicEntry{topic_names::kMapPoints, "MapPointState", QosRole::kMapState},
    TopicEntry{topic_names::kMapperKeyframes, "Keyframe", QosRole::kKeyframes},
    TopicEntry{topic_names::kLoopCorrections, "LoopCorrection", QosRole::kCorrections},
    TopicEntry{topic_names::kFrameDone, "FrameDone", QosRole::kLockstep},
    TopicEntry{topic_names::kKeyframeDone, "KeyframeDone", QosRole::kLockstep},
    TopicEntry{topic_names::kTurns, "FrameDone", QosRole::kLockstep},
    TopicEntry{topic_names::kStatus, "ComponentStatus", QosRole::kStatus},
    TopicEntry{topic_names::kOccupancyGrid, "OccupancyGrid2D", QosRole::kCalibration},
    TopicEntry{topic_names::kDenseCloud, "DenseCloud", QosRole::kCalibration},
    TopicEntry{topic_names::kOccupancySaveRequest, "OccupancySaveRequest", QosRole::kLockstep},
    TopicEntry{topic_names::kOccupancySaveReply, "OccupancySaveReply", QosRole::kLockstep},
};

void check_namespace(const char* what, const std::string& ns) {
  bool valid = !ns.empty() && ns.front() != '/' && ns.back() != '/' && !(ns.front() >= '0' && ns.front() <= '9');
  for (char c : ns) valid = valid && valid_namespace_char(c);
  if (!valid) {
    throw std::runtime_error(std::string(what) + " '" + ns +
                             "': expected letters, digits, '_', '-' or inner '/', not starting with a digit");
  }
}

}  // namespace

Topics::Topics(std::string_view ns, std::string_view agent_ns) : ns_(ns), agent_ns_(agent_ns) {
  check_namespace("namespace", ns_);
  if (!agent_ns_.empty()) check_namespace("agent namespace", agent_ns_);
}

std::span<const TopicEntry> all_topics() { return kAllTopics; }

}  // namespace heslam::runtime
