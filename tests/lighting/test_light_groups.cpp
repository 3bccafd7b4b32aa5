// The light-group tree on hand-made maps (every rule once) and on a synthetic street whose
// true groups are known, and its errors.

#include <solo/core/error.h>
#include <solo/lighting/light_groups.h>
#include <solo/synth/scene_raster.h>
#include <solo/synth/street_scene.h>

#include "test_support.h"

#include <map>

namespace {

using solo::LightCategory;
using solo::LightGroupKind;

struct HandMadeMaps {
  cv::Mat lights = cv::Mat(12, 20, CV_32S, cv::Scalar(0));
  cv::Mat instances = cv::Mat(12, 20, CV_32S, cv::Scalar(11));  // building
  cv::Mat floors = cv::Mat(12, 20, CV_32S, cv::Scalar(0));
  HandMadeMaps() {
    instances(cv::Rect(0, 4, 8, 8)).setTo(26001);    // a car
    instances(cv::Rect(10, 4, 10, 8)).setTo(28001);  // a bus
    floors(cv::Rect(0, 0, 20, 3)).setTo(5);          // one building floor
    lights(cv::Rect(1, 0, 2, 2)).setTo(1001);        // two windows of the floor
    lights(cv::Rect(5, 0, 2, 2)).setTo(1002);
    lights.at<int>(3, 1) = 1003;                     // a window on no floor: root
    lights.at<int>(10, 3) = 1004;                    // a window_building on the car: incompatible, root
    lights(cv::Rect(1, 8, 2, 1)).setTo(10001);       // one moving_front id, two lamps: split
    lights(cv::Rect(5, 8, 2, 1)).setTo(10001);
    lights.at<int>(9, 1) = 12001;                    // one moving_rear id, two lamps: not split
    lights.at<int>(9, 6) = 12001;
    lights(cv::Rect(6, 6, 7, 1)).setTo(2001);        // window_parked: 2 px on the car, 3 on the bus
    lights.at<int>(6, 8) = 0;
    lights.at<int>(6, 9) = 0;
    lights(cv::Rect(2, 5, 4, 1)).setTo(3001);        // window_transport: 4 px on the car, 1 on the bus
    lights.at<int>(5, 10) = 3001;
    lights.at<int>(0, 15) = 7001;                    // street light, two separate heads
    lights.at<int>(2, 18) = 7001;
    lights.at<int>(0, 12) = 7002;                    // street light touching diagonally: one head
    lights.at<int>(1, 13) = 7002;
  }
};

const solo::Light& lightOf(const solo::LightGroupTree& tree, int map_id, int component = 0) {
  for (const auto& l : tree.lights)
    if (l.map_id == map_id && l.component == component) return l;
  throw std::runtime_error("no light " + std::to_string(map_id) + "/" + std::to_string(component));
}

const solo::LightGroup& groupOf(const solo::LightGroupTree& tree, int map_id, int component = 0) {
  return tree.groups[lightOf(tree, map_id, component).group];
}

}  // namespace

TEST(LightGroups, HandMadeMapsFollowEveryRule) {
  const HandMadeMaps maps;
  const solo::LightGroupTree tree = solo::buildLightGroups(maps.lights, maps.instances, maps.floors, "lights.png");
  ASSERT_EQ(tree.lights.size(), 12u);
  ASSERT_EQ(tree.groups.size(), 4u);  // root, floor 5, car, bus
  EXPECT_EQ(tree.groups[0].kind, LightGroupKind::Root);
  EXPECT_EQ(tree.groups[1].kind, LightGroupKind::BuildingFloor);
  EXPECT_EQ(tree.groups[1].source_id, 5);
  EXPECT_EQ(tree.groups[1].bbox, cv::Rect(0, 0, 20, 3));
  EXPECT_EQ(tree.groups[2].kind, LightGroupKind::Car);
  EXPECT_EQ(tree.groups[2].source_id, 26001);
  EXPECT_EQ(tree.groups[3].kind, LightGroupKind::Bus);

  EXPECT_EQ(groupOf(tree, 1001).id, 1);
  EXPECT_EQ(groupOf(tree, 1002).id, 1);
  EXPECT_EQ(groupOf(tree, 1003).id, 0) << "no overlap: root";
  EXPECT_EQ(groupOf(tree, 1004).id, 0) << "a car cannot hold a building window";
  EXPECT_EQ(groupOf(tree, 10001, 1).id, 2);
  EXPECT_EQ(groupOf(tree, 10001, 2).id, 2);
  EXPECT_EQ(lightOf(tree, 10001, 1).pixels, 2);
  EXPECT_EQ(lightOf(tree, 10001, 1).bbox, cv::Rect(1, 8, 2, 1));
  EXPECT_EQ(lightOf(tree, 10001, 2).bbox, cv::Rect(5, 8, 2, 1));
  EXPECT_EQ(lightOf(tree, 12001).pixels, 2) << "rear lights are not split";
  EXPECT_EQ(lightOf(tree, 12001).runs.size(), 2u);
  EXPECT_EQ(groupOf(tree, 2001).id, 3) << "joins the group it overlaps most";
  EXPECT_EQ(groupOf(tree, 3001).id, 3) << "joins the most-overlapped compatible group";
  EXPECT_EQ(groupOf(tree, 7001, 1).id, 0);
  EXPECT_EQ(groupOf(tree, 7001, 2).id, 0);
  EXPECT_EQ(lightOf(tree, 7002, 1).pixels, 2) << "8-connected: a diagonal neighbour is the same head";
  EXPECT_THROW(lightOf(tree, 7002, 2), std::runtime_error);
  // Leaves listed under their groups, ids 1..N.
  std::size_t leaves = 0;
  for (const auto& g : tree.groups) leaves += g.lights.size();
  EXPECT_EQ(leaves, tree.lights.size());
  for (std::size_t i = 0; i < tree.lights.size(); ++i) EXPECT_EQ(tree.lights[i].id, static_cast<int>(i) + 1);
}

