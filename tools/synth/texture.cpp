// Mip-mapped textures: photographs from opencv-doc and seeded procedural materials.
#include "tools/synth/texture.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace heslam::synth {
namespace {

// Coarsest mip level kept: below 4x4 texels the average is all that is left.
constexpr int kMinLevelSize = 4;

bool is_power_of_two(int n) { return n > 0 && (n & (n - 1)) == 0; }

// Smooth tileable noise: white noise blurred with wrap-around borders, scaled to unit std.
cv::Mat tileable_noise(cv::RNG& rng, int size_px, double sigma_px) {
  cv::Mat white(size_px, size_px, CV_32F);
  rng.fill(white, cv::RNG::NORMAL, 0.0, 1.0);
  const int pad = static_cast<int>(std::ceil(3.0 * sigma_px)) + 1;
  cv::Mat padded;
  cv::copyMakeBorder(white, padded, pad, pad, pad, pad, cv::BORDER_WRAP);
  cv::GaussianBlur(padded, padded, cv::Size(0, 0), sigma_px, sigma_px, cv::BORDER_REFLECT);
  cv::Mat out = padded(cv::Rect(pad, pad, size_px, size_px)).clone();
  cv::Scalar mean, stddev;
  cv::meanStdDev(out, mean, stddev);
  out = (out - mean[0]) / std::max(stddev[0], 1e-9);
  return out;
}

// Fractal noise: octaves of tileable noise with halving amplitude.
cv::Mat fractal_noise(cv::RNG& rng, int size_px, double coarsest_sigma_px, int octaves) {
  cv::Mat sum = cv::Mat::zeros(size_px, size_px, CV_32F);
  double amplitude = 1.0;
  double sigma = coarsest_sigma_px;
  for (int o = 0; o < octaves; ++o) {
    sum += amplitude * tileable_noise(rng, size_px, std::max(sigma, 0.7));
    amplitude *= 0.55;
    sigma *= 0.5;
  }
  return sum;
}

cv::Mat clamp01(const cv::Mat& m) {
  cv::Mat out;
  cv::min(cv::max(m, 0.0), 1.0, out);
  return out;
}

}  // namespace

MipTexture::MipTexture(const cv::Mat& image, int size_px) {
  if (!is_power_of_two(size_px)) {
    throw std::runtime_error("texture size " + std::to_string(size_px) + " is not a power of two");
  }
  cv::Mat grey;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else {
    grey = image;
  }
  cv::Mat level0;
  grey.convertTo(level0, CV_32F, grey.depth() == CV_8U ? 1.0 / 255.0 : 1.0);
  if (level0.cols != size_px || level0.rows != size_px) {
    const int interp = level0.cols > size_px ? cv::INTER_AREA : cv::INTER_CUBIC;
    cv::resize(level0, level0, cv::Size(size_px, size_px), 0, 0, interp);
  }
  levels_.push_back(clamp01(level0));
  while (levels_.back().cols > kMinLevelSize) {
    // 2x2 box average keeps level boundaries on multiples of 2^level, so marker corners stay exact.
    const cv::Mat& fine = levels_.back();
    cv::Mat coarse;
    cv::resize(fine, coarse, cv::Size(fine.cols / 2, fine.rows / 2), 0, 0, cv::INTER_AREA);
    levels_.push_back(coarse);
  }
}

MipTexture load_photo_texture(const std::filesystem::path& photo_dir, const std::string& file_name, int size_px) {
  const auto path = photo_dir / file_name;
  const cv::Mat image = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
  if (image.empty()) {
    throw std::runtime_error("texture photograph " + path.string() +
                             " cannot be read (install the Debian package opencv-doc)");
  }
  return MipTexture(image, size_px);
}

MipTexture make_procedural_texture(ProceduralKind kind, std::uint64_t seed, int size_px) {
  cv::RNG rng(seed * 0x9E3779B97F4A7C15ull + static_cast<std::uint64_t>(kind) + 1);
  cv::Mat tex;
  switch (kind) {
    case ProceduralKind::kConcrete: {
      // Coarse stains plus fine grain: concrete has texture at every scale a camera resolves.
      tex = 0.55 + 0.06 * fractal_noise(rng, size_px, size_px / 16.0, 3) + 0.05 * tileable_noise(rng, size_px, 1.5);
      cv::Mat speckle(size_px, size_px, CV_32F);
      rng.fill(speckle, cv::RNG::NORMAL, 0.0, 0.04);
      tex += speckle;
      break;
    }
    case ProceduralKind::kPlaster: tex = 0.75 + 0.04 * fractal_noise(rng, size_px, size_px / 8.0, 4); break;
    case ProceduralKind::kAsphalt: {
      tex = 0.32 + 0.05 * fractal_noise(rng, size_px, size_px / 32.0, 4);
      cv::Mat grit(size_px, size_px, CV_32F);
      rng.fill(grit, cv::RNG::NORMAL, 0.0, 0.06);
      tex += grit;
      break;
    }
    case ProceduralKind::kTiles:
    case ProceduralKind::kBricks: {
      const bool bricks = kind == ProceduralKind::kBricks;
      const int cell_w = size_px / (bricks ? 4 : 8);
      const int cell_h = size_px / 8;
      const int grout = std::max(2, size_px / 128);
      tex = cv::Mat(size_px, size_px, CV_32F);
      const cv::Mat noise = fractal_noise(rng, size_px, size_px / 32.0, 4);
      std::vector<float> cell_level(static_cast<std::size_t>(64));
      for (auto& v : cell_level) v = static_cast<float>(rng.uniform(bricks ? 0.35 : 0.6, bricks ? 0.6 : 0.8));
      for (int r = 0; r < size_px; ++r) {
        const int row_cell = r / cell_h;
        const int offset = (bricks && (row_cell % 2 == 1)) ? cell_w / 2 : 0;
        for (int c = 0; c < size_px; ++c) {
          const int cc = (c + offset) % size_px;
          const bool in_grout = (r % cell_h) < grout || (cc % cell_w) < grout;
          const int id = (row_cell % 8) * 8 + (cc / cell_w) % 8;
          const float base = in_grout ? (bricks ? 0.75f : 0.3f) : cell_level[static_cast<std::size_t>(id)];
          tex.at<float>(r, c) = base + 0.04f * noise.at<float>(r, c);
        }
      }
      break;
    }
    case ProceduralKind::kChecker: {
      tex = cv::Mat(size_px, size_px, CV_32F);
      const int cell = size_px / 8;
      for (int r = 0; r < size_px; ++r)
        for (int c = 0; c < size_px; ++c) tex.at<float>(r, c) = ((r / cell + c / cell) % 2) ? 0.85f : 0.15f;
      break;
    }
  }
  return MipTexture(clamp01(tex), size_px);
}

MipTexture make_checker_marker(const CheckerLayout& layout) {
  const int size = layout.size_px();
  cv::Mat tex(size, size, CV_32F, cv::Scalar(0.9));
  for (int r = 0; r < layout.squares; ++r) {
    for (int c = 0; c < layout.squares; ++c) {
      if ((r + c) % 2 == 0) {
        const cv::Rect cell(layout.border_texels + c * layout.cell_texels,
                            layout.border_texels + r * layout.cell_texels, layout.cell_texels, layout.cell_texels);
        tex(cell).setTo(0.08);
      }
    }
  }
  return MipTexture(tex, size);
}

}  // namespace heslam::synth
