// EuRoC / KITTI writers and metadata, in the exact text formats the datasets and ORB-SLAM2 use.
#include "tools/synth/writers.hpp"

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tools/synth/imu_synth.hpp"

namespace heslam::synth {
namespace {

namespace fs = std::filesystem;

// Readable by cv::FileStorage and by standard YAML parsers (PyYAML rejects "%YAML:1.0").
constexpr const char* kYamlHeader = "%YAML 1.0\n---\n";
// ORB-SLAM2's shipped stereo settings ask 1200 ORB features of EuRoC's 752x480 images and 2000 of
// KITTI's 1241x376 ones; wider images than this get the KITTI count (the street preset's
// settings asked 1200 of a KITTI-sized image).
constexpr int kOrbslam2KittiWidthPx = 1000;
constexpr int kOrbslam2FeaturesEuroc = 1200;
constexpr int kOrbslam2FeaturesKitti = 2000;

std::string fmt(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* format, ...) {
  char buf[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buf, sizeof(buf), format, args);
  va_end(args);
  return buf;
}

void make_dirs(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot create directory (" + ec.message() + ")");
}

std::ofstream open_out(const fs::path& file) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file.string() + ": cannot open for writing");
  return out;
}

void write_png(const fs::path& file, const cv::Mat& image) {
  if (!cv::imwrite(file.string(), image)) throw std::runtime_error(file.string() + ": cannot write PNG");
}

std::string matrix_rows(const Pose3& T) {
  std::string s;
  const Eigen::Matrix4d m = T.matrix();
  for (int r = 0; r < 4; ++r) {
    s += r == 0 ? "  data: [" : "         ";
    for (int c = 0; c < 4; ++c) {
      s += fmt("%.12g", m(r, c));
      s += (r == 3 && c == 3) ? "]\n" : (c == 3 ? ",\n" : ", ");
    }
  }
  return s;
}

void write_euroc_sensor_yaml(const fs::path& file, const SequenceRenderer& r, int camera) {
  const CameraSpec& c = r.preset().camera;
  const bool distorted = r.distortion_applied();
  auto out = open_out(file);
  // The EuRoC text behind "%YAML 1.0 / ---": cv::FileStorage needs a %YAML line, and this spelling
  // (unlike OpenCV's own "%YAML:1.0") is also valid YAML for the EuRoC Python tools.
  out << kYamlHeader << "# General sensor definitions.\n"
      << "sensor_type: camera\n"
      << "comment: heslam-synth cam" << camera << " (preset " << r.preset().name << ")\n\n"
      << "# Sensor extrinsics wrt. the body-frame.\n"
      << "T_BS:\n  cols: 4\n  rows: 4\n"
      << matrix_rows(camera == 0 ? r.T_BS_left() : r.T_BS_right()) << "\n"
      << "# Camera specific definitions.\n"
      << "rate_hz: " << fmt("%g", c.rate_hz) << "\n"
      << "resolution: [" << c.width_px << ", " << c.height_px << "]\n"
      << "camera_model: pinhole\n"
      << "intrinsics: [" << fmt("%.9g, %.9g, %.9g, %.9g", c.fx_px, c.fy_px, c.cx_px, c.cy_px) << "] #fu, fv, cu, cv\n"
      << "distortion_model: " << (distorted && c.lens == LensModel::kEquidistant ? "equidistant" : "radial-tangential")
      << "\n";
  if (distorted) {
    // A fisheye's with 17 significant digits: the reader gets the lens the images were rendered with.
    const std::vector<double>& k = c.distortion;
    out << "distortion_coefficients: ["
        << (c.lens == LensModel::kEquidistant ? fmt("%.17g, %.17g, %.17g, %.17g", k[0], k[1], k[2], k[3])
                                              : fmt("%.9g, %.9g, %.9g, %.9g", k[0], k[1], k[2], k[3]))
        << "]\n";
  } else {
    out << "distortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n";
  }
}

