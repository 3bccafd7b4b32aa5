// Depth completion (geometry/depth_completion.h): planes stay planes, instance borders hold,
// the sky stays empty, sparse rows become dense, and the output is always finite and bounded.

#include <solo/geometry/depth_completion.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

namespace {

// Inverse depth of a plane is affine in the pixel coordinates: 1/z = a x + b y + c.
cv::Mat planeDepth(cv::Size size, double a, double b, double c) {
  cv::Mat depth(size, CV_32F);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) depth.at<float>(y, x) = static_cast<float>(1.0 / (a * x + b * y + c));
  return depth;
}

double meanAbsRelOver(const cv::Mat& estimate, const cv::Mat& truth, const cv::Mat& mask) {
  double sum = 0;
  int n = 0;
  for (int y = 0; y < truth.rows; ++y)
    for (int x = 0; x < truth.cols; ++x)
      if (mask.at<std::uint8_t>(y, x)) {
        sum += std::abs(estimate.at<float>(y, x) - truth.at<float>(y, x)) / truth.at<float>(y, x);
        ++n;
      }
  return n > 0 ? sum / n : 0;
}

TEST(PullPush, ReproducesAConstantFromOneSample) {
  cv::Mat value(37, 53, CV_32F, cv::Scalar(0)), weight(37, 53, CV_32F, cv::Scalar(0));
  value.at<float>(20, 7) = 3.5f, weight.at<float>(20, 7) = 1;
  const cv::Mat dense = solo::pullPushInterpolate(value, weight);
  double lo = 0, hi = 0;
  cv::minMaxLoc(dense, &lo, &hi);
  EXPECT_FLOAT_EQ(lo, 3.5);
  EXPECT_FLOAT_EQ(hi, 3.5);
}

TEST(PullPush, NoSampleGivesZeros) {
  const cv::Mat dense = solo::pullPushInterpolate(cv::Mat(9, 5, CV_32F, cv::Scalar(2)), cv::Mat(9, 5, CV_32F, cv::Scalar(0)));
  EXPECT_EQ(cv::countNonZero(dense), 0);
}

TEST(DepthCompletion, AHoleInATiltedPlaneIsFilledOnThePlane) {
  // A road-like plane seen at a slant: depth 5 m at the bottom to 40 m at the top.
  const cv::Size size(160, 120);
  const cv::Mat truth = planeDepth(size, 0.0004, 0.0017, 0.025);
  cv::Mat depth = truth.clone();
  const cv::Rect hole(50, 40, 40, 30);
  depth(hole).setTo(0);
  const solo::DepthCompletionResult r = solo::completeDepth(depth, {}, {}, {});
  EXPECT_EQ(cv::countNonZero(r.filled), hole.area());
  EXPECT_EQ(cv::countNonZero(r.depth_m > 0), size.area());
  // The road's inverse depth fits a plane: the hole continues it.
  EXPECT_LT(meanAbsRelOver(r.depth_m, truth, r.filled), 1e-4);
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("planar_segments")), 1);
  // Valid pixels are returned unchanged.
  EXPECT_EQ(cv::countNonZero((r.depth_m != truth) & (depth > 0)), 0);
}

TEST(DepthCompletion, TheRelaxationBringsACurvedSurfaceCloserThanPullPushAlone) {
  // A curved surface (no plane fits): pull-push blends scales, the membrane is smoother.
  const cv::Size size(160, 120);
  cv::Mat truth(size, CV_32F);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x)
      truth.at<float>(y, x) = static_cast<float>(1.0 / (0.05 + 0.02 * std::sin(x / 25.0) + 0.0004 * y));
  cv::Mat depth = truth.clone();
  depth(cv::Rect(50, 40, 40, 30)).setTo(0);
  solo::DepthCompletionOptions relaxed, pull_push_only;
  pull_push_only.relax_iterations = 0;
  const solo::DepthCompletionResult r = solo::completeDepth(depth, {}, {}, {}, relaxed);
  const solo::DepthCompletionResult coarse = solo::completeDepth(depth, {}, {}, {}, pull_push_only);
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("planar_segments")), 0);
  EXPECT_LT(meanAbsRelOver(r.depth_m, truth, r.filled), 0.5 * meanAbsRelOver(coarse.depth_m, truth, coarse.filled));
  EXPECT_LT(meanAbsRelOver(r.depth_m, truth, r.filled), 0.02);
}

TEST(DepthCompletion, NeverFillsAcrossAnInstanceBorderWhereBothSidesHaveDepth) {
  const cv::Size size(80, 40);
  cv::Mat depth(size, CV_32F, cv::Scalar(10)), instances(size, CV_32S, cv::Scalar(26000));
  depth(cv::Rect(40, 0, 40, 40)).setTo(20);
  instances(cv::Rect(40, 0, 40, 40)).setTo(11);  // a building behind a car
  depth(cv::Rect(30, 10, 20, 20)).setTo(0);      // a hole across the border
  const solo::DepthCompletionResult r = solo::completeDepth(depth, {}, {}, instances);
  for (int y = 10; y < 30; ++y)
    for (int x = 30; x < 50; ++x) ASSERT_NEAR(r.depth_m.at<float>(y, x), x < 40 ? 10.f : 20.f, 1e-4) << x << "," << y;
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("segments_filled_within")), 2);
}

