// Simulated depth sensors (synth/depth_sensor.h): stereo disparities, holes and noise growth,
// the LiDAR's firing pattern and range noise, the monocular scale error, determinism, and the
// files `solo synth --depth-source` writes.

#include <solo/core/camera.h>
#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/synth/depth_sensor.h>
#include <solo/synth/scene_folder.h>

#include "test_support.h"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <vector>

using solo::test::TempDir;

namespace {

constexpr double kPi = 3.14159265358979323846;

solo::PinholeCamera camera(int width, int height, double focal_px) {
  return {focal_px, focal_px, (width - 1) / 2.0, (height - 1) / 2.0, width, height};
}

cv::Mat plane(int width, int height, float z_m) { return cv::Mat(height, width, CV_32F, cv::Scalar(z_m)); }

// Uniform random sRGB values: texture everywhere.
cv::Mat texturedDay(int width, int height, std::uint64_t seed = 7) {
  cv::Mat day(height, width, CV_32FC3);
  cv::RNG rng(seed);
  rng.fill(day, cv::RNG::UNIFORM, 0.0, 1.0);
  return day;
}

solo::StereoSensorOptions noiselessStereo() {
  solo::StereoSensorOptions o;
  o.disparity_noise_px = 0;
  return o;
}

// Standard deviation of depth - z over the valid pixels of `depth_m`.
double errorStd(const cv::Mat& depth_m, double z_m) {
  double sum = 0, sum_sq = 0;
  std::int64_t n = 0;
  for (auto it = depth_m.begin<float>(); it != depth_m.end<float>(); ++it)
    if (*it > 0) {
      const double e = *it - z_m;
      sum += e;
      sum_sq += e * e;
      ++n;
    }
  EXPECT_GT(n, 1000);
  const double mean = sum / n;
  return std::sqrt(sum_sq / n - mean * mean);
}

double median(std::vector<double> values) {
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

bool identical(const cv::Mat& a, const cv::Mat& b) { return a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0; }

}  // namespace

TEST(DepthSensor, NamesRoundTrip) {
  for (auto source :
       {solo::DepthSource::Exact, solo::DepthSource::Mono, solo::DepthSource::Stereo, solo::DepthSource::Lidar})
    EXPECT_EQ(solo::depthSourceFromName(solo::depthSourceName(source)), source);
  EXPECT_THROW(solo::depthSourceFromName("radar"), std::invalid_argument);
}

TEST(StereoSensor, FrontoParallelPlaneGivesQuantisedDisparity) {
  const int width = 640, height = 60;
  const float z_m = 7.3f;
  const solo::StereoSensorOptions o = noiselessStereo();
  const solo::StereoDepth stereo = solo::simulateStereoDepth(plane(width, height, z_m), camera(width, height, 500),
                                                             texturedDay(width, height), 1, o);
  const double exact_px = o.baseline_m * 500 / z_m;
  const double expected_px = std::round(exact_px * 256) / 256;
  const float expected_depth_m = static_cast<float>(o.baseline_m * 500 / expected_px);
  EXPECT_DOUBLE_EQ(stereo.max_disparity_px, 40.0);  // 640 * 128 / 2048
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      if (x < 40) {  // the left band without a partner
        ASSERT_EQ(stereo.disparity_px.at<float>(y, x), 0.f);
        ASSERT_EQ(stereo.depth_m.at<float>(y, x), 0.f);
        continue;
      }
      ASSERT_EQ(stereo.disparity_px.at<float>(y, x), static_cast<float>(expected_px)) << x << "," << y;
      ASSERT_EQ(stereo.depth_m.at<float>(y, x), expected_depth_m);
    }
  EXPECT_EQ(stereo.holes.left_border, 40 * height);
  EXPECT_EQ(stereo.holes.occluded + stereo.holes.textureless + stereo.holes.too_far + stereo.holes.too_close, 0);

  const cv::Mat png = solo::cityscapesDisparityPng(stereo.disparity_px);
  EXPECT_EQ(png.at<std::uint16_t>(0, 0), 0);
  EXPECT_EQ(png.at<std::uint16_t>(10, 100), static_cast<std::uint16_t>(expected_px * 256 + 1));
}