// imu0/ as EuRoC has it: data.csv (stamp, w_RS_S [rad/s], a_RS_S [m/s^2]) and sensor.yaml (T_BS =
// identity: the IMU is the body; rate; the noise model). Readings with 17 significant digits, so a
// reader gets the doubles back exactly.
void write_euroc_imu(const fs::path& dir, const SequenceRenderer& r, const SynthImu& imu) {
  make_dirs(dir);
  const RenderOptions& o = r.options();
  {
    auto out = open_out(dir / "sensor.yaml");
    out << kYamlHeader << "# General sensor definitions.\n"
        << "sensor_type: imu\n"
        << "comment: heslam-synth IMU at the body (preset " << r.preset().name << ", seed " << o.seed << ")"
        << (o.imu_noise_free ? ", noise-free readings; the figures below are the model" : "") << "\n\n"
        << "# Sensor extrinsics wrt. the body-frame.\n"
        << "T_BS:\n  cols: 4\n  rows: 4\n"
        << matrix_rows(Pose3::Identity()) << "\n"
        << "rate_hz: " << fmt("%g", o.imu_rate_hz) << "\n\n"
        << "# inertial sensor noise model parameters (static)\n"
        << "gyroscope_noise_density: " << fmt("%.9g", o.imu_noise.gyro_noise_density)
        << "     # [ rad / s / sqrt(Hz) ]   ( gyro \"white noise\" )\n"
        << "gyroscope_random_walk: " << fmt("%.9g", o.imu_noise.gyro_random_walk)
        << "       # [ rad / s^2 / sqrt(Hz) ] ( gyro bias diffusion )\n"
        << "accelerometer_noise_density: " << fmt("%.9g", o.imu_noise.accel_noise_density)
        << "  # [ m / s^2 / sqrt(Hz) ]   ( accel \"white noise\" )\n"
        << "accelerometer_random_walk: " << fmt("%.9g", o.imu_noise.accel_random_walk)
        << "    # [ m / s^3 / sqrt(Hz) ].  ( accel bias diffusion )\n";
  }
  auto csv = open_out(dir / "data.csv");
  csv << "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
         "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
  for (const ImuSample& sample : imu.samples) {
    csv << sample.stamp_ns
        << fmt(",%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", sample.gyro_rad_s.x(), sample.gyro_rad_s.y(),
               sample.gyro_rad_s.z(), sample.accel_m_s2.x(), sample.accel_m_s2.y(), sample.accel_m_s2.z());
  }
}

// ORB-SLAM2 stereo settings: the same file works for stereo_euroc and stereo_kitti. stereo_euroc
// refuses to start unless LEFT/RIGHT .K .D .R .P .width .height are all present, and rectifies every
// image with them, so they are written for every sequence: from cv::stereoRectify when the images
// are distorted, the identity rectification (D = 0, R = I, P = [K | 0] and [K | -fx b]) when they
// are ideal pinhole images. stereo_kitti reads only Camera.*. ORB parameters are ORB-SLAM2's defaults.
void write_orbslam_settings(const fs::path& file, const SequenceRenderer& r) {
  const CameraSpec& c = r.preset().camera;
  auto out = open_out(file);
  cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx_px, 0, c.cx_px, 0, c.fy_px, c.cy_px, 0, 0, 1);
  cv::Mat D = cv::Mat::zeros(1, 5, CV_64F);
  cv::Mat R1 = cv::Mat::eye(3, 3, CV_64F), R2 = R1.clone();
  cv::Mat P1 = (cv::Mat_<double>(3, 4) << c.fx_px, 0, c.cx_px, 0, 0, c.fy_px, c.cy_px, 0, 0, 0, 1, 0);
  cv::Mat P2 = P1.clone();
  P2.at<double>(0, 3) = -c.fx_px * c.baseline_m;
  if (r.distortion_applied()) {
    for (int i = 0; i < 4; ++i) D.at<double>(0, i) = c.distortion[static_cast<std::size_t>(i)];
    // p_right = R p_left + T: the right camera is baseline_m along +x, so T = (-b, 0, 0).
    const cv::Mat R = cv::Mat::eye(3, 3, CV_64F);
    const cv::Mat T = (cv::Mat_<double>(3, 1) << -c.baseline_m, 0, 0);
    cv::Mat Q;
    cv::stereoRectify(K, D, K, D, cv::Size(c.width_px, c.height_px), R, T, R1, R2, P1, P2, Q, cv::CALIB_ZERO_DISPARITY,
                      0);
  }
  const double fx = P1.at<double>(0, 0);
  const double fy = P1.at<double>(1, 1);
  const double cx = P1.at<double>(0, 2);
  const double cy = P1.at<double>(1, 2);
  out << "%YAML:1.0\n\n# ORB-SLAM2 stereo settings for a heslam-synth sequence (preset " << r.preset().name << ").\n"
      << "# stereo_euroc VOC THIS_FILE SEQ/mav0/cam0/data SEQ/mav0/cam1/data SEQ/timestamps.txt\n"
      << "# stereo_kitti VOC THIS_FILE SEQ (KITTI layout)\n"
      << fmt("Camera.fx: %.9g\nCamera.fy: %.9g\nCamera.cx: %.9g\nCamera.cy: %.9g\n\n", fx, fy, cx, cy)
      << "Camera.k1: 0.0\nCamera.k2: 0.0\nCamera.p1: 0.0\nCamera.p2: 0.0\n\n"
      << "Camera.width: " << c.width_px << "\nCamera.height: " << c.height_px << "\n\n"
      << fmt("Camera.fps: %g\n\n# stereo baseline times fx\nCamera.bf: %.9g\n\n", c.rate_hz, fx * c.baseline_m)
      << "# Color order of the images (0: BGR, 1: RGB. It is ignored if images are grayscale)\nCamera.RGB: 1\n\n"
      << "# Close/Far threshold. Baseline times.\nThDepth: 35\n\n";
  auto mat = [&](const char* name, const cv::Mat& m) {
    out << name << ": !!opencv-matrix\n   rows: " << m.rows << "\n   cols: " << m.cols << "\n   dt: d\n   data: [";
    for (int i = 0; i < m.rows * m.cols; ++i)
      out << (i ? ", " : "") << fmt("%.12g", m.at<double>(i / m.cols, i % m.cols));
    out << "]\n";
  };
  out << "LEFT.height: " << c.height_px << "\nLEFT.width: " << c.width_px << "\n";
  mat("LEFT.D", D);
  mat("LEFT.K", K);
  mat("LEFT.R", R1);
  mat("LEFT.P", P1);
  out << "\nRIGHT.height: " << c.height_px << "\nRIGHT.width: " << c.width_px << "\n";
  mat("RIGHT.D", D);
  mat("RIGHT.K", K);
  mat("RIGHT.R", R2);
  mat("RIGHT.P", P2);
  out << "\n";
  const int features = c.width_px >= kOrbslam2KittiWidthPx ? kOrbslam2FeaturesKitti : kOrbslam2FeaturesEuroc;
  out << "ORBextractor.nFeatures: " << features << "\nORBextractor.scaleFactor: 1.2\nORBextractor.nLevels: 8\n"
      << "ORBextractor.iniThFAST: 20\nORBextractor.minThFAST: 7\n\n"
      << "Viewer.KeyFrameSize: 0.05\nViewer.KeyFrameLineWidth: 1\nViewer.GraphLineWidth: 0.9\nViewer.PointSize: 2\n"
      << "Viewer.CameraSize: 0.08\nViewer.CameraLineWidth: 3\nViewer.ViewpointX: 0\nViewer.ViewpointY: -0.7\n"
      << "Viewer.ViewpointZ: -1.8\nViewer.ViewpointF: 500\n";
}

