#pragma once
// Step 4 of depth refinement: SOLO's normal-guided depth optimisation solved with Ceres.
// Minimises NormalGuidedObjective (normal_guided_objective.h) from z = d~.
//
// Layouts (docs/depth-refinement.md has the measurements behind the default):
//  - WholeImageLbfgs (default): one ceres::GradientProblem whose FirstOrderFunction is the
//    whole image with its analytic gradient (two parallel passes over the pixels), solved by
//    Ceres' L-BFGS line search. Unknowns are Jacobi-scaled (z = z0 + s w, s = 1 / sqrt of the
//    Gauss-Newton diagonal), which equalises the 1 / z^2 stiffness of near and far pixels.
//    Optionally the start comes from the same objective solved on a pyramid of half
//    resolutions (coarse-to-fine: the coarse corrections z - d~ are upsampled and added to d~),
//    used only when it is better than d~ itself. Ceres' line search only accepts decreasing
//    steps, and a result worse than d~ is replaced by d~: never worse than d~ on the objective.
//  - PerPixelResidualBlocks: one ceres::Problem with a parameter block per pixel and an
//    analytic residual block per pixel (2 tangent residuals, 1 data residual), solved by
//    Levenberg-Marquardt with CGNR + Jacobi. Kept as the reference layout for comparison.

#include "solo/core/camera.h"
#include "solo/geometry/normal_guided_objective.h"
#include "solo/core/report.h"

#include <opencv2/core.hpp>

#include <functional>
#include <string>
#include <vector>

namespace solo {

enum class DepthSolverLayout { WholeImageLbfgs, PerPixelResidualBlocks };

struct NormalGuidedOptimizationOptions {
  NormalGuidedObjectiveOptions objective;
  /// Differences do not pair pixels of two instances (false: the paper's stencil everywhere,
  /// which lets unmasked depth edges dominate the objective; docs/depth-refinement.md).
  bool stencil_within_instances = true;
  DepthSolverLayout layout = DepthSolverLayout::WholeImageLbfgs;
  /// Solver iterations at full resolution. 10: with the default objective about 3/4 of the
  /// normal improvement of 30 iterations, at a third of the time (docs/depth-refinement.md).
  int max_iterations = 10;
  /// Half-resolution levels solved first (L-BFGS layout). 0: measured not to help, their start
  /// was worse than d~ on the full-resolution objective.
  int coarse_levels = 0;
  int coarse_max_iterations = 150; ///< per coarse level
  int lbfgs_rank = 6;              ///< L-BFGS memory (each pair costs 2 vectors of m doubles)
  bool jacobi_scaling = true;      ///< L-BFGS in Jacobi-scaled unknowns
  double function_tolerance = 1e-9;  ///< stop when the relative decrease of L is below this
  int threads = 2;                   ///< Ceres threads (per-pixel layout)
};

/// One solver iteration: level 0 is the full resolution, level k is 2^-k of it (its value is
/// that level's objective). seconds: time since the optimisation started, observers excluded.
struct OptimizationIteration {
  int level = 0;
  int iteration = 0;
  double seconds = 0;
  ObjectiveValue value;
};

/// Called at every full-resolution iteration (the start included) with the current depth
/// (CV_32F metres); its time is not counted in `seconds`.
using OptimizationObserver = std::function<void(const OptimizationIteration&, const cv::Mat& depth_m)>;

struct NormalGuidedOptimizationResult {
  cv::Mat depth_m;                    ///< CV_32F metres, 0 where d~ was invalid
  ObjectiveValue initial, final;      ///< full-resolution objective at d~ and at the result
  std::vector<OptimizationIteration> trace;
  std::string termination;            ///< Ceres' message of the full-resolution solve
  StageReport report;                 ///< "optimize"
};

/// filtered_depth_m: d~ (CV_32F metres, 0 = invalid); normals: CV_32FC3 predicted normals at
/// the same resolution; uncertain: CV_8U mask (non-zero = U = 1) or empty; instances: CV_32S
/// labels or empty, used when options.stencil_within_instances (see NormalGuidedObjective);
/// camera at this resolution. Deterministic for the same input and thread count.
NormalGuidedOptimizationResult optimizeDepthWithNormals(const cv::Mat& filtered_depth_m, const cv::Mat& normals,
                                                        const cv::Mat& uncertain, const cv::Mat& instances,
                                                        const PinholeCamera& camera,
                                                        const NormalGuidedOptimizationOptions& options = {},
                                                        const OptimizationObserver& observer = {});

}  // namespace solo
