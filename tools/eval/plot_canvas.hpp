// A minimal 2-D drawing surface with two back ends, so one plot layout yields PNG and SVG alike.
//
// API:
//   std::unique_ptr<Canvas> canvas = make_canvas(path, width_px, height_px);  // by extension
//   canvas->polyline(points_px, kBlue, 2.0); canvas->text({x, y}, "x [m]", kBlack, 14, Anchor::middle);
//   canvas->save();                          // throws std::runtime_error naming the file on failure
// Coordinates are pixels, origin top-left, y down.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace heslam::eval {

struct Color {
  unsigned char r = 0, g = 0, b = 0;
};

enum class Anchor { start, middle, end };

class Canvas {
 public:
  virtual ~Canvas() = default;
  virtual void polyline(const std::vector<Eigen::Vector2d>& points_px, Color color, double width_px) = 0;
  virtual void circle(const Eigen::Vector2d& center_px, double radius_px, Color color) = 0;
  // `position_px` is the baseline point at the anchor.
  virtual void text(const Eigen::Vector2d& position_px, const std::string& text, Color color, double size_px,
                    Anchor anchor) = 0;
  virtual void save() = 0;

  void line(const Eigen::Vector2d& a_px, const Eigen::Vector2d& b_px, Color color, double width_px) {
    polyline({a_px, b_px}, color, width_px);
  }
};

// ".png" (drawn with OpenCV) or ".svg"; throws std::runtime_error for other extensions.
std::unique_ptr<Canvas> make_canvas(const std::filesystem::path& path, int width_px, int height_px);

}  // namespace heslam::eval
