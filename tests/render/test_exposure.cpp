#include <solo/post/exposure.h>

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

// The night camera at f/2.8, ISO 100-3200, 1/8000-1/30 s, K = 12.5, H_sat S = 78 lux s, q = 0.65:
// the meter asks for S t = K N^2 / L = 98 / L (ISO s); white = 78 N^2 / (q S t) = 940.8 / (S t).
TEST(NightCamera, MetersTheMeanToTheMetersGreyWithinItsLimits) {
  // 10 cd/m^2: S t = 9.8; at ISO 100 that is 0.098 s > 1/30, so 1/30 s and ISO 294.
  const solo::NightCameraExposure mid = solo::nightCameraExposure(10.0);
  EXPECT_DOUBLE_EQ(mid.camera.shutter_s, 1.0 / 30.0);
  EXPECT_NEAR(mid.camera.iso, 294.0, 1e-9);
  EXPECT_NEAR(mid.white_cd_m2, 96.0, 1e-9);  // 9.6 x the mean: the mean at 10.4 % of white
  EXPECT_FALSE(mid.at_exposure_limit);
  EXPECT_FALSE(mid.at_bright_limit);
  // 1000 cd/m^2: S t = 0.098, reached at ISO 100 with 0.98 ms.
  const solo::NightCameraExposure day = solo::nightCameraExposure(1000.0);
  EXPECT_DOUBLE_EQ(day.camera.iso, 100.0);
  EXPECT_NEAR(day.camera.shutter_s, 0.00098, 1e-15);
  EXPECT_NEAR(day.white_cd_m2, 9600.0, 1e-6);
}

TEST(NightCamera, ADarkStreetRunsOutOfExposureAndStaysDark) {
  // 0.1 cd/m^2 asks for S t = 980; the camera stops at 3200 x 1/30 = 106.67: white 8.82 cd/m^2,
  // so the mean lands at 0.1 / 8.82 = 1.1 % of white, not at the meter's 10.4 %.
  const double limit_white = 78.0 * 2.8 * 2.8 / (0.65 * 3200.0 / 30.0);
  for (const double metered : {0.1, 0.5, 0.0}) {
    const solo::NightCameraExposure e = solo::nightCameraExposure(metered);
    EXPECT_TRUE(e.at_exposure_limit) << metered;
    EXPECT_DOUBLE_EQ(e.camera.iso, 3200.0);
    EXPECT_DOUBLE_EQ(e.camera.shutter_s, 1.0 / 30.0);
    EXPECT_NEAR(e.white_cd_m2, limit_white, 1e-9);
  }
  EXPECT_NEAR(limit_white, 8.82, 0.005);
  // Just bright enough for the limit: 98 / 106.67 = 0.91875 cd/m^2 is exactly at it, not past.
  EXPECT_FALSE(solo::nightCameraExposure(98.0 / (3200.0 / 30.0) * 1.000001).at_exposure_limit);
}

TEST(NightCamera, SunlitFrameHitsTheShortestShutter) {
  const solo::NightCameraExposure e = solo::nightCameraExposure(1e7);
  EXPECT_TRUE(e.at_bright_limit);
  EXPECT_DOUBLE_EQ(e.camera.iso, 100.0);
  EXPECT_DOUBLE_EQ(e.camera.shutter_s, 1.0 / 8000.0);
  EXPECT_NEAR(e.white_cd_m2, 940.8 / (100.0 / 8000.0), 1e-6);
}

TEST(NightCamera, GivenWhiteGivesTheIsoAtTheLongestShutter) {
  // white 96 cd/m^2 at 1/30 s: S = 940.8 / (96 / 30) = 294.
  const solo::NightCameraExposure e = solo::nightCameraForWhite(96.0);
  EXPECT_NEAR(e.camera.iso, 294.0, 1e-9);
  EXPECT_DOUBLE_EQ(e.white_cd_m2, 96.0);
  const solo::NightCameraExposure dark = solo::nightCameraForWhite(1.0);  // would need ISO 28224
  EXPECT_DOUBLE_EQ(dark.camera.iso, 3200.0);
  EXPECT_TRUE(dark.at_exposure_limit);
  EXPECT_DOUBLE_EQ(dark.white_cd_m2, 1.0);
  EXPECT_THROW(solo::nightCameraForWhite(0.0), std::invalid_argument);
}

TEST(NightCamera, RejectsInvalidInput) {
  EXPECT_THROW(solo::nightCameraExposure(-1.0), std::invalid_argument);
  EXPECT_THROW(solo::nightCameraExposure(std::nan("")), std::invalid_argument);
  solo::NightCameraOptions o;
  o.max_iso = 50;  // below min_iso
  EXPECT_THROW(solo::nightCameraExposure(1.0, o), std::invalid_argument);
  o = {};
  o.f_number = 0;
  EXPECT_THROW(solo::nightCameraExposure(1.0, o), std::invalid_argument);
}

TEST(NightCamera, MeterAveragesTheFrameWithoutTheLampsSeenDirectly) {
  // Four pixels: Y = 1, 2, 3 and a lamp of 10^4 (coverage 0.25): the mean of the first three.
  cv::Mat radiance(1, 4, CV_32FC3, cv::Scalar(0, 0, 0));
  cv::Mat coverage(1, 4, CV_32F, cv::Scalar(0));
  for (int i = 0; i < 3; ++i) radiance.at<cv::Vec3f>(0, i) = cv::Vec3f(0, static_cast<float>(i + 1), 0);
  radiance.at<cv::Vec3f>(0, 3) = cv::Vec3f(0, 1e4f, 0);
  coverage.at<float>(0, 3) = 0.25f;
  EXPECT_DOUBLE_EQ(solo::meteredMeanLuminance(radiance, coverage), 2.0);
  coverage.setTo(1.f);
  EXPECT_EQ(solo::meteredMeanLuminance(radiance, coverage), 0.0);
  EXPECT_THROW(solo::meteredMeanLuminance(radiance, cv::Mat(1, 3, CV_32F, cv::Scalar(0))), std::invalid_argument);
}

TEST(NightCamera, CompensationScalesTheExposureTheMeterAsksFor) {
  // -2 EV: S t = 9.8 / 4 = 2.45 for 10 cd/m^2, reached at ISO 100 with 24.5 ms; white 4 x 96.
  solo::NightCameraOptions o;
  o.compensation_ev = -2;
  const solo::NightCameraExposure e = solo::nightCameraExposure(10.0, o);
  EXPECT_DOUBLE_EQ(e.camera.iso, 100.0);
  EXPECT_NEAR(e.camera.shutter_s, 0.0245, 1e-12);
  EXPECT_NEAR(e.white_cd_m2, 384.0, 1e-9);
  // At the limit the compensation changes nothing: the camera gives all it has.
  EXPECT_NEAR(solo::nightCameraExposure(0.01, o).white_cd_m2, solo::nightCameraExposure(0.01).white_cd_m2, 1e-12);
  o.compensation_ev = 20;
  EXPECT_THROW(solo::nightCameraExposure(1.0, o), std::invalid_argument);
}
