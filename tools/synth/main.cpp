// heslam-synth: renders a synthetic stereo sequence with exact ground truth to EuRoC or KITTI layout.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "tools/synth/preset.hpp"
#include "tools/synth/progress_report.hpp"
#include "tools/synth/sequence.hpp"
#include "tools/synth/writers.hpp"

namespace {

constexpr const char* kUsage =
    "usage: heslam-synth --preset NAME|FILE.yaml --out DIR [--seed N] [--frames N] [--format euroc|kitti]\n"
    "                    [--threads 1|2] [--no-events] [--quiet]\n"
    "  progress on stderr: a live line on a terminal, a line per 10 % otherwise, none with --quiet\n"
    "       heslam-synth --list\n";

std::uint64_t parse_u64(const std::string& flag, const std::string& value) {
  char* end = nullptr;
  const unsigned long long v = std::strtoull(value.c_str(), &end, 10);
  if (value.empty() || *end != '\0' || value[0] == '-') {
    throw std::runtime_error(flag + " expects a non-negative integer, got '" + value + "'");
  }
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace heslam::synth;
  try {
    std::string preset_name, out_dir, format = "euroc";
    bool quiet = false;
    RenderOptions options;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw std::runtime_error(arg + " needs a value");
        return argv[++i];
      };
      if (arg == "--preset") preset_name = value();
      else if (arg == "--out") out_dir = value();
      else if (arg == "--seed") options.seed = parse_u64(arg, value());
      else if (arg == "--frames") options.frames = static_cast<int>(parse_u64(arg, value()));
      else if (arg == "--format") format = value();
      else if (arg == "--threads") options.threads = static_cast<int>(parse_u64(arg, value()));
      else if (arg == "--no-events") options.events = false;
      else if (arg == "--quiet" || arg == "-q") quiet = true;
      else if (arg == "--list") {
        for (const auto& n : known_presets()) std::cout << n << "\n";
        return 0;
      } else if (arg == "--help" || arg == "-h") {
        std::cout << kUsage;
        return 0;
      } else {
        throw std::runtime_error("unknown argument '" + arg + "'\n" + kUsage);
      }
    }
    if (preset_name.empty() || out_dir.empty()) throw std::runtime_error(std::string("--preset and --out are required\n") + kUsage);
    if (format != "euroc" && format != "kitti") throw std::runtime_error("--format is '" + format + "', expected euroc or kitti");
    const OutputFormat fmt = format == "euroc" ? OutputFormat::kEuroc : OutputFormat::kKitti;
    // KITTI images are rectified by definition: render ideal pinhole images for it.
    if (fmt == OutputFormat::kKitti) options.apply_distortion = false;

    const Preset preset = load_preset(find_preset(preset_name));
    SequenceRenderer renderer(preset, options);
    const auto start = std::chrono::steady_clock::now();
    ProgressReport progress(std::cerr, ProgressReport::mode_for(quiet, isatty(STDERR_FILENO) == 1), preset.name);
    write_sequence(renderer, fmt, out_dir, [&](int done, int total) {
      progress.update(done, total, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    });
    if (!quiet) {
      std::fprintf(stderr, "heslam-synth: wrote %s (%s, seed %llu, %.1f m path)\n", out_dir.c_str(), format.c_str(),
                   static_cast<unsigned long long>(options.seed), renderer.trajectory().length_m());
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "heslam-synth: " << e.what() << "\n";
    return 1;
  }
}
