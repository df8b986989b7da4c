// Do keypoints move between consecutive frames as the camera did? For each stereo keypoint of frame
// k, the ground truth's relative pose (k -> k+1) and the keypoint's depth predict where it lands in
// frame k+1; the keypoint found there (same octave, best Hamming distance within a window) gives the
// measured displacement. The slope of measured on predicted displacement is 1 for keypoints fixed in
// the scene, below 1 for keypoints that partly stay with the image (a clip edge is an isophote: where
// the brightness crosses the clip level, which need not stay on one scene point). The measurement has
// its own small deficit (0.995 on MH01 exposed equally): compare classes and runs, not against 1.
// Printed by class: near a clip edge or not (StereoFeatures::near_clip), depth below or above 3 m.
#pragma once

#include "components/core/feature/stereo_feature_pipeline.hpp"
#include "tools/bench/frontend_offline/euroc_sequence.hpp"
#include "tools/photometric/photometric_variant.hpp"

namespace heslam::bench {

struct FeatureMotionOptions {
  StereoFeaturePipelineOptions pipeline;
  // Depths from a ZNCC match in the unaltered pair at the same left pixel (zncc_reference.hpp)
  // instead of the run's own stereo: takes the stereo noise out of the prediction, whose regression
  // dilution otherwise lowers every slope.
  bool reference_depth = false;
};

// Needs the ground truth (mav0/state_groundtruth_estimate0/data.csv, one row per frame stamp).
void print_feature_motion(const EurocSequence& sequence, const photometric::StereoGain& gain,
                          const FeatureMotionOptions& options);

}  // namespace heslam::bench
