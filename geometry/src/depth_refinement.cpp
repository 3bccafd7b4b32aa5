#include "solo/geometry/depth_refinement.h"

#include "solo/geometry/depth_completion.h"
#include "solo/geometry/downsample_depth.h"
#include "solo/geometry/normals_from_depth.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace solo {
namespace {

StageReport skippedStep(const std::string& name, const std::string& reason) {
  StageReport r;
  r.name = name;
  r.skipped = true;
  r.skip_reason = reason;
  return r;
}

NormalGuidedOptimizationResult optimizeAtSize(const cv::Mat& filtered_depth_m, const cv::Mat& normals,
                                              const cv::Mat& uncertain, const cv::Mat& instances,
                                              const PinholeCamera& camera, const DepthRefinementOptions& options) {
  return options.optimizer == DepthOptimizer::Ceres
             ? optimizeDepthWithNormals(filtered_depth_m, normals, uncertain, instances, camera, options.optimization)
             : optimizeDepthWithAdam(filtered_depth_m, normals, uncertain, instances, camera, options.adam);
}

cv::Mat resizedNearest(const cv::Mat& m, cv::Size size) {
  if (m.empty()) return m;
  cv::Mat out;
  cv::resize(m, out, size, 0, 0, cv::INTER_NEAREST);
  return out;
}

// The optimisation at the filtered depth's size divided by options.optimization_downsample
// (DepthRefinementOptions): its multiplicative change, upsampled, on the full-size depth.
NormalGuidedOptimizationResult optimizeDownsampled(const DepthRefinementResult& out, const PinholeCamera& camera,
                                                   const DepthRefinementOptions& options) {
  const int factor = options.optimization_downsample;
  const cv::Mat low_depth_m = downsampleDepth(out.filtered_depth_m, factor);
  const cv::Size low_size = low_depth_m.size();
  cv::Mat low_uncertain;  // uncertain where any pixel of the block is
  cv::resize(out.uncertain, low_uncertain, low_size, 0, 0, cv::INTER_AREA);
  low_uncertain = low_uncertain > 0;
  NormalGuidedOptimizationResult low =
      optimizeAtSize(low_depth_m, resizedNearest(out.normals, low_size), low_uncertain,
                     resizedNearest(out.maps.instances, low_size), camera.scaledTo(low_size.width, low_size.height),
                     options);
  cv::Mat ratio(low_size, CV_32F, cv::Scalar(1));
  for (int y = 0; y < low_size.height; ++y)
    for (int x = 0; x < low_size.width; ++x) {
      const float before = low_depth_m.at<float>(y, x), after = low.depth_m.at<float>(y, x);
      if (before > 0.f && after > 0.f && std::isfinite(before) && std::isfinite(after))
        ratio.at<float>(y, x) = after / before;
    }
  cv::Mat full_ratio;
  cv::resize(ratio, full_ratio, out.filtered_depth_m.size(), 0, 0, cv::INTER_LINEAR);
  NormalGuidedOptimizationResult result;
  result.depth_m = out.filtered_depth_m.mul(full_ratio);
  result.report = std::move(low.report);
  char note[200];
  std::snprintf(note, sizeof note,
                "optimised at %dx%d (the depth downsampled %dx), its change upsampled onto the %dx%d filtered depth",
                low_size.width, low_size.height, factor, out.filtered_depth_m.cols, out.filtered_depth_m.rows);
  result.report.notes.push_back(note);
  result.report.add("optimization_downsample", factor);
  return result;
}

}  // namespace

