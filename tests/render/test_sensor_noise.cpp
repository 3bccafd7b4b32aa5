#include <solo/render/sensor_noise.h>

#include "test_support.h"

#include <cmath>

namespace {

struct Moments {
  double mean = 0, variance = 0;
  std::int64_t n = 0;
};

/// Sample mean and unbiased variance of all channel values.
Moments moments(const cv::Mat& image) {
  Moments m;
  const cv::Mat flat = image.reshape(1, 1);
  m.n = static_cast<std::int64_t>(flat.total());
  double sum = 0, sum_sq = 0;
  for (int i = 0; i < flat.cols; ++i) sum += flat.at<float>(0, i);
  m.mean = sum / m.n;
  for (int i = 0; i < flat.cols; ++i) sum_sq += std::pow(flat.at<float>(0, i) - m.mean, 2);
  m.variance = sum_sq / (m.n - 1);
  return m;
}

}  // namespace

TEST(SensorNoise, CalibrationTableAndInterpolationByIso) {
  const auto& table = solo::referenceNoiseCalibration();
  ASSERT_EQ(table.size(), 6u);
  const solo::NoiseCalibration at3200 = solo::noiseCalibrationAtIso(3200);
  EXPECT_DOUBLE_EQ(at3200.beta1, 4.245);
  EXPECT_DOUBLE_EQ(at3200.beta2, -231.0);
  // Linear in ISO between 400 and 800.
  const solo::NoiseCalibration at566 = solo::noiseCalibrationAtIso(566);
  EXPECT_NEAR(at566.beta1, 0.5615 + (166.0 / 400.0) * (1.1175 - 0.5615), 1e-12);
  EXPECT_NEAR(at566.beta2, -35.5 + (166.0 / 400.0) * (-69.6 + 35.5), 1e-12);
  EXPECT_THROW(solo::noiseCalibrationAtIso(50), std::invalid_argument);
  EXPECT_THROW(solo::noiseCalibrationAtIso(6400), std::invalid_argument);
  // Variance at the black level (64 counts), before the x3: about 0.2 at ISO 100, about 40 at 3200.
  solo::SensorNoiseOptions plain;
  plain.std_scale = 1;
  plain.quantise = false;
  plain.iso = 100;
  EXPECT_NEAR(solo::noiseVarianceCounts(64, plain), 0.141 * 64 - 8.8, 1e-12);
  plain.iso = 3200;
  EXPECT_NEAR(solo::noiseVarianceCounts(64, plain), 4.245 * 64 - 231.0, 1e-12);
  EXPECT_NEAR(solo::noiseVarianceCounts(64, plain), 40.0, 1.0);
  // Below the level where beta1 I + beta2 crosses zero there is no noise, never a negative variance.
  EXPECT_EQ(solo::noiseVarianceCounts(10, plain), 0.0);
}

TEST(SensorNoise, FlatPatchMeanAndVarianceMatchTheModel) {
  // 256 x 256 x 3 samples; tolerances are 5 standard errors of the estimators.
  struct Case {
    double iso, scale, level;
    bool clip;
  };
  for (const Case& c : {Case{3200, 3.0, 0.5, false}, Case{400, 1.0, 0.5, true}, Case{1131, 1.0, 0.1, true}}) {
    solo::SensorNoiseOptions options;
    options.iso = c.iso;
    options.std_scale = c.scale;
    options.clip = c.clip;
    options.seed = 42;
    cv::Mat patch(256, 256, CV_32FC3, cv::Scalar::all(c.level));
    const solo::StageReport report = solo::applySensorNoise(patch, options);
    EXPECT_FALSE(report.skipped);
    const Moments m = moments(patch * 959.0 + 64.0);  // back to raw counts
    const double level_counts = 64 + c.level * 959;
    const double variance = solo::noiseVarianceCounts(level_counts, options);  // includes rounding's 1/12
    const double mean_tolerance = 5 * std::sqrt(variance / m.n);
    const double variance_tolerance = 5 * variance * std::sqrt(2.0 / (m.n - 1));
    EXPECT_NEAR(m.mean, level_counts, mean_tolerance) << "ISO " << c.iso;
    EXPECT_NEAR(m.variance, variance, variance_tolerance) << "ISO " << c.iso;
  }
}

