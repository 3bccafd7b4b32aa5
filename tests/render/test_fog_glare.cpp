#include <solo/post/fog_glare.h>

#include "test_support.h"

#include <cmath>
#include <random>

namespace {

std::string method(const solo::StageReport& r) {
  const solo::MetricValue* v = r.find("method");
  return v ? std::get<std::string>(*v) : std::string();
}

double maxAbsDifference(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_INF); }

}  // namespace

TEST(FogGlare, KernelSumsToOneIsSymmetricAndHasTheReferenceEnergyProfile) {
  const cv::Mat k = solo::fogGlowKernel(9);
  ASSERT_EQ(k.rows, 512);
  ASSERT_EQ(k.cols, 512);
  EXPECT_NEAR(cv::sum(k)[0], 1.0, 1e-5);
  const int c = 256;
  EXPECT_EQ(cv::countNonZero(k.row(0)), 0);
  EXPECT_EQ(cv::countNonZero(k.col(0)), 0);
  for (const auto& [dy, dx] : std::vector<std::pair<int, int>>{{0, 1}, {3, 7}, {100, 20}, {255, 255}}) {
    EXPECT_FLOAT_EQ(k.at<float>(c + dy, c + dx), k.at<float>(c - dy, c - dx));
    EXPECT_FLOAT_EQ(k.at<float>(c + dy, c + dx), k.at<float>(c + dx, c + dy));
  }
  // Share of the energy within a radius (reference.md: 42 / 58 / 81 / 94 / 99 %).
  const double radii[] = {0, 5, 20, 50, 100};
  const double shares[] = {0.42, 0.58, 0.81, 0.94, 0.99};
  for (int i = 0; i < 5; ++i) {
    double inside = 0;
    for (int y = 0; y < 512; ++y)
      for (int x = 0; x < 512; ++x)
        if (std::hypot(y - c, x - c) <= radii[i]) inside += k.at<float>(y, x);
    EXPECT_NEAR(inside, shares[i], 0.006) << "radius " << radii[i];
  }
  EXPECT_THROW(solo::fogGlowKernel(12), std::invalid_argument);
}

TEST(FogGlare, SinglePixelGlowIsTheKernelAndPreservesEnergyByEveryMethod) {
  const cv::Mat k = solo::fogGlowKernel(9);
  for (const solo::GlareMethod m : {solo::GlareMethod::Direct, solo::GlareMethod::Fft, solo::GlareMethod::TiledFft}) {
    cv::Mat image = cv::Mat::zeros(600, 640, CV_32FC3);
    image.at<cv::Vec3f>(300, 310) = {2.f, 4.f, 6.f};
    solo::FogGlareOptions options;
    options.method = m;
    const solo::StageReport report = solo::applyFogGlare(image, options);
    ASSERT_FALSE(report.skipped);
    // output = input + glow: total energy doubles exactly when the kernel fits in the frame.
    const cv::Scalar total = cv::sum(image);
    EXPECT_NEAR(total[0], 4.0, 4.0 * 1e-4);
    EXPECT_NEAR(total[1], 8.0, 8.0 * 1e-4);
    EXPECT_NEAR(total[2], 12.0, 12.0 * 1e-4);
    EXPECT_NEAR(solo::test::metricNumber(report, "glow_in_frame_fraction"), 1.0, 1e-4);
    // The glow is the kernel times the pixel.
    EXPECT_NEAR(image.at<cv::Vec3f>(300, 310)[1], 4.0 * (1.0 + k.at<float>(256, 256)), 1e-4);
    EXPECT_NEAR(image.at<cv::Vec3f>(300 + 40, 310 - 17)[1], 4.0 * k.at<float>(256 + 40, 256 - 17), 1e-6);
    EXPECT_NEAR(image.at<cv::Vec3f>(300 - 255, 310)[2], 6.0 * k.at<float>(1, 256), 1e-7);
    EXPECT_NEAR(image.at<cv::Vec3f>(300 - 256, 310)[2], 0.0, 1e-7);
  }
}

