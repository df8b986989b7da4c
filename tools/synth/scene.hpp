// The synthetic world: textured planar rectangles (walls, floors, box faces, markers) in a z-up world.
//
// Every surface is a Quad: a rectangle spanned from `origin_w` by size_u_m along `axis_u_w` and
// size_v_m along `axis_v_w`. Texture coordinates are (s, t) = (u / texel_m + s0, v / texel_m + t0),
// so a texture corner at texel (i, j) is the exact world point origin + u axis_u + v axis_v.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products

#include "tools/synth/texture.hpp"

namespace heslam::synth {

struct Quad {
  Eigen::Vector3d origin_w = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_u_w = Eigen::Vector3d::UnitX();  // unit
  Eigen::Vector3d axis_v_w = Eigen::Vector3d::UnitY();  // unit, orthogonal to axis_u_w
  double size_u_m = 1.0;
  double size_v_m = 1.0;
  int texture = 0;         // index into Scene::textures
  double texel_m = 0.005;  // metres per level-0 texel
  double s0_texels = 0.0;  // texture offset, so repeated photos do not all start at one corner
  double t0_texels = 0.0;
  float shade = 1.0f;  // albedo x illumination of this face, multiplies the texture

  Eigen::Vector3d normal_w() const { return axis_u_w.cross(axis_v_w); }
  Eigen::Vector3d point(double u_m, double v_m) const { return origin_w + u_m * axis_u_w + v_m * axis_v_w; }
};

// A known 3D point with a sharp image signature (an inner checkerboard corner) for geometry tests.
struct MarkerCorner {
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  int quad = 0;  // the marker quad it lies on
};

struct Scene {
  std::vector<MipTexture> textures;
  std::vector<Quad> quads;
  std::vector<MarkerCorner> marker_corners;
  float sky_radiance = 0.0f;  // radiance of rays that hit nothing (outdoor scenes)
  Eigen::Vector3d light_dir_w = Eigen::Vector3d(0.3, 0.2, 1.0).normalized();  // towards the light
  float ambient = 0.55f;
  float diffuse = 0.45f;

  int add_texture(MipTexture texture);
  // Adds a quad and sets its shade from the face normal and the scene light times `albedo`.
  int add_quad(Quad quad, float albedo = 1.0f);
  // A box rotated by yaw standing on base_center_w.z(): four sides and the top.
  // side_textures are used round-robin; texel_m sets the texture scale.
  void add_box(const Eigen::Vector3d& base_center_w, const Eigen::Vector3d& size_m, double yaw_rad,
               const std::vector<int>& side_textures, int top_texture, double texel_m, float albedo,
               std::uint64_t variation_seed);
  // A checkerboard marker on a plane: centre, in-plane right and down directions; registers its
  // inner corners in marker_corners. Returns the quad index.
  int add_checker_marker(const Eigen::Vector3d& center_w, const Eigen::Vector3d& right_w, const Eigen::Vector3d& down_w,
                         double cell_m, const CheckerLayout& layout);

  // All quad corners (world), e.g. box corners for geometry tests.
  std::vector<Eigen::Vector3d> quad_corners_w() const;
};

}  // namespace heslam::synth
