#pragma once
// Depth accuracy metrics of the monocular-depth literature (Eigen et al. 2014; the
// Monodepth2 / BTS evaluation scripts): AbsRel, SqRel, RMSE, RMSElog and the delta
// thresholds, over the pixels where both maps are valid. Definitions: docs/evaluation.md.

#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>

namespace solo {

/// The maps to compare and the files they came from (the files are only named in errors).
struct DepthEvaluationInput {
  cv::Mat prediction_m;    ///< single channel CV_32F or CV_64F, metres
  cv::Mat ground_truth_m;  ///< same size and type family, metres
  cv::Mat mask;            ///< empty (all pixels) or single channel, same size: non-zero = evaluate
  std::filesystem::path prediction_file = "prediction";
  std::filesystem::path ground_truth_file = "ground truth";
  std::filesystem::path mask_file = "mask";
};

struct DepthMetricsOptions {
  /// Ground-truth range: a pixel is evaluated only if min_depth_m < gt < max_depth_m
  /// (strict, as the Monodepth2 and BTS scripts). Unset = no bound on that side.
  std::optional<double> min_depth_m, max_depth_m;
  /// Multiply the prediction by median(gt) / median(pred) over the valid pixels first.
  bool median_scaling = false;
  /// After scaling, clamp the prediction into [min_depth_m, max_depth_m] (the bounds that are
  /// set), as the Monodepth2 and BTS scripts do. Does not change which pixels are valid.
  bool clamp_prediction = false;
};

struct DepthMetrics {
  // Pixel accounting: every pixel is counted once, in the first reason that excludes it.
  std::int64_t pixels = 0;                ///< width * height
  std::int64_t masked_out = 0;            ///< mask given and zero there
  std::int64_t ground_truth_invalid = 0;  ///< gt zero, negative, NaN or inf
  std::int64_t outside_range = 0;         ///< gt outside (min_depth_m, max_depth_m)
  std::int64_t prediction_invalid = 0;    ///< prediction zero, negative, NaN or inf
  std::int64_t valid_pixels = 0;          ///< the pixels every metric is averaged over

  double scale = 1;     ///< factor applied to the prediction (median scaling), else 1
  double abs_rel = 0;   ///< mean(|g - p| / g), unitless
  double sq_rel_m = 0;  ///< mean((g - p)^2 / g), metres
  double rmse_m = 0;    ///< sqrt(mean((g - p)^2)), metres
  double rmse_log = 0;  ///< sqrt(mean((ln g - ln p)^2)), unitless
  double delta1 = 0;    ///< fraction (0..1) with max(g/p, p/g) < 1.25
  double delta2 = 0;    ///< ... < 1.25^2
  double delta3 = 0;    ///< ... < 1.25^3
};

/// Compares a predicted depth map with ground truth, in double precision. A pixel is valid
/// when it is inside the mask, gt and prediction are both finite and > 0, and gt is inside
/// the range. Throws InputError naming the files for a size or channel mismatch, an
/// unsupported pixel type, an inconsistent range, or no valid pixel at all (never NaN).
DepthMetrics evaluateDepth(const DepthEvaluationInput& input, const DepthMetricsOptions& options = {});

}  // namespace solo