TEST(FogGlare, ScatterFractionScalesTheGlowOfTheExcessOnly) {
  // A pixel of Y = 101 over a threshold of 1 with a 2 % scatter: the glow carries 0.02 x 100 = 2
  // in luminance, spread as the kernel; the pixel's own value stays (it clips anyway).
  const cv::Mat k = solo::fogGlowKernel(7);
  for (const solo::GlareMethod m : {solo::GlareMethod::Direct, solo::GlareMethod::Fft}) {
    cv::Mat image = cv::Mat::zeros(200, 220, CV_32FC3);
    image.at<cv::Vec3f>(100, 110) = {101.f, 101.f, 101.f};
    solo::FogGlareOptions options;
    options.size = 7;
    options.threshold = 1.0;
    options.scatter_fraction = 0.02;
    options.method = m;
    const solo::StageReport report = solo::applyFogGlare(image, options);
    EXPECT_NEAR(cv::sum(image)[1], 101.0 + 2.0, 1e-3);
    EXPECT_NEAR(image.at<cv::Vec3f>(100 + 9, 110 - 4)[1], 2.0 * k.at<float>(64 + 9, 64 - 4), 1e-6);
    EXPECT_NEAR(solo::test::metricNumber(report, "glow_in_frame_fraction"), 1.0, 1e-4);
    EXPECT_DOUBLE_EQ(solo::test::metricNumber(report, "scatter_fraction"), 0.02);
  }
  cv::Mat image = cv::Mat::zeros(8, 8, CV_32FC3);
  solo::FogGlareOptions options;
  options.scatter_fraction = 0;
  EXPECT_THROW(solo::applyFogGlare(image, options), std::invalid_argument);
  options.scatter_fraction = 1.5;
  EXPECT_THROW(solo::applyFogGlare(image, options), std::invalid_argument);
}

TEST(FogGlare, MethodsAgreeOnScatteredSpotsNearTheBorders) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> ys(0, 399), xs(0, 899);
  std::uniform_real_distribution<float> v(0.5f, 50.f);
  cv::Mat original = cv::Mat::zeros(400, 900, CV_32FC3);
  for (int i = 0; i < 40; ++i) original.at<cv::Vec3f>(ys(rng), xs(rng)) = {v(rng), v(rng), v(rng)};
  original.at<cv::Vec3f>(0, 0) = {30, 30, 30};
  original.at<cv::Vec3f>(399, 899) = {30, 30, 30};
  cv::Mat results[3];
  int i = 0;
  for (const solo::GlareMethod m : {solo::GlareMethod::Direct, solo::GlareMethod::Fft, solo::GlareMethod::TiledFft}) {
    results[i] = original.clone();
    solo::FogGlareOptions options;
    options.method = m;
    solo::applyFogGlare(results[i++], options);
  }
  EXPECT_LT(maxAbsDifference(results[0], results[1]), 1e-4);
  EXPECT_LT(maxAbsDifference(results[0], results[2]), 1e-4);
}

TEST(FogGlare, FullBrightFieldDoublesAwayFromTheBorders) {
  cv::Mat image(600, 700, CV_32FC3, cv::Scalar(1.0, 2.0, 0.5));
  const solo::StageReport report = solo::applyFogGlare(image, {});
  EXPECT_EQ(method(report), "fft");
  // Farther than the kernel radius (255 px) from every border the whole kernel (sum 1) lands.
  const cv::Vec3f centre = image.at<cv::Vec3f>(300, 350);
  EXPECT_NEAR(centre[0], 2.0, 1e-4);
  EXPECT_NEAR(centre[1], 4.0, 2e-4);
  EXPECT_NEAR(centre[2], 1.0, 1e-4);
  // A corner gets only the quarter of the kernel inside the frame, plus the centre tap.
  EXPECT_LT(image.at<cv::Vec3f>(0, 0)[1], 2.0 + 2.0 * 0.75);
  // The FFT is the image plus one kernel radius, not plus the full kernel width.
  EXPECT_LE(solo::test::metricNumber(report, "fft_rows"), cv::getOptimalDFTSize(600 + 256));
  EXPECT_LE(solo::test::metricNumber(report, "fft_cols"), cv::getOptimalDFTSize(700 + 256));
}

