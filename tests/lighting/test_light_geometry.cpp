// Light geometry: pixel footprints on analytic planes, and windows of a synthetic street.

#include <solo/lighting/light_geometry.h>
#include <solo/synth/scene_raster.h>
#include <solo/synth/street_scene.h>

#include "test_support.h"

#include <algorithm>

namespace {

solo::PinholeCamera camera100() {
  solo::PinholeCamera c;
  c.fx = c.fy = 100;
  c.cx = 49.5;
  c.cy = 39.5;
  c.width = 100;
  c.height = 80;
  return c;
}

solo::LightGroupTree treeWithRectangle(const cv::Rect& rect, int width = 100, int height = 80) {
  cv::Mat lights(height, width, CV_32S, cv::Scalar(0));
  lights(rect).setTo(1001);
  return solo::buildLightGroups(lights, cv::Mat(), cv::Mat(), "lights");
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

TEST(LightGeometry, FrontoParallelPlaneHasExactArea) {
  const solo::PinholeCamera camera = camera100();
  const cv::Mat depth(80, 100, CV_32F, cv::Scalar(10));
  const auto g = solo::measureLightGeometry(treeWithRectangle({30, 20, 20, 10}), depth, camera);
  ASSERT_EQ(g.size(), 1u);
  EXPECT_EQ(g[0].pixels_with_depth, 200);
  EXPECT_NEAR(g[0].area_m2, 200 * 0.1 * 0.1, 1e-9);  // each pixel covers (z / f)^2
  EXPECT_EQ(g[0].normal_source, solo::NormalSource::PlaneFit);
  EXPECT_NEAR(g[0].normal.z(), -1, 1e-9);
  EXPECT_NEAR(g[0].centroid_m.x(), 10 * (39.5 - 49.5) / 100, 1e-9);  // mean column 39.5
  EXPECT_NEAR(g[0].centroid_m.y(), 10 * (24.5 - 39.5) / 100, 1e-9);  // mean row 24.5
  EXPECT_NEAR(g[0].centroid_m.z(), 10, 1e-9);
}

TEST(LightGeometry, AGivenNormalMapSetsTheNormalAndTheFootprints) {
  // Depth of a fronto-parallel plane but normals tilted by 36.87 deg: each pixel near the
  // principal point then covers (z / f)^2 / cos = (z / f)^2 / 0.8.
  const solo::PinholeCamera camera = camera100();
  const cv::Mat depth(80, 100, CV_32F, cv::Scalar(10));
  const cv::Mat normals(80, 100, CV_32FC3, cv::Scalar(-0.6f, 0.0f, -0.8f));
  const auto g = solo::measureLightGeometry(treeWithRectangle({40, 35, 20, 10}), depth, camera, {}, normals);
  EXPECT_EQ(g[0].normal_source, solo::NormalSource::NormalMap);
  EXPECT_NEAR(g[0].normal.x(), -0.6, 1e-6);
  EXPECT_NEAR(g[0].area_m2, 200 * 0.01 / 0.8, 0.01 * 200 * 0.01 / 0.8);
}

TEST(LightGeometry, ObliqueFacadeAreaMatchesTheExactPatch) {
  // A facade x = 3 m seen obliquely: z = 3 fx / (u - cx). The pixels [u0, u1] x [v0, v1]
  // see the patch z in [3 fx / (u1 + 0.5 - cx), 3 fx / (u0 - 0.5 - cx)], y / z in
  // [(v0 - 0.5 - cy) / fy, (v1 + 0.5 - cy) / fy], of area (b - a) (z2^2 - z1^2) / 2.
  const solo::PinholeCamera camera = camera100();
  cv::Mat depth(80, 100, CV_32F, cv::Scalar(0));
  for (int v = 0; v < 80; ++v)
    for (int u = 55; u < 100; ++u) depth.at<float>(v, u) = static_cast<float>(3 * camera.fx / (u - camera.cx));
  const int u0 = 70, u1 = 89, v0 = 10, v1 = 29;
  const auto g = solo::measureLightGeometry(treeWithRectangle({u0, v0, u1 - u0 + 1, v1 - v0 + 1}), depth, camera);
  const double z1 = 3 * camera.fx / (u1 + 0.5 - camera.cx), z2 = 3 * camera.fx / (u0 - 0.5 - camera.cx);
  const double a = (v0 - 0.5 - camera.cy) / camera.fy, b = (v1 + 0.5 - camera.cy) / camera.fy;
  const double exact = (b - a) * (z2 * z2 - z1 * z1) / 2;
  EXPECT_NEAR(g[0].area_m2 / exact, 1.0, 0.005) << "area " << g[0].area_m2 << " exact " << exact;
  EXPECT_NEAR(g[0].normal.x(), -1, 1e-4);
  EXPECT_NEAR(g[0].centroid_m.x(), 3, 1e-3);
}

TEST(LightGeometry, PixelsWithoutDepthAreLeftOutAndTinyLightsFaceTheCamera) {
  const solo::PinholeCamera camera = camera100();
  cv::Mat depth(80, 100, CV_32F, cv::Scalar(5));
  depth(cv::Rect(30, 20, 20, 5)).setTo(0);
  auto g = solo::measureLightGeometry(treeWithRectangle({30, 20, 20, 10}), depth, camera);
  EXPECT_EQ(g[0].pixels_with_depth, 100);
  EXPECT_NEAR(g[0].area_m2, 100 * 0.05 * 0.05, 1e-9);
  g = solo::measureLightGeometry(treeWithRectangle({49, 39, 2, 1}), depth, camera);
  EXPECT_EQ(g[0].normal_source, solo::NormalSource::FacingCamera) << "two pixels do not span a plane";
  EXPECT_NEAR(g[0].normal.z(), -1, 1e-3);
  depth.setTo(0);
  g = solo::measureLightGeometry(treeWithRectangle({30, 20, 20, 10}), depth, camera);
  EXPECT_FALSE(g[0].valid());
  EXPECT_EQ(g[0].area_m2, 0);
}

TEST(LightGeometry, MixedPixelsOfTheSilhouetteCountInNeitherTheAreaNorTheCentroid) {
  // A lamp 10 m away over a 20 x 10 block; its rightmost column sees a wall 60 m behind it
  // (mixed pixels). Counted, those 10 pixels would add 10 x (60 / 100)^2 = 3.6 m^2 to the lamp's
  // 190 x 0.01 = 1.9 m^2 and pull the centroid 14 m back.
  const solo::PinholeCamera camera = camera100();
  cv::Mat depth(80, 100, CV_32F, cv::Scalar(10));
  depth(cv::Rect(49, 20, 1, 10)).setTo(60);
  const auto g = solo::measureLightGeometry(treeWithRectangle({30, 20, 20, 10}), depth, camera);
  EXPECT_EQ(g[0].pixels_with_depth, 200);
  EXPECT_EQ(g[0].pixels_off_depth, 10);
  EXPECT_NEAR(g[0].area_m2, 190 * 0.1 * 0.1, 1e-9);
  EXPECT_NEAR(g[0].centroid_m.z(), 10, 1e-9);
  EXPECT_NEAR(g[0].centroid_m.x(), 10 * (39.0 - 49.5) / 100, 1e-9);  // mean column of 30..48
  EXPECT_NEAR(g[0].normal.z(), -1, 1e-9);
  // A facade seen at grazing spreads its depth evenly: none of it is off.
  cv::Mat slanted(80, 100, CV_32F);
  for (int x = 0; x < 100; ++x) slanted.col(x).setTo(5.f + 0.5f * x);
  EXPECT_EQ(solo::measureLightGeometry(treeWithRectangle({30, 20, 20, 10}), slanted, camera)[0].pixels_off_depth, 0);
}

TEST(LightGeometry, TheDepthBandIsTheMedianPlusMinusThreeMadsAtLeastAQuarterMetre) {
  // Three pixels of a lamp at 10 m and one of the wall behind: MAD 0, so the 0.25 m floor.
  const solo::LightDepthBand lamp = solo::lightDepthBand({10, 10, 10, 60});
  EXPECT_DOUBLE_EQ(lamp.median_m, 10);
  EXPECT_DOUBLE_EQ(lamp.half_width_m, 0.25);
  EXPECT_TRUE(lamp.contains(10.25));
  EXPECT_FALSE(lamp.contains(10.26));
  EXPECT_FALSE(lamp.contains(60));
  // Depth spread evenly: median 3, deviations 0 1 1 2 2, MAD 1, half width 3: all inside.
  const solo::LightDepthBand slope = solo::lightDepthBand({5, 1, 4, 2, 3});
  EXPECT_DOUBLE_EQ(slope.median_m, 3);
  EXPECT_DOUBLE_EQ(slope.half_width_m, 3);
  for (double z : {1.0, 5.0}) EXPECT_TRUE(slope.contains(z));
  EXPECT_THROW(solo::lightDepthBand({}), std::invalid_argument);
}

TEST(LightGeometry, SyntheticStreetWindowsHaveTheirTrueSizeAndFacing) {
  solo::StreetSceneOptions options;
  options.width = 960;
  options.height = 540;
  const solo::StreetScene scene = solo::buildStreetScene(options);
  const solo::GroundTruthMaps truth = solo::rasterizeGroundTruth(scene);
  const solo::LightGroupTree tree = solo::buildLightGroups(truth.lights, truth.instances, truth.light_groups, "lights");
  const auto geometry = solo::measureLightGeometry(tree, truth.depth_m, scene.camera);
  // A window is a 1.3 m x 1.6 m pane (2.08 m2) standing 6 cm proud of its facade; its
  // visible side and top or bottom add at most 0.128 + 0.104 m2.
  std::vector<double> areas, facing;
  for (std::size_t i = 0; i < tree.lights.size(); ++i) {
    if (tree.lights[i].category != solo::LightCategory::WindowBuilding || tree.lights[i].pixels < 400) continue;
    areas.push_back(geometry[i].area_m2);
    facing.push_back(std::abs(geometry[i].normal.x()));
    const Eigen::Vector3d c = geometry[i].centroid_m;
    // Panes stand at x = 7.25 - 0.06 (right facade) or -10.75 + 0.06 (left facade).
    EXPECT_TRUE(std::abs(c.x() - 7.19) < 0.1 || std::abs(c.x() + 10.69) < 0.1) << "centroid " << c.transpose();
  }
  ASSERT_GE(areas.size(), 10u);
  EXPECT_GT(median(areas), 2.08 * 0.97);
  EXPECT_LT(median(areas), (2.08 + 0.128 + 0.104) * 1.03);
  EXPECT_GT(median(facing), 0.99) << "windows face across the street";
}

TEST(LightGeometry, DepthResamplingIgnoresInvalidPixels) {
  cv::Mat depth(2, 2, CV_32F, cv::Scalar(0));
  depth.at<float>(0, 0) = 4;
  depth.at<float>(0, 1) = 8;
  const cv::Mat up = solo::resampleDepthIgnoringInvalid(depth, {4, 4});
  EXPECT_FLOAT_EQ(up.at<float>(0, 0), 4);
  EXPECT_FLOAT_EQ(up.at<float>(0, 3), 8);
  EXPECT_FLOAT_EQ(up.at<float>(1, 0), 4) << "the invalid row below does not pull depth toward 0";
  EXPECT_FLOAT_EQ(up.at<float>(3, 0), 0) << "no valid source pixel within reach";
  EXPECT_NEAR(up.at<float>(1, 1), 4 * 0.75 + 8 * 0.25, 1e-5);
}
