// Layout of the evaluation plot: two panels with metre axes, ticks, grid, legend and title.
#include "tools/eval/plot.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "tools/eval/plot_canvas.hpp"

namespace heslam::eval {

namespace {

constexpr int kWidthPx = 1400;
constexpr int kHeightPx = 700;
constexpr double kMarginLeftPx = 80;  // room for tick labels
constexpr double kMarginRightPx = 30;
constexpr double kMarginTopPx = 70;     // title and legend
constexpr double kMarginBottomPx = 60;  // tick labels and axis label
constexpr double kPanelGapPx = 90;
constexpr int kTargetTicks = 6;
constexpr double kTitlePx = 22;
constexpr double kLabelPx = 16;
constexpr double kTickPx = 13;
// Error samples further apart than this many typical steps are not joined by a line.
constexpr double kGapSteps = 5.0;

constexpr Color kBlack{0, 0, 0};
constexpr Color kGrid{225, 225, 225};
constexpr Color kGroundTruth{90, 90, 90};
constexpr Color kEstimate{31, 119, 180};
constexpr Color kError{214, 39, 40};
constexpr Color kRmse{255, 127, 14};
constexpr Color kStart{44, 160, 44};

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  double span() const { return hi - lo; }
  // A degenerate range (a still camera, constant error) still gets a visible extent.
  void pad(double fraction, double min_span) {
    const double extra = std::max(span() * fraction, 0.5 * std::max(0.0, min_span - span()));
    lo -= extra;
    hi += extra;
  }
};

// Tick spacing of 1, 2 or 5 times a power of ten.
double nice_step(double span, int target_ticks) {
  const double raw = span / target_ticks;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0}) {
    if (m * power >= raw) return m * power;
  }
  return 10.0 * power;
}

std::string tick_label(double value, double step) {
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, std::abs(value) < step * 1e-6 ? 0.0 : value);
  return buffer;
}

// A rectangle of the canvas showing the data box [x.lo, x.hi] x [y.lo, y.hi], y up.
struct Panel {
  double left_px, top_px, width_px, height_px;
  Range x, y;

  Eigen::Vector2d to_px(double vx, double vy) const {
    return {left_px + (vx - x.lo) / x.span() * width_px, top_px + height_px - (vy - y.lo) / y.span() * height_px};
  }

  void draw_axes(Canvas& canvas, const std::string& x_label, const std::string& y_label) const {
    const double bottom = top_px + height_px;
    const double step_x = nice_step(x.span(), kTargetTicks);
    for (double v = std::ceil(x.lo / step_x) * step_x; v <= x.hi; v += step_x) {
      const double px = to_px(v, y.lo).x();
      canvas.line({px, top_px}, {px, bottom}, kGrid, 1);
      canvas.text({px, bottom + 18}, tick_label(v, step_x), kBlack, kTickPx, Anchor::middle);
    }
    const double step_y = nice_step(y.span(), kTargetTicks);
    for (double v = std::ceil(y.lo / step_y) * step_y; v <= y.hi; v += step_y) {
      const double py = to_px(x.lo, v).y();
      canvas.line({left_px, py}, {left_px + width_px, py}, kGrid, 1);
      canvas.text({left_px - 6, py + 5}, tick_label(v, step_y), kBlack, kTickPx, Anchor::end);
    }
    canvas.polyline({{left_px, top_px},
                     {left_px, bottom},
                     {left_px + width_px, bottom},
                     {left_px + width_px, top_px},
                     {left_px, top_px}},
                    kBlack, 1);
    canvas.text({left_px + width_px / 2, bottom + 42}, x_label, kBlack, kLabelPx, Anchor::middle);
    canvas.text({left_px, top_px - 8}, y_label, kBlack, kLabelPx, Anchor::start);
  }
};

// The two axes along which the ground truth extends most, in axis order.
std::array<int, 2> top_view_axes(const Trajectory& gt) {
  std::array<Range, 3> ranges;
  for (const Pose3& T : gt.poses_wc) {
    for (int k = 0; k < 3; ++k) ranges[static_cast<std::size_t>(k)].add(T.translation()[k]);
  }
  int smallest = 0;
  for (int k = 1; k < 3; ++k) {
    if (ranges[static_cast<std::size_t>(k)].span() < ranges[static_cast<std::size_t>(smallest)].span()) smallest = k;
  }
  if (smallest == 0) return {1, 2};
  if (smallest == 1) return {0, 2};
  return {0, 1};
}