// ORB-SLAM3 stereo settings (File.version "1.0") for a fisheye sequence: ORB-SLAM2's format has no
// fisheye lens, ORB-SLAM3's "KannalaBrandt8" has (its TUM-VI examples): Camera1/2 with k1..k4 and
// Stereo.T_c1_c2 (camera 2 -> camera 1: the right camera baseline_m along +x).
void write_orbslam3_fisheye_settings(const fs::path& file, const SequenceRenderer& r) {
  const CameraSpec& c = r.preset().camera;
  auto out = open_out(file);
  out << "%YAML:1.0\n\n# ORB-SLAM3 stereo fisheye settings for a heslam-synth sequence (preset " << r.preset().name
      << ").\n# stereo_euroc VOC THIS_FILE SEQ/mav0/cam0/data SEQ/mav0/cam1/data SEQ/timestamps.txt\n"
      << "File.version: \"1.0\"\nCamera.type: \"KannalaBrandt8\"\n\n";
  for (const char* camera : {"Camera1", "Camera2"}) {
    out << fmt("%s.fx: %.17g\n%s.fy: %.17g\n%s.cx: %.17g\n%s.cy: %.17g\n", camera, c.fx_px, camera, c.fy_px, camera,
               c.cx_px, camera, c.cy_px)
        << fmt("%s.k1: %.17g\n%s.k2: %.17g\n%s.k3: %.17g\n%s.k4: %.17g\n", camera, c.distortion[0], camera,
               c.distortion[1], camera, c.distortion[2], camera, c.distortion[3])
        << fmt("%s.overlappingBegin: 0\n%s.overlappingEnd: %d\n\n", camera, camera, c.width_px - 1);
  }
  out << "Camera.width: " << c.width_px << "\nCamera.height: " << c.height_px << "\n"
      << fmt("Camera.fps: %g\nCamera.RGB: 1\n\n", c.rate_hz)
      << "Stereo.ThDepth: 35.0\nStereo.T_c1_c2: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d\n"
      << fmt("   data: [1.0, 0.0, 0.0, %.17g, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\n\n",
             c.baseline_m)
      << "ORBextractor.nFeatures: " << kOrbslam2FeaturesEuroc
      << "\nORBextractor.scaleFactor: 1.2\nORBextractor.nLevels: 8\n"
      << "ORBextractor.iniThFAST: 20\nORBextractor.minThFAST: 7\n";
}

