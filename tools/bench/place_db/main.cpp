// heslam-bench-place-db: how long the keyframe database takes to answer ORB-SLAM2's two place queries
// (relocalization candidates for a frame, loop candidates for a keyframe) as it grows. Keyframes are
// made from a real EuRoC clip's ORB descriptors (left images, the frontend's HE + ORB), replicated
// with bit noise so that every keyframe is different; each is linked to its 5 neighbours by id on
// either side (a covisibility chain, as along a trajectory).
// `heslam-bench-place-db --help` lists the flags.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "components/core/place/image_descriptors.hpp"
#include "components/core/place/keyframe_database.hpp"
#include "components/core/place/vocabulary_setting.hpp"
#include "runtime/flags.hpp"
#include "tools/bench/bench_util.hpp"
#include "tools/bench/frontend_offline/euroc_sequence.hpp"

namespace {

using heslam::bench::percentile;

using namespace heslam;

constexpr int kNeighboursEachSide = 5;  // covisible keyframes per keyframe on each side
constexpr int kNeighbourWeight = 100;   // shared points with the nearest neighbour, minus 10 per step

std::vector<Descriptor> with_noise(std::vector<Descriptor> descriptors, std::mt19937_64& rng, int bits) {
  for (Descriptor& d : descriptors) {
    for (int b = 0; b < bits; ++b) {
      const std::uint64_t at = rng() % 256;
      d[at / 8] ^= static_cast<std::uint8_t>(1u << (at % 8));
    }
  }
  return descriptors;
}

int run(int argc, char** argv) {
  std::string vocabulary_setting;
  std::string dataset = "../shared/data/euroc_mh01_handheld";  // from the repository root
  std::vector<int> sizes{100, 1000, 10000};
  int queries = 50;
  int noise_bits = 8;
  bool help = false;
  runtime::Flags flags("heslam-bench-place-db [options]");
  flags.text("--vocabulary", "FILE", &vocabulary_setting, "the vocabulary (default: the build's)")
      .text("--dataset", "DIR", &dataset, "the EuRoC clip whose descriptors make the keyframes (MH01)")
      .integer_list("--sizes", "N,N,...", &sizes, 1, std::numeric_limits<int>::max(),
                    "database sizes in keyframes (100,1000,10000)")
      .integer("--queries", "N", &queries, "queries per size (50)")
      .integer("--noise-bits", "B", &noise_bits, "bits flipped per replicated descriptor (8)")
      .toggle("--help", &help, "this help")
      .alias("-h");
  flags.parse(argc, argv);
  if (help) {
    std::fputs(flags.usage().c_str(), stdout);
    return 0;
  }
  const auto vocabulary = load_vocabulary_setting(vocabulary_setting.empty() ? "" : vocabulary_setting);
  if (!vocabulary) throw std::runtime_error("--vocabulary none: this benchmark needs a vocabulary");
  std::printf("vocabulary %s: k %d, L %d, %zu words\n", describe_vocabulary_setting(vocabulary_setting).c_str(),
              vocabulary->branching(), vocabulary->levels(), vocabulary->word_count());

  const auto sequence = bench::load_euroc_sequence(dataset);
  ImageDescriptorExtractor extractor;
  std::vector<std::vector<Descriptor>> images;
  for (const auto& frame : sequence.frames) {
    images.push_back(extractor.extract(cv::imread(frame.left_png.string(), cv::IMREAD_GRAYSCALE)));
  }
  std::printf("dataset %s: %zu images, %zu descriptors in the first\n", dataset.c_str(), images.size(),
              images.front().size());

  for (const int size : sizes) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(size));
    Map map;
    KeyframeDatabase database(*vocabulary);
    const auto add_start = std::chrono::steady_clock::now();
    for (int k = 1; k <= size; ++k) {
      const KeyframeId id = static_cast<KeyframeId>(k);
      Keyframe& keyframe = map.keyframes[id];
      keyframe.id = id;
      for (int step = 1; step <= kNeighboursEachSide; ++step) {
        for (const int neighbour : {k - step, k + step}) {
          if (neighbour >= 1 && neighbour <= size) {
            keyframe.covisible.emplace_back(static_cast<KeyframeId>(neighbour), kNeighbourWeight - 10 * step);
          }
        }
      }
      database.add(id, with_noise(images[static_cast<std::size_t>(k - 1) % images.size()], rng, noise_bits));
    }
    const double add_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - add_start).count();

    std::vector<double> reloc_ms;
    std::vector<double> loop_ms;
    std::vector<double> reloc_candidates;
    for (int q = 0; q < queries; ++q) {
      BowVector bow;
      const auto& image = images[static_cast<std::size_t>(q * 7) % images.size()];
      vocabulary->transform(with_noise(image, rng, noise_bits), bow, nullptr, 0);
      auto start = std::chrono::steady_clock::now();
      const auto candidates = database.relocalization_candidates(bow, map);
      reloc_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      reloc_candidates.push_back(static_cast<double>(candidates.size()));
      const KeyframeId query = static_cast<KeyframeId>(1 + (q * 7919) % size);
      start = std::chrono::steady_clock::now();
      database.loop_candidates(query, map, 0.0);
      loop_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    }
    std::printf(
        "%6d keyframes: add %.2f ms each; relocalization query median %.3f ms p90 %.3f ms (%.0f candidates); "
        "loop query median %.3f ms p90 %.3f ms\n",
        size, add_ms / size, percentile(reloc_ms, 0.5), percentile(reloc_ms, 0.9), percentile(reloc_candidates, 0.5),
        percentile(loop_ms, 0.5), percentile(loop_ms, 0.9));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return heslam::bench::bench_main("heslam-bench-place-db", argc, argv, run); }
