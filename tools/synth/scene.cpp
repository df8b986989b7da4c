// Building blocks of synthetic scenes: textures, shaded quads, boxes and checkerboard markers.
#include "tools/synth/scene.hpp"

#include <algorithm>
#include <cmath>

namespace heslam::synth {
namespace {

// Offsets of repeated photographs are drawn from this many texels so neighbouring faces differ.
constexpr int kOffsetRangeTexels = 512;

std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

}  // namespace

int Scene::add_texture(MipTexture texture) {
  textures.push_back(std::move(texture));
  return static_cast<int>(textures.size()) - 1;
}

int Scene::add_quad(Quad quad, float albedo) {
  // Two-sided diffuse lighting: a quad's facing side is not tracked, only its orientation matters.
  const double lambert = std::abs(quad.normal_w().dot(light_dir_w));
  quad.shade = albedo * (ambient + diffuse * static_cast<float>(lambert));
  quads.push_back(quad);
  return static_cast<int>(quads.size()) - 1;
}

void Scene::add_box(const Eigen::Vector3d& base_center_w, const Eigen::Vector3d& size_m, double yaw_rad,
                    const std::vector<int>& side_textures, int top_texture, double texel_m, float albedo,
                    std::uint64_t variation_seed) {
  const Eigen::Vector3d ex(std::cos(yaw_rad), std::sin(yaw_rad), 0.0);
  const Eigen::Vector3d ey(-std::sin(yaw_rad), std::cos(yaw_rad), 0.0);
  const Eigen::Vector3d ez = Eigen::Vector3d::UnitZ();
  const double hx = size_m.x() / 2, hy = size_m.y() / 2, h = size_m.z();
  // Sides: walking counter-clockwise round the base, u along the side, v downwards.
  const Eigen::Vector3d corners[4] = {base_center_w - hx * ex - hy * ey, base_center_w + hx * ex - hy * ey,
                                      base_center_w + hx * ex + hy * ey, base_center_w - hx * ex + hy * ey};
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d& a = corners[i];
    const Eigen::Vector3d& b = corners[(i + 1) % 4];
    Quad q;
    q.origin_w = a + h * ez;
    q.axis_u_w = (b - a).normalized();
    q.axis_v_w = -ez;
    q.size_u_m = (b - a).norm();
    q.size_v_m = h;
    q.texture = side_textures[static_cast<std::size_t>(i) % side_textures.size()];
    q.texel_m = texel_m;
    const std::uint64_t r = mix(variation_seed * 8 + static_cast<std::uint64_t>(i));
    q.s0_texels = static_cast<double>(r % kOffsetRangeTexels);
    q.t0_texels = static_cast<double>((r >> 20) % kOffsetRangeTexels);
    add_quad(q, albedo);
  }
  Quad top;
  top.origin_w = corners[0] + h * ez;
  top.axis_u_w = ex;
  top.axis_v_w = ey;
  top.size_u_m = size_m.x();
  top.size_v_m = size_m.y();
  top.texture = top_texture;
  top.texel_m = texel_m;
  add_quad(top, albedo);
}

int Scene::add_checker_marker(const Eigen::Vector3d& center_w, const Eigen::Vector3d& right_w,
                              const Eigen::Vector3d& down_w, double cell_m, const CheckerLayout& layout) {
  const int texture = add_texture(make_checker_marker(layout));
  const double texel_m = cell_m / layout.cell_texels;
  const double side_m = layout.size_px() * texel_m;
  Quad q;
  q.axis_u_w = right_w.normalized();
  q.axis_v_w = down_w.normalized();
  q.origin_w = center_w - 0.5 * side_m * (q.axis_u_w + q.axis_v_w);
  q.size_u_m = side_m;
  q.size_v_m = side_m;
  q.texture = texture;
  q.texel_m = texel_m;
  // Markers are lit evenly (a flat print facing the room), so their corners are symmetric.
  q.shade = 1.0f;
  quads.push_back(q);
  const int quad_index = static_cast<int>(quads.size()) - 1;
  for (int j = 1; j < layout.squares; ++j) {
    for (int i = 1; i < layout.squares; ++i) {
      const double u = (layout.border_texels + i * layout.cell_texels) * texel_m;
      const double v = (layout.border_texels + j * layout.cell_texels) * texel_m;
      marker_corners.push_back({q.point(u, v), quad_index});
    }
  }
  return quad_index;
}

std::vector<Eigen::Vector3d> Scene::quad_corners_w() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(quads.size() * 4);
  for (const Quad& q : quads) {
    out.push_back(q.point(0, 0));
    out.push_back(q.point(q.size_u_m, 0));
    out.push_back(q.point(q.size_u_m, q.size_v_m));
    out.push_back(q.point(0, q.size_v_m));
  }
  return out;
}

}  // namespace heslam::synth
