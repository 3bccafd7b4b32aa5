#include <solo/render/exposure.h>

#include "test_support.h"

#include <cmath>

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
