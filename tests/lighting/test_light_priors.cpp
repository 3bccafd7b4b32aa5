// Physical priors per light category: implausible lights move onto their support, lights without
// depth are placed at a prior depth, and the light stage and the night scene count the lights
// without depth alike.

#include <solo/geometry/depth_mesh.h>
#include <solo/lighting/light_priors.h>
#include <solo/lighting/light_record.h>
#include <solo/lighting/light_stage.h>
#include <solo/render/night_scene.h>

#include "test_support.h"

#include <cmath>

namespace {

constexpr int kWidth = 200, kHeight = 150;
const solo::PinholeCamera kCamera{150, 150, 99.5, 74.5, kWidth, kHeight};
constexpr double kCameraHeightM = 1.5;
constexpr int kRoad = 7, kBuilding = 11, kPole = 17, kSky = 23;
const std::filesystem::path kTable =
    std::filesystem::path(SOLO_PROJECT_DATA_DIR) / "illuminants" / "night_illuminants.csv";

// A street seen by a level camera 1.5 m above the road: road (exact depth) from row 80 down, sky
// (no depth) above; the tests paint facades, poles and lights over it.
struct StreetMaps {
  cv::Mat depth_m = cv::Mat(kHeight, kWidth, CV_32F, cv::Scalar(0));
  cv::Mat labels = cv::Mat(kHeight, kWidth, CV_32S, cv::Scalar(kSky));
  cv::Mat lights = cv::Mat(kHeight, kWidth, CV_32S, cv::Scalar(0));

  StreetMaps() {
    for (int v = 80; v < kHeight; ++v) {
      depth_m.row(v).setTo(kCameraHeightM * kCamera.fy / (v - kCamera.cy));
      labels.row(v).setTo(kRoad);
    }
  }
  void paint(const cv::Rect& box, int label, float depth) {
    labels(box).setTo(label);
    depth_m(box).setTo(depth);
  }
};

// A pole at columns 130-131 and `pole_m` deep, rising 8 m above the road, and a street-light head
// above it (rows 20-24, columns 124-131) at `lamp_m` (0 = no depth).
StreetMaps lampOnPole(float pole_m, float lamp_m) {
  StreetMaps m;
  const int base = static_cast<int>(kCamera.cy + kCameraHeightM * kCamera.fy / pole_m);
  const int top = static_cast<int>(kCamera.cy - (8 - kCameraHeightM) * kCamera.fy / pole_m);
  m.paint(cv::Rect(130, top, 2, base - top + 1), kPole, pole_m);
  m.paint(cv::Rect(124, 20, 8, 5), kPole, lamp_m);
  m.lights(cv::Rect(124, 20, 8, 5)).setTo(7001);
  return m;
}

solo::LightGroupTree treeOf(const StreetMaps& m) { return solo::buildLightGroups(m.lights, {}, {}, "lights"); }

solo::LightPriorInputs inputsOf(const StreetMaps& m) {
  solo::LightPriorInputs in;
  in.depth_m = m.depth_m;
  in.labels = m.labels;
  in.camera = kCamera;
  in.ground = solo::fitGroundPlaneToRoad(m.depth_m, m.labels, kCamera);
  return in;
}

double heightOf(const solo::LightPriorInputs& in, const solo::LightGeometry& g) {
  return in.ground.heightOf(g.centroid_m);
}

}  // namespace

TEST(LightPriors, TheGroundPlaneFitsTheRoadAndFallsBackToTheCameraHeight) {
  const StreetMaps m;
  const solo::GroundPlaneFit ground = solo::fitGroundPlaneToRoad(m.depth_m, m.labels, kCamera);
  ASSERT_TRUE(ground.fitted);
  EXPECT_NEAR(ground.offset_m, kCameraHeightM, 0.01);
  EXPECT_NEAR(ground.up.y(), -1.0, 1e-3);
  EXPECT_GT(ground.inliers, 0.9 * static_cast<double>(ground.points));
  // The same seed, the same plane.
  const solo::GroundPlaneFit again = solo::fitGroundPlaneToRoad(m.depth_m, m.labels, kCamera);
  EXPECT_EQ(again.offset_m, ground.offset_m);

  // No road or sidewalk, no depth, no labels: the level camera 1.5 m up.
  const cv::Mat sky(kHeight, kWidth, CV_32S, cv::Scalar(kSky));
  const cv::Mat no_depth(kHeight, kWidth, CV_32F, cv::Scalar(0));
  for (const solo::GroundPlaneFit& prior :
       {solo::fitGroundPlaneToRoad(m.depth_m, sky, kCamera), solo::fitGroundPlaneToRoad(no_depth, m.labels, kCamera),
        solo::fitGroundPlaneToRoad(m.depth_m, cv::Mat(), kCamera)}) {
    EXPECT_FALSE(prior.fitted);
    EXPECT_EQ(prior.offset_m, solo::kCameraHeightPriorM);
    EXPECT_EQ(prior.up, Eigen::Vector3d(0, -1, 0));
  }
}

