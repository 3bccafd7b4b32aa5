#pragma once
// Step 3 of depth refinement: uncertain regions U (SOLO, reference.md section 1.3). A k x k
// window is uncertain when it overlaps at least two semantic segments AND the variance of
// the valid depths in it exceeds t AND its largest depth is not beyond r (the scene's
// mid-range, (max + min) / 2 of the valid depth). Every pixel of an uncertain window is
// uncertain. The normal-guided optimisation drops its tangent term there.

#include "solo/core/report.h"

#include <opencv2/core.hpp>

namespace solo {

struct UncertainRegionOptions {
  int window_px = 10;                 ///< k, pixels (reference: 10)
  double variance_threshold_m2 = 0.01;  ///< t, square metres (reference: 0.01)
  /// r, metres: windows whose largest depth exceeds it are ignored. <= 0 (default): the
  /// scene's mid-range (max + min) / 2 of the valid depth.
  double max_depth_m = 0;
};

struct UncertainRegionResult {
  cv::Mat mask;        ///< CV_8U, 255 = uncertain, same size as the depth
  StageReport report;  ///< "uncertain": count and share of uncertain pixels, r used
};

/// depth_m: CV_32F metres (0 = invalid; invalid pixels add nothing to the variance),
/// labels: CV_32S Cityscapes labelIds of the same size. Windows are all k x k positions
/// inside the image; an image narrower or lower than k uses windows of its full width or
/// height. The variance needs at least two valid depths in the window.
UncertainRegionResult findUncertainRegions(const cv::Mat& depth_m, const cv::Mat& labels,
                                           const UncertainRegionOptions& options = {});

}  // namespace solo