void write_metadata(const fs::path& file, const SequenceRenderer& r, OutputFormat format) {
  const Preset& p = r.preset();
  auto out = open_out(file);
  out << kYamlHeader
      << "# heslam-synth sequence metadata: what was rendered and when each photometric event is active.\n"
      << "generator: heslam-synth\n"
      << "preset: " << p.name << "\n"
      << "preset_file: \"" << p.source.string() << "\"\n"
      << "scene: " << to_string(p.scene) << "\n"
      << "seed: " << r.options().seed << "\n"
      << "format: " << (format == OutputFormat::kEuroc ? "euroc" : "kitti") << "\n"
      << "frames: " << r.num_frames() << "\n"
      << "rate_hz: " << fmt("%g", p.camera.rate_hz) << "\n"
      << "first_stamp_ns: \"" << r.stamp_ns(0) << "\"\n"
      << "last_stamp_ns: \"" << r.stamp_ns(r.num_frames() - 1) << "\"\n"
      << "duration_s: " << fmt("%.6f", r.time_s(r.num_frames() - 1)) << "\n"
      << "distortion_applied: " << (r.distortion_applied() ? 1 : 0) << "\n"
      << "# one lap for closed paths (room), the whole path for open ones\n"
      << "path_length_m: " << fmt("%.3f", r.trajectory().length_m()) << "\n"
      << "baseline_m: " << fmt("%.9g", p.camera.baseline_m) << "\n"
      << "events:\n";
  if (p.events.empty() || !r.options().events) out << "  []\n";
  if (!r.options().events) return;
  for (const ExposureEvent& e : p.events) {
    const double period = 1.0 / p.camera.rate_hz;
    const int first = std::max(0, static_cast<int>(std::ceil(e.start_s / period - 1e-9)));
    const int last = static_cast<int>(std::floor(e.end_s / period + 1e-9));
    out << "  - type: " << to_string(e.kind) << "\n"
        << "    start_s: " << fmt("%.6f", e.start_s) << "\n"
        << "    end_s: " << fmt("%.6f", e.end_s) << "\n"
        << "    start_stamp_ns: \"" << kFirstStampNs + std::llround(e.start_s * 1e9) << "\"\n"
        << "    end_stamp_ns: \"" << kFirstStampNs + std::llround(e.end_s * 1e9) << "\"\n"
        << "    first_frame: " << first << "\n"
        << "    last_frame: " << last << "\n"
        << "    in_sequence: " << (first < r.num_frames() ? 1 : 0) << "\n"
        << "    strength: " << fmt("%.6g", e.strength) << "\n"
        << "    ramp_s: " << fmt("%.6g", e.ramp_s) << "\n";
    if (e.kind == EventKind::kStereoGain) {
      out << "    left: " << fmt("%.6g", e.left) << "\n"
          << "    right: " << fmt("%.6g", e.right) << "\n";
    }
  }
}

void write_euroc(SequenceRenderer& r, const fs::path& out_dir, const Progress& progress) {
  const fs::path mav0 = out_dir / "mav0";
  const fs::path cam_dirs[2] = {mav0 / "cam0", mav0 / "cam1"};
  for (const auto& d : cam_dirs) make_dirs(d / "data");
  make_dirs(mav0 / "state_groundtruth_estimate0");
  for (int cam = 0; cam < 2; ++cam) write_euroc_sensor_yaml(cam_dirs[cam] / "sensor.yaml", r, cam);
  {
    auto body = open_out(mav0 / "body.yaml");
    body << kYamlHeader
         << "comment: 'heslam-synth rig body frame: x forward, y left, z up, centred between the cameras.'\n";
  }
  std::ofstream csv[2] = {open_out(cam_dirs[0] / "data.csv"), open_out(cam_dirs[1] / "data.csv")};
  for (auto& c : csv) c << "#timestamp [ns],filename\n";
  auto gt = open_out(mav0 / "state_groundtruth_estimate0" / "data.csv");
  gt << "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
        "v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], "
        "b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]\n";
  auto times = open_out(out_dir / "timestamps.txt");
  SynthImu imu;
  if (r.options().imu) {
    imu = synthesize_imu(r);
    write_euroc_imu(mav0 / "imu0", r, imu);
  }
  for (int i = 0; i < r.num_frames(); ++i) {
    const SynthFrame f = r.render_frame(i);
    const std::string name = std::to_string(f.stamp_ns) + ".png";
    write_png(cam_dirs[0] / "data" / name, f.left);
    write_png(cam_dirs[1] / "data" / name, f.right);
    for (auto& c : csv) c << f.stamp_ns << "," << name << "\n";
    times << f.stamp_ns << "\n";
    const Eigen::Quaterniond q(f.T_wb.linear());
    const Eigen::Vector3d p = f.T_wb.translation();
    const Eigen::Vector3d v = r.trajectory().velocity_w(f.t_s);
    gt << f.stamp_ns
       << fmt(",%.9f,%.9f,%.9f,%.12f,%.12f,%.12f,%.12f,%.9f,%.9f,%.9f", p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z(),
              v.x(), v.y(), v.z());
    if (imu.samples.empty()) {
      gt << ",0,0,0,0,0,0\n";
    } else {  // the true bias at the frame (the reading at or just before its stamp)
      const auto at = std::upper_bound(imu.samples.begin(), imu.samples.end(), f.stamp_ns,
                                       [](std::int64_t stamp, const ImuSample& s) { return stamp < s.stamp_ns; });
      const ImuBias& b =
          imu.biases[static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, at - imu.samples.begin() - 1))];
      gt << fmt(",%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n", b.gyro_rad_s.x(), b.gyro_rad_s.y(), b.gyro_rad_s.z(),
                b.accel_m_s2.x(), b.accel_m_s2.y(), b.accel_m_s2.z());
    }
    if (progress) progress(i + 1, r.num_frames());
  }
}