void draw_top_view(Canvas& canvas, const PlotInput& input, Panel panel) {
  const auto [a, b] = top_view_axes(input.gt);
  for (const Trajectory* t : {&input.gt, &input.est}) {
    for (const Pose3& T : t->poses_wc) {
      panel.x.add(T.translation()[a]);
      panel.y.add(T.translation()[b]);
    }
  }
  constexpr double kPadFraction = 0.05;
  constexpr double kMinSpanM = 0.1;
  panel.x.pad(kPadFraction, kMinSpanM);
  panel.y.pad(kPadFraction, kMinSpanM);
  // Equal scale: widen the range that is short for its side of the panel.
  const double m_per_px = std::max(panel.x.span() / panel.width_px, panel.y.span() / panel.height_px);
  for (auto [range, side_px] : {std::pair{&panel.x, panel.width_px}, std::pair{&panel.y, panel.height_px}}) {
    const double extra = 0.5 * (m_per_px * side_px - range->span());
    range->lo -= extra;
    range->hi += extra;
  }
  const char* names[] = {"x [m]", "y [m]", "z [m]"};
  panel.draw_axes(canvas, names[a], names[b]);
  for (const auto& [t, color, width] :
       {std::tuple{&input.gt, kGroundTruth, 3.0}, std::tuple{&input.est, kEstimate, 1.5}}) {
    std::vector<Eigen::Vector2d> points;
    points.reserve(t->size());
    for (const Pose3& T : t->poses_wc) points.push_back(panel.to_px(T.translation()[a], T.translation()[b]));
    canvas.polyline(points, color, width);
  }
  if (!input.gt.empty()) {
    canvas.circle(panel.to_px(input.gt.poses_wc[0].translation()[a], input.gt.poses_wc[0].translation()[b]), 5, kStart);
  }
  // Legend inside the panel's top-left corner.
  const double lx = panel.left_px + 12;
  const double ly = panel.top_px + 20;
  canvas.line({lx, ly - 5}, {lx + 30, ly - 5}, kGroundTruth, 2);
  canvas.text({lx + 38, ly}, "ground truth", kBlack, kTickPx, Anchor::start);
  canvas.line({lx, ly + 15}, {lx + 30, ly + 15}, kEstimate, 2);
  canvas.text({lx + 38, ly + 20}, "estimate (aligned)", kBlack, kTickPx, Anchor::start);
  canvas.circle({lx + 15, ly + 35}, 5, kStart);
  canvas.text({lx + 38, ly + 40}, "start", kBlack, kTickPx, Anchor::start);
}

void draw_errors(Canvas& canvas, const PlotInput& input, Panel panel) {
  for (std::size_t i = 0; i < input.errors.size(); ++i) {
    panel.x.add(input.error_x[i]);
    panel.y.add(input.errors[i]);
  }
  panel.y.add(0.0);
  constexpr double kMinSpan = 1e-3;
  if (panel.x.span() < kMinSpan) panel.x.pad(0.0, kMinSpan);
  panel.y.hi += std::max(panel.y.span() * 0.05, kMinSpan);
  panel.draw_axes(canvas, input.error_x_label, input.error_label);
  // A gap (tracking lost, no association) breaks the line instead of bridging it.
  std::vector<double> steps;
  for (std::size_t i = 1; i < input.error_x.size(); ++i) steps.push_back(input.error_x[i] - input.error_x[i - 1]);
  double typical_step = 0.0;
  if (!steps.empty()) {
    std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
    typical_step = steps[steps.size() / 2];
  }
  std::vector<Eigen::Vector2d> points;
  for (std::size_t i = 0; i < input.errors.size(); ++i) {
    if (i > 0 && input.error_x[i] - input.error_x[i - 1] > kGapSteps * typical_step) {
      canvas.polyline(points, kError, 1.0);
      points.clear();
    }
    points.push_back(panel.to_px(input.error_x[i], input.errors[i]));
  }
  canvas.polyline(points, kError, 1.0);
  const double y_rmse = panel.to_px(panel.x.lo, input.rmse).y();
  // Dashed: short segments across the panel.
  constexpr double kDashPx = 8;
  for (double x = panel.left_px; x < panel.left_px + panel.width_px; x += 2 * kDashPx) {
    canvas.line({x, y_rmse}, {std::min(x + kDashPx, panel.left_px + panel.width_px), y_rmse}, kRmse, 2);
  }
  char label[64];
  std::snprintf(label, sizeof label, "- - rmse %.4g", input.rmse);
  canvas.text({panel.left_px + panel.width_px, panel.top_px - 8}, label, kRmse, kLabelPx, Anchor::end);
}

