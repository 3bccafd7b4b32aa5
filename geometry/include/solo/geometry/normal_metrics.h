#pragma once
// Surface-normal accuracy metrics of the literature (Fouhey et al. 2013 and later): the
// angle between predicted and true normal per pixel, summarised by mean, median, RMSE and
// the share of pixels under 5, 7.5, 11.25, 22.5 and 30 degrees. Definitions: docs/evaluation.md.

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <filesystem>

namespace solo {

/// The maps to compare and the files they came from (the files are only named in errors).
struct NormalEvaluationInput {
  cv::Mat prediction;    ///< CV_32FC3 or CV_64FC3 normals; (0,0,0) = no prediction
  cv::Mat ground_truth;  ///< same size; (0,0,0) = no ground truth
  cv::Mat mask;          ///< empty (all pixels) or single channel, same size: non-zero = evaluate
  std::filesystem::path prediction_file = "prediction";
  std::filesystem::path ground_truth_file = "ground truth";
  std::filesystem::path mask_file = "mask";
};

/// The angular thresholds of the "share under" figures, degrees.
inline constexpr std::array<double, 5> kNormalAngleThresholdsDeg = {5.0, 7.5, 11.25, 22.5, 30.0};

struct NormalMetrics {
  // Pixel accounting: every pixel is counted once, in the first reason that excludes it.
  std::int64_t pixels = 0;                ///< width * height
  std::int64_t masked_out = 0;            ///< mask given and zero there
  std::int64_t ground_truth_invalid = 0;  ///< zero or non-finite ground-truth vector
  std::int64_t prediction_invalid = 0;    ///< zero or non-finite predicted vector
  std::int64_t valid_pixels = 0;          ///< the pixels every figure is computed over

  double mean_deg = 0;    ///< mean angular error, degrees
  double median_deg = 0;  ///< median angular error (NumPy's median), degrees
  double rmse_deg = 0;    ///< sqrt(mean(angle^2)), degrees
  /// Fraction (0..1) of valid pixels with angle < kNormalAngleThresholdsDeg[i].
  std::array<double, kNormalAngleThresholdsDeg.size()> share_under{};
};

/// Per pixel, the angle between the two vectors as atan2(|a x b|, a . b) in double (accurate
/// near 0 and 180 degrees, and independent of the vectors' lengths). A pixel is valid when it
/// is inside the mask and both vectors are finite and non-zero. Throws InputError naming the
/// files for a size or channel mismatch or when no pixel is valid (never NaN).
NormalMetrics evaluateNormals(const NormalEvaluationInput& input);

}  // namespace solo
