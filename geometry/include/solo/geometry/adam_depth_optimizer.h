#pragma once
// The paper's own optimiser for the normal-guided objective, kept as the baseline: Adam
// (Kingma & Ba 2015) on the depths themselves, learning rate 2e-4, 1000 iterations, z
// initialised with d~ (reference.md section 1.4). Same objective as the Ceres solver
// (normal_guided_objective.h), so values compare directly.

#include "solo/core/camera.h"
#include "solo/geometry/normal_guided_objective.h"
#include "solo/geometry/normal_guided_optimization.h"
#include "solo/core/report.h"

#include <opencv2/core.hpp>

namespace solo {

struct AdamOptions {
  NormalGuidedObjectiveOptions objective;
  bool stencil_within_instances = true;  ///< as NormalGuidedOptimizationOptions
  double learning_rate_m = 2e-4;  ///< step size, metres per iteration (reference: 2e-4)
  int iterations = 1000;          ///< (reference: 1000)
  double beta1 = 0.9, beta2 = 0.999, epsilon = 1e-8;  ///< Adam's moment decays and guard
};

/// Runs Adam from d~. The returned depth is the iterate with the lowest objective seen (the
/// last one whenever the objective decreases monotonically), so it is never worse than d~.
/// The observer sees every iteration (0 = the start); its time is excluded from `seconds`.
/// A step that would make a depth non-positive halves that depth instead (the objective is
/// undefined at z <= 0).
NormalGuidedOptimizationResult optimizeDepthWithAdam(const cv::Mat& filtered_depth_m, const cv::Mat& normals,
                                                     const cv::Mat& uncertain, const cv::Mat& instances,
                                                     const PinholeCamera& camera,
                                                     const AdamOptions& options = {},
                                                     const OptimizationObserver& observer = {});

}  // namespace solo
