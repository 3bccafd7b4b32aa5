// The light record: round trip, and edits a user might get wrong.

#include <solo/core/error.h>
#include <solo/lighting/light_record.h>

#include <nlohmann/json.hpp>

#include <functional>

#include "test_support.h"

namespace {

solo::LightRecord smallRecord() {
  cv::Mat lights(12, 20, CV_32S, cv::Scalar(0));
  cv::Mat instances(12, 20, CV_32S, cv::Scalar(11));
  instances(cv::Rect(0, 4, 8, 8)).setTo(26001);
  lights(cv::Rect(1, 8, 2, 1)).setTo(10001);
  lights(cv::Rect(5, 8, 2, 1)).setTo(10001);
  lights(cv::Rect(10, 1, 3, 2)).setTo(7001);
  solo::LightRecord r;
  r.scene = "scene.json";
  r.seed = 9;
  r.illuminant_table = "table.csv";
  r.tree = solo::buildLightGroups(lights, instances, cv::Mat(), "lights");
  solo::PinholeCamera camera;
  camera.fx = camera.fy = 20;
  camera.cx = 9.5;
  camera.cy = 5.5;
  r.geometry = solo::measureLightGeometry(r.tree, cv::Mat(12, 20, CV_32F, cv::Scalar(4)), camera);
  r.geometry[0].pixels_off_depth = 3;  // as if three of its pixels saw the background
  solo::IlluminantTable table;
  table.samples.push_back({solo::LightCategory::MovingFront, {0.42, 0.40}, "halogen"});
  table.samples.push_back({solo::LightCategory::StreetLightHighCct, {0.37, 0.38}, "metal halide"});
  solo::InstantiationOptions options;
  options.seed = 9;
  r.instantiation = solo::instantiateLights(r.tree, table, options);
  return r;
}

std::string errorOf(const std::filesystem::path& file) {
  try {
    solo::readLightRecord(file);
  } catch (const solo::InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(LightRecord, RoundTripKeepsEveryField) {
  solo::test::TempDir dir;
  const solo::LightRecord written = smallRecord();
  solo::writeLightRecord(dir / "lights.json", written);
  const solo::LightRecord read = solo::readLightRecord(dir / "lights.json");
  EXPECT_EQ(read.scene, "scene.json");
  EXPECT_EQ(read.seed, 9u);
  EXPECT_EQ(read.tree.width, 20);
  ASSERT_EQ(read.tree.lights.size(), 3u);
  ASSERT_EQ(read.tree.groups.size(), 2u);
  EXPECT_EQ(read.tree.groups[1].kind, solo::LightGroupKind::Car);
  EXPECT_EQ(read.tree.groups[1].lights, (std::vector<int>{2, 3}));  // light 1 is the street light (map id 7001)
  for (std::size_t i = 0; i < 3; ++i) {
    const auto& a = written.tree.lights[i];
    const auto& b = read.tree.lights[i];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.map_id, b.map_id);
    EXPECT_EQ(a.component, b.component);
    EXPECT_EQ(a.category, b.category);
    EXPECT_EQ(a.group, b.group);
    EXPECT_EQ(a.pixels, b.pixels);
    EXPECT_EQ(a.bbox, b.bbox);
    EXPECT_EQ(written.instantiation.lights[i].on, read.instantiation.lights[i].on);
    EXPECT_DOUBLE_EQ(written.instantiation.lights[i].xy.x(), read.instantiation.lights[i].xy.x());
    EXPECT_DOUBLE_EQ(written.instantiation.lights[i].strength, read.instantiation.lights[i].strength);
    EXPECT_EQ(written.instantiation.lights[i].unit, read.instantiation.lights[i].unit);
    EXPECT_DOUBLE_EQ(written.geometry[i].area_m2, read.geometry[i].area_m2);
    EXPECT_EQ(written.geometry[i].pixels_off_depth, read.geometry[i].pixels_off_depth);
    EXPECT_TRUE(written.geometry[i].centroid_m.isApprox(read.geometry[i].centroid_m));
  }
  EXPECT_EQ(read.instantiation.draws.size(), written.instantiation.draws.size());
  // Written again, it is the same text.
  EXPECT_EQ(solo::lightRecordJson(read), solo::lightRecordJson(written));
}

TEST(LightRecord, BadEditsAreRefusedNamingTheLight) {
  solo::test::TempDir dir;
  const nlohmann::json original = nlohmann::json::parse(solo::lightRecordJson(smallRecord()));
  const auto edited = [&](const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json j = original;
    edit(j);
    solo::test::writeText(dir / "edited.json", j.dump());
    return errorOf(dir / "edited.json");
  };
  EXPECT_NE(edited([](auto& j) { j["lights"][2]["runs"][0] = {30, 1, 2}; })
                .find("edited.json: light 3: pixel run [30, 1, 2] lies outside the 20x12 image"),
            std::string::npos);
  EXPECT_NE(edited([](auto& j) { j["lights"][0]["runs"][0] = {8, 18, 25}; }).find("outside the 20x12 image"),
            std::string::npos);
  EXPECT_NE(edited([](auto& j) { j["lights"][1]["category"] = "lantern"; })
                .find("light 2: unknown light category \"lantern\""),
            std::string::npos);
  EXPECT_NE(edited([](auto& j) { j["lights"][1]["category"] = "window_building"; })
                .find("light 2: a car group cannot hold a window_building light"),
            std::string::npos);
  EXPECT_NE(edited([](auto& j) { j["lights"][0]["group"] = 7; }).find("light 1: group 7 does not exist"),
            std::string::npos);
  EXPECT_NE(edited([](auto& j) { j["lights"][0]["x"] = 0.9; }).find("light 1: chromaticity"), std::string::npos);
  EXPECT_NE(edited([](auto& j) { j["lights"][0]["strength"] = -1; }).find("light 1: negative strength"),
            std::string::npos);
  EXPECT_NE(edited([](auto& j) { j["lights"][0]["on"] = "yes"; }).find("light 1: \"on\" must be true or false"),
            std::string::npos);
  EXPECT_NE(edited([](auto& j) { j["lights"][1]["id"] = 1; }).find("unique"), std::string::npos);
  EXPECT_NE(edited([](auto& j) { j["format"] = "other"; }).find("not a light record"), std::string::npos);
  solo::test::writeText(dir / "broken.json", "{\"format\": ");
  EXPECT_NE(errorOf(dir / "broken.json").find("malformed JSON"), std::string::npos);
  // A deleted light and a light switched off are fine.
  EXPECT_EQ(edited([](auto& j) {
              j["lights"].erase(1);
              j["lights"][0]["on"] = false;
            }),
            "no error");
}
