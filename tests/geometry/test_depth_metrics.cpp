// Depth metrics on hand-computed cases, their invariances, and their failure cases.

#include <solo/geometry/depth_metrics.h>
#include <solo/core/error.h>
#include <solo/core/quantile.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

/// A 1-row float depth map.
cv::Mat row(const std::vector<float>& values) { return cv::Mat(values, true).reshape(1, 1); }

solo::DepthMetrics evaluate(const cv::Mat& pred, const cv::Mat& gt, const solo::DepthMetricsOptions& options = {},
                            const cv::Mat& mask = {}) {
  solo::DepthEvaluationInput input;
  input.prediction_m = pred;
  input.ground_truth_m = gt;
  input.mask = mask;
  return solo::evaluateDepth(input, options);
}

std::string errorOf(const solo::DepthEvaluationInput& input, const solo::DepthMetricsOptions& options = {}) {
  try {
    solo::evaluateDepth(input, options);
  } catch (const solo::InputError& e) {
    return e.what();
  }
  return "no error";
}

/// A random positive depth map, metres.
cv::Mat randomDepth(int rows, int cols, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<float> depth(1.0f, 60.0f);
  cv::Mat d(rows, cols, CV_32F);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x) d.at<float>(y, x) = depth(random);
  return d;
}

}  // namespace

// gt   = 2, 4, 5, 10 | 0 (no gt) | 3 (no prediction)
// pred = 1, 4, 4, 12 | 7         | NaN
// Valid: the first four. Per pixel |g-p|/g = 0.5, 0, 0.2, 0.2; (g-p)^2/g = 0.5, 0, 0.2, 0.4;
// (g-p)^2 = 1, 0, 1, 4; max(g/p, p/g) = 2, 1, 1.25, 1.2.
// AbsRel = 0.9/4 = 0.225; SqRel = 1.1/4 = 0.275 m; RMSE = sqrt(6/4) = sqrt(1.5) m;
// RMSElog = sqrt((ln 2^2 + ln 1.25^2 + ln 1.2^2) / 4); delta1: 1 and 1.2 < 1.25 (1.25 itself is
// not: strict) -> 2/4; delta2 (< 1.5625) and delta3 (< 1.953125): 1, 1.25, 1.2 -> 3/4.
TEST(DepthMetrics, HandComputedCase) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const solo::DepthMetrics m = evaluate(row({1, 4, 4, 12, 7, nan}), row({2, 4, 5, 10, 0, 3}));
  EXPECT_EQ(m.pixels, 6);
  EXPECT_EQ(m.valid_pixels, 4);
  EXPECT_EQ(m.ground_truth_invalid, 1);
  EXPECT_EQ(m.prediction_invalid, 1);
  EXPECT_EQ(m.masked_out, 0);
  EXPECT_EQ(m.outside_range, 0);
  EXPECT_DOUBLE_EQ(m.abs_rel, 0.225);
  EXPECT_DOUBLE_EQ(m.sq_rel_m, 0.275);
  EXPECT_DOUBLE_EQ(m.rmse_m, std::sqrt(1.5));
  const double l2 = std::log(2.0), l125 = std::log(1.25), l12 = std::log(1.2);
  EXPECT_NEAR(m.rmse_log, std::sqrt((l2 * l2 + l125 * l125 + l12 * l12) / 4), 1e-15);
  EXPECT_DOUBLE_EQ(m.delta1, 0.5);
  EXPECT_DOUBLE_EQ(m.delta2, 0.75);
  EXPECT_DOUBLE_EQ(m.delta3, 0.75);
  EXPECT_DOUBLE_EQ(m.scale, 1.0);
}