TEST(StereoSensor, DepthNoiseGrowsWithTheSquareOfDepth) {
  const int width = 800, height = 300;
  const double near_m = 8, far_m = 16;
  const solo::PinholeCamera cam = camera(width, height, 1000);
  const cv::Mat day = texturedDay(width, height);
  const double near_std =
      errorStd(solo::simulateStereoDepth(plane(width, height, near_m), cam, day, 3).depth_m, near_m);
  const double far_std = errorStd(solo::simulateStereoDepth(plane(width, height, far_m), cam, day, 4).depth_m, far_m);
  // sigma_z = z^2 sigma_d / (B f): 8 m gives 4.6 cm.
  const solo::StereoSensorOptions o;
  EXPECT_NEAR(near_std, near_m * near_m * o.disparity_noise_px / (o.baseline_m * 1000), 0.003);
  EXPECT_NEAR(far_std / near_std, (far_m / near_m) * (far_m / near_m), 0.1);
}

TEST(StereoSensor, OcclusionBandLeftOfANearBoxHasTheDisparityJumpAsWidth) {
  const int width = 640, height = 40, box_left = 300, box_right = 400;
  const double focal_px = 500, near_m = 5, far_m = 20;
  cv::Mat depth = plane(width, height, static_cast<float>(far_m));
  depth.colRange(box_left, box_right + 1).setTo(near_m);
  const solo::StereoSensorOptions o = noiselessStereo();
  const solo::StereoDepth stereo =
      solo::simulateStereoDepth(depth, camera(width, height, focal_px), texturedDay(width, height), 1, o);
  const double band_px = o.baseline_m * focal_px * (1 / near_m - 1 / far_m);  // 15.7
  const int expected_width = static_cast<int>(std::floor(band_px));
  EXPECT_EQ(stereo.holes.occluded, std::int64_t{expected_width} * height);
  for (int y = 0; y < height; ++y)
    for (int x = static_cast<int>(stereo.max_disparity_px) + 1; x < width; ++x) {
      const bool in_band = x >= box_left - expected_width && x < box_left;
      ASSERT_EQ(stereo.depth_m.at<float>(y, x) == 0, in_band) << "x " << x;
    }
}

TEST(StereoSensor, TexturelessImageIsMostlyInvalid) {
  const int width = 320, height = 80;
  const cv::Mat flat(height, width, CV_32FC3, cv::Scalar::all(0.5));
  const solo::StereoDepth stereo =
      solo::simulateStereoDepth(plane(width, height, 10), camera(width, height, 300), flat, 1);
  EXPECT_LT(cv::countNonZero(stereo.depth_m), width * height / 100);
  EXPECT_GT(stereo.holes.textureless, width * height * 8 / 10);
}

TEST(StereoSensor, FlatRegionsAreMatchedUpToTheReachFromTexture) {
  const int width = 640, height = 60, flat_left = 200, flat_right = 440;
  cv::Mat day = texturedDay(width, height);
  day.colRange(flat_left, flat_right).setTo(cv::Scalar::all(0.4));
  const solo::StereoDepth stereo =
      solo::simulateStereoDepth(plane(width, height, 10), camera(width, height, 500), day, 1, noiselessStereo());
  EXPECT_DOUBLE_EQ(stereo.texture_reach_px, 20.0);  // 640 * 64 / 2048
  const cv::Mat row = stereo.depth_m.row(height / 2);
  EXPECT_GT(row.at<float>(flat_left + 10), 0.f);  // 10 px into the flat region: carried
  EXPECT_GT(row.at<float>(flat_right - 10), 0.f);
  EXPECT_EQ(row.at<float>(320), 0.f);  // 120 px in: textureless
  // Flat windows start 4 px inside (half the 9 px window); the reach adds 20 px on each side.
  EXPECT_EQ(stereo.holes.textureless, std::int64_t{height} * (flat_right - flat_left - 2 * (4 + 20)));
}

TEST(StereoSensor, FarBeyondTheMinimumDisparityIsInvalid) {
  const int width = 320, height = 80;
  // 0.1 px of disparity: 6 sigma below the 1 px minimum.
  const solo::StereoDepth stereo =
      solo::simulateStereoDepth(plane(width, height, 1000), camera(width, height, 500), texturedDay(width, height), 1);
  EXPECT_EQ(cv::countNonZero(stereo.depth_m), 0);
  EXPECT_EQ(stereo.holes.too_far + stereo.holes.left_border, std::int64_t{width} * height);
}