void write_kitti(SequenceRenderer& r, const fs::path& out_dir, const Progress& progress) {
  if (r.distortion_applied()) {
    throw std::runtime_error("KITTI output holds rectified images: render with apply_distortion = false");
  }
  make_dirs(out_dir / "image_0");
  make_dirs(out_dir / "image_1");
  const CameraSpec& c = r.preset().camera;
  {
    auto calib = open_out(out_dir / "calib.txt");
    const std::string p0 =
        fmt("%.12e 0.000000000000e+00 %.12e 0.000000000000e+00 0.000000000000e+00 %.12e %.12e "
            "0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 1.000000000000e+00 "
            "0.000000000000e+00",
            c.fx_px, c.cx_px, c.fy_px, c.cy_px);
    const std::string p1 =
        fmt("%.12e 0.000000000000e+00 %.12e %.12e 0.000000000000e+00 %.12e %.12e "
            "0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 1.000000000000e+00 "
            "0.000000000000e+00",
            c.fx_px, c.cx_px, -c.fx_px * c.baseline_m, c.fy_px, c.cy_px);
    calib << "P0: " << p0 << "\nP1: " << p1 << "\nP2: " << p0 << "\nP3: " << p1 << "\n"
          << "Tr: 1.000000000000e+00 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 "
             "1.000000000000e+00 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 "
             "1.000000000000e+00 0.000000000000e+00\n";
  }
  auto times = open_out(out_dir / "times.txt");
  auto poses = open_out(out_dir / "poses.txt");
  const Pose3 T_0w = r.T_wc_left(0).inverse();
  for (int i = 0; i < r.num_frames(); ++i) {
    const SynthFrame f = r.render_frame(i);
    const std::string name = fmt("%06d.png", i);
    write_png(out_dir / "image_0" / name, f.left);
    write_png(out_dir / "image_1" / name, f.right);
    times << fmt("%e\n", f.t_s);
    const Eigen::Matrix4d m = (T_0w * f.T_wc_left).matrix();
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 4; ++col) poses << fmt("%e", m(row, col)) << (row == 2 && col == 3 ? "\n" : " ");
    if (progress) progress(i + 1, r.num_frames());
  }
}

}  // namespace

void write_sequence(SequenceRenderer& renderer, OutputFormat format, const fs::path& out_dir,
                    const Progress& progress) {
  if (format == OutputFormat::kKitti && renderer.distortion_applied()) {
    throw std::runtime_error("KITTI output holds rectified images: render with apply_distortion = false");
  }
  make_dirs(out_dir);
  if (format == OutputFormat::kEuroc) {
    write_euroc(renderer, out_dir, progress);
  } else {
    write_kitti(renderer, out_dir, progress);
  }
  write_metadata(out_dir / "synth.yaml", renderer, format);
  if (renderer.distortion_applied() && renderer.preset().camera.lens == LensModel::kEquidistant) {
    write_orbslam3_fisheye_settings(out_dir / "orbslam3_settings.yaml", renderer);
  } else {
    write_orbslam_settings(out_dir / "orbslam2_settings.yaml", renderer);
  }
}

}  // namespace heslam::synth
