#pragma once
// Step 2 of depth refinement: the instance-reference cross-bilateral depth filter (SOLO,
// reference.md section 1.2). For every valid pixel p:
//   d~(p) = sum_q G(|q - p|) [h(q) == h(p)] d(q) / sum_q G(|q - p|) [h(q) == h(p)]
// over valid q (depth > 0) in a (2 * ceil(3 sigma) + 1)^2 window, G a Gaussian of sigma_s
// pixels and h the instance label. No colour term: colour edges are not depth edges.

#include "solo/core/report.h"

#include <opencv2/core.hpp>

namespace solo {

struct InstanceBilateralFilterOptions {
  double sigma_spatial_px = 5;  ///< sigma_s of the spatial Gaussian, pixels (reference: 5)
  double window_sigmas = 3;     ///< the window reaches this many sigmas from its centre
};

struct InstanceBilateralFilterResult {
  cv::Mat depth_m;     ///< CV_32F metres, filtered; invalid input pixels stay 0
  StageReport report;  ///< "filter": labels used, window, mean absolute change
};

/// depth_m: CV_32F metres, 0 = invalid. instances: CV_32S of the same size, or empty, in
/// which case every pixel has the same label (a plain Gaussian over valid pixels) and the
/// report says so. Exact (no grid approximation): one separable Gaussian per label over the
/// label's bounding box, so the cost grows with the summed box areas, not with sigma^2.
InstanceBilateralFilterResult instanceBilateralFilter(const cv::Mat& depth_m, const cv::Mat& instances,
                                                      const InstanceBilateralFilterOptions& options = {});

}  // namespace solo
