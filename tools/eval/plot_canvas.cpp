// The PNG (OpenCV) and SVG back ends of Canvas.
#include "tools/eval/plot_canvas.hpp"

#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace heslam::eval {

namespace {

// OpenCV's Hershey font is ~22 px tall at scale 1.
constexpr double kHersheyPxPerScale = 22.0;
// Lines are drawn at 4x sub-pixel precision (cv::LINE_AA with shift 2).
constexpr int kSubPixelShift = 2;
constexpr double kSubPixelScale = 4.0;

class PngCanvas final : public Canvas {
 public:
  PngCanvas(std::filesystem::path path, int width_px, int height_px)
      : path_(std::move(path)), image_(height_px, width_px, CV_8UC3, cv::Scalar(255, 255, 255)) {}

  void polyline(const std::vector<Eigen::Vector2d>& points_px, Color color, double width_px) override {
    if (points_px.size() < 2) return;
    std::vector<cv::Point> points;
    points.reserve(points_px.size());
    for (const auto& p : points_px) {
      points.emplace_back(static_cast<int>(p.x() * kSubPixelScale), static_cast<int>(p.y() * kSubPixelScale));
    }
    cv::polylines(image_, points, false, scalar(color), std::max(1, static_cast<int>(width_px + 0.5)), cv::LINE_AA,
                  kSubPixelShift);
  }

  void circle(const Eigen::Vector2d& center_px, double radius_px, Color color) override {
    cv::circle(image_, cv::Point(static_cast<int>(center_px.x()), static_cast<int>(center_px.y())),
               static_cast<int>(radius_px), scalar(color), cv::FILLED, cv::LINE_AA);
  }

  void text(const Eigen::Vector2d& position_px, const std::string& text, Color color, double size_px,
            Anchor anchor) override {
    const double scale = size_px / kHersheyPxPerScale;
    const int thickness = size_px >= 18.0 ? 2 : 1;
    int baseline = 0;
    const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline);
    double x = position_px.x();
    if (anchor == Anchor::middle) x -= size.width / 2.0;
    if (anchor == Anchor::end) x -= size.width;
    cv::putText(image_, text, cv::Point(static_cast<int>(x), static_cast<int>(position_px.y())),
                cv::FONT_HERSHEY_SIMPLEX, scale, scalar(color), thickness, cv::LINE_AA);
  }

  void save() override {
    bool written = false;
    try {
      written = cv::imwrite(path_.string(), image_);
    } catch (const cv::Exception&) {
      written = false;
    }
    if (!written) throw std::runtime_error("cannot write plot " + path_.string());
  }

 private:
  static cv::Scalar scalar(Color c) { return cv::Scalar(c.b, c.g, c.r); }

  std::filesystem::path path_;
  cv::Mat image_;
};

class SvgCanvas final : public Canvas {
 public:
  SvgCanvas(std::filesystem::path path, int width_px, int height_px) : path_(std::move(path)) {
    body_ << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width_px << "\" height=\"" << height_px
          << "\" viewBox=\"0 0 " << width_px << ' ' << height_px << "\" font-family=\"sans-serif\">\n"
          << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  }

  void polyline(const std::vector<Eigen::Vector2d>& points_px, Color color, double width_px) override {
    if (points_px.size() < 2) return;
    body_ << "<polyline fill=\"none\" stroke=\"" << css(color) << "\" stroke-width=\"" << width_px
          << "\" stroke-linejoin=\"round\" points=\"";
    char number[64];
    for (const auto& p : points_px) {
      std::snprintf(number, sizeof number, "%.2f,%.2f ", p.x(), p.y());
      body_ << number;
    }
    body_ << "\"/>\n";
  }

  void circle(const Eigen::Vector2d& center_px, double radius_px, Color color) override {
    body_ << "<circle cx=\"" << center_px.x() << "\" cy=\"" << center_px.y() << "\" r=\"" << radius_px << "\" fill=\""
          << css(color) << "\"/>\n";
  }

  void text(const Eigen::Vector2d& position_px, const std::string& text, Color color, double size_px,
            Anchor anchor) override {
    const char* anchor_name = anchor == Anchor::start ? "start" : anchor == Anchor::middle ? "middle" : "end";
    body_ << "<text x=\"" << position_px.x() << "\" y=\"" << position_px.y() << "\" font-size=\"" << size_px
          << "\" fill=\"" << css(color) << "\" text-anchor=\"" << anchor_name << "\">" << escape(text) << "</text>\n";
  }

  void save() override {
    std::ofstream out(path_);
    out << body_.str() << "</svg>\n";
    if (!out) throw std::runtime_error("cannot write plot " + path_.string());
  }

 private:
  static std::string css(Color c) {
    char buffer[16];
    std::snprintf(buffer, sizeof buffer, "#%02x%02x%02x", c.r, c.g, c.b);
    return buffer;
  }

  static std::string escape(const std::string& text) {
    std::string out;
    for (const char c : text) {
      if (c == '<')
        out += "&lt;";
      else if (c == '>')
        out += "&gt;";
      else if (c == '&')
        out += "&amp;";
      else
        out += c;
    }
    return out;
  }

  std::filesystem::path path_;
  std::ostringstream body_;
};

}  // namespace

std::unique_ptr<Canvas> make_canvas(const std::filesystem::path& path, int width_px, int height_px) {
  const std::string extension = path.extension().string();
  if (extension == ".png") return std::make_unique<PngCanvas>(path, width_px, height_px);
  if (extension == ".svg") return std::make_unique<SvgCanvas>(path, width_px, height_px);
  throw std::runtime_error("plot " + path.string() + ": expected a .png or .svg file name");
}

}  // namespace heslam::eval