TEST(DepthCompletion, AnInstanceWithoutDepthIsFilledFromItsSurroundings) {
  const cv::Size size(60, 60);
  cv::Mat depth(size, CV_32F, cv::Scalar(12)), instances(size, CV_32S, cv::Scalar(11));
  const cv::Rect pole(25, 10, 10, 50);
  instances(pole).setTo(17);
  depth(pole).setTo(0);
  const solo::DepthCompletionResult r = solo::completeDepth(depth, {}, {}, instances);
  EXPECT_EQ(cv::countNonZero(r.filled), pole.area());
  double lo = 0, hi = 0;
  cv::minMaxLoc(r.depth_m(pole), &lo, &hi);
  EXPECT_NEAR(lo, 12, 1e-4);
  EXPECT_NEAR(hi, 12, 1e-4);
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("segments_without_depth")), 1);
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("pixels_filled_across_segments")), pole.area());
}

TEST(DepthCompletion, TheSkyStaysEmpty) {
  const cv::Size size(50, 40);
  cv::Mat depth(size, CV_32F, cv::Scalar(8)), labels(size, CV_32S, cv::Scalar(7));
  labels(cv::Rect(0, 0, 50, 15)).setTo(23);
  depth(cv::Rect(0, 0, 50, 15)).setTo(0);
  depth(cv::Rect(10, 25, 5, 5)).setTo(0);
  const solo::DepthCompletionResult with_labels = solo::completeDepth(depth, {}, labels, {});
  EXPECT_EQ(cv::countNonZero(with_labels.depth_m(cv::Rect(0, 0, 50, 15))), 0);
  EXPECT_EQ(cv::countNonZero(with_labels.filled), 25);
  EXPECT_EQ(cv::countNonZero(with_labels.sky), 50 * 15);
  // Without labels: the invalid pixels above a column's first depth are sky.
  const solo::DepthCompletionResult by_rule = solo::completeDepth(depth, {}, {}, {});
  EXPECT_EQ(cv::countNonZero(by_rule.sky), 50 * 15);
  EXPECT_EQ(cv::countNonZero(by_rule.filled), 25);
  EXPECT_FLOAT_EQ(by_rule.depth_m.at<float>(27, 12), 8);
}

TEST(DepthCompletion, SparseRowsLikeLidarBecomeDense) {
  const cv::Size size(200, 100);
  const cv::Mat truth = planeDepth(size, 0.0002, 0.002, 0.02);
  cv::Mat depth(size, CV_32F, cv::Scalar(0));
  for (int y = 14; y < size.height; y += 7)
    for (int x = 0; x < size.width; x += 3) depth.at<float>(y, x) = truth.at<float>(y, x);
  const solo::DepthCompletionResult r = solo::completeDepth(depth, {}, {}, {});
  // Every pixel from the first row of returns down has a depth (the columns between returns
  // take their neighbours' sky bound); the rows above the highest beam are sky.
  EXPECT_EQ(cv::countNonZero(r.sky), 14 * size.width);
  EXPECT_EQ(cv::countNonZero(r.depth_m > 0), size.area() - 14 * size.width);
  EXPECT_LT(meanAbsRelOver(r.depth_m, truth, r.filled), 0.01);
}

TEST(DepthCompletion, ScatteredReturnsWithoutLabelsAreInterpolatedNotCarriedUpColumns) {
  // A far facade (40-48 m) over a road (5-20 m toward the horizon), 1 % of the pixels with a
  // return, scattered (a projected LiDAR sweep), no labels. A column whose first return lies on
  // the road must not carry the road's depth up into the facade: the facade's holes are
  // interpolated from the facade's returns around them.
  const cv::Size size(240, 120);
  cv::Mat truth(size, CV_32F);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x)
      truth.at<float>(y, x) = y < 50 ? 40.0f + 8.0f * x / size.width : static_cast<float>(1.0 / (0.05 + 0.0025 * (y - 50)));
  std::mt19937 rng(7);
  std::bernoulli_distribution keep(0.01);
  cv::Mat depth(size, CV_32F, cv::Scalar(0));
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x)
      if (keep(rng)) depth.at<float>(y, x) = truth.at<float>(y, x);
  const solo::DepthCompletionResult r = solo::completeDepth(depth, {}, {}, {});
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("extended_upward_pixels")), 0);
  cv::Mat facade_filled = r.filled.clone();
  facade_filled(cv::Rect(0, 50, size.width, size.height - 50)).setTo(0);
  ASSERT_GT(cv::countNonZero(facade_filled), 1000);
  // Measured 0.14 (pull-push mixes the two surfaces in the rows next to their edge); carried
  // up the columns (4 974 pixels extended) the facade's filled pixels were 0.57 off.
  EXPECT_LT(meanAbsRelOver(r.depth_m, truth, facade_filled), 0.2);
}

