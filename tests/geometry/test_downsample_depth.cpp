// Downsampling a depth map for a coarser mesh (geometry/downsample_depth.h).

#include <solo/core/camera.h>
#include <solo/geometry/downsample_depth.h>

#include <gtest/gtest.h>

#include <cmath>

namespace {

// Depth of the plane n . X = offset seen through pixel (u, v) of `camera` (pixel centres at
// integer coordinates).
double planeDepth(const solo::PinholeCamera& camera, double u, double v) {
  const double nx = 0.3, ny = -0.5, nz = 0.8, offset = 6.0;
  const double x = (u - camera.cx) / camera.fx, y = (v - camera.cy) / camera.fy;
  return offset / (nx * x + ny * y + nz);
}

}  // namespace

TEST(DownsampleDepth, ATiltedPlaneGivesThePlanesDepthAtTheCoarsePixelCentres) {
  const solo::PinholeCamera camera{500, 500, 63.5, 47.5, 128, 96};
  cv::Mat depth(96, 128, CV_32F);
  for (int v = 0; v < 96; ++v)
    for (int u = 0; u < 128; ++u) depth.at<float>(v, u) = static_cast<float>(planeDepth(camera, u, v));
  for (const int factor : {2, 4}) {
    const cv::Mat coarse = solo::downsampleDepth(depth, factor);
    ASSERT_EQ(coarse.cols, 128 / factor);
    ASSERT_EQ(coarse.rows, 96 / factor);
    const solo::PinholeCamera coarse_camera = camera.scaledTo(coarse.cols, coarse.rows);
    double worst = 0;
    for (int v = 0; v < coarse.rows; ++v)
      for (int u = 0; u < coarse.cols; ++u) {
        const double truth = planeDepth(coarse_camera, u, v);
        worst = std::max(worst, std::abs(coarse.at<float>(v, u) - truth) / truth);
      }
    // Exact up to float rounding: inverse depth is affine in the image on a plane.
    EXPECT_LT(worst, 2e-6) << "factor " << factor;
  }
}

TEST(DownsampleDepth, AOnePixelPoleInFrontOfAWallSurvivesAtItsOwnDepth) {
  cv::Mat depth(8, 8, CV_32F, cv::Scalar(40.f));
  depth.col(5).setTo(5.f);  // a pole, one pixel wide, 35 m in front of the wall
  const cv::Mat coarse = solo::downsampleDepth(depth, 2);
  for (int v = 0; v < 4; ++v) {
    EXPECT_FLOAT_EQ(coarse.at<float>(v, 2), 5.f) << "the block holding the pole keeps the nearer depth, not a mean";
    EXPECT_FLOAT_EQ(coarse.at<float>(v, 1), 40.f);
    EXPECT_FLOAT_EQ(coarse.at<float>(v, 3), 40.f);
  }
}

TEST(DownsampleDepth, InvalidPixelsAreLeftOutAndAnEmptyBlockHasNoDepth) {
  cv::Mat depth(4, 4, CV_32F, cv::Scalar(10.f));
  depth(cv::Rect(0, 0, 2, 2)).setTo(0.f);                                       // sky
  depth.at<float>(2, 2) = std::numeric_limits<float>::quiet_NaN();              // invalid
  depth.at<float>(3, 3) = -1.f;                                                 // invalid
  depth.at<float>(0, 2) = 12.f;  // within 5 %? no: 20 % spread -> the nearer depth
  const cv::Mat coarse = solo::downsampleDepth(depth, 2);
  EXPECT_EQ(coarse.at<float>(0, 0), 0.f);
  EXPECT_FLOAT_EQ(coarse.at<float>(1, 1), 10.f);  // two valid pixels of 10 m
  EXPECT_FLOAT_EQ(coarse.at<float>(0, 1), 10.f);  // 10, 10, 10 and 12 m: spread 20 %, nearest
  depth.at<float>(0, 2) = 10.2f;                  // spread 2 %: the harmonic mean
  const cv::Mat near_plane = solo::downsampleDepth(depth, 2);
  EXPECT_NEAR(near_plane.at<float>(0, 1), 4.0 / (3 / 10.0 + 1 / 10.2), 1e-5);
}

TEST(DownsampleDepth, OddSizesDropTheRemainderAndBadArgumentsThrow) {
  const cv::Mat depth(9, 7, CV_32F, cv::Scalar(3.f));
  const cv::Mat coarse = solo::downsampleDepth(depth, 2);
  EXPECT_EQ(coarse.cols, 3);
  EXPECT_EQ(coarse.rows, 4);
  EXPECT_EQ(cv::countNonZero(coarse != 3.f), 0);
  EXPECT_THROW(solo::downsampleDepth(depth, 0), std::invalid_argument);
  EXPECT_THROW(solo::downsampleDepth(cv::Mat(4, 4, CV_64F, cv::Scalar(1.0)), 2), std::invalid_argument);
  const cv::Mat same = solo::downsampleDepth(depth, 1);
  EXPECT_EQ(cv::countNonZero(same != depth), 0);
}