TEST(SensorNoise, VarianceInRenderUnitsMatchesWhatTheNoiseAdds) {
  solo::SensorNoiseOptions options;
  options.clip = false;
  options.quantise = false;
  const double exposure = 9.513656920021768, render_value = 0.04;
  const double predicted = solo::noiseVarianceRenderUnits(render_value, exposure, options);
  const double counts = 64 + render_value * exposure * 959;
  EXPECT_NEAR(predicted, solo::noiseVarianceCounts(counts, options) / std::pow(959 * exposure, 2), 1e-15);
  cv::Mat patch(256, 256, CV_32FC3, cv::Scalar::all(render_value * exposure));
  solo::applySensorNoise(patch, options);
  const Moments m = moments(patch / exposure);
  EXPECT_NEAR(m.variance, predicted, 5 * predicted * std::sqrt(2.0 / (m.n - 1)));
  const cv::Mat per_pixel =
      solo::noiseVarianceRenderUnits(cv::Mat(2, 2, CV_32FC3, cv::Scalar::all(render_value)), exposure, options);
  EXPECT_NEAR(per_pixel.at<cv::Vec3f>(1, 1)[2], predicted, predicted * 1e-6);
}

TEST(SensorNoise, SeededAndIndependentOfTheThreadCount) {
  cv::Mat base(64, 80, CV_32FC3, cv::Scalar(0.2, 0.3, 0.4));
  solo::SensorNoiseOptions options;
  options.seed = 9;
  cv::Mat a = base.clone(), b = base.clone(), c = base.clone();
  solo::applySensorNoise(a, options);
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  solo::applySensorNoise(b, options);
  cv::setNumThreads(threads);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  options.seed = 10;
  solo::applySensorNoise(c, options);
  EXPECT_GT(cv::norm(a, c, cv::NORM_INF), 0.0);
}

TEST(SensorNoise, AllBlackImageStaysAroundZeroAndClipsAtTheRawRange) {
  cv::Mat black = cv::Mat::zeros(128, 128, CV_32FC3);
  const solo::StageReport report = solo::applySensorNoise(black, {});
  double lo = 0, hi = 0;
  cv::minMaxLoc(black.reshape(1), &lo, &hi);
  EXPECT_GE(lo, -64.0 / 959.0 - 1e-7);  // raw 0 is the floor
  EXPECT_LE(hi, 1.0);
  EXPECT_TRUE(cv::checkRange(black));
  // sigma at the black level = 3 sqrt(40.68) = 19.1 counts: mean ~ 0 within 5 standard errors.
  const Moments m = moments(black * 959.0);
  EXPECT_NEAR(m.mean, 0.0, 5 * 19.2 / std::sqrt(static_cast<double>(m.n)));
  EXPECT_NEAR(std::sqrt(m.variance), 19.1, 0.4);
  // Bright values saturate at the white level.
  cv::Mat bright(16, 16, CV_32FC3, cv::Scalar::all(5.0));
  const solo::StageReport saturated = solo::applySensorNoise(bright, {});
  EXPECT_EQ(cv::countNonZero(bright.reshape(1) != 1.0f), 0);
  EXPECT_EQ(std::get<std::int64_t>(*saturated.find("clipped_at_white")), 16 * 16 * 3);
  EXPECT_NEAR(std::get<double>(*report.find("std_at_black_level")), 3 * std::sqrt(4.245 * 64 - 231), 1e-9);
}

TEST(SensorNoise, SigmaInRenderUnitsFollowsTheCalibrationThroughBothScales) {
  // A render of luminance Y is multiplied by c = 0.01 before the post-process and by the
  // exposure e = 9.5: raw counts 64 + Y c e 959; sigma in render units = sigma_counts / (959 e c).
  const solo::SensorNoiseOptions options;
  const double c = 0.01, e = 9.5;
  const auto sigma = solo::sensorNoiseSigma(c, e, options);
  for (double y : {0.0, 1.0, 5.0, 10.0}) {
    const double counts = 64 + y * c * e * 959;
    const double expected = 3 * std::sqrt(4.245 * counts - 231) / (959 * e * c);
    EXPECT_NEAR(sigma(y), expected, 1e-9 * expected) << y;
    EXPECT_NEAR(sigma(y), std::sqrt(solo::noiseVarianceRenderUnits(y * c, e, options)) / c, 1e-9 * expected);
  }
  EXPECT_THROW(solo::sensorNoiseSigma(0.0, e, options), std::invalid_argument);
}
