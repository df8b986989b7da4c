// The viewer's colours (BGR), one place for the top view, the 3D view and the docs' legend.
#pragma once

#include <opencv2/core.hpp>

#include "tools/viewer/scene.hpp"

namespace heslam::viewer::colours {

inline const cv::Scalar kBackground(255, 255, 255);
inline const cv::Scalar kMapPoint(0, 0, 0);
inline const cv::Scalar kRecentPoint(0, 0, 230);
inline const cv::Scalar kLoopMergedPoint(220, 0, 220);
inline const cv::Scalar kCulledPoint(190, 190, 190);
// Pure blue is used by keyframe frustums only, so a picture can be checked for them.
inline const cv::Scalar kKeyframe(255, 0, 0);
inline const cv::Scalar kCurrentCamera(0, 190, 0);
inline const cv::Scalar kCovisibility(120, 220, 120);
inline const cv::Scalar kSpanningTree(0, 140, 255);
inline const cv::Scalar kTrajectory(140, 90, 40);
inline const cv::Scalar kGroundTruth(150, 170, 255);  // light orange-pink, under the estimate
inline const cv::Scalar kMapMatch(0, 220, 0);
inline const cv::Scalar kStereoOnly(255, 120, 0);
inline const cv::Scalar kLoopFlash(0, 230, 255);
inline const cv::Scalar kText(30, 30, 30);
// The top view's grid, scale bar and axis arrows: colours nothing else uses, so a picture can be
// checked for them.
inline const cv::Scalar kGrid(228, 228, 228);
inline const cv::Scalar kScaleBar(0, 0, 110);  // dark red: no anti-aliased grey text or line blends into it
inline const cv::Scalar kAxisX(40, 40, 200);
inline const cv::Scalar kAxisZ(40, 150, 40);
// heslam-occupancy's grid under the top view: occupied cells dark slate, free cells pale green
// (colours nothing else uses, so a picture can be checked for them); unknown cells are not drawn.
inline const cv::Scalar kOccupiedCell(90, 70, 60);
inline const cv::Scalar kFreeCell(215, 240, 215);

inline cv::Scalar of(PointCategory category) {
  switch (category) {
    case PointCategory::kRecent: return kRecentPoint;
    case PointCategory::kLoopMerged: return kLoopMergedPoint;
    case PointCategory::kCulled: return kCulledPoint;
    case PointCategory::kMap: break;
  }
  return kMapPoint;
}

}  // namespace heslam::viewer::colours
