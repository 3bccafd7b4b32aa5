// Normal metrics on hand-computed angles, their robustness, invariances and failure cases.

#include <solo/core/error.h>
#include <solo/geometry/normal_metrics.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace {

constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;

/// A 1-row CV_64FC3 normal map.
cv::Mat row(const std::vector<cv::Vec3d>& normals) { return cv::Mat(normals, true).reshape(3, 1); }

/// The unit vector at `degrees` from (0, 0, -1), tilted towards +x.
cv::Vec3d tilted(double degrees) { return {std::sin(degrees * kRadPerDeg), 0, -std::cos(degrees * kRadPerDeg)}; }

solo::NormalMetrics evaluate(const cv::Mat& pred, const cv::Mat& gt, const cv::Mat& mask = {}) {
  solo::NormalEvaluationInput input;
  input.prediction = pred;
  input.ground_truth = gt;
  input.mask = mask;
  return solo::evaluateNormals(input);
}

std::string errorOf(const solo::NormalEvaluationInput& input) {
  try {
    solo::evaluateNormals(input);
  } catch (const solo::InputError& e) {
    return e.what();
  }
  return "no error";
}

cv::Mat randomNormals(int rows, int cols, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<float> gauss;
  cv::Mat n(rows, cols, CV_32FC3);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x) {
      const cv::Vec3f v(gauss(random), gauss(random), gauss(random));
      n.at<cv::Vec3f>(y, x) = v / cv::norm(v);
    }
  return n;
}

}  // namespace

// Eight valid pixels at 0, 6, 10, 20, 25, 45, 90, 180 degrees (90 and 180 as the exact
// vectors (1,0,0) and (0,0,1); 45 as the non-unit (0, 1, -1): length does not matter), plus
// one pixel without prediction and one without ground truth.
// mean = 376 / 8 = 47; median = (20 + 25) / 2 = 22.5;
// RMSE = sqrt((0 + 36 + 100 + 400 + 625 + 2025 + 8100 + 32400) / 8) = sqrt(5460.75);
// under 5: {0} 1/8; 7.5: {0, 6} 2/8; 11.25: {0, 6, 10} 3/8; 22.5: 4/8; 30: {.., 25} 5/8.
TEST(NormalMetrics, HandComputedAngles) {
  const cv::Vec3d down(0, 0, -1), zero(0, 0, 0);
  const cv::Mat gt = row({down, down, down, down, down, down, down, down, down, zero});
  const cv::Mat pred = row({down, tilted(6), tilted(10), tilted(20), tilted(25), cv::Vec3d(0, 1, -1),
                            cv::Vec3d(1, 0, 0), cv::Vec3d(0, 0, 1), zero, down});
  const solo::NormalMetrics m = evaluate(pred, gt);
  EXPECT_EQ(m.pixels, 10);
  EXPECT_EQ(m.valid_pixels, 8);
  EXPECT_EQ(m.prediction_invalid, 1);
  EXPECT_EQ(m.ground_truth_invalid, 1);
  EXPECT_NEAR(m.mean_deg, 47.0, 1e-12);
  EXPECT_NEAR(m.median_deg, 22.5, 1e-12);
  EXPECT_NEAR(m.rmse_deg, std::sqrt(5460.75), 1e-12);
  const double expected_shares[] = {1.0 / 8, 2.0 / 8, 3.0 / 8, 4.0 / 8, 5.0 / 8};
  for (std::size_t t = 0; t < solo::kNormalAngleThresholdsDeg.size(); ++t)
    EXPECT_DOUBLE_EQ(m.share_under[t], expected_shares[t]) << solo::kNormalAngleThresholdsDeg[t] << " deg";
}

// 1e-8 rad between two float vectors: acos(dot) sees dot == 1.0f and returns 0; atan2 of the
// cross and dot products keeps the angle, 1e-8 rad = 5.7296e-7 deg.
// A constructed field of 100 angles, 0.15 + 0.4 i degrees (i = 0..99), none within 0.025 deg
// of a threshold. Below 5: 0.4 i < 4.85, i <= 12 (13); 7.5: i <= 18 (19); 11.25: i <= 27 (28);
// 22.5: i <= 55 (56); 30: i <= 74 (75). Mean and median 0.15 + 0.4 x 49.5 = 19.95;
// RMSE^2 = mean((0.15 + 0.4 i)^2) = 0.0225 + 0.12 x 49.5 + 0.16 x 3283.5 = 531.3225.
TEST(NormalMetrics, ConstructedAngleFieldSharesUnderEachThreshold) {
  std::vector<cv::Vec3d> truth, prediction;
  for (int i = 0; i < 100; ++i) {
    truth.push_back(tilted(0));
    prediction.push_back(tilted(0.15 + 0.4 * i));
  }
  const solo::NormalMetrics m = evaluate(cv::Mat(prediction, true).reshape(3, 10), cv::Mat(truth, true).reshape(3, 10));
  EXPECT_EQ(m.valid_pixels, 100);
  const double expected_shares[] = {0.13, 0.19, 0.28, 0.56, 0.75};
  for (std::size_t t = 0; t < solo::kNormalAngleThresholdsDeg.size(); ++t)
    EXPECT_DOUBLE_EQ(m.share_under[t], expected_shares[t]) << solo::kNormalAngleThresholdsDeg[t] << " deg";
  EXPECT_NEAR(m.mean_deg, 19.95, 1e-9);
  EXPECT_NEAR(m.median_deg, 19.95, 1e-9);
  EXPECT_NEAR(m.rmse_deg, std::sqrt(531.3225), 1e-9);
}

