// heslam-loop-closer: ORB-SLAM2's loop closing in its own process, loop candidates by bag of words.
//   heslam-loop-closer [common options] [--vocabulary FILE] [--state-file FILE]
#include <memory>
#include <stdexcept>
#include <string>

#include "components/core/loop/bow_loop_detector.hpp"
#include "components/core/place/vocabulary_setting.hpp"
#include "components/loop_closer/loop_closer_node.hpp"

namespace heslam::loop_closer {
namespace {

class BowLoopCloser final : public LoopCloserNode {
 public:
  explicit BowLoopCloser(const runtime::CommonArgs& args) : LoopCloserNode("loop_closer", args) {}

 private:
  std::unique_ptr<LoopDetector> make_detector(const runtime::Config& config,
                                              const LoopCloserProcessOptions& options) override {
    BowLoopDetectorOptions detector;
    detector.min_keyframes_in_map =
        config.get_int("detection.min_keyframes_in_map", detector.min_keyframes_in_map, 1, 100000);
    detector.keyframes_after_loop =
        config.get_int("detection.keyframes_after_loop", detector.keyframes_after_loop, 0, 100000);
    detector.consistency_threshold =
        config.get_int("detection.consistency_threshold", detector.consistency_threshold, 0, 1000);
    detector.matching.ratio =
        static_cast<float>(config.get_double("verification.bow_ratio", detector.matching.ratio, 0.1, 1.0));
    const std::string setting = options.vocabulary.string();
    if (setting == kNoVocabularySetting)
      throw std::runtime_error("vocabulary.file: the bag-of-words loop closer needs a vocabulary");
    std::shared_ptr<const Vocabulary> vocabulary = load_vocabulary_setting(setting);
    log().info("vocabulary ", describe_vocabulary_setting(setting), ": ", vocabulary->word_count(), " words, k ",
               vocabulary->branching(), ", L ", vocabulary->levels());
    return std::make_unique<BowLoopDetector>(std::move(vocabulary), detector);
  }
};

}  // namespace
}  // namespace heslam::loop_closer

int main(int argc, char** argv) {
  return heslam::runtime::component_main<heslam::loop_closer::BowLoopCloser>(argc, argv, "loop_closer");
}