DepthRefinementResult refineDepth(const Scene& scene, const DepthRefinementOptions& options) {
  if (options.optimization_downsample < 1 || options.optimization_downsample > 8)
    throw std::invalid_argument("refineDepth: optimization_downsample must be 1 to 8");
  Stopwatch clock;
  DepthRefinementResult out;
  StageReport& stage = out.report;
  stage.name = "refine";

  // 1. Upsampling (nearest-neighbour resizing when switched off).
  out.maps = upsampleMaps(scene, options.upsampling);
  out.steps.push_back(out.maps.report);
  if (!options.upsampling.enabled) out.steps.back().notes.push_back("upsampling switched off");
  out.upsampled_depth_m = out.maps.depth_m;
  out.normals = out.maps.normals;

  // 1b. Completion: a depth for every pixel that is not sky.
  if (!options.complete) {
    out.completed_depth_m = out.upsampled_depth_m;
    out.filled = cv::Mat(out.upsampled_depth_m.size(), CV_8U, cv::Scalar(0));
    out.steps.push_back(skippedStep("complete", "switched off"));
  } else {
    DepthCompletionResult completed = completeDepth(out.upsampled_depth_m, scene.image, out.maps.labels,
                                                    out.maps.instances, options.completion);
    out.completed_depth_m = completed.depth_m;
    out.filled = completed.filled;
    out.steps.push_back(completed.report);
  }
  const cv::Mat& depth = out.completed_depth_m;

  // 2. Instance-reference cross-bilateral filter.
  if (!options.filter) {
    out.filtered_depth_m = depth.clone();
    out.steps.push_back(skippedStep("filter", "switched off"));
  } else {
    InstanceBilateralFilterResult filtered = instanceBilateralFilter(depth, out.maps.instances, options.filtering);
    out.filtered_depth_m = filtered.depth_m;
    out.steps.push_back(filtered.report);
  }

  // 2b. Normals of the filtered depth when the scene has none, for the optimisation and shading.
  if (out.normals.empty() && options.normals_from_depth) {
    out.normals = normalsFromDepth(out.filtered_depth_m, scene.camera);
    out.normals_from_depth = true;
    out.steps.back().notes.push_back(
        "no normals given: the optimisation uses the normals of the filtered depth (normalsFromDepth after the "
        "instance filter's Gaussian)");
  }

  // 3. Uncertain regions.
  out.uncertain = cv::Mat(depth.size(), CV_8U, cv::Scalar(0));
  if (!options.uncertain_regions) {
    out.steps.push_back(skippedStep("uncertain", "switched off"));
  } else if (out.maps.labels.empty()) {
    out.steps.push_back(skippedStep("uncertain", "no semantic labels (labels or instances): no uncertain regions"));
  } else {
    UncertainRegionResult uncertain = findUncertainRegions(out.filtered_depth_m, out.maps.labels, options.uncertainty);
    out.uncertain = uncertain.mask;
    out.steps.push_back(uncertain.report);
  }

  // 4. Normal-guided optimisation.
  if (!options.optimize) {
    out.depth_m = out.filtered_depth_m.clone();
    out.steps.push_back(skippedStep("optimize", "switched off"));
  } else if (out.normals.empty()) {
    out.depth_m = out.filtered_depth_m.clone();
    out.steps.push_back(skippedStep("optimize", "no normals: no normal-guided optimisation"));
  } else {
    NormalGuidedOptimizationResult optimized =
        options.optimization_downsample > 1
            ? optimizeDownsampled(out, scene.camera, options)
            : optimizeAtSize(out.filtered_depth_m, out.normals, out.uncertain, out.maps.instances, scene.camera,
                             options);
    out.depth_m = optimized.depth_m;
    out.steps.push_back(optimized.report);
  }
  out.depth_normals = normalsFromDepth(out.depth_m, scene.camera);

  for (const StageReport& step : out.steps) {
    stage.add(step.name + "_seconds", step.seconds, "s");
    if (step.skipped) stage.notes.push_back(step.name + " skipped: " + step.skip_reason);
    for (const std::string& note : step.notes) stage.notes.push_back(step.name + ": " + note);
  }
  stage.add("valid_pixels", static_cast<std::int64_t>(cv::countNonZero(out.depth_m > 0)));
  stage.add("uncertain_pixels", static_cast<std::int64_t>(cv::countNonZero(out.uncertain)));
  if (const MetricValue* v = out.steps.back().find("objective_final")) stage.add("objective_final", *v);
  stage.seconds = clock.seconds();
  return out;
}

}  // namespace solo