TEST(NormalMetrics, TinyAnglesAreResolved) {
  cv::Mat gt(1, 1, CV_32FC3, cv::Scalar(0, 0, 1));
  cv::Mat pred(1, 1, CV_32FC3, cv::Scalar(1e-8, 0, 1));
  const solo::NormalMetrics m = evaluate(pred, gt);
  EXPECT_NEAR(m.mean_deg, 1e-8 / kRadPerDeg, 1e-12);  // 1e-8f is 1e-8 within 6e-8 relative
  EXPECT_GT(m.mean_deg, 0.0);
}

TEST(NormalMetrics, IdenticalMapsScoreZeroAndOppositeMapsScore180) {
  const cv::Mat n = randomNormals(16, 24, 5);
  const solo::NormalMetrics same = evaluate(n, n);
  EXPECT_EQ(same.valid_pixels, 16 * 24);
  EXPECT_NEAR(same.mean_deg, 0.0, 1e-5);
  EXPECT_DOUBLE_EQ(same.share_under[0], 1.0);
  const cv::Mat negated = -n;
  const solo::NormalMetrics opposite = evaluate(negated, n);
  EXPECT_NEAR(opposite.mean_deg, 180.0, 1e-5);
  EXPECT_NEAR(opposite.median_deg, 180.0, 1e-5);
  EXPECT_DOUBLE_EQ(opposite.share_under[4], 0.0);
}

TEST(NormalMetrics, MaskExcludesExactlyTheMaskedPixels) {
  const cv::Mat gt = randomNormals(12, 10, 6), pred = randomNormals(12, 10, 7);
  cv::Mat mask(gt.size(), CV_8U, cv::Scalar(1));
  cv::Mat gt_without_masked = gt.clone();
  int masked = 0;
  for (int y = 0; y < gt.rows; ++y)
    for (int x = 0; x < gt.cols; ++x)
      if ((x * 7 + y * 3) % 4 == 0) {
        mask.at<unsigned char>(y, x) = 0;
        gt_without_masked.at<cv::Vec3f>(y, x) = cv::Vec3f(0, 0, 0);
        ++masked;
      }
  const solo::NormalMetrics with_mask = evaluate(pred, gt, mask);
  const solo::NormalMetrics dropped = evaluate(pred, gt_without_masked);
  EXPECT_EQ(with_mask.masked_out, masked);
  EXPECT_EQ(with_mask.valid_pixels, 120 - masked);
  EXPECT_EQ(dropped.valid_pixels, with_mask.valid_pixels);
  EXPECT_DOUBLE_EQ(with_mask.mean_deg, dropped.mean_deg);
  EXPECT_DOUBLE_EQ(with_mask.median_deg, dropped.median_deg);
  EXPECT_DOUBLE_EQ(with_mask.rmse_deg, dropped.rmse_deg);
}

TEST(NormalMetrics, SizeMismatchAndNoValidPixelAreClearErrors) {
  solo::NormalEvaluationInput input;
  input.prediction = cv::Mat(4, 5, CV_32FC3, cv::Scalar(0, 0, -1));
  input.ground_truth = cv::Mat(4, 6, CV_32FC3, cv::Scalar(0, 0, -1));
  input.prediction_file = "p.exr";
  input.ground_truth_file = "g.png";
  EXPECT_EQ(errorOf(input), "p.exr: prediction is 5x4 but ground truth g.png is 6x4");
  input.ground_truth = cv::Mat(4, 5, CV_32FC3, cv::Scalar(0, 0, 0));
  EXPECT_EQ(errorOf(input),
            "g.png: no valid pixel to evaluate (of 20 pixels: 0 masked out, 20 without ground truth, 0 without "
            "prediction)");
  input.ground_truth = cv::Mat(4, 5, CV_32F, cv::Scalar(1));
  EXPECT_EQ(errorOf(input), "g.png: ground truth has 1 channels, normals need 3");
}
