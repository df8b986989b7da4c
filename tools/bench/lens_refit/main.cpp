// heslam-bench-lens-refit: does a saved map's own geometry ask for a different lens model at the
// image's edges? Re-fits the map with a residual radial term (lens_refit.hpp) and prints the estimate,
// its standard deviation and what it does to the keyframe path's length (the trajectory's scale).
//
// usage: heslam-bench-lens-refit MAP EUROC_DATASET [--window FIRST,LAST] [--profile K,K,...]
//   MAP            a mapper map file (a pipeline run's STEM.map, or --save-map's output)
//   EUROC_DATASET  the EuRoC folder the run used (its mav0/cam*/sensor.yaml give the rectified camera)
//   --window F,L   only the keyframes of stamp rank [F, L) x count (fractions), e.g. 0,0.5
//   --profile ...  also the cost and path length with k held at each value
// Exit code 0 on success, 1 when the map or calibration cannot be read, 2 on a usage error.
#include <cstdio>
#include <exception>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/mapping/map_file.hpp"
#include "tools/bench/lens_refit/lens_refit.hpp"

namespace {

constexpr const char* kUsage =
    "usage: heslam-bench-lens-refit MAP EUROC_DATASET [--window FIRST,LAST] [--profile K,K,...]";

bool parse_numbers(const std::string& text, std::vector<double>& numbers) {
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    try {
      std::size_t used = 0;
      numbers.push_back(std::stod(item, &used));
      if (used != item.size()) return false;
    } catch (const std::exception&) {
      return false;
    }
  }
  return !numbers.empty();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace heslam;
  std::vector<std::string> positional;
  bench::LensRefitOptions options;
  std::vector<double> profile;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if ((arg == "--window" || arg == "--profile") && i + 1 < argc) {
      std::vector<double> values;
      if (!parse_numbers(argv[++i], values) || (arg == "--window" && values.size() != 2)) {
        std::fprintf(stderr, "heslam-bench-lens-refit: %s '%s': expected %s\n", arg.c_str(), argv[i],
                     arg == "--window" ? "two fractions FIRST,LAST" : "comma-separated numbers");
        return 2;
      }
      if (arg == "--window") {
        options.first_fraction = values[0];
        options.last_fraction = values[1];
      } else {
        profile = values;
      }
    } else if (arg.starts_with("--")) {
      std::fprintf(stderr, "heslam-bench-lens-refit: unknown option '%s'\n%s\n", arg.c_str(), kUsage);
      return 2;
    } else {
      positional.push_back(arg);
    }
  }
  if (positional.size() != 2) {
    std::fprintf(stderr, "%s\n", kUsage);
    return 2;
  }
  try {
    const MapSnapshot snapshot = load_map_file(positional[0]);
    const std::filesystem::path mav0 = std::filesystem::path(positional[1]) / "mav0";
    if (!std::filesystem::is_directory(mav0)) {
      std::fprintf(stderr, "heslam-bench-lens-refit: '%s' is not an EuRoC folder (no mav0/)\n", positional[1].c_str());
      return 1;
    }
    const StereoRectifier rectifier(load_euroc_calibration(mav0));
    const PinholeStereo& camera = rectifier.camera();
    const bench::LensRefitResult fit = bench::refit_residual_radial(snapshot.map, camera, options);
    std::printf("keyframes %d  points %d  observations %d (stereo %d, skipped %d)  rectified fx %.2f px, baseline %.4f m\n",
                fit.keyframes, fit.points, fit.observations, fit.stereo_observations, fit.skipped_observations,
                camera.fx_px, camera.baseline_m);
    std::printf("k held at 0:  cost %.1f  keyframe path %.4f m\n", fit.cost_at_zero, fit.path_m_at_zero);
    std::printf("k estimated:  k %+.5f +- %.5f  cost %.1f  keyframe path %.4f m (x%.5f)\n", fit.radial_k,
                fit.radial_k_sigma, fit.cost_free, fit.path_m_free, fit.path_m_free / fit.path_m_at_zero);
    for (const bench::LensRefitProfilePoint& point : bench::refit_profile(snapshot.map, camera, options, profile))
      std::printf("  k held at %+.4f:  cost %.1f  keyframe path x%.5f\n", point.radial_k, point.cost,
                  point.path_m / fit.path_m_at_zero);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "heslam-bench-lens-refit: %s\n", error.what());
    return 1;
  }
  return 0;
}
