// Step 2 of depth refinement: the instance-reference cross-bilateral filter.

#include <solo/geometry/instance_bilateral_filter.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

double gaussian(double d, double sigma) { return std::exp(-d * d / (2 * sigma * sigma)); }

TEST(InstanceBilateralFilter, HandComputedRow) {
  // One row, one label, sigma 1 px, window radius 3: truncated at the image ends.
  const std::vector<float> values = {1, 2, 4, 8, 16};
  const cv::Mat depth = cv::Mat(values, true).reshape(1, 1);
  const cv::Mat labels(1, 5, CV_32S, cv::Scalar(7));
  const auto result = solo::instanceBilateralFilter(depth, labels, {1.0, 3.0});
  for (int p = 0; p < 5; ++p) {
    double num = 0, den = 0;
    for (int q = std::max(0, p - 3); q <= std::min(4, p + 3); ++q)
      num += gaussian(q - p, 1) * values[q], den += gaussian(q - p, 1);
    EXPECT_NEAR(result.depth_m.at<float>(0, p), num / den, 1e-5) << p;
  }
}

TEST(InstanceBilateralFilter, DepthEdgesBetweenInstancesStaySharp) {
  cv::Mat depth(20, 40, CV_32F, cv::Scalar(5));
  cv::Mat labels(20, 40, CV_32S, cv::Scalar(26001));
  depth.colRange(20, 40).setTo(50);
  labels.colRange(20, 40).setTo(11);
  const auto result = solo::instanceBilateralFilter(depth, labels);
  EXPECT_NEAR(cv::norm(result.depth_m, depth, cv::NORM_INF), 0.0, 1e-4) << "constant per instance: unchanged";
  EXPECT_TRUE(*std::get_if<bool>(result.report.find("label_term")));
}

TEST(InstanceBilateralFilter, InvalidAndSkyPixelsAreExcludedAndStayInvalid) {
  cv::Mat depth(15, 15, CV_32F, cv::Scalar(10));
  depth.at<float>(7, 7) = 0;                                    // a hole
  depth(cv::Rect(0, 0, 15, 3)).setTo(0);                        // sky band
  const auto result = solo::instanceBilateralFilter(depth, cv::Mat(15, 15, CV_32S, cv::Scalar(11)));
  EXPECT_EQ(result.depth_m.at<float>(7, 7), 0.f);
  EXPECT_EQ(cv::countNonZero(result.depth_m(cv::Rect(0, 0, 15, 3))), 0);
  cv::Mat valid = depth > 0;
  EXPECT_NEAR(cv::norm(result.depth_m, depth, cv::NORM_INF, valid), 0.0, 1e-4) << "no pull towards 0";
}

TEST(InstanceBilateralFilter, WithoutInstancesItIsAGaussianOverValidPixelsAndSaysSo) {
  cv::Mat depth(9, 9, CV_32F, cv::Scalar(2));
  depth.colRange(5, 9).setTo(4);
  const auto result = solo::instanceBilateralFilter(depth, cv::Mat(), {1.0, 3.0});
  EXPECT_FALSE(*std::get_if<bool>(result.report.find("label_term")));
  ASSERT_FALSE(result.report.notes.empty());
  EXPECT_NE(result.report.notes[0].find("no instances"), std::string::npos);
  EXPECT_GT(result.depth_m.at<float>(4, 4), 2.1f) << "blurred across the step without labels";
}

TEST(InstanceBilateralFilter, NoiseShrinksAndFarAndNearDepthsKeepTheirPrecision) {
  // Left half 0.5 m, right half 1000 m (two labels), 1 % noise; filtered values stay in each
  // label's range and the noise drops by roughly the kernel's effective sample count.
  std::mt19937_64 random(3);
  std::normal_distribution<float> noise(0.f, 0.01f);
  cv::Mat depth(40, 80, CV_32F), labels(40, 80, CV_32S);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 80; ++x) {
      const float base = x < 40 ? 0.5f : 1000.f;
      depth.at<float>(y, x) = base * (1 + noise(random));
      labels.at<int>(y, x) = x < 40 ? 24001 : 11;
    }
  const auto result = solo::instanceBilateralFilter(depth, labels);
  double before = 0, after = 0;
  for (int y = 10; y < 30; ++y)
    for (int x = 0; x < 80; ++x) {
      const double base = x < 40 ? 0.5 : 1000.0;
      const double d = result.depth_m.at<float>(y, x);
      ASSERT_TRUE(std::isfinite(d));
      ASSERT_NEAR(d, base, 0.01 * base);
      if (x >= 10 && x < 30) before += std::pow(depth.at<float>(y, x) / base - 1, 2), after += std::pow(d / base - 1, 2);
    }
  EXPECT_LT(after, before / 50) << "sigma 5 px averages about 4 pi 25 = 314 samples";
}

}  // namespace
