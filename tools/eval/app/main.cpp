// heslam-eval: trajectory evaluation (APE, RPE, KITTI drift) agreeing with evo and the KITTI devkit.
#include <exception>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "tools/eval/app/cli_options.hpp"
#include "tools/eval/app/frame_check.hpp"
#include "tools/eval/app/table.hpp"
#include "tools/eval/association.hpp"
#include "tools/eval/json_output.hpp"
#include "tools/eval/kitti_metrics.hpp"
#include "tools/eval/plot.hpp"

namespace {

using namespace heslam::eval;

// "folder/file": result files of different tools often share the file name (09.txt vs 09.txt).
std::string short_name(const std::filesystem::path& path) {
  const std::filesystem::path folder = path.parent_path().filename();
  return folder.empty() ? path.filename().string() : (folder / path.filename()).string();
}

std::string plot_title(const app::CliOptions& options, const char* metric) {
  return std::string(metric) + ": " + short_name(options.est_path) + " vs " + short_name(options.gt_path);
}

// The JSON document goes to its file, or alone on stdout.
void emit_json(const app::CliOptions& options, const std::string& json) {
  if (options.json_path == app::kStdout)
    std::cout << json;
  else if (!options.json_path.empty())
    write_text_file(options.json_path, json);
}

int run(const app::CliOptions& options) {
  const Trajectory gt = read_trajectory(options.gt_path, options.gt_read);
  const Trajectory est = read_trajectory(options.est_path, options.est_read);
  const app::FrameCheck frames = app::check_frames(options, gt, est);
  if (frames.error) throw std::runtime_error(*frames.error);
  if (frames.warning) std::cerr << "heslam-eval: warning: " << *frames.warning << "\n";
  // With JSON on stdout, the human-readable lines would make it unparsable: they are dropped.
  std::ostringstream discarded;
  std::ostream& text = options.json_path == app::kStdout ? discarded : std::cout;
  const app::Precision precision = options.full_precision ? app::Precision::full : app::Precision::readable;
  text << "gt:  " << options.gt_path.string() << " (" << gt.size() << " poses)\n"
       << "est: " << options.est_path.string() << " (" << est.size() << " poses)\n";
  JsonContext context{options.gt_path.string(), options.est_path.string(), gt.size(), est.size(), false,
                      options.max_dt_s};

  if (options.command == app::Command::kitti) {
    const KittiResult kitti =
        compute_kitti_metrics(gt, est, KittiOptions{.align = options.align.value_or(AlignMode::none)});
    app::print_kitti(text, kitti, precision);
    emit_json(options, to_json(kitti, context));
    if (!options.plot_path.empty()) write_plot(options.plot_path, kitti_plot(kitti, plot_title(options, "KITTI")));
    return 0;
  }

  const AlignedPair pair = associate(gt, est,
                                     AssociationOptions{.max_dt_s = options.max_dt_s,
                                                        .est_offset_s = options.est_offset_s,
                                                        .interpolate_gt = options.interpolate_gt});
  context.associated_by_time = pair.by_time;
  text << "associated " << pair.size() << " pairs by "
       << (pair.by_time ? (options.interpolate_gt ? "time stamp, ground truth interpolated" : "time stamp")
                        : "frame index")
       << "\n";
  if (options.command == app::Command::ape) {
    const ApeResult ape = compute_ape(pair, ApeOptions{.align = options.align.value_or(AlignMode::se3)});
    if (ape.align == AlignMode::se3 || ape.align == AlignMode::sim3) {
      if (const auto degenerate = alignment_degeneracy(ape.gt, pair.est, ape.alignment)) {
        std::cerr << "heslam-eval: warning: " << *degenerate << " (a near-still or straight trajectory); "
                  << "--align origin compares from the first pose instead\n";
      }
    }
    app::print_ape(text, ape, precision);
    emit_json(options, to_json(ape, context));
    if (!options.plot_path.empty()) write_plot(options.plot_path, ape_plot(ape, plot_title(options, "APE")));
    if (!options.errors_path.empty()) write_text_file(options.errors_path, app::ape_error_rows(ape, pair, gt));
  } else {
    RpeOptions rpe_options = options.rpe;
    rpe_options.align = options.align.value_or(AlignMode::none);
    const RpeResult rpe = compute_rpe(pair, rpe_options);
    app::print_rpe(text, rpe, precision);
    emit_json(options, to_json(rpe, context));
    if (!options.plot_path.empty()) write_plot(options.plot_path, rpe_plot(pair, rpe, plot_title(options, "RPE")));
    if (!options.errors_path.empty()) write_text_file(options.errors_path, app::rpe_error_rows(rpe, pair));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const app::CliOptions options = app::parse_cli(argc, argv);
    if (options.help) {
      std::cout << app::usage();
      return 0;
    }
    return run(options);
  } catch (const std::exception& e) {
    std::cerr << "heslam-eval: " << e.what() << "\n";
    return 1;
  }
}