TEST(FogGlare, NothingAboveTheThresholdLeavesTheImageUnchanged) {
  cv::Mat image(50, 60, CV_32FC3);
  cv::randu(image, 0.0, 0.99);
  const cv::Mat before = image.clone();
  solo::FogGlareOptions options;
  options.threshold = 1.0;
  const solo::StageReport report = solo::applyFogGlare(image, options);
  EXPECT_TRUE(report.skipped);
  EXPECT_NE(report.skip_reason.find("no pixel brighter than the threshold"), std::string::npos);
  EXPECT_EQ(maxAbsDifference(image, before), 0.0);

  cv::Mat black = cv::Mat::zeros(40, 40, CV_32FC3);  // threshold 0: Y = 0 does not exceed it
  EXPECT_TRUE(solo::applyFogGlare(black, {}).skipped);
  EXPECT_EQ(cv::countNonZero(black.reshape(1)), 0);
  solo::FogGlareOptions negative;
  negative.threshold = -1;  // would make every black pixel divide by zero
  EXPECT_THROW(solo::applyFogGlare(black, negative), std::invalid_argument);
}

TEST(FogGlare, ThresholdKeepsOnlyTheExcessLuminanceAndTheColour) {
  cv::Mat image = cv::Mat::zeros(600, 600, CV_32FC3);
  image.at<cv::Vec3f>(300, 300) = {1.5f, 3.f, 6.f};  // Y = 3
  image.at<cv::Vec3f>(100, 100) = {0.5f, 0.9f, 0.5f};  // below the threshold
  solo::FogGlareOptions options;
  options.threshold = 1.0;
  const solo::StageReport report = solo::applyFogGlare(image, options);
  EXPECT_EQ(solo::test::metricNumber(report, "bright_pixels"), 1);
  // Contribution = colour * (3 - 1) / 3 = (1, 2, 4).
  const cv::Scalar total = cv::sum(image);
  EXPECT_NEAR(total[0], 1.5 + 0.5 + 1.0, 1e-4);
  EXPECT_NEAR(total[1], 3.0 + 0.9 + 2.0, 1e-4);
  EXPECT_NEAR(total[2], 6.0 + 0.5 + 4.0, 1e-4);
}

TEST(FogGlare, TinyVeryBrightSourceIsSplattedDirectlyAndStaysFinite) {
  cv::Mat image = cv::Mat::zeros(1080, 1920, CV_32FC3);
  image.at<cv::Vec3f>(0, 1919) = {1e6f, 1e6f, 1e6f};  // in a corner: 3/4 of the glow leaves the frame
  const solo::StageReport report = solo::applyFogGlare(image, {});
  EXPECT_EQ(method(report), "direct");
  EXPECT_TRUE(cv::checkRange(image));
  const cv::Mat k = solo::fogGlowKernel(9);
  EXPECT_NEAR(image.at<cv::Vec3f>(0, 1919)[1], 1e6 * (1.0 + k.at<float>(256, 256)), 1.0);
  // Quarter plane including its two edge lines and the centre: between 1/4 and 1/2 + centre.
  const double in_frame = solo::test::metricNumber(report, "glow_in_frame_fraction");
  EXPECT_GT(in_frame, 0.42 + 0.25 * 0.58);
  EXPECT_LT(in_frame, 0.42 + 0.5 * 0.58);
}

TEST(FogGlare, SpreadBrightClustersAreConvolvedTileByTile) {
  // Two dense 60x60 clusters near opposite corners of a 1080p frame, each inside one tile: too many pixels to
  // splat, and their common bounding box is the whole frame.
  cv::Mat image = cv::Mat::zeros(1080, 1920, CV_32FC3);
  image(cv::Rect(0, 0, 60, 60)).setTo(cv::Scalar(5, 5, 5));
  image(cv::Rect(1800, 900, 60, 60)).setTo(cv::Scalar(5, 5, 5));
  cv::Mat reference = image.clone();
  const solo::StageReport report = solo::applyFogGlare(image, {});
  EXPECT_EQ(method(report), "tiled-fft");
  EXPECT_EQ(solo::test::metricNumber(report, "fft_regions"), 2);
  solo::FogGlareOptions whole;
  whole.method = solo::GlareMethod::Fft;
  solo::applyFogGlare(reference, whole);
  EXPECT_LT(maxAbsDifference(image, reference), 1e-4);
}