// Seconds since the first stamp, or the row index when there are no stamps.
std::vector<double> error_x_of_rows(const Trajectory& t, const std::vector<std::size_t>& rows, std::string& label) {
  std::vector<double> x;
  label = t.has_stamps() ? "time [s]" : "frame";
  for (const std::size_t r : rows) {
    x.push_back(t.has_stamps() ? t.stamps_s[r] - t.stamps_s.front() : static_cast<double>(t.frame_ids[r]));
  }
  return x;
}

}  // namespace

PlotInput ape_plot(const ApeResult& ape, const std::string& title) {
  PlotInput input;
  input.title = title;
  input.gt = ape.gt;
  input.est = ape.est_aligned;
  std::vector<std::size_t> rows(ape.gt.size());
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = i;
  input.error_x = error_x_of_rows(ape.gt, rows, input.error_x_label);
  input.errors = ape.translation_errors_m;
  input.error_label = "APE translation [m]";
  input.rmse = ape.translation_m.rmse;
  return input;
}

PlotInput rpe_plot(const AlignedPair& pair, const RpeResult& rpe, const std::string& title) {
  PlotInput input;
  input.title = title;
  input.gt = pair.gt;
  input.est = pair.est;
  apply_sim3(input.est,
             compute_alignment(pair.gt, pair.est,
                               rpe.options.align == AlignMode::none ? AlignMode::origin : rpe.options.align));
  std::vector<std::size_t> rows;
  for (const auto& [i, j] : rpe.pairs) rows.push_back(i);
  input.error_x = error_x_of_rows(pair.gt, rows, input.error_x_label);
  input.errors = rpe.translation_errors_m;
  input.error_label = "RPE translation [m]";
  input.rmse = rpe.translation_m.rmse;
  return input;
}

PlotInput kitti_plot(const KittiResult& kitti, const std::string& title) {
  PlotInput input;
  input.title = title;
  input.gt = kitti.gt_relative;
  input.est = kitti.est_aligned;
  input.error_x_label = "frame";
  for (std::size_t i = 0; i < input.gt.size(); ++i) {
    input.error_x.push_back(static_cast<double>(input.gt.frame_ids[i]));
    input.errors.push_back((input.gt.position_m(i) - input.est.position_m(i)).norm());
  }
  input.error_label = "position error [m]";
  input.rmse = kitti.ate_m;
  return input;
}

void write_plot(const std::filesystem::path& path, const PlotInput& input) {
  const std::unique_ptr<Canvas> canvas = make_canvas(path, kWidthPx, kHeightPx);
  const double panel_height = kHeightPx - kMarginTopPx - kMarginBottomPx;
  // The top view is square; the error panel takes the rest of the width.
  const double top_view_width = panel_height;
  const double errors_left = kMarginLeftPx + top_view_width + kPanelGapPx;
  const double errors_width = kWidthPx - errors_left - kMarginRightPx;
  canvas->text({kMarginLeftPx, 30}, input.title, kBlack, kTitlePx, Anchor::start);
  draw_top_view(*canvas, input, Panel{kMarginLeftPx, kMarginTopPx, top_view_width, panel_height, {}, {}});
  draw_errors(*canvas, input, Panel{errors_left, kMarginTopPx, errors_width, panel_height, {}, {}});
  canvas->save();
}

}  // namespace heslam::eval
