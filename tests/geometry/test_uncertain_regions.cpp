// Step 3 of depth refinement: uncertain regions.

#include <solo/geometry/uncertain_regions.h>

#include <gtest/gtest.h>

namespace {

struct Scene2 {
  cv::Mat depth, labels;
};

// 40 x 40: left half label 26 at near_m, right half label 11 at far_m.
Scene2 twoSegments(float near_m, float far_m, int right_label = 11) {
  Scene2 s{cv::Mat(40, 40, CV_32F, cv::Scalar(near_m)), cv::Mat(40, 40, CV_32S, cv::Scalar(26))};
  s.depth.colRange(20, 40).setTo(far_m);
  s.labels.colRange(20, 40).setTo(right_label);
  return s;
}

solo::UncertainRegionOptions farLimit() {
  solo::UncertainRegionOptions o;
  o.max_depth_m = 100;
  return o;
}

TEST(UncertainRegions, BandAroundASegmentBoundaryWithADepthStep) {
  // Windows with x0 in 11..19 straddle columns 19|20; their variance is at least
  // 0.1 * 0.9 * 1 m^2 > 0.01. Their pixels: columns 11..28, every row.
  const Scene2 s = twoSegments(5, 6);
  const auto r = solo::findUncertainRegions(s.depth, s.labels, farLimit());
  for (int x = 0; x < 40; ++x)
    EXPECT_EQ(s.depth.rows * (x >= 11 && x <= 28), cv::countNonZero(r.mask.col(x))) << "column " << x;
  EXPECT_EQ(std::get<std::int64_t>(*r.report.find("uncertain_pixels")), 18 * 40);
}

TEST(UncertainRegions, NeedsTwoSegmentsAndEnoughVariance) {
  const Scene2 same_label = twoSegments(5, 6, 26);
  EXPECT_EQ(cv::countNonZero(solo::findUncertainRegions(same_label.depth, same_label.labels, farLimit()).mask), 0);
  const Scene2 flat = twoSegments(5, 5.05f);  // variance <= 0.25 * 0.05^2 < 0.01
  EXPECT_EQ(cv::countNonZero(solo::findUncertainRegions(flat.depth, flat.labels, farLimit()).mask), 0);
}

TEST(UncertainRegions, WindowsReachingBeyondTheMidRangeAreIgnored) {
  // Default r = (5 + 6) / 2: every straddling window holds a 6 m depth > r.
  const Scene2 s = twoSegments(5, 6);
  const auto r = solo::findUncertainRegions(s.depth, s.labels);
  EXPECT_EQ(cv::countNonZero(r.mask), 0);
  EXPECT_DOUBLE_EQ(std::get<double>(*r.report.find("max_depth")), 5.5);
}

TEST(UncertainRegions, InvalidAndSkyPixelsDoNotCountInTheVariance) {
  Scene2 s = twoSegments(5, 0);  // right half: sky (label 23), no depth
  s.labels.colRange(20, 40).setTo(23);
  const auto r = solo::findUncertainRegions(s.depth, s.labels, farLimit());
  EXPECT_EQ(cv::countNonZero(r.mask), 0) << "one valid depth value: variance 0";
}

TEST(UncertainRegions, EverythingUncertainOnACheckerboard) {
  cv::Mat depth(20, 20, CV_32F), labels(20, 20, CV_32S);
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 20; ++x) {
      const bool odd = (x + y) % 2;
      depth.at<float>(y, x) = odd ? 2.f : 3.f;
      labels.at<int>(y, x) = odd ? 24 : 26;
    }
  const auto r = solo::findUncertainRegions(depth, labels, farLimit());
  EXPECT_EQ(cv::countNonZero(r.mask), 400);
  EXPECT_DOUBLE_EQ(std::get<double>(*r.report.find("uncertain_share")), 1.0);
}

TEST(UncertainRegions, AnImageOnePixelWideUsesWindowsOfItsWidth) {
  cv::Mat depth(30, 1, CV_32F, cv::Scalar(2)), labels(30, 1, CV_32S, cv::Scalar(17));
  depth.rowRange(15, 30).setTo(4);
  labels.rowRange(15, 30).setTo(11);
  const auto r = solo::findUncertainRegions(depth, labels, farLimit());
  // 10 x 1 windows with y0 in 6..14 straddle rows 14|15: rows 6..23.
  for (int y = 0; y < 30; ++y) EXPECT_EQ(r.mask.at<uchar>(y, 0) != 0, y >= 6 && y <= 23) << y;
  const auto tiny = solo::findUncertainRegions(cv::Mat(1, 1, CV_32F, cv::Scalar(1)), cv::Mat(1, 1, CV_32S, cv::Scalar(7)));
  EXPECT_EQ(cv::countNonZero(tiny.mask), 0);
}

}  // namespace
