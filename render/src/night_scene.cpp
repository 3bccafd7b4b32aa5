#include "solo/render/night_scene.h"

#include <solo/lighting/colorimetry.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <map>

namespace solo {
namespace {

float srgbToLinear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

}  // namespace

NightScene buildNightScene(const DepthMesh& depth_mesh, const cv::Mat& albedo, const cv::Mat& roughness,
                           const cv::Mat& day_image, const LightRecord& record, const NightSceneOptions& options) {
  Stopwatch clock;
  NightScene out;
  RenderScene& scene = out.scene;
  StageReport& report = out.report;
  report.name = "scene";
  // The maps' (and the render's) resolution: the albedo's, else the light record's, else the
  // mesh's. A mesh made from a downsampled depth map (--mesh-downsample) is coarser than the maps.
  int width = depth_mesh.width, height = depth_mesh.height;
  if (!albedo.empty()) {
    width = albedo.cols;
    height = albedo.rows;
  } else if (record.tree.width > 0 && record.tree.height > 0) {
    width = record.tree.width;
    height = record.tree.height;
  }
  scene.camera = (width == depth_mesh.width && height == depth_mesh.height) ? depth_mesh.camera
                                                                              : depth_mesh.camera.scaledTo(width, height);

  cv::Mat reflectance_map = albedo;
  if (reflectance_map.empty() && !day_image.empty()) {
    cv::Mat resized;
    cv::resize(day_image, resized, cv::Size(width, height), 0, 0, cv::INTER_AREA);
    resized.forEach<cv::Vec3f>([](cv::Vec3f& c, const int*) {
      for (int k = 0; k < 3; ++k) c[k] = srgbToLinear(std::clamp(c[k], 0.f, 1.f));
    });
    reflectance_map = resized;
    report.notes.push_back("no albedo map: the linearised day image stands in for the reflectance");
  }
  CV_Assert(reflectance_map.empty() || reflectance_map.size() == cv::Size(width, height));
  CV_Assert(roughness.empty() || roughness.size() == cv::Size(width, height));

  // Light index per pixel (into record.tree.lights), -1 = none.
  cv::Mat light_index(height, width, CV_32S, cv::Scalar(-1));
  const bool lights_match = record.tree.width == width && record.tree.height == height;
  if (!record.tree.lights.empty() && !lights_match)
    report.notes.push_back("light record is " + std::to_string(record.tree.width) + "x" +
                           std::to_string(record.tree.height) + ", the mesh " + std::to_string(width) + "x" +
                           std::to_string(height) + ": lights not mapped");
  if (lights_match)
    for (std::size_t i = 0; i < record.tree.lights.size(); ++i)
      for (const PixelRun& run : record.tree.lights[i].runs)
        for (int c = run.first_col; c <= run.last_col; ++c) light_index.at<int>(run.row, c) = static_cast<int>(i);

  // One emitter per light that is on and has an area.
  std::vector<int> emitter_of_light(record.tree.lights.size(), -1);
  std::map<std::string, std::int64_t> lights_on_by_category;
  for (std::size_t i = 0; i < record.tree.lights.size(); ++i) {
    const Light& light = record.tree.lights[i];
    const LightState& state = record.instantiation.lights[i];
    if (!state.on) continue;
    const double area = record.geometry[i].area_m2;
    const double luminance = emittedLuminance(state, light.category, area);
    if (!(luminance > 0) || !std::isfinite(luminance)) continue;
    const Eigen::Vector3d xyz = xyzFromChromaticity(state.xy, luminance);
    Emitter e;
    e.radiance = xyz.cast<float>();
    e.directional_profile = emissionProfile(light.category) == EmissionProfile::CosineLobe;
    e.light_id = light.map_id;
    emitter_of_light[i] = static_cast<int>(scene.emitters.size());
    scene.emitters.push_back(e);
    ++lights_on_by_category[lightCategoryName(light.category)];
  }

  // Geometry, and per face the pixel under its vertices' mean pixel position.
  const SurfaceMesh& mesh = depth_mesh.mesh;
  const std::optional<ImageVertexProperties> props = ImageVertexProperties::find(mesh);
  std::vector<int> index_of_vertex(mesh.n_vertices(), -1);
  std::int64_t emitting_faces = 0, faces_without_pixel = 0;
  // Pixel coordinates on the mesh are of its own grid; pixel centres map by the camera's rule.
  const double scale_x = depth_mesh.width > 0 ? static_cast<double>(width) / depth_mesh.width : 1.0;
  const double scale_y = depth_mesh.height > 0 ? static_cast<double>(height) / depth_mesh.height : 1.0;
  for (const auto f : mesh.faces()) {
    if (mesh.status(f).deleted()) continue;
    std::array<std::uint32_t, 3> face{};
    int k = 0;
    double u = 0, v = 0;
    int with_pixel = 0;
    for (const auto vh : mesh.fv_range(f)) {
      int& index = index_of_vertex[static_cast<std::size_t>(vh.idx())];
      if (index < 0) {
        const auto p = mesh.point(vh);
        index = static_cast<int>(scene.vertices.size());
        scene.vertices.emplace_back(static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2]));
      }
      face[static_cast<std::size_t>(k++)] = static_cast<std::uint32_t>(index);
      if (props) {
        const OpenMesh::Vec2i pixel = mesh.property(props->pixel, vh);
        if (pixel[0] >= 0 && pixel[1] >= 0) {
          u += pixel[0];
          v += pixel[1];
          ++with_pixel;
        }
      }
    }
    scene.faces.push_back(face);
    Eigen::Vector3f rgb = Eigen::Vector3f::Constant(options.default_reflectance);
    float rough = 0.5f;
    int emitter = -1;
    if (with_pixel > 0) {
      const int x =
          std::clamp(static_cast<int>(std::lround((u / with_pixel + 0.5) * scale_x - 0.5)), 0, width - 1);
      const int y =
          std::clamp(static_cast<int>(std::lround((v / with_pixel + 0.5) * scale_y - 0.5)), 0, height - 1);
      if (!reflectance_map.empty()) {
        const cv::Vec3f a = reflectance_map.at<cv::Vec3f>(y, x);
        rgb = Eigen::Vector3f(a[0], a[1], a[2]).cwiseMax(0.f).cwiseMin(1.f);
      }
      if (!roughness.empty()) rough = std::clamp(roughness.at<float>(y, x), 0.f, 1.f);
      const int light = light_index.at<int>(y, x);
      if (light >= 0) emitter = emitter_of_light[static_cast<std::size_t>(light)];
    } else {
      ++faces_without_pixel;
    }
    scene.face_reflectance.push_back(reflectanceFromLinearSrgb(rgb));
    if (!roughness.empty()) scene.face_roughness.push_back(rough);
    scene.face_emitter.push_back(emitter);
    emitting_faces += emitter >= 0;
  }

  if (options.headlights) {
    const double area = 0.3 * 0.15;
    scene.rectangle_lights = egoHeadlights(static_cast<float>(options.headlight_flux_lm / (3.14159265358979 * area)));
  } else {
    report.notes.push_back("ego headlights switched off");
  }
  if (options.sky_luminance_cd_m2 > 0) {
    scene.sky_radiance = xyzFromChromaticity({0.3, 0.3}, options.sky_luminance_cd_m2).cast<float>();
  }

  report.add("faces", static_cast<std::int64_t>(scene.faces.size()));
  report.add("emitting_faces", emitting_faces);
  report.add("emitters", static_cast<std::int64_t>(scene.emitters.size()));
  report.add("faces_without_pixel", faces_without_pixel);
  for (const auto& [category, count] : lights_on_by_category) report.add("on_" + category, count);
  if (scene.emitters.empty()) report.notes.push_back("no active light in view");
  report.seconds = clock.seconds();
  return out;
}

}  // namespace solo