// A 90x60 wall seen at an angle (depth varies along x only, as for any vertical plane; its
// exact depth in `truth`), the sky in rows 0-9 and no depth in rows 10-24 (above a LiDAR's
// highest beam); labels 11 (building, or `wall_label`) and 23 (sky).
struct WallAboveTheHighestReturn {
  cv::Mat depth, labels, truth;
  explicit WallAboveTheHighestReturn(int wall_label = 11)
      : depth(60, 90, CV_32F), labels(60, 90, CV_32S, cv::Scalar(wall_label)) {
    truth = planeDepth(depth.size(), 0.0008, 0, 0.02);
    labels(cv::Rect(0, 0, 90, 10)).setTo(23);
    truth.copyTo(depth);
    depth(cv::Rect(0, 0, 90, 25)).setTo(0);
  }
  // An object of labelId `label` at depth_m over `rect`, in the truth and, below row 25 or
  // where it rises above it, in the depth.
  void placeObject(const cv::Rect& rect, int label, float depth_m) {
    labels(rect).setTo(label);
    truth(rect).setTo(depth_m);
    depth(rect).setTo(depth_m);
  }
  // Completes the depth; every pixel of `rect` must come back on the wall's plane.
  solo::DepthCompletionResult completedOnTheWallOver(const cv::Rect& rect) const {
    const solo::DepthCompletionResult r = solo::completeDepth(depth, {}, labels, {});
    for (int y = rect.y; y < rect.y + rect.height; ++y)
      for (int x = rect.x; x < rect.x + rect.width; ++x)
        EXPECT_NEAR(r.depth_m.at<float>(y, x), truth.at<float>(y, x), 1e-3 * truth.at<float>(y, x)) << x << ", " << y;
    return r;
  }
};

TEST(DepthCompletion, AFacadeAboveTheHighestReturnKeepsItsColumnsDepth) {
  // A near car in front of the wall's lower part, below its highest return.
  WallAboveTheHighestReturn wall;
  wall.placeObject(cv::Rect(20, 30, 30, 20), 26, 6);
  const solo::DepthCompletionResult r = wall.completedOnTheWallOver(cv::Rect(0, 10, 90, 15));
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("extended_upward_pixels")), 90 * 15);
  EXPECT_EQ(cv::countNonZero(r.depth_m(cv::Rect(0, 0, 90, 10))), 0);
}

TEST(DepthCompletion, AFacadeAboveACarTallerThanTheHighestReturnKeepsTheFacadesPlane) {
  // A car in front of the wall (columns 30-45) whose roof at row 20 is above the wall's highest
  // return: in those columns the highest return is the car's. The wall above the car takes the
  // wall's own plane, not the car's 6 m.
  WallAboveTheHighestReturn wall;
  wall.placeObject(cv::Rect(30, 20, 16, 40), 26, 6);
  const solo::DepthCompletionResult r = wall.completedOnTheWallOver(cv::Rect(30, 10, 16, 10));
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("extended_upward_pixels")), 74 * 15);
}

TEST(DepthCompletion, ASegmentWithDepthIsKnownWhateverItsIdAndWhereverItsDepthIs) {
  // The wall unlabelled (id 0) and the car from column 30 to the right edge: the wall's only
  // depth starts every row it has depth in, before the car's.
  WallAboveTheHighestReturn wall(0);
  wall.placeObject(cv::Rect(30, 20, 60, 40), 26, 6);
  wall.completedOnTheWallOver(cv::Rect(30, 10, 60, 10));
}

TEST(DepthCompletion, ExtremeRangesAndImageEdgesStayFiniteAndBounded) {
  // 0.5 m beside 1 km, a hole between them, and an edge-aware guide with a hard edge.
  const cv::Size size(64, 48);
  cv::Mat depth(size, CV_32F, cv::Scalar(0.5)), image(size, CV_32FC3, cv::Scalar::all(0.2));
  depth(cv::Rect(32, 0, 32, 48)).setTo(1000);
  image(cv::Rect(32, 0, 32, 48)).setTo(cv::Scalar::all(0.9));
  depth(cv::Rect(20, 10, 24, 30)).setTo(0);
  const solo::DepthCompletionResult r = solo::completeDepth(depth, image, {}, {});
  double lo = 0, hi = 0;
  cv::minMaxLoc(r.depth_m, &lo, &hi);
  EXPECT_GE(lo, 0.5);
  EXPECT_LE(hi, 1000.0);
  EXPECT_TRUE(cv::checkRange(r.depth_m));
  // The guide's edge keeps the two sides apart: the hole's left half stays near, its right far.
  EXPECT_LT(r.depth_m.at<float>(25, 22), 1.0f);
  EXPECT_GT(r.depth_m.at<float>(25, 41), 100.0f);
}

TEST(DepthCompletion, NoValidDepthIsReturnedAsItIs) {
  const cv::Mat depth(10, 10, CV_32F, cv::Scalar(0));
  const solo::DepthCompletionResult r = solo::completeDepth(depth, {}, {}, {});
  EXPECT_EQ(cv::countNonZero(r.depth_m), 0);
  EXPECT_EQ(cv::countNonZero(r.filled), 0);
}

}  // namespace
