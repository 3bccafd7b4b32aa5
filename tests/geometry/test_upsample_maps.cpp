// Step 1 of depth refinement: upsampling to the image resolution.

#include <solo/geometry/upsample_maps.h>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>

namespace {

TEST(UpsampleMaps, BilinearDepthReproducesARampExactlyInside) {
  // d(x_low) = 10 + 2 x_low; at output x the input coordinate is (x + 0.5) / 2 - 0.5.
  cv::Mat low(4, 6, CV_32F);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 6; ++x) low.at<float>(y, x) = 10.f + 2.f * x + 0.5f * y;
  const cv::Mat up = solo::resizeValidBilinear(low, {12, 8});
  for (int y = 1; y < 7; ++y)
    for (int x = 1; x < 11; ++x) {
      const double xl = (x + 0.5) / 2 - 0.5, yl = (y + 0.5) / 2 - 0.5;
      EXPECT_NEAR(up.at<float>(y, x), 10 + 2 * xl + 0.5 * yl, 1e-4) << x << "," << y;
    }
}

TEST(UpsampleMaps, InvalidDepthIsNeitherBlendedNorInvented) {
  cv::Mat low(2, 2, CV_32F, cv::Scalar(4));
  low.at<float>(0, 1) = 0;  // sky in the top-right quarter
  const cv::Mat up = solo::resizeValidBilinear(low, {4, 4});
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      const float d = up.at<float>(y, x);
      EXPECT_TRUE(d == 0.f || std::abs(d - 4.f) < 1e-5f) << "valid depths are averages of valid samples only";
    }
  EXPECT_EQ(up.at<float>(0, 3), 0.f) << "deep inside the invalid quarter";
  EXPECT_FLOAT_EQ(up.at<float>(3, 0), 4.f);
}

TEST(UpsampleMaps, NormalsAreRenormalisedAndInvalidOnesExcluded) {
  cv::Mat low(1, 2, CV_32FC3);
  low.at<cv::Vec3f>(0, 0) = {0, 0, -1};
  low.at<cv::Vec3f>(0, 1) = {1, 0, 0};
  const cv::Mat up = solo::resizeNormalsBilinear(low, {4, 1});
  for (int x = 0; x < 4; ++x) {
    const cv::Vec3f n = up.at<cv::Vec3f>(0, x);
    EXPECT_NEAR(n.dot(n), 1.0, 1e-5);
  }
  // Between the two: the bisector direction of the weights 3/4 and 1/4 at x = 1.
  const cv::Vec3f mid = up.at<cv::Vec3f>(0, 1);
  EXPECT_NEAR(mid[0] / -mid[2], (0.25 / 0.75), 1e-5);
  cv::Mat with_invalid = low.clone();
  with_invalid.at<cv::Vec3f>(0, 1) = {0, 0, 0};
  const cv::Mat up2 = solo::resizeNormalsBilinear(with_invalid, {4, 1});
  EXPECT_NEAR(up2.at<cv::Vec3f>(0, 1)[2], -1.0, 1e-6) << "an invalid normal adds nothing";
  EXPECT_EQ(up2.at<cv::Vec3f>(0, 3), cv::Vec3f(0, 0, 0));
}

TEST(UpsampleMaps, JointBilateralUpsamplingFollowsTheGuidesEdge) {
  // Guide: black left of column 9, white from column 9 on (not on a low-res pixel boundary).
  // Map: 0.2 where the low-res pixel is mostly dark, 0.8 where mostly bright.
  cv::Mat guide(16, 16, CV_32FC3, cv::Scalar::all(0));
  guide.colRange(9, 16).setTo(cv::Scalar::all(1));
  cv::Mat low(4, 4, CV_32F, cv::Scalar(0.2));
  low.colRange(2, 4).setTo(0.8);
  const cv::Mat up = solo::jointBilateralUpsample(low, guide, 0.1, 1.0);
  cv::Mat bilinear;
  cv::resize(low, bilinear, guide.size(), 0, 0, cv::INTER_LINEAR);
  for (int y = 0; y < 16; ++y) {
    EXPECT_NEAR(up.at<float>(y, 7), 0.2, 0.02) << "dark side of the guide edge";
    EXPECT_NEAR(up.at<float>(y, 9), 0.8, 0.02) << "bright side of the guide edge";
    EXPECT_GT(std::abs(bilinear.at<float>(y, 7) - 0.2f), 0.1f) << "bilinear blends across it";
  }
}

TEST(UpsampleMaps, MapsAtTheImageResolutionPassThroughUnchanged) {
  solo::Scene scene;
  scene.image = cv::Mat(6, 8, CV_32FC3, cv::Scalar::all(0.5));
  scene.depth_m = cv::Mat(6, 8, CV_32F, cv::Scalar(3));
  scene.depth_m.at<float>(2, 3) = 7;
  scene.labels = cv::Mat(3, 4, CV_32S, cv::Scalar(7));
  const solo::UpsampledMaps maps = solo::upsampleMaps(scene);
  EXPECT_EQ(cv::norm(maps.depth_m, scene.depth_m, cv::NORM_INF), 0.0);
  ASSERT_EQ(maps.labels.size(), cv::Size(8, 6));
  EXPECT_EQ(cv::countNonZero(maps.labels != 7), 0);
  EXPECT_TRUE(maps.normals.empty());
  EXPECT_EQ(std::get<std::int64_t>(*maps.report.find("maps_resized")), 1);
}

}  // namespace
