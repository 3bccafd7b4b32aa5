// Street lights become instances of their own before the depth filter (street_light_instances.h).

#include <solo/geometry/instance_bilateral_filter.h>
#include <solo/lighting/street_light_instances.h>

#include "test_support.h"

namespace {

// 12 x 8 pixels: a wall (building, instance 11) at 30 m; a lamp head at 10 m over columns
// 4-7 of rows 2-3 (street light 7003), which the estimated instance map calls building too; a
// window (light 1001) and a car's front light (light 10002 on car 26001) elsewhere.
struct Maps {
  cv::Mat depth{8, 12, CV_32F, cv::Scalar(30.f)};
  cv::Mat instances{8, 12, CV_32S, cv::Scalar(11)};
  cv::Mat lights{8, 12, CV_32S, cv::Scalar(0)};
  Maps() {
    depth(cv::Rect(4, 2, 4, 2)).setTo(10.f);
    lights(cv::Rect(4, 2, 4, 2)).setTo(7003);
    lights(cv::Rect(0, 6, 2, 2)).setTo(1001);
    instances(cv::Rect(9, 5, 3, 3)).setTo(26001);
    lights(cv::Rect(10, 6, 1, 1)).setTo(10002);
  }
};

}  // namespace

TEST(StreetLightInstances, EachStreetLightBecomesAPoleInstanceOfItsOwnAndNothingElseChanges) {
  const Maps m;
  const cv::Mat before = m.instances.clone();
  std::int64_t changed = -1;
  const cv::Mat out = solo::streetLightsAsPoles(m.instances, m.lights, &changed);
  EXPECT_EQ(changed, 8);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 12; ++x) {
      const bool lamp = x >= 4 && x <= 7 && y >= 2 && y <= 3;
      EXPECT_EQ(out.at<int>(y, x), lamp ? 17003 : before.at<int>(y, x)) << x << "," << y;
    }
  EXPECT_EQ(cv::countNonZero(m.instances != before), 0) << "the input is untouched";
  // Applied twice, nothing more changes.
  solo::streetLightsAsPoles(out, m.lights, &changed);
  EXPECT_EQ(changed, 0);
  // A light map at half the size is sampled at the nearest pixel: its lamp pixel (2..3, 1)
  // covers columns 4-7 of row 2-3.
  cv::Mat half(4, 6, CV_32S, cv::Scalar(0));
  half(cv::Rect(2, 1, 2, 1)).setTo(8001);  // a low-CCT street light
  const cv::Mat scaled = solo::streetLightsAsPoles(m.instances, half, &changed);
  EXPECT_EQ(changed, 8);
  EXPECT_EQ(scaled.at<int>(2, 4), 17001);
  EXPECT_EQ(scaled.at<int>(3, 7), 17001);
  EXPECT_EQ(scaled.at<int>(1, 4), 11);
  // Either map empty: the instances as they are.
  EXPECT_TRUE(solo::streetLightsAsPoles(cv::Mat(), m.lights, &changed).empty());
  EXPECT_EQ(solo::streetLightsAsPoles(m.instances, cv::Mat(), &changed).data, m.instances.data);
  EXPECT_EQ(changed, 0);
}

TEST(StreetLightInstances, LampsWithTheSameNumberOrAPoleIdInUseGetIdsOfTheirOwn) {
  // A high-CCT lamp 7003 (columns 4-7 of rows 2-3), a low-CCT lamp 8003 (columns 0-1 of rows
  // 0-1) and a pole that the instance map already calls 17004 (column 11, rows 0-3): 7003 keeps
  // 17003; 8003 finds 17003 taken by 7003 and 17004 by the pole, so it gets 17005.
  Maps m;
  m.lights(cv::Rect(0, 0, 2, 2)).setTo(8003);
  m.instances(cv::Rect(11, 0, 1, 4)).setTo(17004);
  std::int64_t changed = -1;
  const cv::Mat out = solo::streetLightsAsPoles(m.instances, m.lights, &changed);
  EXPECT_EQ(changed, 12);
  EXPECT_EQ(out.at<int>(2, 4), 17003);
  EXPECT_EQ(out.at<int>(3, 7), 17003);
  EXPECT_EQ(out.at<int>(0, 0), 17005);
  EXPECT_EQ(out.at<int>(1, 1), 17005);
  EXPECT_EQ(out.at<int>(0, 11), 17004);
  // The same ids again from the result: nothing more changes.
  EXPECT_EQ(cv::countNonZero(solo::streetLightsAsPoles(out, m.lights, &changed) != out), 0);
  EXPECT_EQ(changed, 0);
  // Lamp 999 starts at 17999; taken, it wraps to 17001.
  cv::Mat lights(1, 2, CV_32S, cv::Scalar(7999));
  cv::Mat instances(1, 2, CV_32S, cv::Scalar(0));
  lights.at<int>(0, 1) = 0;
  instances.at<int>(0, 1) = 17999;
  EXPECT_EQ(solo::streetLightsAsPoles(instances, lights).at<int>(0, 0), 17001);
}

TEST(StreetLightInstances, TheDepthFilterKeepsALampsDepthOnceItIsItsOwnInstance) {
  // With the lamp called building, the instance-reference filter averages its 8 pixels at
  // 10 m with the 88 wall pixels at 30 m around it; as an instance of its own it keeps 10 m.
  const Maps m;
  const cv::Mat mixed = solo::instanceBilateralFilter(m.depth, m.instances).depth_m;
  EXPECT_GT(mixed.at<float>(2, 5), 15.f) << "the wall pulls the lamp back";
  const cv::Mat own = solo::instanceBilateralFilter(m.depth, solo::streetLightsAsPoles(m.instances, m.lights)).depth_m;
  for (int y = 2; y <= 3; ++y)
    for (int x = 4; x <= 7; ++x) EXPECT_NEAR(own.at<float>(y, x), 10.f, 1e-4f) << x << "," << y;
  EXPECT_NEAR(own.at<float>(0, 0), 30.f, 1e-4f);
}