TEST(LightPriors, ALampFarBehindItsPoleMovesOntoThePoleAtAPlausibleHeight) {
  // The head measured at 60 m is 22 m above the road with 6.4 m^2 of lamp; its pole stands 20 m
  // away. Moved onto the pole it hangs 8.5 m up with 0.71 m^2.
  const StreetMaps m = lampOnPole(20, 60);
  const solo::LightGroupTree tree = treeOf(m);
  const solo::LightPriorInputs in = inputsOf(m);
  std::vector<solo::LightGeometry> g = solo::measureLightGeometry(tree, m.depth_m, kCamera);
  ASSERT_EQ(g.size(), 1u);
  EXPECT_GT(heightOf(in, g[0]), 20.0);
  const std::uint32_t before = solo::checkLightPriors(tree.lights[0].category, g[0], in.ground);
  EXPECT_TRUE(before & static_cast<std::uint32_t>(solo::LightPriorCheck::Height));
  EXPECT_TRUE(before & static_cast<std::uint32_t>(solo::LightPriorCheck::Area));

  const solo::LightPriorSummary summary = solo::applyLightPriors(tree, g, in);
  EXPECT_EQ(g[0].placement, solo::LightPlacement::MovedToSupport);
  EXPECT_EQ(g[0].implausible, 0u);
  EXPECT_NEAR(g[0].centroid_m.z(), 20.0, 1e-6);
  EXPECT_GE(heightOf(in, g[0]), 4.0);
  EXPECT_LE(heightOf(in, g[0]), 12.0);
  EXPECT_NEAR(g[0].area_m2, 40 * (20.0 / 150) * (20.0 / 150), 0.05);
  const auto street = static_cast<std::size_t>(solo::LightCategory::StreetLightHighCct);
  EXPECT_EQ(summary.by_category[street].moved, 1);
  EXPECT_EQ(summary.by_category[street].flagged, 0);
  EXPECT_EQ(summary.total.moved, 1);
  ASSERT_EQ(summary.lines.size(), 1u);
  EXPECT_NE(summary.lines[0].find("moved from 60.0 m to its support at 20.0 m"), std::string::npos) << summary.lines[0];
}

TEST(LightPriors, APlausibleLampStaysWhereItsDepthPutsIt) {
  const StreetMaps m = lampOnPole(20, 20.5);
  const solo::LightGroupTree tree = treeOf(m);
  std::vector<solo::LightGeometry> g = solo::measureLightGeometry(tree, m.depth_m, kCamera);
  const std::vector<solo::LightGeometry> measured = g;
  const solo::LightPriorSummary summary = solo::applyLightPriors(tree, g, inputsOf(m));
  EXPECT_EQ(g[0].placement, solo::LightPlacement::Measured);
  EXPECT_EQ(g[0].implausible, 0u);
  EXPECT_EQ(g[0].centroid_m, measured[0].centroid_m);
  EXPECT_EQ(g[0].area_m2, measured[0].area_m2);
  EXPECT_EQ(summary.total.checked, 1);
  EXPECT_EQ(summary.total.moved + summary.total.flagged, 0);
  EXPECT_TRUE(summary.lines.empty());
}

TEST(LightPriors, AnImplausibleLampWithoutAPoleIsFlaggedNotMoved) {
  StreetMaps m = lampOnPole(20, 60);
  m.labels.setTo(kSky, m.labels == kPole);  // the pole's pixels are not labelled
  const solo::LightGroupTree tree = treeOf(m);
  std::vector<solo::LightGeometry> g = solo::measureLightGeometry(tree, m.depth_m, kCamera);
  const Eigen::Vector3d measured = g[0].centroid_m;
  const solo::LightPriorSummary summary = solo::applyLightPriors(tree, g, inputsOf(m));
  EXPECT_EQ(g[0].placement, solo::LightPlacement::Measured);
  EXPECT_EQ(g[0].centroid_m, measured);
  EXPECT_EQ(solo::lightPriorCheckNames(g[0].implausible), (std::vector<std::string>{"height", "area"}));
  EXPECT_EQ(summary.total.flagged, 1);
  EXPECT_EQ(summary.total.moved, 0);
}

