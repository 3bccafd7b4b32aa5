#pragma once
// The depth refinement stage ("refine", SOLO reference.md sections 1.1-1.4): upsample the
// estimated maps to the image resolution, complete the depth (every pixel that is not sky gets
// one, depth_completion.h), filter it with the instance-reference cross-bilateral filter, find the uncertain regions, and optimise the depth against the
// predicted normals. Each step can be switched off and is skipped, with the reason in its
// report, when its input is missing. docs/depth-refinement.md has the measurements.

#include "solo/geometry/adam_depth_optimizer.h"
#include "solo/geometry/depth_completion.h"
#include "solo/geometry/instance_bilateral_filter.h"
#include "solo/geometry/normal_guided_optimization.h"
#include "solo/core/report.h"
#include "solo/core/scene.h"
#include "solo/geometry/uncertain_regions.h"
#include "solo/geometry/upsample_maps.h"

#include <opencv2/core.hpp>

#include <vector>

namespace solo {

enum class DepthOptimizer { Ceres, Adam };

/// The paper's optimiser on the paper's objective (NormalGuidedObjectiveOptions::paper()).
inline AdamOptions paperAdamOptions() {
  AdamOptions a;
  a.objective = NormalGuidedObjectiveOptions::paper();
  return a;
}

struct DepthRefinementOptions {
  UpsampleOptions upsampling;  ///< .enabled = false: nearest-neighbour resizing only
  bool complete = true;        ///< a depth for every non-sky pixel (depth_completion.h)
  DepthCompletionOptions completion;
  bool filter = true;
  InstanceBilateralFilterOptions filtering;
  bool uncertain_regions = true;
  UncertainRegionOptions uncertainty;
  bool optimize = true;
  /// Without normals in the scene: the optimisation uses the normals of the filtered depth.
  bool normals_from_depth = true;
  DepthOptimizer optimizer = DepthOptimizer::Ceres;
  /// The optimisation runs on the filtered depth downsampled by this factor (downsample_depth.h;
  /// normals, instances nearest, the uncertain mask where any of a block's pixels is), and its
  /// change, as a ratio to the downsampled filtered depth, is upsampled bilinearly onto the
  /// full-size filtered depth. 1: at the full size. 1 to 8. `solo night` sets the mesh's factor:
  /// the mesh is made at that size.
  int optimization_downsample = 1;
  NormalGuidedOptimizationOptions optimization;  ///< Ceres
  AdamOptions adam = paperAdamOptions();         ///< the paper's optimiser and objective
};

/// Everything at the image resolution.
struct DepthRefinementResult {
  cv::Mat depth_m;           ///< CV_32F metres, refined; 0 = invalid (sky, no estimate)
  cv::Mat uncertain;         ///< CV_8U, 255 = uncertain (all 0 when the step is off or skipped)
  cv::Mat normals;           ///< CV_32FC3 upsampled predicted normals (empty when the scene has none)
  cv::Mat depth_normals;     ///< CV_32FC3 normals of the refined depth (normalsFromDepth)
  cv::Mat upsampled_depth_m; ///< the estimated depth after step 1
  cv::Mat completed_depth_m; ///< after completion (= upsampled when it is off)
  cv::Mat filled;            ///< CV_8U, 255 where completion gave the pixel its depth
  bool normals_from_depth = false;  ///< `normals` are the filtered depth's (the scene had none)
  cv::Mat filtered_depth_m;  ///< d~ after step 2 (= upsampled when the filter is off)
  UpsampledMaps maps;        ///< albedo, roughness, instances, labels at the image resolution
  /// One report per step ("upsample", "complete", "filter", "uncertain", "optimize"), skipped steps with
  /// their reason, then the whole stage ("refine": total time and the key figures).
  std::vector<StageReport> steps;
  StageReport report;
};

/// Runs the stage on a loaded scene (its camera is already at the image resolution).
DepthRefinementResult refineDepth(const Scene& scene, const DepthRefinementOptions& options = {});

}  // namespace solo
