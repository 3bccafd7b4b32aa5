// The night scene: faces take the reflectance and the light of the pixel under them.

#include <solo/geometry/depth_mesh.h>
#include <solo/lighting/colorimetry.h>
#include <solo/render/night_scene.h>
#include <solo/render/path_tracer.h>

#include "test_support.h"

#include <Eigen/Geometry>

namespace {

// A fronto-parallel plane 4 m away, 6x4 pixels: 5 x 3 quads = 30 faces.
solo::DepthMesh planeMesh() {
  const cv::Mat depth(4, 6, CV_32F, cv::Scalar(4.f));
  return solo::meshFromDepth(depth, {10, 10, 2.5, 1.5, 6, 4});
}

// A record at width x height pixels (6x4 by default) with one light that is on over columns
// first..last of every row.
solo::LightRecord oneLightRecord(solo::LightCategory category, int first_col, int last_col, double strength,
                                 solo::StrengthUnit unit, int map_id, Eigen::Vector2d xy, double record_area_m2,
                                 int width = 6, int height = 4) {
  solo::LightRecord record;
  record.tree.width = width;
  record.tree.height = height;
  record.tree.groups.push_back({});
  solo::Light light;
  light.id = 1;
  light.map_id = map_id;
  light.category = category;
  for (int row = 0; row < height; ++row) light.runs.push_back({row, first_col, last_col});
  light.pixels = height * (last_col - first_col + 1);
  record.tree.lights.push_back(light);
  record.geometry.push_back({});
  record.geometry.back().area_m2 = record_area_m2;
  record.geometry.back().pixels_with_depth = light.pixels;
  solo::LightState state;
  state.on = true;
  state.xy = xy;
  state.strength = strength;
  state.unit = unit;
  record.instantiation.lights.push_back(state);
  return record;
}

// A 1000 lm front light over columns 2-5 of a lamp 4 m away whose column 5 sees a wall
// `wall_m` away: the faces between columns 4 and 5 are stretched across the depth jump.
solo::NightScene lampBeforeAWall(float wall_m) {
  cv::Mat depth(4, 6, CV_32F, cv::Scalar(4.f));
  depth.col(5).setTo(wall_m);
  const solo::DepthMesh mesh = solo::meshFromDepth(depth, {10, 10, 2.5, 1.5, 6, 4});
  const solo::LightRecord record =
      oneLightRecord(solo::LightCategory::MovingFront, 2, 5, 1000, solo::StrengthUnit::FluxLm, 2600, {0.44, 0.40}, 1.0);
  solo::NightSceneOptions options;
  options.headlights = false;
  return solo::buildNightScene(mesh, {}, {}, {}, record, options);
}

// Area of face f of a scene whose faces are fronto-parallel (their extent in x and y), m^2.
double frontoParallelArea(const solo::RenderScene& scene, std::size_t f) {
  const auto& face = scene.faces[f];
  const Eigen::Vector3f a = scene.vertices[face[0]];
  const Eigen::Vector3f ab = scene.vertices[face[1]] - a, ac = scene.vertices[face[2]] - a;
  return 0.5 * std::abs(static_cast<double>(ab.x() * ac.y() - ab.y() * ac.x()));
}

std::int64_t countMetric(const solo::StageReport& report, const std::string& name) {
  const solo::MetricValue* value = report.find(name);
  EXPECT_NE(value, nullptr) << name;
  return value ? std::get<std::int64_t>(*value) : -1;
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
  for (const std::string& warning : night.report.warnings) said_no_light |= warning == "no active light in view";
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
  EXPECT_EQ(night.scene.emitters[0].profile, solo::EmitterProfile::Uniform) << "windows emit uniformly";
  int emitting = 0;
  for (int e : night.scene.face_emitter) emitting += e == 0;
  EXPECT_GT(emitting, 0);
  EXPECT_LT(emitting, 30) << "faces over the light that is off do not emit";
  // The report compares the luminance lights' emitting area on the mesh with the record's (the
  // light that is on only).
  double emitting_area_m2 = 0;
  for (std::size_t f = 0; f < night.scene.faces.size(); ++f)
    if (night.scene.face_emitter[f] == 0) emitting_area_m2 += frontoParallelArea(night.scene, f);
  const auto area = [&](const std::string& name) {
    const solo::MetricValue* value = night.report.find(name);
    EXPECT_NE(value, nullptr) << name;
    return value ? std::get<double>(*value) : -1.0;
  };
  EXPECT_NEAR(area("luminance_lights_area_mesh"), emitting_area_m2, 1e-6);
  EXPECT_EQ(area("luminance_lights_area_record"), 1.0);
  EXPECT_EQ(area("flux_lights_area_mesh"), 0.0);
}

// A fronto-parallel plane 4 m away, 12x8 pixels, albedo 0.2 over columns 0-5 and 0.6 over 6-11,
// a lit window (50 cd/m^2) over columns 9-11; nothing else lights it. A face takes the pixel
// under its centroid: of a quad's two triangles the upper-left one takes the quad's upper-left
// pixel, the lower-right one the lower-right pixel, so an edge between columns follows the
// quads' diagonals. The pixel texture gives each camera sample its own pixel's values.
TEST(NightScene, ACameraRayTakesItsOwnPixelsMaterialAndLightNotItsQuadsDiagonal) {
  const cv::Mat depth(8, 12, CV_32F, cv::Scalar(4.f));
  const solo::DepthMesh mesh = solo::meshFromDepth(depth, {10, 10, 5.5, 3.5, 12, 8});
  cv::Mat albedo(8, 12, CV_32FC3, cv::Scalar(0.2f, 0.2f, 0.2f));
  albedo(cv::Rect(6, 0, 6, 8)).setTo(cv::Scalar(0.6f, 0.6f, 0.6f));
  const solo::LightRecord record = oneLightRecord(solo::LightCategory::WindowBuilding, 9, 11, 50,
                                                  solo::StrengthUnit::LuminanceCdPerM2, 1000, {1.0 / 3.0, 1.0 / 3.0},
                                                  1.0, 12, 8);
  solo::NightSceneOptions options;
  options.headlights = false;
  const solo::NightScene night = solo::buildNightScene(mesh, albedo, {}, {}, record, options);
  const solo::RenderScene& scene = night.scene;

  // The texture: a texel per pixel with the pixel's values, a texel per pixel vertex.
  ASSERT_EQ(scene.texture_width, 12);
  ASSERT_EQ(scene.texture_height, 8);
  ASSERT_EQ(scene.texel_reflectance.size(), 96u);
  EXPECT_NEAR(scene.texel_reflectance[3 * 12 + 5].y(), 0.2f, 1e-5f);
  EXPECT_NEAR(scene.texel_reflectance[3 * 12 + 6].y(), 0.6f, 1e-5f);
  EXPECT_EQ(scene.texel_emitter[3 * 12 + 8], -1);
  EXPECT_EQ(scene.texel_emitter[3 * 12 + 9], 0);
  EXPECT_EQ(scene.texel_reflectance[3 * 12 + 9].norm(), 0.f) << "an emitting pixel reflects nothing";
  ASSERT_EQ(scene.vertex_texel.size(), scene.vertices.size());
  for (std::size_t v = 0; v < scene.vertices.size(); ++v) {
    const Eigen::Vector2d uv = mesh.camera.project(scene.vertices[v].cast<double>());
    EXPECT_EQ(scene.vertex_texel[v], std::lround(uv.y()) * 12 + std::lround(uv.x())) << "vertex " << v;
  }

  solo::PathTracerOptions o;
  o.min_samples = o.max_samples = 64;
  o.progress = false;
  const solo::RenderOutput textured = solo::renderPathTraced(scene, o);
  o.pixel_texture = false;
  const solo::RenderOutput by_face = solo::renderPathTraced(scene, o);
  for (int y = 1; y < 7; ++y) {
    // Every sample of column 5 sees albedo 0.2, of column 6 0.6; by face, part of each sees
    // the other column's (the lower-right triangles of the quads between them).
    EXPECT_NEAR(textured.mean_albedo.at<cv::Vec3f>(y, 5)[1], 0.2f, 1e-5f) << "row " << y;
    EXPECT_NEAR(textured.mean_albedo.at<cv::Vec3f>(y, 6)[1], 0.6f, 1e-5f) << "row " << y;
    EXPECT_GT(by_face.mean_albedo.at<cv::Vec3f>(y, 5)[1], 0.2f + 0.02f) << "row " << y;
    // The window's light: column 9 emits 50 over the whole pixel, column 8 nothing (the window
    // lies in the plane: it lights no part of it); by face, part of column 8 emits.
    EXPECT_NEAR(textured.radiance.at<cv::Vec3f>(y, 9)[1], 50.f, 1e-3f) << "row " << y;
    EXPECT_EQ(textured.radiance.at<cv::Vec3f>(y, 8)[1], 0.f) << "row " << y;
    EXPECT_EQ(textured.emitter_coverage.at<float>(y, 8), 0.f) << "row " << y;
    EXPECT_GT(by_face.radiance.at<cv::Vec3f>(y, 8)[1], 1.f) << "row " << y;
  }
  // A render at another size keeps the faces' values.
  solo::RenderScene half = scene;
  half.camera = scene.camera.scaledTo(6, 4);
  o.pixel_texture = true;
  const solo::RenderOutput other = solo::renderPathTraced(half, o);
  o.pixel_texture = false;
  const solo::RenderOutput other_by_face = solo::renderPathTraced(half, o);
  EXPECT_EQ(cv::norm(other.radiance, other_by_face.radiance, cv::NORM_INF), 0.0);
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

TEST(NightScene, SurfacePixelsAreThePixelsThatHadDepthAtTheRenderResolution) {
  // A 12x8 image, its mesh from the depth downsampled 2x; coarse pixel (1, 1) is sky and (4, 2)
  // lost its vertex in cleanup: both make no vertex, but only (4, 2) had depth.
  const solo::PinholeCamera image_camera{20, 20, 5.5, 3.5, 12, 8};
  cv::Mat coarse_depth(4, 6, CV_32F, cv::Scalar(4.f));
  coarse_depth.at<float>(1, 1) = 0.f;
  coarse_depth.at<float>(2, 4) = 0.f;
  solo::DepthMesh mesh = solo::meshFromDepth(coarse_depth, image_camera);
  cv::Mat albedo(8, 12, CV_32FC3, cv::Scalar(0.5f, 0.5f, 0.5f));
  solo::NightSceneOptions options;
  options.headlights = false;
  const auto surface = [](const solo::RenderScene& scene, int x, int y) {
    return static_cast<int>(scene.surface_pixels[static_cast<std::size_t>(y) * 12 + static_cast<std::size_t>(x)]);
  };
  // Before cleanup (no had_depth): the pixels with a vertex.
  const solo::NightScene raw = solo::buildNightScene(mesh, albedo, {}, {}, solo::LightRecord{}, options);
  ASSERT_EQ(raw.scene.surface_pixels.size(), 96u);
  EXPECT_EQ(countMetric(raw.report, "surface_pixels"), 96 - 8);
  for (int y = 2; y < 4; ++y)
    for (int x = 2; x < 4; ++x) EXPECT_EQ(surface(raw.scene, x, y), 0) << x << "," << y;
  EXPECT_EQ(surface(raw.scene, 9, 5), 0);
  EXPECT_EQ(surface(raw.scene, 1, 1), 1);
  EXPECT_EQ(surface(raw.scene, 11, 7), 1);
  // After cleanup: the pixels that had depth, also where the vertex went.
  mesh.had_depth = cv::Mat(4, 6, CV_8U, cv::Scalar(1));
  mesh.had_depth.at<std::uint8_t>(1, 1) = 0;
  const solo::NightScene cleaned = solo::buildNightScene(mesh, albedo, {}, {}, solo::LightRecord{}, options);
  EXPECT_EQ(countMetric(cleaned.report, "surface_pixels"), 96 - 4);
  EXPECT_EQ(surface(cleaned.scene, 2, 3), 0);
  for (int y = 4; y < 6; ++y)
    for (int x = 8; x < 10; ++x) EXPECT_EQ(surface(cleaned.scene, x, y), 1) << x << "," << y;
}

TEST(NightScene, AFluxLightKeepsItsFluxOnTheSeenFacesAndHiddenFacesUnderItDoNotEmit) {
  // A street light over the right half of the plane (columns 3-5), 6000 lm. Vertices of
  // column 5 are marked as the back of a closed solid: the faces touching them share the
  // light's pixels but are not what the pixels see, so they must not emit, and the flux must
  // sit on the faces that remain.
  solo::DepthMesh mesh = planeMesh();
  const auto props = solo::ImageVertexProperties::find(mesh.mesh);
  ASSERT_TRUE(props.has_value());
  for (const auto vh : mesh.mesh.vertices())
    if (mesh.mesh.property(props->pixel, vh)[0] == 5)
      mesh.mesh.property(props->origin, vh) = static_cast<std::uint8_t>(solo::VertexOrigin::SolidBack);
  const solo::LightRecord record =
      oneLightRecord(solo::LightCategory::StreetLightLowCct, 3, 5, 6000, solo::StrengthUnit::FluxLm, 1900, {0.5, 0.42},
                     0.05);  // the record's area estimate: the mesh decides
  solo::NightSceneOptions options;
  options.headlights = false;
  const solo::NightScene night = solo::buildNightScene(mesh, {}, {}, {}, record, options);
  ASSERT_EQ(night.scene.emitters.size(), 1u);
  EXPECT_EQ(night.scene.emitters[0].profile, solo::EmitterProfile::CosineLobe);

  // Faces whose mean pixel column rounds into 3-5: quads 2-3 (mean columns 2.33 and 2.67: one
  // of each pair rounds to 3), 3-4 and 4-5. Those touching column 5 are hidden.
  double area = 0;
  int emitting = 0, hidden_under_light = 0;
  for (std::size_t f = 0; f < night.scene.faces.size(); ++f) {
    const auto& face = night.scene.faces[f];
    bool touches_back = false;
    double mean_x = 0;
    for (const std::uint32_t v : face) {
      // The plane is 4 m away with fx = 10 and cx = 2.5: x = 0.4 (u - 2.5) m.
      const double u = night.scene.vertices[v].x() / 0.4 + 2.5;
      touches_back |= std::lround(u) == 5;
      mean_x += u / 3;
    }
    const bool under_light = std::lround(mean_x) >= 3;
    if (under_light && touches_back) ++hidden_under_light;
    if (night.scene.face_emitter[f] < 0) {
      EXPECT_NEAR(night.scene.face_reflectance[f].y(), options.default_reflectance, 1e-6f) << "face " << f;
      continue;
    }
    ++emitting;
    EXPECT_EQ(night.scene.face_reflectance[f], Eigen::Vector3f::Zero()) << "an emitting face reflects nothing";
    EXPECT_FALSE(touches_back) << "face " << f << " is behind what the pixels see";
    EXPECT_TRUE(under_light);
    area += frontoParallelArea(night.scene, f);
  }
  EXPECT_EQ(hidden_under_light, 6) << "quad 4-5 of 3 rows, two faces each";
  EXPECT_EQ(emitting, 9) << "quad 3-4 (6 faces) and one face of each quad 2-3 (3)";
  // Each face is half of a 0.4 x 0.4 m quad.
  EXPECT_NEAR(area, 9 * 0.08, 1e-5);
  // Flux = L * area * (8 / pi) for the g profile: all 6000 lm, whatever the record's area said.
  const double flux = night.scene.emitters[0].radiance.y() * area * solo::profileProjectedSolidAngle(
                                                                          solo::EmissionProfile::CosineLobe);
  EXPECT_NEAR(flux, 6000.0, 6000.0 * 1e-5);
  EXPECT_EQ(countMetric(night.report, "hidden_faces_under_lights"), 6);
}

TEST(NightScene, FacesALightsSilhouetteStretchesToTheBackgroundDoNotEmit) {
  // The lamp's column 5 sees a wall 9 m away: the faces between columns 4 and 5 span 4-9 m of
  // depth (mixed pixels at a silhouette). The light covers columns 2-5, so some of those
  // stretched faces lie under its pixels; they must not emit, and the lamp's 1000 lm must sit
  // on the faces at its own depth.
  const solo::NightScene night = lampBeforeAWall(9.f);
  ASSERT_EQ(night.scene.emitters.size(), 1u);
  double area = 0;
  int emitting = 0;
  for (std::size_t f = 0; f < night.scene.faces.size(); ++f) {
    if (night.scene.face_emitter[f] < 0) continue;
    ++emitting;
    for (const std::uint32_t v : night.scene.faces[f]) EXPECT_FLOAT_EQ(night.scene.vertices[v].z(), 4.f) << "face " << f;
    area += frontoParallelArea(night.scene, f);
  }
  // Under columns 2-5 (mean column rounded): one face of quad 1-2, quads 2-3 and 3-4 (the
  // flat lamp: 3 + 12 faces) and quad 4-5 (6 stretched faces, left out).
  EXPECT_EQ(emitting, 15);
  EXPECT_NEAR(area, 15 * 0.08, 1e-5);
  const double flux = night.scene.emitters[0].radiance.y() * area *
                      solo::profileProjectedSolidAngle(solo::EmissionProfile::CosineLobe);
  EXPECT_NEAR(flux, 1000.0, 1e-2);
  EXPECT_EQ(countMetric(night.report, "faces_off_light_depth"), 6);
}

TEST(NightScene, AFilledFaceEmitsWhereItIsTheSeenSurfaceNotBehindIt) {
  // The light covers columns 3-5 of the plane 4 m away. Column 4's vertices are marked as
  // added by hole filling (the lamp's faces removed as spurious and filled again): those faces
  // are what the pixels see and must emit. A filled quad 4 m behind the plane, under the same
  // pixels (a backdrop), must not.
  solo::DepthMesh mesh = planeMesh();
  const auto props = solo::ImageVertexProperties::find(mesh.mesh);
  ASSERT_TRUE(props.has_value());
  for (const auto vh : mesh.mesh.vertices())
    if (mesh.mesh.property(props->pixel, vh)[0] == 4)
      mesh.mesh.property(props->origin, vh) = static_cast<std::uint8_t>(solo::VertexOrigin::HoleFill);
  std::array<solo::SurfaceMesh::VertexHandle, 4> back;
  const int corner_u[4] = {3, 5, 5, 3}, corner_v[4] = {0, 0, 3, 3};
  for (int k = 0; k < 4; ++k) {
    // (u - cx) z / fx with z = 8 m: behind the plane's pixels 3-5.
    back[static_cast<std::size_t>(k)] = mesh.mesh.add_vertex(
        solo::SurfaceMesh::Point(0.8f * (corner_u[k] - 2.5f), 0.8f * (corner_v[k] - 1.5f), 8.f));
    mesh.mesh.property(props->pixel, back[static_cast<std::size_t>(k)]) = OpenMesh::Vec2i(corner_u[k], corner_v[k]);
    mesh.mesh.property(props->origin, back[static_cast<std::size_t>(k)]) =
        static_cast<std::uint8_t>(solo::VertexOrigin::HoleFill);
  }
  mesh.mesh.add_face(back[0], back[1], back[2]);
  mesh.mesh.add_face(back[0], back[2], back[3]);
  const solo::LightRecord record =
      oneLightRecord(solo::LightCategory::WindowBuilding, 3, 5, 40, solo::StrengthUnit::LuminanceCdPerM2, 1100, {0.45, 0.41}, 1.0);
  solo::NightSceneOptions options;
  options.headlights = false;
  const solo::NightScene night = solo::buildNightScene(mesh, {}, {}, {}, record, options);
  ASSERT_EQ(night.scene.faces.size(), 32u);
  int emitting_filled = 0, emitting = 0;
  for (std::size_t f = 0; f < night.scene.faces.size(); ++f) {
    if (night.scene.face_emitter[f] < 0) continue;
    ++emitting;
    bool touches_column_4 = false;
    for (const std::uint32_t v : night.scene.faces[f]) {
      EXPECT_FLOAT_EQ(night.scene.vertices[v].z(), 4.f) << "the backdrop behind the light emits";
      touches_column_4 |= std::lround(night.scene.vertices[v].x() / 0.4f + 2.5f) == 4;
    }
    emitting_filled += touches_column_4;
  }
  // Faces under columns 3-5 (one of each quad 2-3, quads 3-4 and 4-5: 3 + 6 + 6 = 15), of
  // which those touching column 4 (quads 3-4 and 4-5) are filled.
  EXPECT_EQ(emitting, 15);
  EXPECT_EQ(emitting_filled, 12);
  EXPECT_EQ(countMetric(night.report, "hidden_faces_under_lights"), 2) << "the backdrop's two faces";
}

TEST(NightScene, AFluxLightDropsTheFacesItShowsEdgeOn) {
  // The lamp's column 5 sees a wall 60 m away: the faces between columns 4 and 5 lie within
  // about a degree of the camera's rays (edge-on), so the lamp drops them before its depth
  // band is even needed.
  const solo::NightScene night = lampBeforeAWall(60.f);
  int emitting = 0;
  for (std::size_t f = 0; f < night.scene.faces.size(); ++f) emitting += night.scene.face_emitter[f] >= 0;
  EXPECT_EQ(emitting, 15);
  EXPECT_EQ(countMetric(night.report, "flux_light_faces_edge_on"), 6);
  EXPECT_EQ(countMetric(night.report, "faces_off_light_depth"), 0);
}

namespace {

// The record's plane for a light over columns 3-5 of the 6x4 plane 4 m away: what the light
// stage measures before the mesh stage removes the lamp's faces.
void setRecordPlane(solo::LightRecord& record, const Eigen::Vector3d& normal) {
  solo::LightGeometry& g = record.geometry.at(0);
  g.centroid_m = {4.0 * (4 - 2.5) / 10, 0.0, 4.0};  // mean column 4, mean row 1.5
  g.normal = normal;
  g.area_m2 = 12 * 0.4 * 0.4;
  g.pixels_with_depth = 12;
}

// The 6x4 plane 4 m away without depth in columns 3-5: the mesh stage took the lamp's faces.
solo::DepthMesh planeWithoutTheLamp() {
  cv::Mat depth(4, 6, CV_32F, cv::Scalar(4.f));
  depth.colRange(3, 6).setTo(0.f);
  return solo::meshFromDepth(depth, {10, 10, 2.5, 1.5, 6, 4});
}

// Camera-frame point -> pixel coordinates of the 6x4 test camera (fx = fy = 10, c = (2.5, 1.5)).
Eigen::Vector2d pixelOf(const Eigen::Vector3f& p) {
  return {10.0 * p.x() / p.z() + 2.5, 10.0 * p.y() / p.z() + 1.5};
}

double faceArea(const solo::RenderScene& scene, std::size_t f) {
  const auto& face = scene.faces[f];
  const Eigen::Vector3d a = scene.vertices[face[0]].cast<double>();
  return 0.5 * (scene.vertices[face[1]].cast<double>() - a).cross(scene.vertices[face[2]].cast<double>() - a).norm();
}

}  // namespace

TEST(NightScene, ALightWithoutFacesEmitsItsFluxFromItsPixelsOnTheRecordsPlane) {
  // Columns 3-5 have no depth (the mesh stage took the lamp's faces), so no face shows the
  // 6000 lm street light there. It emits from its pixels on its record's plane: per row a quad
  // whose corners project to the pixel corners (columns 2.5 and 5.5), on z = 4 (1 - d / |c|)
  // with d = 1 cm + 0.2 % of the centroid's distance |c|, a black plate half way behind it.
  const solo::DepthMesh mesh = planeWithoutTheLamp();
  solo::LightRecord record =
      oneLightRecord(solo::LightCategory::StreetLightHighCct, 3, 5, 6000, solo::StrengthUnit::FluxLm, 7001, {0.38, 0.37}, 0);
  setRecordPlane(record, {0, 0, -1});
  solo::NightSceneOptions options;
  options.headlights = false;
  const solo::NightScene night = solo::buildNightScene(mesh, {}, {}, {}, record, options);
  ASSERT_EQ(night.scene.emitters.size(), 1u);
  const double distance = std::sqrt(0.6 * 0.6 + 16.0);
  const double z_front = 4.0 * (1.0 - (0.01 + 0.002 * distance) / distance), z_plate = 0.5 * (z_front + 4.0);
  int emitting = 0, plates = 0;
  double area = 0;
  for (std::size_t f = 0; f < night.scene.faces.size(); ++f) {
    const bool emits = night.scene.face_emitter[f] >= 0;
    bool plate = false;
    for (const std::uint32_t v : night.scene.faces[f]) plate |= std::abs(night.scene.vertices[v].z() - z_plate) < 1e-5;
    if (!emits && !plate) continue;
    EXPECT_EQ(night.scene.face_reflectance[f], Eigen::Vector3f::Zero()) << "face " << f;
    for (const std::uint32_t v : night.scene.faces[f]) {
      const Eigen::Vector3f& p = night.scene.vertices[v];
      EXPECT_NEAR(p.z(), emits ? z_front : z_plate, 1e-5) << "face " << f;
      const Eigen::Vector2d pixel = pixelOf(p);
      EXPECT_TRUE(std::abs(pixel.x() - 2.5) < 1e-4 || std::abs(pixel.x() - 5.5) < 1e-4) << pixel.transpose();
      EXPECT_NEAR(pixel.y() - std::round(pixel.y() + 0.5), -0.5, 1e-4) << pixel.transpose();
    }
    if (emits) {
      ++emitting;
      area += faceArea(night.scene, f);
    } else {
      ++plates;
    }
  }
  EXPECT_EQ(emitting, 8) << "two per row";
  EXPECT_EQ(plates, 8);
  EXPECT_NEAR(area, 12 * (z_front / 10) * (z_front / 10), 1e-5) << "12 pixel footprints at the plane's depth";
  const double flux = night.scene.emitters[0].radiance.y() * area *
                      solo::profileProjectedSolidAngle(solo::EmissionProfile::CosineLobe);
  EXPECT_NEAR(flux, 6000.0, 6000.0 * 1e-5);
  EXPECT_EQ(countMetric(night.report, "light_proxies"), 1);
  EXPECT_EQ(countMetric(night.report, "light_proxies_for_area"), 0);
  EXPECT_EQ(countMetric(night.report, "lights_on_without_faces"), 1) << "it shows no face, and emits from its proxy";
  EXPECT_EQ(countMetric(night.report, "lights_on_not_emitting"), 0);

  // A record of another resolution than the maps' is not mapped at all: its runs are not the
  // render camera's pixels.
  solo::LightRecord other_size = record;
  other_size.tree.width = 12;
  other_size.tree.height = 8;
  const cv::Mat albedo(4, 6, CV_32FC3, cv::Scalar(0.5f, 0.5f, 0.5f));
  EXPECT_TRUE(solo::buildNightScene(mesh, albedo, {}, {}, other_size, options).scene.emitters.empty());
  EXPECT_EQ(solo::buildNightScene(mesh, albedo, {}, {}, record, options).scene.emitters.size(), 1u);

  // Without a usable plane (no depth under the light and no placement by the light stage's
  // priors) there is nothing to emit from, and the report says so.
  record.geometry[0] = {};
  const solo::NightScene unlit = solo::buildNightScene(mesh, {}, {}, {}, record, options);
  EXPECT_TRUE(unlit.scene.emitters.empty());
  EXPECT_EQ(countMetric(unlit.report, "lights_on_without_faces"), 1);
  EXPECT_EQ(countMetric(unlit.report, "lights_on_not_emitting"), 1);
  EXPECT_EQ(countMetric(unlit.report, "lights_on_without_depth"), 1);
  EXPECT_EQ(countMetric(unlit.report, "light_proxies"), 0);
  EXPECT_EQ(unlit.report.warnings.size(), 2u) << "the light that emits nothing, and no active light";

  // Placed at a prior depth by the light stage (no depth of its own), it emits from that plane.
  setRecordPlane(record, {0, 0, -1});
  record.geometry[0].pixels_with_depth = 0;
  record.geometry[0].placement = solo::LightPlacement::PriorDistance;
  const solo::NightScene placed = solo::buildNightScene(mesh, {}, {}, {}, record, options);
  EXPECT_EQ(placed.scene.emitters.size(), 1u);
  EXPECT_EQ(countMetric(placed.report, "lights_on_without_depth"), 1);
  EXPECT_EQ(countMetric(placed.report, "lights_on_not_emitting"), 0);
}

TEST(NightScene, ALightMovedOntoItsSupportEmitsFromItsRecordPlaneNotFromItsFaces) {
  // The mesh shows the lamp's pixels 4 m away; the light stage moved it onto its support at 3 m.
  const solo::DepthMesh mesh = planeMesh();
  solo::LightRecord record =
      oneLightRecord(solo::LightCategory::StreetLightHighCct, 3, 5, 6000, solo::StrengthUnit::FluxLm, 7001, {0.38, 0.37}, 0);
  setRecordPlane(record, {0, 0, -1});
  solo::LightGeometry& g = record.geometry[0];
  g.centroid_m *= 0.75;
  g.area_m2 *= 0.75 * 0.75;
  g.placement = solo::LightPlacement::MovedToSupport;
  solo::NightSceneOptions options;
  options.headlights = false;
  const solo::NightScene night = solo::buildNightScene(mesh, {}, {}, {}, record, options);
  ASSERT_EQ(night.scene.emitters.size(), 1u);
  EXPECT_EQ(countMetric(night.report, "light_proxies"), 1);
  EXPECT_EQ(countMetric(night.report, "light_proxies_moved"), 1);
  EXPECT_EQ(countMetric(night.report, "light_proxies_for_area"), 0);
  EXPECT_EQ(countMetric(night.report, "lights_on_without_faces"), 0);
  int emitting = 0;
  for (std::size_t f = 0; f < night.scene.faces.size(); ++f) {
    if (night.scene.face_emitter[f] < 0) continue;
    ++emitting;
    for (const std::uint32_t v : night.scene.faces[f]) EXPECT_LT(night.scene.vertices[v].z(), 3.0f) << "face " << f;
  }
  EXPECT_EQ(emitting, 8) << "the proxy's two quads per row; the mesh's faces at 4 m stay dark";
}

TEST(NightScene, AFluxLightWhoseFacesOutgrowItsRecordEmitsFromItsPixelsInstead) {
  // The plane's faces under columns 3-5 cover 15 x 0.08 = 1.2 m^2; the record measured 0.5 m^2 of
  // lamp. Past max_flux_area_ratio (2) the faces stay dark and the proxy emits the flux.
  const solo::DepthMesh mesh = planeMesh();
  solo::LightRecord record =
      oneLightRecord(solo::LightCategory::StreetLightHighCct, 3, 5, 6000, solo::StrengthUnit::FluxLm, 7001, {0.38, 0.37}, 0);
  setRecordPlane(record, {0, 0, -1});
  record.geometry[0].area_m2 = 0.5;
  solo::NightSceneOptions options;
  options.headlights = false;
  const auto emittingFaces = [](const solo::NightScene& night) {
    int n = 0;
    for (const std::int32_t e : night.scene.face_emitter) n += e >= 0;
    return n;
  };
  const solo::NightScene proxied = solo::buildNightScene(mesh, {}, {}, {}, record, options);
  EXPECT_EQ(emittingFaces(proxied), 8) << "the proxy's two faces per row, none of the mesh's";
  EXPECT_EQ(proxied.scene.faces.size(), 30u + 16u);
  EXPECT_EQ(countMetric(proxied.report, "light_proxies_for_area"), 1);
  for (std::size_t f = 0; f < 30; ++f) EXPECT_EQ(proxied.scene.face_emitter[f], -1) << "mesh face " << f;

  options.max_flux_area_ratio = 10;  // the mesh's faces are within it: they emit
  const solo::NightScene meshed = solo::buildNightScene(mesh, {}, {}, {}, record, options);
  EXPECT_EQ(meshed.scene.faces.size(), 30u);
  EXPECT_GT(emittingFaces(meshed), 8);
  EXPECT_EQ(countMetric(meshed.report, "light_proxies"), 0);
}

TEST(NightScene, AProxyOnAGrazingRecordPlaneFacesTheCameraAndStaysFinite) {
  // A record normal across the camera's rays (the plane fit of a sliver, or a normal map's
  // grazing estimate) would put the pixel corners kilometres away or at infinity. Past 85
  // degrees of incidence the proxy's plane faces the camera instead.
  const solo::DepthMesh mesh = planeWithoutTheLamp();
  solo::LightRecord record =
      oneLightRecord(solo::LightCategory::WindowBuilding, 3, 5, 50, solo::StrengthUnit::LuminanceCdPerM2, 1001, {0.45, 0.41}, 0);
  setRecordPlane(record, {1, 0, 0});
  solo::NightSceneOptions options;
  options.headlights = false;
  const solo::NightScene night = solo::buildNightScene(mesh, {}, {}, {}, record, options);
  ASSERT_EQ(night.scene.emitters.size(), 1u);
  EXPECT_NEAR(night.scene.emitters[0].radiance.y(), 50.f, 1e-3f) << "a luminance is emitted as it is";
  double area = 0;
  for (std::size_t f = 0; f < night.scene.faces.size(); ++f) {
    for (const std::uint32_t v : night.scene.faces[f]) ASSERT_TRUE(night.scene.vertices[v].allFinite());
    if (night.scene.face_emitter[f] >= 0) area += faceArea(night.scene, f);
  }
  // Facing the camera through the centroid 4.04 m away: close to the pixels' 1.92 m^2 at 4 m.
  EXPECT_GT(area, 1.7);
  EXPECT_LT(area, 2.0);
}

TEST(NightScene, AProxyAKilometreAwayKeepsItsFluxAndFiniteCorners) {
  // A lamp at the far end of a 1 km depth range: the proxy's quads are 100 m pixel footprints
  // (fx = 10), moved 2.01 m toward the camera, and the flux still comes out whole.
  const solo::DepthMesh mesh = planeWithoutTheLamp();
  solo::LightRecord record =
      oneLightRecord(solo::LightCategory::StreetLightHighCct, 3, 5, 6000, solo::StrengthUnit::FluxLm, 7001, {0.38, 0.37}, 0);
  setRecordPlane(record, {0, 0, -1});
  record.geometry[0].centroid_m *= 250.0;  // (150, 0, 1000) m
  solo::NightSceneOptions options;
  options.headlights = false;
  const solo::NightScene night = solo::buildNightScene(mesh, {}, {}, {}, record, options);
  ASSERT_EQ(night.scene.emitters.size(), 1u);
  const double distance = std::sqrt(150.0 * 150.0 + 1000.0 * 1000.0);
  const double z_front = 1000.0 * (1.0 - (0.01 + 0.002 * distance) / distance);
  double area = 0;
  for (std::size_t f = 0; f < night.scene.faces.size(); ++f) {
    for (const std::uint32_t v : night.scene.faces[f]) ASSERT_TRUE(night.scene.vertices[v].allFinite());
    if (night.scene.face_emitter[f] < 0) continue;
    for (const std::uint32_t v : night.scene.faces[f]) EXPECT_NEAR(night.scene.vertices[v].z(), z_front, 1e-3);
    area += faceArea(night.scene, f);
  }
  EXPECT_NEAR(area, 12 * (z_front / 10) * (z_front / 10), 1e-4 * area);
  const double flux = night.scene.emitters[0].radiance.y() * area *
                      solo::profileProjectedSolidAngle(solo::EmissionProfile::CosineLobe);
  EXPECT_NEAR(flux, 6000.0, 6000.0 * 1e-4);
}

TEST(NightScene, FacesShadeWithTheNormalMapsMeanNormalWhereItFacesTheCamera) {
  // A plane 4 m away with depth noise that folds it (column 3 one metre nearer): the normal map
  // says the plane faces the camera, (0, 0, -1), except in row 0, whose normals face away.
  cv::Mat depth(4, 6, CV_32F, cv::Scalar(4.f));
  depth.col(3).setTo(3.7f);
  const solo::DepthMesh mesh = solo::meshFromDepth(depth, {10, 10, 2.5, 1.5, 6, 4});
  cv::Mat normals(4, 6, CV_32FC3, cv::Scalar(0.f, 0.f, -1.f));
  normals.row(0).setTo(cv::Scalar(0.f, 0.f, 1.f));
  solo::NightSceneOptions options;
  options.headlights = false;
  const solo::NightScene night = solo::buildNightScene(mesh, {}, {}, {}, solo::LightRecord{}, options, normals);
  const auto& shading = night.scene.face_shading_normal;
  ASSERT_EQ(shading.size(), night.scene.faces.size());
  std::int64_t with_map = 0;
  for (std::size_t f = 0; f < shading.size(); ++f) {
    bool touches_row0 = false;
    for (const std::uint32_t v : night.scene.faces[f]) {
      const Eigen::Vector3f& p = night.scene.vertices[v];
      touches_row0 = touches_row0 || std::abs(p.y() / p.z() * 10.f + 1.5f) < 1e-3f;  // v = 0
    }
    if (touches_row0) {
      // Mean of (0,0,1) and (0,0,-1) normals: too short (disagreeing), or facing away.
      EXPECT_EQ(shading[f], Eigen::Vector3f::Zero()) << "face " << f;
    } else {
      EXPECT_NEAR((shading[f] - Eigen::Vector3f(0.f, 0.f, -1.f)).norm(), 0.f, 1e-6f) << "face " << f;
      ++with_map;
    }
  }
  EXPECT_EQ(with_map, 2 * 5 * 2);  // rows 1-3: two rows of five quads
  EXPECT_EQ(countMetric(night.report, "faces_with_shading_normal"), with_map);
  // Off, or without a normal map: no shading normals.
  options.shading_normals = false;
  EXPECT_TRUE(solo::buildNightScene(mesh, {}, {}, {}, solo::LightRecord{}, options, normals).scene.face_shading_normal.empty());
  options.shading_normals = true;
  EXPECT_TRUE(solo::buildNightScene(mesh, {}, {}, {}, solo::LightRecord{}, options).scene.face_shading_normal.empty());
}

TEST(NightScene, AProxyLiesInFrontOfItsLampsFacesAndThoseReflectNothing) {
  // The lamp's faces (the plane under columns 3-5, 4 m away) lie 0.5 m in front of the record's
  // plane (centroid 4.5 m away): a proxy on that plane would sit behind them, hidden, its light
  // trapped between them and it. It moves toward the camera along its pixels' rays to 0.2 %
  // in front of them (3.992 m), its black plate with it, and the lamp's faces reflect nothing.
  const solo::DepthMesh mesh = planeMesh();
  solo::LightRecord record =
      oneLightRecord(solo::LightCategory::StreetLightHighCct, 3, 5, 6000, solo::StrengthUnit::FluxLm, 7001, {0.38, 0.37}, 0);
  setRecordPlane(record, {0, 0, -1});
  record.geometry[0].centroid_m *= 4.5 / 4.0;
  record.geometry[0].area_m2 = 0.5;  // the faces cover 1.2 m^2: too large, so the proxy emits
  solo::NightSceneOptions options;
  options.headlights = false;
  const solo::NightScene night = solo::buildNightScene(mesh, {}, {}, {}, record, options);
  ASSERT_EQ(countMetric(night.report, "light_proxies_for_area"), 1);
  ASSERT_EQ(night.scene.faces.size(), 30u + 16u);
  int emitting = 0;
  for (std::size_t f = 30; f < night.scene.faces.size(); ++f) {
    if (night.scene.face_emitter[f] < 0) continue;  // the plate, 1 cm behind the quads
    ++emitting;
    for (const std::uint32_t v : night.scene.faces[f]) {
      EXPECT_LT(night.scene.vertices[v].z(), 4.0f * (1 - 0.0019f)) << "proxy face " << f;
      EXPECT_GT(night.scene.vertices[v].z(), 4.0f * (1 - 0.0021f)) << "proxy face " << f;
    }
  }
  EXPECT_EQ(emitting, 8);
  int dark = 0;
  for (std::size_t f = 0; f < 30; ++f) {
    bool left = true;  // all three corners in columns 0-2: a face that never shows the lamp
    for (const std::uint32_t v : night.scene.faces[f]) left &= night.scene.vertices[v].x() / 4.0f * 10 + 2.5f < 2.5f;
    const bool black = night.scene.face_reflectance[f].isZero();
    dark += black;
    if (left) {
      EXPECT_FALSE(black) << "mesh face " << f;
    }
  }
  EXPECT_GE(dark, 12) << "the lamp's faces under columns 3-5 (two per quad, two quads per row)";
}