// SILog of the hand case: e = ln p - ln g = -ln 2, 0, -ln 1.25, ln 1.2 over the valid pixels;
// sqrt(mean(e^2) - mean(e)^2) = 0.327418 (the BTS / KITTI definition before their factor 100).
// A prediction off by one global factor has SILog 0: it measures the error up to scale.
TEST(DepthMetrics, ScaleInvariantLogErrorHandComputed) {
  const solo::DepthMetrics m = evaluate(row({1, 4, 4, 12}), row({2, 4, 5, 10}));
  const double e[] = {-std::log(2.0), 0.0, -std::log(1.25), std::log(1.2)};
  double sum = 0, sum_squares = 0;
  for (const double v : e) {
    sum += v;
    sum_squares += v * v;
  }
  EXPECT_NEAR(m.silog, std::sqrt(sum_squares / 4 - (sum / 4) * (sum / 4)), 1e-15);
  EXPECT_NEAR(m.silog, 0.327418, 1e-6);
  const solo::DepthMetrics scaled = evaluate(row({2.5f, 5, 7.5f, 30}), row({1, 2, 3, 12}));
  EXPECT_NEAR(scaled.silog, 0.0, 1e-7);
  EXPECT_GT(scaled.rmse_log, 0.9);  // ln 2.5: RMSElog is not scale invariant
}

