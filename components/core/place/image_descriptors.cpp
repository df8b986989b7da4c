// One image through the frontend's HE and ORB.
#include "components/core/place/image_descriptors.hpp"

#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace heslam {

ImageDescriptorExtractor::ImageDescriptorExtractor(const HistogramEqualizerOptions& he, const OrbOptions& orb)
    : equalizer_(he), extractor_(orb) {}

std::vector<Descriptor> ImageDescriptorExtractor::extract(const cv::Mat& image) {
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3)) {
    throw std::invalid_argument("ImageDescriptorExtractor: expected an 8-bit grey or BGR image");
  }
  if (image.channels() == 3)
    cv::cvtColor(image, grey_, cv::COLOR_BGR2GRAY);
  else
    grey_ = image;
  // The equalizer maps a stereo pair by its joint histogram; the image paired with itself is the
  // image's own histogram.
  equalizer_.equalize(grey_, grey_, equalized_, unused_);
  extractor_.extract(equalized_, features_);
  return features_.descriptors;
}

}  // namespace heslam