TEST(LidarSensor, ReturnsMatchTheFiringsInTheFieldOfView) {
  // 90 x 90 degrees: every beam (-24.8 to 2 degrees) is in view at every azimuth within
  // +-45 degrees, one pixel at most per firing (azimuth step 1.57 px, beams 7 px apart).
  const int side = 2000;
  const double focal_px = 1000, z_m = 10;
  const solo::LidarSensorOptions o;
  const solo::LidarDepth lidar = solo::simulateLidarDepth(plane(side, side, z_m), camera(side, side, focal_px), 1, o);
  const int azimuths = 2 * static_cast<int>(std::floor(45 / o.azimuth_step_deg - 1e-9)) + 1;  // |k * step| < 45 deg
  const double expected = 64.0 * azimuths;
  EXPECT_NEAR(lidar.returns, expected, 2 * 64);
  EXPECT_EQ(cv::countNonZero(lidar.depth_m), lidar.returns);

  double highest_deg = -90;
  double sum = 0, sum_sq = 0, worst_m = 0;
  for (int v = 0; v < side; ++v)
    for (int u = 0; u < side; ++u) {
      const float z = lidar.depth_m.at<float>(v, u);
      if (z <= 0) continue;
      const double x = (u - (side - 1) / 2.0) / focal_px, y = (v - (side - 1) / 2.0) / focal_px;
      highest_deg = std::max(highest_deg, std::atan2(-y, std::hypot(x, 1.0)) * 180 / kPi);
      sum += z - z_m;
      sum_sq += (z - z_m) * (z - z_m);
      worst_m = std::max(worst_m, std::abs(z - z_m));
    }
  // No return above the top beam (half a pixel is 0.03 degrees), and the top beam is there.
  EXPECT_LE(highest_deg, o.max_elevation_deg + 0.03);
  EXPECT_GE(highest_deg, o.max_elevation_deg - 0.03);
  // z noise = range noise * cos(angle to the axis), the cosine between 0.64 and 1.
  const double std_m = std::sqrt(sum_sq / lidar.returns - (sum / lidar.returns) * (sum / lidar.returns));
  EXPECT_GT(std_m, 0.64 * o.range_noise_m * 0.95);
  EXPECT_LT(std_m, o.range_noise_m * 1.05);
  EXPECT_LT(worst_m, 6 * o.range_noise_m);
}

TEST(LidarSensor, ShareOfPixelsAt1920x1080IsSparse) {
  const solo::PinholeCamera cam = solo::PinholeCamera::acdc();
  const solo::LidarDepth lidar = solo::simulateLidarDepth(plane(1920, 1080, 15), cam, 1);
  const double share = static_cast<double>(cv::countNonZero(lidar.depth_m)) / (1920 * 1080);
  EXPECT_GT(share, 0.01);
  EXPECT_LT(share, 0.04);
}

TEST(LidarSensor, NothingBeyondTheMaximumRange) {
  const solo::LidarDepth lidar = solo::simulateLidarDepth(plane(400, 300, 130), camera(400, 300, 300), 1);
  EXPECT_EQ(lidar.returns, 0);
  EXPECT_EQ(cv::countNonZero(lidar.depth_m), 0);
}

TEST(MonoSensor, MedianRatioIsTheDrawnScale) {
  // A receding ground plane under a sky band, with a box in front.
  const int width = 400, height = 300;
  cv::Mat depth(height, width, CV_32F, cv::Scalar(0));
  for (int y = 60; y < height; ++y) depth.row(y).setTo(1.5 * 300 / (y - 50));
  depth(cv::Rect(150, 100, 80, 120)).setTo(6);
  solo::MonoSensorOptions o;
  o.inverse_shift_max_per_m = 0;
  const solo::MonoDepth mono = solo::simulateMonoDepth(depth, 5, o);
  EXPECT_NE(mono.scale, 1.0);
  EXPECT_LE(std::abs(mono.scale - 1), o.scale_error_max);
  std::vector<double> ratios;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const float exact = depth.at<float>(y, x), est = mono.depth_m.at<float>(y, x);
      ASSERT_EQ(exact > 0, est > 0) << "dense, holes only where the exact depth has none";
      if (exact > 0) ratios.push_back(est / exact);
    }
  EXPECT_NEAR(median(ratios), mono.scale, 0.002);

  // With the default shift: the inverse depths are offset by the drawn shift.
  const solo::MonoDepth shifted = solo::simulateMonoDepth(depth, 5);
  EXPECT_NE(shifted.inverse_shift_per_m, 0.0);
  std::vector<double> offsets;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      if (depth.at<float>(y, x) > 0)
        offsets.push_back(1 / shifted.depth_m.at<float>(y, x) - 1 / (shifted.scale * depth.at<float>(y, x)));
  EXPECT_NEAR(median(offsets), shifted.inverse_shift_per_m, 1e-4);
}

