#include <solo/render/exposure.h>

#include "test_support.h"

#include <cmath>
#include <stdexcept>

TEST(Exposure, DefaultIsTheReferencesPlus325Stops) {
  const solo::ExposureOptions options;
  EXPECT_DOUBLE_EQ(solo::exposureStops(options), 3.25);
  EXPECT_NEAR(solo::exposureScale(options), 9.513656920021768, 1e-12);
  cv::Mat image(2, 3, CV_32FC3, cv::Scalar(0.1, 0.2, 0.4));
  const solo::StageReport report = solo::applyExposure(image, options);
  EXPECT_FALSE(report.skipped);
  EXPECT_NEAR(image.at<cv::Vec3f>(1, 2)[2], 0.4 * 9.513656920021768, 1e-5);
}

TEST(Exposure, PhysicalCameraMapsToStops) {
  solo::ExposureOptions options;
  options.camera = solo::CameraExposure{};  // the reference camera: ISO 3200, 1/30 s, f/2
  EXPECT_NEAR(solo::exposureStops(options), 3.25, 1e-12);
  options.camera->iso = 6400;  // one stop more
  EXPECT_NEAR(solo::exposureStops(options), 4.25, 1e-12);
  options.camera = solo::CameraExposure{3200, 1.0 / 60.0, 2.0};  // half the time
  EXPECT_NEAR(solo::exposureStops(options), 2.25, 1e-12);
  options.camera = solo::CameraExposure{3200, 1.0 / 30.0, 4.0};  // two f-stops closed
  EXPECT_NEAR(solo::exposureStops(options), 1.25, 1e-12);
  options.camera = solo::CameraExposure{3200, 1.0 / 30.0, 0.0};
  EXPECT_THROW(solo::exposureStops(options), std::invalid_argument);
}

TEST(Exposure, ZeroStopsIsSkippedAndLeavesTheImage) {
  solo::ExposureOptions options;
  options.stops = 0;
  cv::Mat image(1, 1, CV_32FC3, cv::Scalar(0.3, 0.3, 0.3));
  const solo::StageReport report = solo::applyExposure(image, options);
  EXPECT_TRUE(report.skipped);
  EXPECT_NE(report.skip_reason.find("0 stops"), std::string::npos);
  EXPECT_EQ(image.at<cv::Vec3f>(0, 0)[0], 0.3f);
}

TEST(Exposure, MeteringPutsThe95thPercentileOfTheStreetAt80PercentOfWhite) {
  // 100 street pixels with Y = 1..100, one lamp far brighter, one pixel a lamp covers a quarter
  // of (its first sample may have missed the lamp, so it shows no light id, but it carries the
  // lamp's light) and one unlit pixel: the lamp, the partly covered pixel and the unlit pixel are
  // ignored; the 95th percentile is element floor(0.95 * 99) = 94 of the sorted luminances,
  // Y = 95, so sensor white is 95 / 0.8.
  cv::Mat radiance(1, 103, CV_32FC3, cv::Scalar(0, 0, 0));
  cv::Mat coverage(1, 103, CV_32F, cv::Scalar(0));
  for (int i = 0; i < 100; ++i) radiance.at<cv::Vec3f>(0, (i * 37) % 100) = cv::Vec3f(0, static_cast<float>(i + 1), 0);
  radiance.at<cv::Vec3f>(0, 100) = cv::Vec3f(0, 1e6f, 0);
  coverage.at<float>(0, 100) = 1.f;
  radiance.at<cv::Vec3f>(0, 101) = cv::Vec3f(0, 2.5e5f, 0);
  coverage.at<float>(0, 101) = 0.25f;
  EXPECT_DOUBLE_EQ(solo::meteredSensorWhite(radiance, coverage), 95.0 / 0.8);
  EXPECT_DOUBLE_EQ(solo::meteredSensorWhite(radiance, coverage, 0.5, 1.0), 50.0);
  // Counted, the partly covered pixel would be the brightest street pixel and move the 95th
  // percentile to element floor(0.95 * 100) = 95, Y = 96.
  coverage.at<float>(0, 101) = 0.f;
  EXPECT_DOUBLE_EQ(solo::meteredSensorWhite(radiance, coverage), 96.0 / 0.8);
  // Nothing lit: white stays 1 rather than dividing by zero.
  EXPECT_EQ(solo::meteredSensorWhite(cv::Mat(2, 2, CV_32FC3, cv::Scalar(0, 0, 0)), cv::Mat(2, 2, CV_32F, cv::Scalar(0))),
            1.0);
}

TEST(Exposure, MeteringRejectsACoverageMapOfAnotherTypeOrSize) {
  const cv::Mat radiance(2, 2, CV_32FC3, cv::Scalar(0, 1, 0));
  EXPECT_THROW(solo::meteredSensorWhite(radiance, cv::Mat(2, 2, CV_32S, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(solo::meteredSensorWhite(radiance, cv::Mat(2, 3, CV_32F, cv::Scalar(0))), std::invalid_argument);
}

TEST(Exposure, ThePreviewIsAQuarterOfEachSideUnlessThatExceeds10000Pixels) {
  EXPECT_EQ(solo::meteringPreviewSize(960, 540), cv::Size(120, 67));   // a quarter: 32 400 pixels; an eighth
  EXPECT_EQ(solo::meteringPreviewSize(1920, 1080), cv::Size(120, 67)); // a sixteenth
  EXPECT_EQ(solo::meteringPreviewSize(3840, 2160), cv::Size(120, 67)); // a thirty-second
  EXPECT_EQ(solo::meteringPreviewSize(128, 72), cv::Size(32, 18));
  EXPECT_EQ(solo::meteringPreviewSize(40, 30), cv::Size(16, 16));       // never below 16 x 16
  EXPECT_EQ(solo::meteringPreviewSize(1000, 1000, 1000000), cv::Size(250, 250));
  // 1/64 at most, however many pixels.
  EXPECT_EQ(solo::meteringPreviewSize(64000, 64000), cv::Size(1000, 1000));
}