TEST(LightGroups, WithoutInstanceOrFloorMapsEverythingHangsFromTheRoot) {
  const HandMadeMaps maps;
  const solo::LightGroupTree tree = solo::buildLightGroups(maps.lights, cv::Mat(), cv::Mat(), "lights.png");
  ASSERT_EQ(tree.groups.size(), 1u);
  EXPECT_EQ(tree.groups[0].lights.size(), tree.lights.size());
}

TEST(LightGroups, ActivationBoundsFollowTheReference) {
  const auto b = [](LightGroupKind k, LightCategory c) { return solo::activationBounds(k, c); };
  EXPECT_DOUBLE_EQ(b(LightGroupKind::BuildingFloor, LightCategory::WindowBuilding)->low, 0.3);
  EXPECT_DOUBLE_EQ(b(LightGroupKind::BuildingFloor, LightCategory::WindowBuilding)->high, 0.6);
  EXPECT_DOUBLE_EQ(b(LightGroupKind::Car, LightCategory::MovingFront)->low, 0.95);
  EXPECT_DOUBLE_EQ(b(LightGroupKind::Bicycle, LightCategory::ParkedRear)->high, 0.2);
  EXPECT_DOUBLE_EQ(b(LightGroupKind::Bus, LightCategory::WindowTransport)->low, 0.9);
  EXPECT_DOUBLE_EQ(b(LightGroupKind::Root, LightCategory::Advertisement)->low, 0.6);
  EXPECT_DOUBLE_EQ(b(LightGroupKind::Root, LightCategory::Clock)->low, 0.8);
  EXPECT_DOUBLE_EQ(b(LightGroupKind::Root, LightCategory::StreetLightLowCct)->low, 1.0);
  EXPECT_FALSE(b(LightGroupKind::Tram, LightCategory::WindowParked));
  EXPECT_FALSE(b(LightGroupKind::Motorcycle, LightCategory::WindowTransport));
  EXPECT_FALSE(b(LightGroupKind::Car, LightCategory::TrafficLightRed));
}

TEST(LightGroups, SyntheticStreetLightsJoinTheirTrueGroups) {
  solo::StreetSceneOptions options;
  options.width = 480;
  options.height = 270;
  const solo::StreetScene scene = solo::buildStreetScene(options);
  const solo::GroundTruthMaps truth = solo::rasterizeGroundTruth(scene);
  const solo::LightGroupTree tree =
      solo::buildLightGroups(truth.lights, truth.instances, truth.light_groups, "lightIds.png");
  int windows = 0, vehicle_lamps = 0;
  for (const solo::Light& light : tree.lights) {
    std::map<int, int> parts;
    for (const auto& run : light.runs)
      for (int x = run.first_col; x <= run.last_col; ++x) ++parts[truth.part.at<int>(run.row, x)];
    int part = -1, best = 0;
    for (const auto& [p, n] : parts)
      if (n > best) part = p, best = n;
    ASSERT_GE(part, 0);
    const solo::ScenePart& truth_part = scene.parts[part];
    const solo::LightGroup& group = tree.groups[light.group];
    if (light.category == LightCategory::WindowBuilding) {
      EXPECT_EQ(group.kind, LightGroupKind::BuildingFloor);
      EXPECT_EQ(group.source_id, truth_part.group_id);
      ++windows;
    } else if (const auto kind = solo::vehicleGroupKind(truth_part.label_id)) {
      EXPECT_EQ(group.kind, *kind) << solo::lightCategoryName(light.category);
      EXPECT_EQ(group.source_id, truth_part.instance_id);
      ++vehicle_lamps;
    } else {
      EXPECT_EQ(group.kind, LightGroupKind::Root) << solo::lightCategoryName(light.category);
    }
  }
  EXPECT_GT(windows, 20);
  EXPECT_GT(vehicle_lamps, 5);
}

TEST(LightGroups, UnknownCategoryIsAnErrorNamingThePixel) {
  HandMadeMaps maps;
  maps.lights.at<int>(4, 7) = 16001;
  try {
    solo::buildLightGroups(maps.lights, maps.instances, maps.floors, "lights.png");
    FAIL() << "no error";
  } catch (const solo::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("lights.png: light id 16001 at pixel (7, 4) has the unknown category 16"),
              std::string::npos)
        << e.what();
  }
  maps.lights.at<int>(4, 7) = -3;
  EXPECT_THROW(solo::buildLightGroups(maps.lights, maps.instances, maps.floors, "lights.png"), solo::InputError);
}

TEST(LightGroups, MapsOfAnotherSizeAreAnError) {
  const HandMadeMaps maps;
  try {
    solo::buildLightGroups(maps.lights, maps.instances(cv::Rect(0, 0, 10, 12)).clone(), maps.floors, "lights.png");
    FAIL() << "no error";
  } catch (const solo::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("instances: 10x12 differs from the light map"), std::string::npos) << e.what();
  }
}
