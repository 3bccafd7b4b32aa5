// The night scene: faces take the reflectance and the light of the pixel under them.

#include <solo/geometry/depth_mesh.h>
#include <solo/lighting/colorimetry.h>
#include <solo/render/night_scene.h>

#include "test_support.h"

namespace {

// A fronto-parallel plane 4 m away, 6x4 pixels: 5 x 3 quads = 30 faces.
solo::DepthMesh planeMesh() {
  const cv::Mat depth(4, 6, CV_32F, cv::Scalar(4.f));
  return solo::meshFromDepth(depth, {10, 10, 2.5, 1.5, 6, 4});
}

}  // namespace

TEST(NightScene, FacesTakeTheAlbedoOfTheirPixelAndNoLightMeansNoEmitter) {
  const solo::DepthMesh mesh = planeMesh();
  cv::Mat albedo(4, 6, CV_32FC3, cv::Scalar(0.2f, 0.2f, 0.2f));
  albedo(cv::Rect(3, 0, 3, 4)).setTo(cv::Scalar(0.6f, 0.6f, 0.6f));  // right half brighter
  solo::NightSceneOptions options;
  options.headlights = false;
  const solo::NightScene night = solo::buildNightScene(mesh, albedo, {}, {}, solo::LightRecord{}, options);
  ASSERT_EQ(night.scene.faces.size(), 30u);
  int dark = 0, bright = 0;
  for (const Eigen::Vector3f& r : night.scene.face_reflectance) {
    // Greys stay grey in XYZ relative to E.
    EXPECT_NEAR(r.x(), r.y(), 1e-5);
    EXPECT_NEAR(r.z(), r.y(), 1e-5);
    dark += std::abs(r.y() - 0.2f) < 1e-5f;
    bright += std::abs(r.y() - 0.6f) < 1e-5f;
  }
  EXPECT_EQ(dark + bright, 30);
  EXPECT_GT(dark, 0);
  EXPECT_GT(bright, 0);
  EXPECT_TRUE(night.scene.emitters.empty());
  EXPECT_TRUE(night.scene.rectangle_lights.empty());
  bool said_no_light = false;
  for (const std::string& note : night.report.notes) said_no_light |= note == "no active light in view";
  EXPECT_TRUE(said_no_light);
}

TEST(NightScene, AnOnLightEmitsItsLuminanceInItsColourAndAnOffLightNothing) {
  const solo::DepthMesh mesh = planeMesh();
  solo::LightRecord record;
  record.tree.width = 6;
  record.tree.height = 4;
  record.tree.groups.push_back({});
  for (int i = 0; i < 2; ++i) {
    solo::Light light;
    light.id = i + 1;
    light.map_id = 1000 + i;
    light.category = solo::LightCategory::WindowBuilding;
    for (int row = 0; row < 4; ++row) light.runs.push_back({row, 3 * i, 3 * i + 2});
    light.pixels = 12;
    record.tree.lights.push_back(light);
    record.geometry.push_back({});
    record.geometry.back().area_m2 = 1.0;
    record.geometry.back().pixels_with_depth = 12;
    solo::LightState state;
    state.on = i == 0;
    state.xy = {0.45, 0.41};
    state.strength = 50;
    state.unit = solo::StrengthUnit::LuminanceCdPerM2;
    record.instantiation.lights.push_back(state);
  }
  solo::NightSceneOptions options;
  options.headlights = false;
  const solo::NightScene night = solo::buildNightScene(mesh, {}, {}, {}, record, options);
  ASSERT_EQ(night.scene.emitters.size(), 1u) << "only the light that is on";
  const Eigen::Vector3f expected = solo::xyzFromChromaticity({0.45, 0.41}, 50).cast<float>();
  EXPECT_NEAR(night.scene.emitters[0].radiance.y(), 50.f, 1e-3f);
  EXPECT_NEAR(night.scene.emitters[0].radiance.x(), expected.x(), 1e-3f);
  EXPECT_EQ(night.scene.emitters[0].light_id, 1000);
  EXPECT_FALSE(night.scene.emitters[0].directional_profile) << "windows emit uniformly";
  int emitting = 0;
  for (int e : night.scene.face_emitter) emitting += e == 0;
  EXPECT_GT(emitting, 0);
  EXPECT_LT(emitting, 30) << "faces over the light that is off do not emit";
}

TEST(NightScene, AMeshFromADownsampledDepthMapTakesTheAlbedoUnderItsFacesAtFullResolution) {
  // The image is 12x8; the mesh is made from its depth downsampled 2x (6x4 vertices), as
  // `solo night --mesh-downsample 2` does. The albedo's left 6 columns are dark, the right 6
  // bright: in coarse pixels the boundary lies between columns 2 and 3.
  const solo::PinholeCamera image_camera{20, 20, 5.5, 3.5, 12, 8};
  const cv::Mat coarse_depth(4, 6, CV_32F, cv::Scalar(4.f));
  const solo::DepthMesh mesh = solo::meshFromDepth(coarse_depth, image_camera);
  ASSERT_EQ(mesh.width, 6);
  cv::Mat albedo(8, 12, CV_32FC3, cv::Scalar(0.2f, 0.2f, 0.2f));
  albedo(cv::Rect(6, 0, 6, 8)).setTo(cv::Scalar(0.6f, 0.6f, 0.6f));
  solo::NightSceneOptions options;
  options.headlights = false;
  const solo::NightScene night = solo::buildNightScene(mesh, albedo, {}, {}, solo::LightRecord{}, options);
  // The render camera is the image's, not the mesh's.
  EXPECT_EQ(night.scene.camera.width, 12);
  EXPECT_EQ(night.scene.camera.height, 8);
  EXPECT_DOUBLE_EQ(night.scene.camera.cx, image_camera.cx);
  const auto props = solo::ImageVertexProperties::find(mesh.mesh);
  ASSERT_TRUE(props.has_value());
  std::size_t face_index = 0;
  int left_faces = 0, right_faces = 0;
  for (const auto f : mesh.mesh.faces()) {
    int min_u = 99, max_u = -1;
    for (const auto vh : mesh.mesh.fv_range(f)) {
      const int u = mesh.mesh.property(props->pixel, vh)[0];
      min_u = std::min(min_u, u);
      max_u = std::max(max_u, u);
    }
    const float y = night.scene.face_reflectance[face_index++].y();
    if (max_u <= 2) {  // covers image columns 0-5 only
      EXPECT_NEAR(y, 0.2f, 1e-5f) << "coarse columns " << min_u << "-" << max_u;
      ++left_faces;
    }
    if (min_u >= 3) {  // image columns 6-11 (read at its own coarse column, they would be dark)
      EXPECT_NEAR(y, 0.6f, 1e-5f) << "coarse columns " << min_u << "-" << max_u;
      ++right_faces;
    }
  }
  EXPECT_EQ(face_index, night.scene.faces.size());
  EXPECT_EQ(left_faces, 12);   // quads 0-1 and 1-2 of 3 rows, two faces each
  EXPECT_EQ(right_faces, 12);  // quads 3-4 and 4-5
}
