// heslam-photometric: writes a copy of an EuRoC or KITTI stereo folder whose images are exposed
// differently (per-camera gains, dark, low contrast), for running the whole system on them:
//
//   heslam-photometric IN OUT [--stereo-gain L,R[/L,R...]] [--variant none|dark|low_contrast]
//                      [--format auto|euroc|kitti]
//
// Calibration, ground truth and every other file are copied unchanged. The images are the ones
// heslam-frontend-offline gives the tracker with the same options (same noise seeds per frame).
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>

#include "runtime/flags.hpp"
#include "runtime/quote_value.hpp"
#include "tools/photometric/dataset_copy.hpp"

namespace {

// The command line, declared once for the parser and the usage.
heslam::runtime::Flags photometric_flags(std::string& input, std::string& output,
                                         heslam::photometric::DatasetCopyOptions& options, bool& help) {
  using namespace heslam;
  runtime::Flags flags(
      "heslam-photometric IN OUT [--stereo-gain L,R[/L,R...]] [--variant none|dark|low_contrast]\n"
      "                          [--format auto|euroc|kitti]",
      "  IN   an EuRoC (mav0/cam0/data.csv) or KITTI (times.txt, image_0/) stereo folder\n"
      "  OUT  the copy to write (must not exist or be empty, not inside IN)");
  flags
      .custom("--stereo-gain", "L,R",
              "left image x L, right x R, rounded and saturated to 8 bit (cameras\n"
              "exposed apart); L,R/L,R/...: the sequence split into equal blocks",
              [&options](const std::string& value) {
                options.stereo_gain = photometric::parse_stereo_gain_schedule(value);
              })
      .custom("--variant", "V",
              "dark (x0.1 plus noise) or low_contrast (x0.12 around mid grey), applied\n"
              "before the gains",
              [&options](const std::string& value) { options.variant = photometric::parse_photometric_variant(value); })
      .custom("--format", "auto|euroc|kitti", "the input's layout (default auto)",
              [&options](const std::string& value) { options.format = parse_dataset_format(value); })
      .toggle("--help", &help, "this help")
      .alias("-h")
      .note("At least one of --stereo-gain and --variant is required.")
      .positional("IN OUT", "", [&input, &output](const std::string& arg) {
        if (input.empty()) {
          input = arg;
        } else if (output.empty()) {
          output = arg;
        } else {
          throw std::runtime_error("unexpected argument '" + runtime::quote_value(arg) +
                                   "' (expected IN OUT and options)");
        }
      });
  return flags;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace heslam;
  std::string input;
  std::string output;
  photometric::DatasetCopyOptions options;
  bool help = false;
  runtime::Flags flags = photometric_flags(input, output, options, help);
  try {
    flags.parse(argc, argv);
    if (help) {
      std::fputs(flags.usage().c_str(), stdout);
      return 0;
    }
    if (input.empty() || output.empty()) throw std::runtime_error("expected the input and output folders");
    if (!flags.given("--stereo-gain") && !flags.given("--variant")) {
      throw std::runtime_error("nothing to do: give --stereo-gain and/or --variant");
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "heslam-photometric: %s\n", error.what());
    std::fputs(flags.usage().c_str(), stderr);
    return 2;
  }
  try {
    const photometric::DatasetCopySummary summary = photometric::write_dataset_copy(input, output, options);
    std::printf(
        "%s -> %s: %s, %zu stereo pairs transformed (variant %s, stereo gain %s), %zu other files copied; "
        "pixels at 255: left %.1f %%, right %.1f %%\n",
        input.c_str(), output.c_str(), to_string(summary.format), summary.frames,
        photometric::to_string(options.variant), photometric::describe(options.stereo_gain).c_str(),
        summary.copied_files, 100.0 * summary.left_saturated_share, 100.0 * summary.right_saturated_share);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "heslam-photometric: %s\n", error.what());
    return 1;
  }
  return 0;
}
