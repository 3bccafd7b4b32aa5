#pragma once
// Depth accuracy metrics of the monocular-depth literature (Eigen et al. 2014; the
// Monodepth2 / BTS evaluation scripts; the KITTI depth benchmark's SILog): AbsRel, SqRel, RMSE,
// RMSElog, SILog and the delta thresholds, over the pixels where both maps are valid, and their
// combination over a dataset (mean per image, pooled over pixels). Definitions: docs/evaluation.md.

#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

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

/// The per-pixel error sums every metric is computed from: adding two images' sums gives the
/// sums of their pixels pooled.
struct DepthErrorSums {
  std::int64_t count = 0;                           ///< valid pixels
  double abs_rel = 0;                               ///< sum |g - p| / g
  double sq_rel_m = 0;                              ///< sum (g - p)^2 / g
  double squared_m2 = 0;                            ///< sum (g - p)^2
  double squared_log = 0;                           ///< sum (ln g - ln p)^2
  double log_difference = 0;                        ///< sum (ln p - ln g)
  std::int64_t below1 = 0, below2 = 0, below3 = 0;  ///< pixels with max(g/p, p/g) < 1.25^k
  DepthErrorSums& operator+=(const DepthErrorSums& other);
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
  /// sqrt(mean(e^2) - mean(e)^2), e = ln p - ln g: the scale-invariant log error (Eigen et al.
  /// 2014 with lambda = 1), unitless; KITTI and BTS print 100 times it.
  double silog = 0;
  double delta1 = 0;    ///< fraction (0..1) with max(g/p, p/g) < 1.25
  double delta2 = 0;    ///< ... < 1.25^2
  double delta3 = 0;    ///< ... < 1.25^3
  DepthErrorSums sums;  ///< what the metrics were computed from
};

/// Adds `other`'s pixel accounting to `to`'s (pixels, the exclusion counts, valid pixels).
void addDepthPixelAccounting(DepthMetrics& to, const DepthMetrics& other);

/// A dataset's metrics: `mean_per_image` averages each metric over the images (as the KITTI,
/// Monodepth2 and Metric3D evaluation scripts report them), `pooled` computes them from the
/// summed error sums of all valid pixels of all images (larger images weigh more). Both carry
/// the summed pixel accounting and the pooled sums; their scale is the mean of the images'.
struct DepthDatasetMetrics {
  DepthMetrics mean_per_image, pooled;
  std::int64_t images = 0;
};

/// Combines per-image metrics; throws std::invalid_argument for an empty list.
DepthDatasetMetrics combineDepthMetrics(const std::vector<DepthMetrics>& per_image);

/// Compares a predicted depth map with ground truth, in double precision. A pixel is valid
/// when it is inside the mask, gt and prediction are both finite and > 0, and gt is inside
/// the range. Throws InputError naming the files for a size or channel mismatch, an
/// unsupported pixel type, an inconsistent range, or no valid pixel at all (never NaN).
DepthMetrics evaluateDepth(const DepthEvaluationInput& input, const DepthMetricsOptions& options = {});

}  // namespace solo