TEST(LightPriors, AWindowWithoutDepthTakesItsFacadesDepthAndAPlausibleArea) {
  // A facade 25 m deep over the left half; a window of 8 x 10 pixels without depth in it.
  StreetMaps m;
  m.paint(cv::Rect(0, 0, 100, 78), kBuilding, 25);
  m.depth_m(cv::Rect(40, 30, 8, 10)).setTo(0);
  m.lights(cv::Rect(40, 30, 8, 10)).setTo(1001);
  const solo::LightGroupTree tree = treeOf(m);
  const solo::LightPriorInputs in = inputsOf(m);
  std::vector<solo::LightGeometry> g = solo::measureLightGeometry(tree, m.depth_m, kCamera);
  ASSERT_FALSE(g[0].valid());
  ASSERT_FALSE(g[0].positioned());
  const solo::LightPriorSummary summary = solo::applyLightPriors(tree, g, in);
  EXPECT_EQ(g[0].placement, solo::LightPlacement::SupportDepth);
  EXPECT_TRUE(g[0].positioned());
  EXPECT_FALSE(g[0].valid()) << "it still has no depth of its own";
  EXPECT_NEAR(g[0].centroid_m.z(), 25.0, 1e-6);
  EXPECT_GE(g[0].area_m2, 0.5);
  EXPECT_LE(g[0].area_m2, 6.0);
  // 80 pixel footprints at 25 m, over the cosine of the horizontal normal facing the camera.
  EXPECT_NEAR(g[0].area_m2, 80 * (25.0 / 150) * (25.0 / 150), 0.3);
  EXPECT_NEAR(g[0].normal.dot(in.ground.up), 0.0, 1e-6) << "a facade's window faces horizontally";
  EXPECT_LT(g[0].normal.dot(g[0].centroid_m), 0.0);
  EXPECT_EQ(g[0].implausible, 0u);
  EXPECT_EQ(summary.by_category[static_cast<std::size_t>(solo::LightCategory::WindowBuilding)].support_depth, 1);
}

TEST(LightPriors, HardCasesStayFinite) {
  // No depth anywhere and no labels: the camera-height prior, every light at its prior distance.
  StreetMaps m = lampOnPole(20, 60);
  m.lights(cv::Rect(40, 30, 8, 10)).setTo(1001);
  m.lights(cv::Rect(60, 120, 6, 3)).setTo(11001);
  m.depth_m.setTo(0);
  const solo::LightGroupTree tree = treeOf(m);
  for (const bool with_labels : {true, false}) {
    solo::LightPriorInputs in = inputsOf(m);
    if (!with_labels) in.labels = cv::Mat();
    EXPECT_FALSE(in.ground.fitted);
    std::vector<solo::LightGeometry> g = solo::measureLightGeometry(tree, m.depth_m, kCamera);
    const solo::LightPriorSummary summary = solo::applyLightPriors(tree, g, in);
    ASSERT_EQ(g.size(), 3u);
    EXPECT_EQ(summary.total.prior_distance, 3);
    for (std::size_t i = 0; i < g.size(); ++i) {
      EXPECT_EQ(g[i].placement, solo::LightPlacement::PriorDistance) << i;
      EXPECT_TRUE(g[i].centroid_m.allFinite()) << i;
      EXPECT_TRUE(g[i].normal.allFinite()) << i;
      EXPECT_GT(g[i].area_m2, 0) << i;
      EXPECT_TRUE(std::isfinite(g[i].area_m2)) << i;
      EXPECT_EQ(g[i].implausible, 0u) << i << ": the prior distance is plausible";
    }
    // Light 0, the window, 25 m away; the lamp where its ray is 8 m above the ground, the rear
    // lamp where its ray meets 0.8 m.
    EXPECT_NEAR(g[0].centroid_m.norm(), 25.0, 0.1);
    EXPECT_NEAR(in.ground.heightOf(g[1].centroid_m), 8.0, 0.05);
    EXPECT_NEAR(in.ground.heightOf(g[2].centroid_m), 0.8, 0.02);
  }
  // Priors off: a light without depth keeps no position.
  std::vector<solo::LightGeometry> g = solo::measureLightGeometry(tree, m.depth_m, kCamera);
  solo::LightPriorOptions off;
  off.enabled = false;
  solo::applyLightPriors(tree, g, inputsOf(m), off);
  for (const solo::LightGeometry& light : g) EXPECT_FALSE(light.positioned());
}

