// Renders the scene radiance seen by one camera: per-pixel inverse mapping (ray / plane intersection
// with a depth test, tile-culled), mip-mapped trilinear texture filtering, and 4x supersampling of
// pixels on object silhouettes so edges are anti-aliased like a real lens + sensor would blur them.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "components/core/geometry/pose.hpp"
#include "tools/synth/camera_rays.hpp"
#include "tools/synth/scene.hpp"

namespace heslam::synth {

class Renderer {
 public:
  // Both must outlive the renderer.
  Renderer(const Scene& scene, const CameraRays& rays);

  // radiance: CV_32F scene radiance (about 0..1); depth_m (optional): CV_32F depth along the optical
  // axis of the visible surface, 0 where the ray hits nothing.
  void render(const Pose3& T_wc, cv::Mat& radiance, cv::Mat* depth_m = nullptr);

 private:
  struct CameraQuad {  // a quad's plane and axes in the camera frame, float for speed
    Eigen::Vector3f n, u, v;
    float n_o, u_o, v_o;  // n.o, u.o, v.o with o the quad origin in the camera frame
    float size_u, size_v;
    float x_min, x_max, y_min, y_max;  // bounds of its projection on the normalized plane
    int index;                         // into scene.quads
    const MipTexture* texture;
    float inv_texel, s0, t0, shade;
  };

  void prepare_quads(const Pose3& T_wc);
  // Nearest hit of ray (x, y, 1) among `candidates` (indices into cam_quads_); returns -1 for none.
  int trace(float x, float y, const int* candidates, int count, float& t_hit) const;
  float shade(const CameraQuad& q, float x, float y, float t, float step) const;
  // Radiance of `count` interior pixels from row-major index `first`, all on quad `q`, into `out`.
  void shade_run(const CameraQuad& q, int first, int count, float* out);
  // Texture coordinates of the ray (x, y) hitting q at depth t, and the pixel footprint in texels
  // (its major axis), for a pixel whose neighbours are `step` apart on the normalized plane.
  static float footprint_texels(const CameraQuad& q, float x, float y, float t, float step, float& s_texel,
                                float& t_texel);
  float sky(const Eigen::Matrix3f& R_wc, float x, float y) const;

  const Scene& scene_;
  const CameraRays& rays_;
  std::vector<CameraQuad> cam_quads_;
  std::vector<float> run_s_, run_t_, run_footprint_;  // shade_run's per-pixel scratch
  std::vector<float> depth_;
  std::vector<int> hit_;  // index into cam_quads_, -1 = sky
};

}  // namespace heslam::synth