// Two images: A, one pixel, gt 1 and pred 3 (|g-p|/g = 2, (g-p)^2 = 4, ratio 3); B, eight
// exact pixels. Mean per image: AbsRel (2 + 0) / 2 = 1, RMSE (2 + 0) / 2 = 1, delta1
// (0 + 1) / 2 = 0.5. Pooled over the 9 pixels: AbsRel 2/9, RMSE sqrt(4/9) = 2/3, delta1 8/9.
TEST(DepthMetrics, DatasetMeanPerImageAndPooled) {
  const solo::DepthMetrics a = evaluate(row({3}), row({1}));
  const solo::DepthMetrics b = evaluate(row({1, 2, 3, 4, 5, 6, 7, 8}), row({1, 2, 3, 4, 5, 6, 7, 8}));
  const solo::DepthDatasetMetrics d = solo::combineDepthMetrics({a, b});
  EXPECT_EQ(d.images, 2);
  EXPECT_DOUBLE_EQ(d.mean_per_image.abs_rel, 1.0);
  EXPECT_DOUBLE_EQ(d.mean_per_image.rmse_m, 1.0);
  EXPECT_DOUBLE_EQ(d.mean_per_image.delta1, 0.5);
  EXPECT_DOUBLE_EQ(d.pooled.abs_rel, 2.0 / 9.0);
  EXPECT_DOUBLE_EQ(d.pooled.rmse_m, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(d.pooled.sq_rel_m, 4.0 / 9.0);
  EXPECT_DOUBLE_EQ(d.pooled.delta1, 8.0 / 9.0);
  EXPECT_NEAR(d.pooled.rmse_log, std::sqrt(std::log(3.0) * std::log(3.0) / 9), 1e-15);
  for (const solo::DepthMetrics* m : {&d.mean_per_image, &d.pooled}) {
    EXPECT_EQ(m->pixels, 9);
    EXPECT_EQ(m->valid_pixels, 9);
    EXPECT_EQ(m->sums.count, 9);
    EXPECT_DOUBLE_EQ(m->scale, 1.0);
  }
  // One image: both are that image's metrics.
  const solo::DepthDatasetMetrics one = solo::combineDepthMetrics({a});
  EXPECT_DOUBLE_EQ(one.mean_per_image.abs_rel, a.abs_rel);
  EXPECT_DOUBLE_EQ(one.pooled.rmse_m, a.rmse_m);
  EXPECT_THROW(solo::combineDepthMetrics({}), std::invalid_argument);
}

// delta thresholds are 1.25, 1.25^2 = 1.5625 and 1.25^3 = 1.953125, all exact in binary:
// p/g = 1.5625 is outside delta2 but inside delta3; 1.953125 is outside all three.
TEST(DepthMetrics, DeltaThresholdsAreStrict) {
  const solo::DepthMetrics m = evaluate(row({1.5625f, 1.953125f}), row({1, 1}));
  EXPECT_DOUBLE_EQ(m.delta1, 0.0);
  EXPECT_DOUBLE_EQ(m.delta2, 0.0);
  EXPECT_DOUBLE_EQ(m.delta3, 0.5);
}

// gt = 1, 2, 3; pred = 2, 4, 10: median(gt) = 2, median(pred) = 4, scale = 0.5, scaled
// pred = 1, 2, 5: AbsRel = (0 + 0 + 2/3) / 3 = 2/9, RMSE = sqrt(4/3).
TEST(DepthMetrics, MedianScalingHandComputed) {
  solo::DepthMetricsOptions options;
  options.median_scaling = true;
  const solo::DepthMetrics m = evaluate(row({2, 4, 10}), row({1, 2, 3}), options);
  EXPECT_DOUBLE_EQ(m.scale, 0.5);
  EXPECT_DOUBLE_EQ(m.abs_rel, 2.0 / 9.0);
  EXPECT_DOUBLE_EQ(m.rmse_m, std::sqrt(4.0 / 3.0));
  // Even count: NumPy's median is the mean of the two middle values, (2 + 3) / 2 = 2.5.
  const solo::DepthMetrics even = evaluate(row({1, 1, 1, 1}), row({1, 2, 3, 4}), options);
  EXPECT_DOUBLE_EQ(even.scale, 2.5);
}

TEST(DepthMetrics, MedianScalingMakesAGloballyScaledPredictionPerfect) {
  const cv::Mat gt = randomDepth(37, 53, 1);
  const cv::Mat pred = gt * 3.7;
  solo::DepthMetricsOptions options;
  options.median_scaling = true;
  const solo::DepthMetrics m = evaluate(pred, gt, options);
  EXPECT_NEAR(m.scale, 1 / 3.7, 1e-7);
  EXPECT_NEAR(m.abs_rel, 0.0, 1e-6);
  EXPECT_NEAR(m.rmse_m, 0.0, 1e-4);
  EXPECT_NEAR(m.rmse_log, 0.0, 1e-6);
  EXPECT_DOUBLE_EQ(m.delta1, 1.0);
  // Without scaling the same prediction is far off: every ratio is 3.7.
  const solo::DepthMetrics raw = evaluate(pred, gt);
  EXPECT_NEAR(raw.abs_rel, 2.7, 1e-6);
  EXPECT_DOUBLE_EQ(raw.delta3, 0.0);
}

TEST(DepthMetrics, MaskExcludesExactlyTheMaskedPixels) {
  const cv::Mat gt = randomDepth(20, 30, 2), pred = randomDepth(20, 30, 3);
  cv::Mat mask(gt.size(), CV_32S, cv::Scalar(1));
  cv::Mat gt_without_masked = gt.clone();
  std::mt19937_64 random(4);
  int masked = 0;
  for (int y = 0; y < gt.rows; ++y)
    for (int x = 0; x < gt.cols; ++x)
      if (random() % 3 == 0) {
        mask.at<int>(y, x) = 0;
        gt_without_masked.at<float>(y, x) = 0;
        ++masked;
      }
  const solo::DepthMetrics with_mask = evaluate(pred, gt, {}, mask);
  const solo::DepthMetrics dropped = evaluate(pred, gt_without_masked);
  EXPECT_EQ(with_mask.masked_out, masked);
  EXPECT_EQ(with_mask.valid_pixels, 600 - masked);
  EXPECT_EQ(dropped.valid_pixels, with_mask.valid_pixels);
  EXPECT_DOUBLE_EQ(with_mask.abs_rel, dropped.abs_rel);
  EXPECT_DOUBLE_EQ(with_mask.rmse_m, dropped.rmse_m);
  EXPECT_DOUBLE_EQ(with_mask.delta1, dropped.delta1);
  // An all-ones mask changes nothing.
  const solo::DepthMetrics full = evaluate(pred, gt, {}, cv::Mat(gt.size(), CV_8U, cv::Scalar(255)));
  EXPECT_EQ(full.valid_pixels, 600);
  EXPECT_DOUBLE_EQ(full.abs_rel, evaluate(pred, gt).abs_rel);
}

// gt = 1, 2, 3, 80 with 1 < gt < 80: only 2 and 3 are evaluated (the bounds are strict, as in
// the Monodepth2 and BTS scripts). pred = 4 everywhere: AbsRel = (2/2 + 1/3) / 2 = 2/3.
TEST(DepthMetrics, DepthRangeIsStrictAndAppliesToGroundTruth) {
  solo::DepthMetricsOptions options;
  options.min_depth_m = 1;
  options.max_depth_m = 80;
  const solo::DepthMetrics m = evaluate(row({4, 4, 4, 4}), row({1, 2, 3, 80}), options);
  EXPECT_EQ(m.outside_range, 2);
  EXPECT_EQ(m.valid_pixels, 2);
  EXPECT_DOUBLE_EQ(m.abs_rel, 2.0 / 3.0);
}

// pred 100 and 0.5 against gt 50 and 2 in (1, 80): clamped to 80 and 1,
// AbsRel = (30/50 + 1/2) / 2 = 0.55; unclamped (50/50 + 1.5/2) / 2 = 0.875.
TEST(DepthMetrics, ClampingPredictionIntoTheRange) {
  solo::DepthMetricsOptions options;
  options.min_depth_m = 1;
  options.max_depth_m = 80;
  EXPECT_DOUBLE_EQ(evaluate(row({100, 0.5f}), row({50, 2}), options).abs_rel, 0.875);
  options.clamp_prediction = true;
  EXPECT_DOUBLE_EQ(evaluate(row({100, 0.5f}), row({50, 2}), options).abs_rel, 0.55);
}

TEST(DepthMetrics, SizeMismatchNamesBothFilesAndSizes) {
  solo::DepthEvaluationInput input;
  input.prediction_m = cv::Mat(2, 3, CV_32F, cv::Scalar(1));
  input.ground_truth_m = cv::Mat(2, 4, CV_32F, cv::Scalar(1));
  input.prediction_file = "p.exr";
  input.ground_truth_file = "g.png";
  EXPECT_EQ(errorOf(input), "p.exr: prediction is 3x2 but ground truth g.png is 4x2");
  input.ground_truth_m = cv::Mat(2, 3, CV_32F, cv::Scalar(1));
  input.mask = cv::Mat(3, 3, CV_8U, cv::Scalar(1));
  input.mask_file = "m.png";
  EXPECT_EQ(errorOf(input), "m.png: mask is 3x3 but ground truth g.png is 3x2");
  input.mask = cv::Mat();
  input.prediction_m = cv::Mat(2, 3, CV_32FC3);
  EXPECT_EQ(errorOf(input), "p.exr: prediction has 3 channels, depth needs 1");
}

TEST(DepthMetrics, NoValidPixelIsAClearErrorNotNaN) {
  solo::DepthEvaluationInput input;
  input.prediction_m = row({1, 2, 3});
  input.ground_truth_m = row({0, -1, std::numeric_limits<float>::infinity()});
  input.ground_truth_file = "g.pfm";
  EXPECT_EQ(errorOf(input),
            "g.pfm: no valid pixel to evaluate (of 3 pixels: 0 masked out, 3 without ground truth, 0 outside the "
            "depth range, 0 without prediction)");
  input.ground_truth_m = row({1, 2, 3});
  input.mask = cv::Mat(1, 3, CV_8U, cv::Scalar(0));
  EXPECT_NE(errorOf(input).find("3 masked out"), std::string::npos);
  input.mask = cv::Mat();
  solo::DepthMetricsOptions options;
  options.min_depth_m = 5;
  EXPECT_NE(errorOf(input, options).find("3 outside the depth range"), std::string::npos);
  options.max_depth_m = 2;
  EXPECT_EQ(errorOf(input, options), "g.pfm: depth range is empty: min depth 5 m is not below max depth 2 m");
}

// NumPy: np.quantile([1, 2, 3, 4, 10], 0.95) = 4 + 0.8 * (10 - 4) = 8.8; median of 4 values
// is the mean of the middle two.
TEST(SampleQuantile, MatchesNumPysLinearDefinition) {
  std::vector<double> v = {10, 3, 1, 4, 2};
  EXPECT_DOUBLE_EQ(solo::sampleQuantile(v, 0.95), 8.8);
  EXPECT_DOUBLE_EQ(solo::sampleQuantile(v, 0.5), 3.0);
  EXPECT_DOUBLE_EQ(solo::sampleQuantile(v, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(solo::sampleQuantile(v, 1.0), 10.0);
  std::vector<double> even = {4, 1, 3, 2};
  EXPECT_DOUBLE_EQ(solo::sampleQuantile(even, 0.5), 2.5);
  std::vector<double> one = {7};
  EXPECT_DOUBLE_EQ(solo::sampleQuantile(one, 0.95), 7.0);
}
