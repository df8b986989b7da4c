// Result tables: statistics as rows, translation and rotation as columns. By default in a unit that
// fits the size of the error (mm below 1 m) with a fixed number of decimals; with full precision (17
// significant digits) a figure can be compared digit for digit with evo or kitti-odom-eval.
#include "tools/eval/app/table.hpp"

#include <cstdio>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace heslam::eval::app {

namespace {

std::string format(const char* pattern, double a, double b) {
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, pattern, a, b);
  return buffer;
}

std::string format(const char* pattern, double a) {
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, pattern, a);
  return buffer;
}

// Errors below this are printed in millimetres: EuRoC / TUM runs are off by millimetres, KITTI by metres.
constexpr double kMillimetreTableBelow_m = 1.0;
constexpr double kMillimetresPerMetre = 1e3;

void print_stats(std::ostream& out, const ErrorStats& t, const ErrorStats& r, Precision precision) {
  const std::pair<const char*, std::pair<double, double>> rows[] = {
      {"rmse", {t.rmse, r.rmse}}, {"mean", {t.mean, r.mean}}, {"median", {t.median, r.median}}, {"std", {t.std, r.std}},
      {"min", {t.min, r.min}},    {"max", {t.max, r.max}},    {"sse", {t.sse, r.sse}}};
  if (precision == Precision::full) {
    out << "          "
        << "   translation [m]"
        << "    rotation [deg]\n";
    for (const auto& [name, values] : rows) {
      char label[16];
      std::snprintf(label, sizeof label, "  %-8s", name);
      out << label << format("%18.12g%18.12g\n", values.first, values.second);
    }
    return;
  }
  const bool millimetres = t.max < kMillimetreTableBelow_m;
  const double scale = millimetres ? kMillimetresPerMetre : 1.0;
  const char* unit = millimetres ? "mm" : "m";
  out << "          "
      << "   translation"
      << "        rotation\n";
  for (const auto& [name, values] : rows) {
    // sse is a sum of squares: its unit is the square of the table's.
    const bool squared = std::string_view(name) == "sse";
    char label[16];
    std::snprintf(label, sizeof label, "  %-8s", name);
    const double translation = values.first * (squared ? scale * scale : scale);
    const std::string translation_unit = squared ? std::string(unit) + "^2" : std::string(unit) + "  ";
    out << label << format("%11.3f ", translation) << translation_unit << format("%12.3f ", values.second)
        << (squared ? "deg^2" : "deg") << "\n";
  }
}

// The stamp of row `i` of `t`, or its frame id when the file had no time.
double stamp_or_id(const Trajectory& t, std::size_t i) {
  return t.has_stamps() ? t.stamps_s[i] : static_cast<double>(t.frame_ids[i]);
}

void print_alignment(std::ostream& out, AlignMode mode, const Sim3& S) {
  out << "alignment: " << align_mode_name(mode);
  if (mode == AlignMode::sim3) out << format(" (scale %.9g)", S.scale);
  out << "\n";
}

}  // namespace

void print_ape(std::ostream& out, const ApeResult& ape, Precision precision) {
  out << "APE: " << ape.translation_m.count << " pairs, ";
  print_alignment(out, ape.align, ape.alignment);
  print_stats(out, ape.translation_m, ape.rotation_deg, precision);
}

void print_rpe(std::ostream& out, const RpeResult& rpe, Precision precision) {
  out << "RPE: delta " << format("%g", rpe.options.delta) << " " << delta_unit_name(rpe.options.unit)
      << (rpe.options.all_pairs ? " (all pairs)" : "") << ", " << rpe.pairs.size() << " pairs, ";
  print_alignment(out, rpe.options.align, Sim3{});
  print_stats(out, rpe.translation_m, rpe.rotation_deg, precision);
}

void print_kitti(std::ostream& out, const KittiResult& kitti, Precision precision) {
  out << "KITTI: " << kitti.pairs << " frames, " << kitti.segments.size() << " sub-sequences, ";
  print_alignment(out, kitti.align, kitti.alignment);
  const bool full = precision == Precision::full;
  out << "  length [m]  segments  translation [%]  rotation [deg/100m]\n";
  for (const KittiLengthError& l : kitti.per_length) {
    char row[160];
    std::snprintf(row, sizeof row, full ? "  %10.0f  %8zu  %15.9g  %19.9g\n" : "  %10.0f  %8zu  %15.3f  %19.4f\n",
                  l.length_m, l.segments, l.translation_error_percent, l.rotation_error_deg_per_100m);
    out << row;
  }
  if (full) {
    out << format("translation drift [%%]:     %.15g\n", kitti.translation_error_percent)
        << format("rotation drift [deg/100m]: %.15g\n", kitti.rotation_error_deg_per_100m)
        << format("ATE [m]:                   %.15g\n", kitti.ate_m)
        << format("RPE [m] / [deg]:           %.15g / %.15g\n", kitti.rpe_m, kitti.rpe_deg);
    return;
  }
  out << format("translation drift:  %.3f %%\n", kitti.translation_error_percent)
      << format("rotation drift:     %.4f deg/100m\n", kitti.rotation_error_deg_per_100m)
      << format("ATE:                %.3f m\n", kitti.ate_m)
      << format("RPE:                %.3f m / %.4f deg\n", kitti.rpe_m, kitti.rpe_deg);
}

std::string ape_error_rows(const ApeResult& ape, const AlignedPair& pair, const Trajectory& gt) {
  // The ground truth's path length up to each of its rows: where along the run an error was reached.
  std::vector<double> gt_path_m(gt.size(), 0.0);
  for (std::size_t i = 1; i < gt.size(); ++i) {
    gt_path_m[i] = gt_path_m[i - 1] + (gt.position_m(i) - gt.position_m(i - 1)).norm();
  }
  std::string out = "# est_row stamp_s translation_error_m dx_m dy_m dz_m rotation_error_deg gt_path_m\n";
  char row[256];
  for (std::size_t i = 0; i < ape.translation_errors_m.size(); ++i) {
    const Eigen::Vector3d d = ape.est_aligned.position_m(i) - ape.gt.position_m(i);
    const double path_m = pair.gt_rows[i] < gt_path_m.size() ? gt_path_m[pair.gt_rows[i]] : 0.0;
    std::snprintf(row, sizeof row, "%zu %.9f %.9g %.9g %.9g %.9g %.9g %.6f\n", pair.est_rows[i],
                  stamp_or_id(pair.est, i), ape.translation_errors_m[i], d.x(), d.y(), d.z(),
                  ape.rotation_errors_deg[i], path_m);
    out += row;
  }
  return out;
}

std::string rpe_error_rows(const RpeResult& rpe, const AlignedPair& pair) {
  std::string out = "# est_row_i est_row_j stamp_i_s stamp_j_s translation_error_m rotation_error_deg\n";
  char row[256];
  for (std::size_t k = 0; k < rpe.pairs.size(); ++k) {
    const auto [i, j] = rpe.pairs[k];
    std::snprintf(row, sizeof row, "%zu %zu %.9f %.9f %.9g %.9g\n", pair.est_rows[i], pair.est_rows[j],
                  stamp_or_id(pair.est, i), stamp_or_id(pair.est, j), rpe.translation_errors_m[k],
                  rpe.rotation_errors_deg[k]);
    out += row;
  }
  return out;
}

}  // namespace heslam::eval::app
