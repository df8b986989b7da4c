// heslam-bench-place: how big vocabulary files are, how long they take to load, and how long one
// keyframe's descriptors take to transform.
//
// Trees: full k = 10 trees with random node descriptors (L = 4: 10,000 words; L = 6: 1,000,000
// words, ORBvoc.txt's shape), written as DBoW2 text and heslam binary; and the default vocabulary.
// The descent costs the same for random and trained node descriptors (k distances per level), so
// the synthetic 1M tree stands in for ORBvoc.txt, which is not available here.
// Descriptors: the frontend's HE + ORB (1,200 features) on a real EuRoC MH01 image.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "components/core/place/default_vocabulary.hpp"
#include "components/core/place/image_descriptors.hpp"
#include "components/core/place/vocabulary_io.hpp"
#include "runtime/flags.hpp"

namespace {

using namespace heslam;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// ORB-SLAM2's feature-vector level for SearchByBoW.
constexpr int kLevelsUp = 4;

Vocabulary full_random_tree(int k, int levels, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Vocabulary::NodeRecord> nodes;
  std::vector<NodeId> level{0};
  for (int depth = 1; depth <= levels; ++depth) {
    std::vector<NodeId> next;
    for (const NodeId parent : level) {
      for (int c = 0; c < k; ++c) {
        Vocabulary::NodeRecord record;
        record.parent = parent;
        record.is_leaf = depth == levels;
        for (auto& byte : record.descriptor) byte = static_cast<std::uint8_t>(rng());
        record.weight = record.is_leaf ? static_cast<float>(rng() % 1000) / 100.f : 0.f;
        nodes.push_back(record);
        next.push_back(static_cast<NodeId>(nodes.size()));
      }
    }
    level = std::move(next);
  }
  return Vocabulary(k, levels, BowScoring::kL1, BowWeighting::kTfIdf, nodes);
}

template <typename Fn>
std::vector<double> time_ms(int repeats, Fn&& fn) {
  std::vector<double> ms;
  for (int i = 0; i < repeats; ++i) {
    const auto start = Clock::now();
    fn();
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }
  std::sort(ms.begin(), ms.end());
  return ms;
}

double median(const std::vector<double>& sorted) { return sorted[sorted.size() / 2]; }

void report_load(const std::string& name, const fs::path& path, int repeats) {
  std::size_t words = 0;
  const auto ms = time_ms(repeats, [&] { words = load_vocabulary(path).word_count(); });
  std::printf("  load %-30s %9.1f MB  median %9.1f ms  min %9.1f ms  (%zu words, %d runs)\n", name.c_str(),
              fs::file_size(path) / 1e6, median(ms), ms.front(), words, repeats);
}

void report_transform(const std::string& name, const Vocabulary& vocabulary, const std::vector<Descriptor>& descriptors,
                      int repeats) {
  BowVector bow;
  FeatureVector features;
  const auto with_features = time_ms(repeats, [&] { vocabulary.transform(descriptors, bow, &features, kLevelsUp); });
  const auto bow_only = time_ms(repeats, [&] { vocabulary.transform(descriptors, bow, nullptr, 0); });
  std::printf(
      "  transform %-25s %zu descriptors: BoW + feature vector median %.3f ms (p90 %.3f), BoW only %.3f ms"
      " -> %zu words, %zu nodes at levels_up %d\n",
      name.c_str(), descriptors.size(), median(with_features), with_features[with_features.size() * 9 / 10],
      median(bow_only), bow.size(), features.nodes.size(), kLevelsUp);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    fs::path scratch = "/tmp/heslam-bench-place";
    fs::path trained = default_vocabulary_path();
    fs::path image_path = fs::path(HESLAM_SHARED_DATA) / "euroc_mh01_handheld/mav0/cam0/data/1403636586763555584.png";
    int repeats = 5;
    bool text_1m = true;
    bool help = false;
    runtime::Flags flags("heslam-bench-place [options]");
    flags.path("--scratch", "DIR", &scratch, "where the synthetic trees are written (default /tmp/heslam-bench-place)")
        .path("--vocabulary", "FILE", &trained,
              "a trained vocabulary to time as well (default: the build's default vocabulary)")
        .path("--image", "PNG", &image_path,
              "grey image whose ORB descriptors are transformed (default: an EuRoC MH01 frame)")
        .integer("--repeats", "N", &repeats, 1, std::numeric_limits<int>::max(), "timed repeats (5)")
        .toggle("--skip-text-1m", &text_1m, "do not write and load the 1M-word tree as DBoW2 text", false)
        .toggle("--help", &help, "this help")
        .alias("-h");
    flags.parse(argc, argv);
    if (help) {
      std::printf("%s", flags.usage().c_str());
      return 0;
    }
    fs::create_directories(scratch);
    const cv::Mat image = cv::imread(image_path.string(), cv::IMREAD_GRAYSCALE);
    if (image.empty()) throw std::runtime_error(image_path.string() + ": cannot read image (--image PNG)");
    ImageDescriptorExtractor extractor;
    const std::vector<Descriptor> descriptors = extractor.extract(image);
    std::printf("descriptors: %zu from %s (HE + ORB, 1200 features)\n", descriptors.size(), image_path.c_str());

    for (const int levels : {4, 6}) {
      const std::string name = levels == 4 ? "10k" : "1M";
      auto start = Clock::now();
      const Vocabulary tree = full_random_tree(10, levels, 42);
      std::printf("tree %s: k 10, L %d, %zu words, %zu nodes, random node descriptors (built in %.2f s)\n",
                  name.c_str(), levels, tree.word_count(), tree.node_count(),
                  std::chrono::duration<double>(Clock::now() - start).count());
      const fs::path binary = scratch / ("random_" + name + ".hvoc");
      const fs::path text = scratch / ("random_" + name + ".txt");
      start = Clock::now();
      save_vocabulary_binary(binary, tree);
      std::printf("  save binary %.2f s\n", std::chrono::duration<double>(Clock::now() - start).count());
      report_load("binary " + name, binary, repeats);
      if (levels == 4 || text_1m) {
        start = Clock::now();
        save_vocabulary_text(text, tree);
        std::printf("  save text %.2f s\n", std::chrono::duration<double>(Clock::now() - start).count());
        report_load("text " + name, text, levels == 4 ? repeats : std::min(repeats, 3));
      }
      report_transform(name + " (random)", tree, descriptors, 200);
    }
    if (fs::exists(trained)) {
      const Vocabulary vocabulary = load_vocabulary(trained);
      std::printf("trained vocabulary %s: %zu words, %zu nodes\n", trained.c_str(), vocabulary.word_count(),
                  vocabulary.node_count());
      report_load(trained.filename().string(), trained, repeats);
      report_transform(trained.filename().string(), vocabulary, descriptors, 200);
    } else {
      std::printf("trained vocabulary %s: not there, skipped\n", trained.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "heslam-bench-place: %s\n", e.what());
    return 1;
  }
}
