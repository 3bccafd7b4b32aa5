#include <solo/post/chromatic_adaptation.h>

#include "test_support.h"

namespace {

// Published Bradford E -> D65 matrix (reference.md section 2, also Lindbloom's table).
const cv::Matx33d kPublishedEToD65{0.9531874, -0.0265906, 0.0238731,  //
                                   -0.0382467, 1.0288406, 0.0094060,  //
                                   0.0026068, -0.0030332, 1.0892565};

}  // namespace

TEST(ChromaticAdaptation, BradfordEToD65MatchesThePublishedMatrix) {
  const cv::Matx33d m = solo::bradfordAdaptation(solo::kWhitePointE, solo::kWhitePointD65);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(m(r, c), kPublishedEToD65(r, c), 1e-6) << "entry " << r << c;
}

TEST(ChromaticAdaptation, SourceWhiteLandsExactlyOnDestinationWhite) {
  const cv::Vec3d d50{0.96422, 1.0, 0.82521};
  const cv::Vec3d mapped = solo::bradfordAdaptation(d50, solo::kWhitePointD65) * d50;
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(mapped[i], solo::kWhitePointD65[i], 1e-12);
  // Going back is the inverse matrix.
  const cv::Matx33d round_trip =
      solo::bradfordAdaptation(solo::kWhitePointD65, d50) * solo::bradfordAdaptation(d50, solo::kWhitePointD65);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(round_trip(r, c), r == c ? 1.0 : 0.0, 1e-12);
}

TEST(ChromaticAdaptation, AppliesToAnImageAndReportsTheMatrix) {
  cv::Mat xyz(2, 2, CV_32FC3, cv::Scalar(0.5, 0.5, 0.5));  // half-intensity E white
  const solo::StageReport report = solo::applyChromaticAdaptation(xyz, {});
  EXPECT_FALSE(report.skipped);
  const cv::Vec3f p = xyz.at<cv::Vec3f>(1, 1);
  EXPECT_NEAR(p[0], 0.5 * 0.95047, 1e-6);
  EXPECT_NEAR(p[1], 0.5, 1e-6);
  EXPECT_NEAR(p[2], 0.5 * 1.08883, 1e-6);
  ASSERT_NE(report.find("m00"), nullptr);
  EXPECT_NEAR(std::get<double>(*report.find("m00")), 0.9531874, 1e-6);
}

TEST(ChromaticAdaptation, EqualWhitesSkipWithAReason) {
  cv::Mat xyz(1, 1, CV_32FC3, cv::Scalar(0.2, 0.3, 0.4));
  solo::ChromaticAdaptationOptions same;
  same.source_white = solo::kWhitePointD65;
  const solo::StageReport report = solo::applyChromaticAdaptation(xyz, same);
  EXPECT_TRUE(report.skipped);
  EXPECT_NE(report.skip_reason.find("white point"), std::string::npos);
  EXPECT_EQ(xyz.at<cv::Vec3f>(0, 0), cv::Vec3f(0.2f, 0.3f, 0.4f));
}

TEST(ChromaticAdaptation, RejectsAWhiteWithoutPositiveConeResponse) {
  EXPECT_THROW(solo::bradfordAdaptation({0, 0, 0}, solo::kWhitePointD65), std::invalid_argument);
}