TEST(DepthSensor, SameSeedSameOutputOtherSeedDifferent) {
  const int width = 320, height = 200;
  cv::Mat depth = plane(width, height, 12);
  depth(cv::Rect(100, 50, 60, 100)).setTo(4);
  const solo::PinholeCamera cam = camera(width, height, 250);
  const cv::Mat day = texturedDay(width, height);
  EXPECT_TRUE(identical(solo::simulateStereoDepth(depth, cam, day, 9).depth_m,
                        solo::simulateStereoDepth(depth, cam, day, 9).depth_m));
  EXPECT_FALSE(identical(solo::simulateStereoDepth(depth, cam, day, 9).depth_m,
                         solo::simulateStereoDepth(depth, cam, day, 10).depth_m));
  EXPECT_TRUE(
      identical(solo::simulateLidarDepth(depth, cam, 9).depth_m, solo::simulateLidarDepth(depth, cam, 9).depth_m));
  EXPECT_FALSE(
      identical(solo::simulateLidarDepth(depth, cam, 9).depth_m, solo::simulateLidarDepth(depth, cam, 10).depth_m));
  EXPECT_TRUE(identical(solo::simulateMonoDepth(depth, 9).depth_m, solo::simulateMonoDepth(depth, 9).depth_m));
  EXPECT_FALSE(identical(solo::simulateMonoDepth(depth, 9).depth_m, solo::simulateMonoDepth(depth, 10).depth_m));
}

TEST(DepthSensor, SynthFolderWithStereoHoldsCityscapesDisparityAndCamera) {
  TempDir dir;
  solo::SyntheticSceneOptions o;
  o.width = 320;
  o.height = 180;
  o.depth_source = "stereo";
  solo::writeSyntheticScene(dir / "s", o);
  const cv::Mat depth = solo::readDepth(dir / "s/est/depth.exr", 0);
  const cv::Mat png = solo::readImageRaw(dir / "s/est/disparity.png");
  const solo::PinholeCamera cam = solo::readCityscapesCamera(dir / "s/est/camera.json");
  std::ifstream camera_file(dir / "s/est/camera.json");
  const double baseline_m = nlohmann::json::parse(camera_file)["extrinsic"]["baseline"].get<double>();
  EXPECT_DOUBLE_EQ(baseline_m, solo::StereoSensorOptions::kCityscapesBaselineM);
  ASSERT_EQ(depth.size(), cv::Size(320, 180));
  ASSERT_EQ(png.size(), depth.size());
  int valid = 0;
  for (int y = 0; y < depth.rows; ++y)
    for (int x = 0; x < depth.cols; ++x) {
      const float p = png.at<float>(y, x);
      ASSERT_EQ(p > 0, depth.at<float>(y, x) > 0);
      if (p <= 0) continue;
      ++valid;
      ASSERT_NEAR(depth.at<float>(y, x), baseline_m * cam.fx / ((p - 1) / 256), 1e-4 * depth.at<float>(y, x));
    }
  EXPECT_GT(valid, 0);
  std::ifstream record_file(dir / "s/synth.json");
  const nlohmann::json record = nlohmann::json::parse(record_file);
  EXPECT_EQ(record["depth_source"]["sensor"], "stereo");
  EXPECT_NEAR(record["depth_source"]["valid_share"].get<double>(), static_cast<double>(valid) / depth.total(), 1e-12);

  // Replacing the folder with --force accepts the stereo files; the default writes neither.
  o.depth_source.clear();
  o.force = true;
  solo::writeSyntheticScene(dir / "s", o);
  EXPECT_FALSE(std::filesystem::exists(dir / "s/est/disparity.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "s/est/camera.json"));
}

TEST(DepthSensor, SynthFolderRefusesAnUnknownSource) {
  TempDir dir;
  solo::SyntheticSceneOptions o;
  o.width = 64;
  o.height = 32;
  o.depth_source = "sonar";
  EXPECT_THROW(solo::writeSyntheticScene(dir / "s", o), solo::InputError);
}
