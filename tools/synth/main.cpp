// heslam-synth: renders a synthetic stereo sequence with exact ground truth to EuRoC or KITTI layout.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "runtime/flags.hpp"
#include "tools/dataset/imu_reader.hpp"
#include "tools/synth/occupancy_truth.hpp"
#include "tools/synth/preset.hpp"
#include "tools/synth/progress_report.hpp"
#include "tools/synth/scene_builders.hpp"
#include "tools/synth/sequence.hpp"
#include "tools/synth/writers.hpp"

namespace {

// The command line, declared once for the parser and the usage.
struct Arguments {
  std::string preset_name;
  std::string camera_name;
  std::string out_dir;
  heslam::synth::OutputFormat format = heslam::synth::OutputFormat::kEuroc;
  bool quiet = false;
  bool list = false;
  bool help = false;
  std::filesystem::path imu_noise_file;
  heslam::synth::RenderOptions options;
  std::filesystem::path occupancy_gt;
  double occupancy_resolution_m = 0.05;
  double occupancy_band_min_m = -0.7;
  double occupancy_band_max_m = 0.3;
  bool occupancy_seen = false;
  double occupancy_max_depth_m = 5.0;
  int occupancy_seen_stride = 2;
};

heslam::runtime::Flags synth_flags(Arguments& a) {
  using heslam::synth::OutputFormat;
  heslam::runtime::Flags flags(
      "heslam-synth --preset NAME|FILE.yaml --out DIR [--camera NAME|FILE.yaml] [--seed N] [--frames N]\n"
      "                    [--format euroc|kitti]\n"
      "                    [--threads 1|2] [--no-events] [--quiet]\n"
      "       heslam-synth --list",
      "  progress on stderr: a live line on a terminal, a line per 10 % otherwise, none with --quiet");
  flags.text("--preset", "NAME|FILE.yaml", &a.preset_name, "a built-in preset (--list) or a preset file")
      .text("--out", "DIR", &a.out_dir, "where the sequence is written")
      .text("--camera", "NAME|FILE.yaml", &a.camera_name,
            "the preset seen through this camera instead (config/synth/cameras/NAME.yaml, e.g.\n"
            "fisheye: an equidistant stereo pair; its camera: fields replace the preset's)")
      .integer("--seed", "N", &a.options.seed, std::uint64_t{0}, std::numeric_limits<std::uint64_t>::max(),
               "trajectory jitter, oscillation phases and sensor noise (1)")
      .integer("--frames", "N", &a.options.frames, 0, std::numeric_limits<int>::max(),
               "frames to render (default: the preset's)")
      .choice("--format", &a.format, {{"euroc", OutputFormat::kEuroc}, {"kitti", OutputFormat::kKitti}},
              "output layout (default euroc)")
      .integer("--threads", "1|2", &a.options.threads, 1, 2,
               "left and right images rendered concurrently (the same bytes)")
      .toggle("--no-events", &a.options.events, "none of the preset's events", false)
      .toggle("--imu", &a.options.imu,
              "also write mav0/imu0/ (200 Hz readings, sensor.yaml) and the true velocity and\n"
              "biases in the ground truth; the motion is then C2 (the images differ from a\n"
              "render without --imu)")
      .toggle("--imu-noise-free", &a.options.imu_noise_free, "--imu readings without noise or bias")
      .path("--imu-noise", "FILE", &a.imu_noise_file,
            "the noise model (and rate_hz) of this IMU sensor.yaml (default: EuRoC's ADIS16448)")
      .path("--occupancy-gt", "STEM", &a.occupancy_gt,
            "also (or, without --out, only) the ground-truth 2D occupancy as STEM.pgm + STEM.yaml\n"
            "(map_server), in heslam-occupancy's grid frame: the first left camera, -y up")
      .number("--occupancy-resolution", "M", &a.occupancy_resolution_m, 0.001, 10.0, "its cell size (0.05)")
      .number("--occupancy-band-min", "M", &a.occupancy_band_min_m, -1000.0, 1000.0,
              "its height band, along -y of the first camera (-0.7, as heslam-occupancy's grid.band_min_m)")
      .number("--occupancy-band-max", "M", &a.occupancy_band_max_m, -1000.0, 1000.0, "(0.3, grid.band_max_m)")
      .toggle("--occupancy-seen", &a.occupancy_seen,
              "the truth is only what the left camera sees within --occupancy-max-depth on the path\n"
              "(every --occupancy-seen-stride-th frame): the cells a mapper can find at best")
      .number("--occupancy-max-depth", "M", &a.occupancy_max_depth_m, 0.01, 1000.0,
              "with --occupancy-seen (5, as heslam-occupancy's stereo.max_depth_m)")
      .integer("--occupancy-seen-stride", "N", &a.occupancy_seen_stride, 1, 1000, "with --occupancy-seen (2)")
      .toggle("--quiet", &a.quiet, "no progress and no summary line")
      .alias("-q")
      .toggle("--list", &a.list, "the built-in presets, one a line: frames, duration, distance travelled, purpose")
      .toggle("--help", &a.help, "this help")
      .alias("-h");
  return flags;
}

// One line per built-in preset: what a run of it costs and what it is for.
void print_presets(std::ostream& out) {
  using namespace heslam::synth;
  std::size_t width = 0;
  for (const auto& name : known_presets()) width = std::max(width, name.size());
  for (const auto& name : known_presets()) {
    Preset preset = load_preset(find_preset(name));
    preset.texture_size_px = 16;  // the path only: the textures' size does not move it
    const Trajectory trajectory(build_scene(preset).path, preset.trajectory, RenderOptions{}.seed);
    // Travelled over the frames (a closed path may be gone round more than once, or not finished).
    double travelled_m = 0.0;
    for (int k = 1; k < preset.frames; ++k) {
      travelled_m += (trajectory.T_wb(k / preset.camera.rate_hz).translation() -
                      trajectory.T_wb((k - 1) / preset.camera.rate_hz).translation())
                         .norm();
    }
    char figures[128];
    std::snprintf(figures, sizeof figures, "%5d frames, %6.1f s at %g Hz, %6.1f m travelled", preset.frames,
                  preset.frames / preset.camera.rate_hz, preset.camera.rate_hz, travelled_m);
    out << name << std::string(width - name.size() + 2, ' ') << figures << ": "
        << (preset.purpose.empty() ? std::string("(no purpose: field)") : preset.purpose) << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace heslam::synth;
  try {
    Arguments arguments;
    heslam::runtime::Flags flags = synth_flags(arguments);
    flags.parse(argc, argv);
    if (arguments.help) {
      std::cout << flags.usage();
      return 0;
    }
    if (arguments.list) {
      print_presets(std::cout);
      return 0;
    }
    const std::string& preset_name = arguments.preset_name;
    const std::string& out_dir = arguments.out_dir;
    const bool quiet = arguments.quiet;
    RenderOptions& options = arguments.options;
    const OutputFormat fmt = arguments.format;
    const std::string format = fmt == OutputFormat::kEuroc ? "euroc" : "kitti";
    if (preset_name.empty() || (out_dir.empty() && arguments.occupancy_gt.empty()))
      throw std::runtime_error("--preset and --out (or --occupancy-gt) are required\n" + flags.usage());
    if (!(arguments.occupancy_band_min_m < arguments.occupancy_band_max_m))
      throw std::runtime_error("--occupancy-band-min must be below --occupancy-band-max");
    if (!arguments.imu_noise_file.empty()) {
      if (!options.imu) throw std::runtime_error("--imu-noise: only with --imu");
      const heslam::ImuRecording model = heslam::read_imu_sensor_yaml(arguments.imu_noise_file);
      options.imu_noise = model.noise;
      options.imu_rate_hz = model.rate_hz;
    }
    if (options.imu_noise_free && !options.imu) throw std::runtime_error("--imu-noise-free: only with --imu");
    if (options.imu && fmt != OutputFormat::kEuroc) throw std::runtime_error("--imu: only with --format euroc");
    // KITTI images are rectified by definition: render ideal pinhole images for it.
    if (fmt == OutputFormat::kKitti) options.apply_distortion = false;

    Preset preset = load_preset(find_preset(preset_name));
    if (!arguments.camera_name.empty()) apply_camera_file(find_camera(arguments.camera_name), preset);
    SequenceRenderer renderer(preset, options);
    if (!arguments.occupancy_gt.empty()) {
      const heslam::GridBand band{arguments.occupancy_band_min_m, arguments.occupancy_band_max_m};
      const heslam::OccupancyGrid truth =
          arguments.occupancy_seen
              ? occupancy_truth_seen(renderer, arguments.occupancy_seen_stride, arguments.occupancy_max_depth_m,
                                     arguments.occupancy_resolution_m, band)
              : occupancy_truth(renderer.scene(), renderer.T_wc_left(0), arguments.occupancy_resolution_m, band);
      truth.write_map_server(arguments.occupancy_gt);
      if (!quiet) {
        std::fprintf(stderr, "heslam-synth: wrote %s.pgm/.yaml (%zu occupied cells)\n", arguments.occupancy_gt.c_str(),
                     truth.count(heslam::CellState::kOccupied));
      }
      if (out_dir.empty()) return 0;
    }
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
