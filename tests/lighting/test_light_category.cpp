#include <solo/lighting/light_category.h>

#include "test_support.h"

TEST(LightCategory, NamesFollowTheSceneFormatIds) {
  EXPECT_STREQ(solo::lightCategoryName(solo::LightCategory::WindowBuilding), "window_building");
  EXPECT_STREQ(solo::lightCategoryName(solo::LightCategory::TrafficLightOrange), "traffic_light_orange");
  EXPECT_STREQ(solo::lightCategoryName(solo::LightCategory::StreetLightHighCct), "street_light_HT");
  EXPECT_STREQ(solo::lightCategoryName(solo::LightCategory::Inferred), "inferred");
  for (int id = solo::kFirstLightCategory; id <= solo::kLastLightCategory; ++id) {
    const auto category = static_cast<solo::LightCategory>(id);
    EXPECT_EQ(solo::lightCategoryFromName(solo::lightCategoryName(category)), category);
  }
  EXPECT_EQ(static_cast<int>(solo::lightCategoryFromName("moving_rear")), 12);
  EXPECT_THROW(solo::lightCategoryFromName("lamp"), std::invalid_argument);
}

TEST(LightCategory, CensusCountsInstancesAndPixelsPerCategory) {
  cv::Mat map(3, 4, CV_32S, cv::Scalar(0));
  map.at<int>(0, 0) = 1001;  // window_building, instance 1: 2 pixels
  map.at<int>(0, 1) = 1001;
  map.at<int>(1, 0) = 1002;  // window_building, instance 2
  map.at<int>(2, 3) = 7001;  // street_light_HT
  map.at<int>(2, 2) = 10000; // moving_front, k = 0
  const solo::LightCensus c = solo::countLights(map);
  EXPECT_EQ(c.instances[1], 2);
  EXPECT_EQ(c.pixels[1], 3);
  EXPECT_EQ(c.instances[7], 1);
  EXPECT_EQ(c.instances[10], 1);
  EXPECT_EQ(c.total_instances(), 4);
}
