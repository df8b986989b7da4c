// heslam-bench-lens-refit: does a saved map's own geometry ask for a different lens model at the
// image's edges? Re-fits the map with a residual radial term (lens_refit.hpp) and prints the estimate,
// its standard deviation and what it does to the keyframe path's length (the trajectory's scale).
// `heslam-bench-lens-refit --help` lists the arguments. Exit code 0 on success, 1 when the map or calibration cannot be
// read, 2 on a usage error.
#include <cstdio>
#include <exception>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/mapping/map_file.hpp"
#include "runtime/flags.hpp"
#include "tools/bench/lens_refit/lens_refit.hpp"

namespace {

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
  bool help = false;
  runtime::Flags flags(
      "heslam-bench-lens-refit MAP EUROC_DATASET [--window FIRST,LAST] [--profile K,K,...]",
      "  MAP            a mapper map file (a pipeline run's STEM.map, or --save-map's output)\n"
      "  EUROC_DATASET  the EuRoC folder the run used (its mav0/cam*/sensor.yaml give the rectified camera)");
  flags
      .custom("--window", "F,L", "only the keyframes of stamp rank [F, L) x count (fractions), e.g. 0,0.5",
              [&options](const std::string& value) {
                std::vector<double> values;
                if (!parse_numbers(value, values) || values.size() != 2) {
                  runtime::throw_bad_flag_value("--window", "two fractions FIRST,LAST", value);
                }
                options.first_fraction = values[0];
                options.last_fraction = values[1];
              })
      .custom("--profile", "K,K,...", "also the cost and path length with k held at each value",
              [&profile](const std::string& value) {
                profile.clear();
                if (!parse_numbers(value, profile))
                  runtime::throw_bad_flag_value("--profile", "comma-separated numbers", value);
              })
      .toggle("--help", &help, "this help")
      .alias("-h")
      .positional("MAP EUROC_DATASET", "", [&positional](const std::string& arg) { positional.push_back(arg); });
  try {
    flags.parse(argc, argv);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "heslam-bench-lens-refit: %s\n", error.what());
    return 2;
  }
  if (help) {
    std::fputs(flags.usage().c_str(), stdout);
    return 0;
  }
  if (positional.size() != 2) {
    std::fprintf(stderr, "%s", flags.usage().c_str());
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
    std::printf(
        "keyframes %d  points %d  observations %d (stereo %d, skipped %d)  rectified fx %.2f px, baseline %.4f m\n",
        fit.keyframes, fit.points, fit.observations, fit.stereo_observations, fit.skipped_observations, camera.fx_px,
        camera.baseline_m);
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
