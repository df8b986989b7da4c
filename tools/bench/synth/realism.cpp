// heslam-bench-synth-realism: does ORB see synthetic frames like real ones? Renders the `room`
// preset to EuRoC layout, then runs both it and the real EuRoC MH_01 clip through heslam's own path
// (EuRoC calibration loader -> rectifier -> StereoFeaturePipeline with config/camera/EuRoC.yaml) and
// prints per-frame ORB keypoints and the fraction with a stereo match, side by side. Reported, not
// asserted.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/feature/stereo_feature_pipeline.hpp"
#include "tools/dataset/stereo_dataset.hpp"
#include "tools/synth/preset.hpp"
#include "tools/synth/sequence.hpp"
#include "tools/synth/writers.hpp"

namespace {

namespace fs = std::filesystem;

struct Summary {
  std::vector<double> keypoints, stereo_fraction, mean_grey, std_grey;
};

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / static_cast<double>(v.size());
}

// Runs `frames` pairs of an EuRoC-layout folder (mav0/...) through rectification and the pipeline.
Summary measure(const fs::path& mav0, const heslam::StereoFeaturePipelineOptions& options, int frames) {
  const heslam::StereoDataset dataset = heslam::open_dataset(mav0, {.format = heslam::DatasetFormat::kEuroc});
  const heslam::StereoRectifier rectifier(dataset.calibration);
  heslam::StereoFeaturePipeline pipeline(rectifier.camera(), options);
  Summary s;
  for (const heslam::StereoFrameFiles& frame : dataset.frames) {
    if (static_cast<int>(s.keypoints.size()) >= frames) break;
    const cv::Mat left = cv::imread(frame.left.string(), cv::IMREAD_GRAYSCALE);
    const cv::Mat right = cv::imread(frame.right.string(), cv::IMREAD_GRAYSCALE);
    if (left.empty() || right.empty()) throw std::runtime_error(frame.left.string() + ": missing pair");
    cv::Mat left_rect, right_rect;
    rectifier.rectify(left, right, left_rect, right_rect);
    const heslam::StereoFeatures f = pipeline.process(left_rect, right_rect);
    const auto matched =
        std::count_if(f.u_right_px.begin(), f.u_right_px.end(), [](float u) { return u != heslam::kNoStereo; });
    s.keypoints.push_back(static_cast<double>(f.keypoints.size()));
    s.stereo_fraction.push_back(
        f.keypoints.empty() ? 0.0 : static_cast<double>(matched) / static_cast<double>(f.keypoints.size()));
    cv::Scalar m, sd;
    cv::meanStdDev(left, m, sd);
    s.mean_grey.push_back(m[0]);
    s.std_grey.push_back(sd[0]);
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace heslam::synth;
  try {
    const int frames = argc > 1 ? std::atoi(argv[1]) : 40;
    const fs::path real = fs::path(HESLAM_SHARED_DATA) / "euroc_mh01_handheld" / "mav0";
    if (!fs::exists(real)) throw std::runtime_error(real.string() + ": shared real data not found");
    const fs::path settings = fs::path(HESLAM_SOURCE_DIR) / "config" / "camera" / "EuRoC.yaml";
    const auto options = heslam::StereoFeaturePipelineOptions::load(settings);

    const fs::path synth_dir = fs::temp_directory_path() / "heslam_synth_realism_room";
    fs::remove_all(synth_dir);
    {
      SequenceRenderer all(load_preset(find_preset("room")), {.seed = 1, .frames = frames});
      write_sequence(all, OutputFormat::kEuroc, synth_dir);
    }
    const Summary syn = measure(synth_dir / "mav0", options, frames);
    const Summary rea = measure(real, options, frames);
    std::printf("ORB (heslam StereoFeaturePipeline, %s settings) over %d frames\n", settings.filename().c_str(),
                frames);
    std::printf("%-28s %12s %12s\n", "", "synth room", "EuRoC MH01");
    std::printf("%-28s %12.0f %12.0f\n", "keypoints/frame (median)", median(syn.keypoints), median(rea.keypoints));
    std::printf("%-28s %12.0f %12.0f\n", "keypoints/frame (min)",
                *std::min_element(syn.keypoints.begin(), syn.keypoints.end()),
                *std::min_element(rea.keypoints.begin(), rea.keypoints.end()));
    std::printf("%-28s %12.2f %12.2f\n", "stereo-matched fraction (mean)", mean(syn.stereo_fraction),
                mean(rea.stereo_fraction));
    std::printf("%-28s %12.2f %12.2f\n", "stereo-matched fraction (min)",
                *std::min_element(syn.stereo_fraction.begin(), syn.stereo_fraction.end()),
                *std::min_element(rea.stereo_fraction.begin(), rea.stereo_fraction.end()));
    std::printf("%-28s %12.1f %12.1f\n", "grey mean (raw left)", mean(syn.mean_grey), mean(rea.mean_grey));
    std::printf("%-28s %12.1f %12.1f\n", "grey std (raw left)", mean(syn.std_grey), mean(rea.std_grey));
    fs::remove_all(synth_dir);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "heslam-bench-synth-realism: %s\n", e.what());
    return 1;
  }
}
