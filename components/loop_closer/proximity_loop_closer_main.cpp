// heslam-loop-closer-proximity: the same loop closing, loop candidates by proximity to the current
// pose (no vocabulary): the second, swappable implementation of the loop closer.
//   heslam-loop-closer-proximity [common options] [--state-file FILE]
#include <memory>

#include "components/core/loop/proximity_loop_detector.hpp"
#include "components/loop_closer/loop_closer_node.hpp"

namespace heslam::loop_closer {
namespace {

class ProximityLoopCloser final : public LoopCloserNode {
 public:
  explicit ProximityLoopCloser(const runtime::CommonArgs& args) : LoopCloserNode("loop_closer", args) {}

 private:
  std::unique_ptr<LoopDetector> make_detector(const runtime::Config& config,
                                              const LoopCloserProcessOptions& /*options*/) override {
    ProximityLoopDetectorOptions o;
    o.base_radius_m = config.get_double("detection.base_radius_m", o.base_radius_m, 0.0, 1000.0);
    o.drift_ratio = config.get_double("detection.drift_ratio", o.drift_ratio, 0.0, 1.0);
    o.max_radius_m = config.get_double("detection.max_radius_m", o.max_radius_m, 0.0, 10000.0);
    o.max_view_angle_deg = config.get_double("detection.max_view_angle_deg", o.max_view_angle_deg, 0.0, 180.0);
    o.min_path_since_m = config.get_double("detection.min_path_since_m", o.min_path_since_m, 0.0, 100000.0);
    o.max_candidates = config.get_int("detection.max_candidates", o.max_candidates, 1, 100);
    o.min_keyframes_in_map = config.get_int("detection.min_keyframes_in_map", o.min_keyframes_in_map, 1, 100000);
    o.keyframes_after_loop = config.get_int("detection.keyframes_after_loop", o.keyframes_after_loop, 0, 100000);
    o.merge_min_matches = config.get_int("detection.merge_min_matches", o.merge_min_matches, 3, 100000);
    o.merge_keyframes_per_query =
        config.get_int("detection.merge_keyframes_per_query", o.merge_keyframes_per_query, 1, 100000);
    return std::make_unique<ProximityLoopDetector>(o);
  }
};

}  // namespace
}  // namespace heslam::loop_closer

int main(int argc, char** argv) {
  return heslam::runtime::component_main<heslam::loop_closer::ProximityLoopCloser>(argc, argv, "loop_closer");
}
