// heslam-bench-image-load: decoding one EuRoC 752x480 grey PNG (euroc_v101_head, cam0) three ways:
// cv::imread (the replay's former path), load_image_file (read the bytes, check the PNG chunk by
// chunk with CRCs, cv::imdecode: the replay's path now) and the check alone.
//   heslam-bench-image-load [--benchmark_repetitions=N ...]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "tools/dataset/png_check.hpp"
#include "tools/dataset/stereo_images.hpp"

namespace {

// The first 20 left images: different content, as a replay reads them.
std::vector<std::filesystem::path> images() {
  const std::filesystem::path dir = std::filesystem::path(HESLAM_SHARED_DATA) / "euroc_v101_head/mav0/cam0/data";
  if (!std::filesystem::exists(dir)) throw std::runtime_error(dir.string() + ": not found (shared data absent)");
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  files.resize(std::min<std::size_t>(files.size(), 20));
  return files;
}

void BM_CvImread(benchmark::State& state) {
  const auto files = images();
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(cv::imread(files[i++ % files.size()].string(), cv::IMREAD_UNCHANGED));
}
BENCHMARK(BM_CvImread)->Unit(benchmark::kMillisecond);

void BM_LoadImageFile(benchmark::State& state) {
  const auto files = images();
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(heslam::load_image_file(files[i++ % files.size()]));
}
BENCHMARK(BM_LoadImageFile)->Unit(benchmark::kMillisecond);

void BM_CheckPngOnly(benchmark::State& state) {
  std::vector<std::vector<std::uint8_t>> contents;
  for (const auto& file : images()) {
    std::ifstream in(file, std::ios::binary);
    contents.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::size_t i = 0;
  for (auto _ : state) heslam::check_png(contents[i++ % contents.size()]);
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * contents[0].size()));
}
BENCHMARK(BM_CheckPngOnly)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