TEST(LightPriors, TheLightStageAndTheNightSceneCountTheLightsWithoutDepthAlike) {
  // A lamp on its pole with depth, a lamp against the sky without, a window without depth in a
  // facade; the ablation switches every light on.
  StreetMaps m = lampOnPole(20, 20);
  m.paint(cv::Rect(0, 0, 100, 78), kBuilding, 25);
  m.depth_m(cv::Rect(40, 30, 8, 10)).setTo(0);
  m.lights(cv::Rect(40, 30, 8, 10)).setTo(1001);
  m.lights(cv::Rect(160, 10, 6, 4)).setTo(7002);
  solo::Scene scene;
  scene.image = cv::Mat(kHeight, kWidth, CV_32FC3, cv::Scalar(0.3f, 0.3f, 0.3f));
  scene.depth_m = m.depth_m;
  scene.labels = m.labels;
  scene.lights = m.lights;
  scene.camera = kCamera;
  solo::LightStageOptions options;
  options.illuminant_table = kTable;
  options.instantiation.ablation = true;
  const solo::LightStageResult stage = solo::runLightStage(scene, cv::Mat(), options);
  EXPECT_EQ(solo::test::metricInt(stage.report, "lights"), 3);
  EXPECT_EQ(solo::test::metricInt(stage.report, "lights_without_depth"), 2);
  EXPECT_EQ(solo::test::metricInt(stage.report, "lights_on_without_depth"), 2);
  EXPECT_EQ(solo::test::metricInt(stage.report, "lights_on_without_position"), 0);
  EXPECT_EQ(solo::test::metricInt(stage.report, "lights_placed_at_support_depth"), 1);
  EXPECT_EQ(solo::test::metricInt(stage.report, "lights_placed_at_prior_distance"), 1);
  EXPECT_EQ(solo::test::metricInt(stage.report, "lights_moved_to_support"), 0);
  EXPECT_NEAR(solo::test::metricNumber(stage.report, "camera_height_m"), kCameraHeightM, 0.01);

  solo::NightSceneOptions night_options;
  night_options.headlights = false;
  const solo::NightScene night =
      solo::buildNightScene(solo::meshFromDepth(m.depth_m, kCamera), {}, {}, {}, stage.record, night_options);
  EXPECT_EQ(solo::test::metricInt(night.report, "lights_on_without_depth"),
            solo::test::metricInt(stage.report, "lights_on_without_depth"));
  EXPECT_EQ(solo::test::metricInt(night.report, "lights_on_without_faces"), 2) << "the two without depth";
  EXPECT_EQ(solo::test::metricInt(night.report, "lights_on_not_emitting"), 0);
  EXPECT_EQ(solo::test::metricInt(night.report, "light_proxies"), 2);
  EXPECT_EQ(night.scene.emitters.size(), 3u) << "every light that is on emits";
  EXPECT_TRUE(night.report.warnings.empty());
}

TEST(LightPriors, TheRecordKeepsEachLightsPlacementAndWhatIsImplausible) {
  StreetMaps m = lampOnPole(20, 60);
  m.labels.setTo(kSky, m.labels == kPole);
  m.lights(cv::Rect(40, 30, 8, 10)).setTo(1001);
  solo::LightRecord record;
  record.tree = treeOf(m);
  record.geometry = solo::measureLightGeometry(record.tree, m.depth_m, kCamera);
  solo::applyLightPriors(record.tree, record.geometry, inputsOf(m));
  record.instantiation.lights.resize(record.tree.lights.size());
  for (solo::LightState& s : record.instantiation.lights) s.xy = {0.4, 0.4};
  const solo::test::TempDir dir;
  solo::writeLightRecord(dir / "lights.json", record);
  const solo::LightRecord back = solo::readLightRecord(dir / "lights.json");
  ASSERT_EQ(back.geometry.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back.geometry[i].placement, record.geometry[i].placement) << i;
    EXPECT_EQ(back.geometry[i].implausible, record.geometry[i].implausible) << i;
    EXPECT_EQ(back.geometry[i].positioned(), record.geometry[i].positioned()) << i;
  }
  EXPECT_EQ(back.geometry[0].placement, solo::LightPlacement::PriorDistance) << "the window: no facade, no depth";
  EXPECT_NE(back.geometry[1].implausible, 0u) << "the lamp at 60 m without a pole";
}
