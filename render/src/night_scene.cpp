#include "solo/render/night_scene.h"

#include <solo/core/srgb.h>
#include <solo/lighting/colorimetry.h>
#include <solo/lighting/light_geometry.h>
#include <solo/lighting/light_priors.h>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <limits>
#include <map>

namespace solo {

namespace {

EmitterProfile emitterProfile(EmissionProfile profile) {
  switch (profile) {
    case EmissionProfile::CosineLobe: return EmitterProfile::CosineLobe;
    case EmissionProfile::SignalBeam: return EmitterProfile::TowardCamera;
    case EmissionProfile::Uniform: break;
  }
  return EmitterProfile::Uniform;
}

// The map pixel (x or y, clamped to [0, size)) under mesh-grid coordinate `coordinate`, pixel
// centres mapped by the camera's rule for a map `scale` times the mesh's grid.
int mapPixel(double coordinate, double scale, int size) {
  return std::clamp(static_cast<int>(std::lround((coordinate + 0.5) * scale - 0.5)), 0, size - 1);
}

// A face that shows one of a light's pixels: a candidate to emit the light.
struct SeenFace {
  std::size_t face;
  float depth_m;  // the face's centroid z
  double area_m2;
  int pixel;    // y * width + x of the pixel it shows
  bool filled;   // has a vertex added by hole filling
  bool edge_on;  // seen within 5 degrees of edge-on
};

// A mesh face's vertex indices in the scene, and what its vertices say about its pixel.
struct FaceVertices {
  std::array<std::uint32_t, 3> face{};
  double u = 0, v = 0;  // sums of the vertices' pixel coordinates (mesh grid)
  int with_pixel = 0;   // vertices that have a pixel
  std::array<OpenMesh::Vec2i, 3> pixels{};  // of the first with_pixel vertices (mesh grid)
  bool behind = false;  // a closed solid's back or an input vertex: never emits
  bool filled = false;  // a vertex added by hole filling
};

// The scene under construction, and what one step of buildNightScene hands to the next.
struct NightSceneBuilder {
  NightSceneBuilder(const DepthMesh& depth_mesh_, const cv::Mat& roughness_, const cv::Mat& normals_,
                    const LightRecord& record_, const NightSceneOptions& options_, NightScene& out)
      : depth_mesh(depth_mesh_), roughness(roughness_), normals(normals_), record(record_), options(options_),
        scene(out.scene), report(out.report), reflectance_xyz(out.reflectance), light_pixels(out.light_id) {}

  const DepthMesh& depth_mesh;
  const cv::Mat& roughness;
  const cv::Mat& normals;  // CV_32FC3 at the maps' resolution, or empty
  const LightRecord& record;
  const NightSceneOptions& options;
  RenderScene& scene;
  StageReport& report;
  cv::Mat& reflectance_xyz;  // NightScene::reflectance
  cv::Mat& light_pixels;     // NightScene::light_id

  int width = 0, height = 0;  // the maps' and the render's resolution
  cv::Mat reflectance_map;
  bool lights_match = false;  // the light record is at the maps' resolution
  cv::Mat light_index;        // per pixel, index into record.tree.lights, -1 = none
  std::vector<bool> light_on;
  std::vector<int> light_of_face;  // per scene face, index into record.tree.lights, -1 = none
  std::vector<std::vector<SeenFace>> seen_faces;  // per light
  std::vector<std::vector<std::size_t>> light_faces;  // per light, every scene face noted as showing it
  cv::Mat nearest_depth_m;  // per light pixel, the depth of the nearest face that shows it
  std::vector<double> seen_area_m2;  // per light, the area of the faces that emit it
  std::vector<int> emitter_of_light;  // per light, index into scene.emitters, -1 = none
  std::vector<std::uint8_t> proxied;  // per light: it emits from a proxy, its faces reflect nothing
  std::vector<int> index_of_vertex;   // per mesh vertex, its index in the scene, -1 = none

  std::int64_t faces_with_shading_normal = 0;
  std::int64_t hidden_faces_under_lights = 0, faces_seen_edge_on = 0, emitting_faces = 0, faces_without_pixel = 0,
               faces_off_light_depth = 0;
  std::map<std::string, std::int64_t> lights_on_by_category;
  std::int64_t lights_on_without_faces = 0, lights_on_not_emitting = 0, light_proxies = 0, light_proxies_for_area = 0,
               light_proxies_moved = 0;
  double flux_area_mesh_m2 = 0, flux_area_record_m2 = 0, luminance_area_mesh_m2 = 0, luminance_area_record_m2 = 0;
  double proxy_area_m2 = 0;

  void chooseResolution(const cv::Mat& albedo);
  void markSurfacePixels();
  void prepareReflectance(const cv::Mat& albedo, const cv::Mat& day_image);
  void mapLights();
  void reserveFaceArrays(std::size_t mesh_faces, std::size_t mesh_vertices);
  void addMeshFaces();
  Eigen::Vector3f shadingNormal(const FaceVertices& fv, double scale_x, double scale_y) const;
  FaceVertices addFaceVertices(SurfaceMesh::FaceHandle f, const std::optional<ImageVertexProperties>& props,
                               std::vector<int>& index_of_vertex);
  void noteLightFace(const std::array<std::uint32_t, 3>& face, int light, int x, int y, bool filled);
  template <typename Drop>
  void dropFaces(std::vector<SeenFace>& faces, const Drop& drop, std::int64_t& count);
  void keepFacesAtLightDepth();
  double proxyScaleInFrontOfFaces(std::size_t i, const Eigen::Vector3d& normal, double plane) const;
  double addProxy(std::size_t i);
  void addEmitters();
  void assignFaceEmitters();
  void markLightPixels();
  void addPixelTexture();
  void addHeadlightsAndSky();
  void writeReport();
};

// The maps' (and the render's) resolution: the albedo's, else the light record's, else the
// mesh's. A mesh made from a downsampled depth map (--mesh-downsample) is coarser than the maps.
void NightSceneBuilder::chooseResolution(const cv::Mat& albedo) {
  width = depth_mesh.width;
  height = depth_mesh.height;
  if (!albedo.empty()) {
    width = albedo.cols;
    height = albedo.rows;
  } else if (record.tree.width > 0 && record.tree.height > 0) {
    width = record.tree.width;
    height = record.tree.height;
  }
  scene.camera = (width == depth_mesh.width && height == depth_mesh.height) ? depth_mesh.camera
                                                                              : depth_mesh.camera.scaledTo(width, height);
}

// RenderScene::surface_pixels: the render pixels whose depth-map pixel made a vertex (depth, not
// sky), also where cleanup removed it. None for a mesh that is not a depth map's.
void NightSceneBuilder::markSurfacePixels() {
  const std::size_t mesh_pixels = static_cast<std::size_t>(depth_mesh.width) * static_cast<std::size_t>(depth_mesh.height);
  if (mesh_pixels == 0 || depth_mesh.vertex_of_pixel.size() != mesh_pixels) return;
  const cv::Mat& had_depth = depth_mesh.had_depth;
  const bool cleaned = had_depth.type() == CV_8U && had_depth.size() == cv::Size(depth_mesh.width, depth_mesh.height);
  scene.surface_pixels.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 0);
  std::int64_t marked = 0;
  for (int y = 0; y < height; ++y) {
    const int v = std::min(depth_mesh.height - 1, static_cast<int>((y + 0.5) * depth_mesh.height / height));
    for (int x = 0; x < width; ++x) {
      const int u = std::min(depth_mesh.width - 1, static_cast<int>((x + 0.5) * depth_mesh.width / width));
      const bool surface = cleaned ? had_depth.at<std::uint8_t>(v, u) != 0 : depth_mesh.vertexAt(u, v) >= 0;
      scene.surface_pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)] = surface;
      marked += surface;
    }
  }
  report.add("surface_pixels", marked);
}

// The reflectance map: the albedo, else the linearised day image at the maps' resolution.
void NightSceneBuilder::prepareReflectance(const cv::Mat& albedo, const cv::Mat& day_image) {
  reflectance_map = albedo;
  if (reflectance_map.empty() && !day_image.empty()) {
    cv::Mat resized;
    cv::resize(day_image, resized, cv::Size(width, height), 0, 0, cv::INTER_AREA);
    resized.forEach<cv::Vec3f>([](cv::Vec3f& c, const int*) {
      for (int k = 0; k < 3; ++k) c[k] = srgbToLinear(std::clamp(c[k], 0.f, 1.f));
    });
    reflectance_map = resized;
    if (options.remove_day_light) {
      const cv::Mat maps_normals = normals.size() == resized.size() ? normals : cv::Mat();
      DayLightRemoval removed =
          removeDayLight(resized, dayLightGeometry(depth_mesh, scene.camera, maps_normals), options.day_light);
      reflectance_map = removed.albedo;
      report.notes.push_back(std::string("no albedo map: the day image with its light taken out (") +
                             dayLightMethodName(removed.method) + ") stands in for the reflectance");
      for (const std::string& note : removed.report.notes) report.notes.push_back("day light: " + note);
      report.add("day_light_method", std::string(dayLightMethodName(removed.method)));
      report.add("day_light_shadows", std::string(options.day_light.shadows_from_image ? "image" : "rays"));
      report.add("day_light_seconds", removed.report.seconds, "s");
    } else {
      report.notes.push_back("no albedo map: the linearised day image stands in for the reflectance");
    }
  }
  CV_Assert(reflectance_map.empty() || reflectance_map.size() == cv::Size(width, height));
  CV_Assert(roughness.empty() || roughness.size() == cv::Size(width, height));
  if (reflectance_map.empty()) return;
  // Per pixel, what a face made from that pixel reflects (addMeshFaces).
  reflectance_xyz.create(height, width, CV_32FC3);
  cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y)
      for (int x = 0; x < width; ++x) {
        const cv::Vec3f a = reflectance_map.at<cv::Vec3f>(y, x);
        const Eigen::Vector3f xyz =
            reflectanceFromLinearSrgb(Eigen::Vector3f(a[0], a[1], a[2]).cwiseMax(0.f).cwiseMin(1.f));
        reflectance_xyz.at<cv::Vec3f>(y, x) = {xyz.x(), xyz.y(), xyz.z()};
      }
  });
}

// The light index per pixel, and which lights are on with a usable strength. A flux becomes a
// luminance once the area of the faces that show the light is known (addEmitters).
void NightSceneBuilder::mapLights() {
  light_index = cv::Mat(height, width, CV_32S, cv::Scalar(-1));
  lights_match = record.tree.width == width && record.tree.height == height;
  if (!record.tree.lights.empty() && !lights_match)
    report.notes.push_back("light record is " + std::to_string(record.tree.width) + "x" +
                           std::to_string(record.tree.height) + ", the mesh " + std::to_string(width) + "x" +
                           std::to_string(height) + ": lights not mapped");
  if (lights_match)
    for (std::size_t i = 0; i < record.tree.lights.size(); ++i)
      for (const PixelRun& run : record.tree.lights[i].runs)
        for (int c = run.first_col; c <= run.last_col; ++c) light_index.at<int>(run.row, c) = static_cast<int>(i);

  light_on.assign(record.tree.lights.size(), false);
  for (std::size_t i = 0; i < record.tree.lights.size(); ++i) {
    light_on[i] = lightIsLit(record.instantiation.lights[i]);
  }
  seen_faces.resize(record.tree.lights.size());
  light_faces.resize(record.tree.lights.size());
  nearest_depth_m = cv::Mat(height, width, CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
}

// Adds face f's vertices to the scene (each mesh vertex once) and sums their pixels.
FaceVertices NightSceneBuilder::addFaceVertices(SurfaceMesh::FaceHandle f,
                                                const std::optional<ImageVertexProperties>& props,
                                                std::vector<int>& index_of_vertex) {
  const SurfaceMesh& mesh = depth_mesh.mesh;
  FaceVertices out;
  out.behind = !props.has_value();
  int k = 0;
  for (const auto vh : mesh.fv_range(f)) {
    if (props) {
      const auto origin = static_cast<VertexOrigin>(mesh.property(props->origin, vh));
      out.behind |= origin == VertexOrigin::SolidBack || origin == VertexOrigin::Input;
      out.filled |= origin == VertexOrigin::HoleFill;
    }
    int& index = index_of_vertex[static_cast<std::size_t>(vh.idx())];
    if (index < 0) {
      const auto p = mesh.point(vh);
      index = static_cast<int>(scene.vertices.size());
      scene.vertices.emplace_back(static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2]));
    }
    out.face[static_cast<std::size_t>(k++)] = static_cast<std::uint32_t>(index);
    if (props) {
      const OpenMesh::Vec2i pixel = mesh.property(props->pixel, vh);
      if (pixel[0] >= 0 && pixel[1] >= 0) {
        out.u += pixel[0];
        out.v += pixel[1];
        out.pixels[static_cast<std::size_t>(out.with_pixel++)] = pixel;
      }
    }
  }
  return out;
}

// Notes the scene's last face, `face`, as showing light `light` at pixel (x, y).
void NightSceneBuilder::noteLightFace(const std::array<std::uint32_t, 3>& face, int light, int x, int y,
                                      bool filled) {
  const double kCosEdgeOn = std::cos(85.0 * 3.14159265358979 / 180.0);
  const Eigen::Vector3d a = scene.vertices[face[0]].cast<double>();
  const Eigen::Vector3d ab = scene.vertices[face[1]].cast<double>() - a;
  const Eigen::Vector3d ac = scene.vertices[face[2]].cast<double>() - a;
  const Eigen::Vector3d normal = ab.cross(ac);
  const Eigen::Vector3d centroid = a + (ab + ac) / 3.0;
  // Seen within 5 degrees of edge-on: stretched across a depth jump (the light's
  // silhouette toward the background), or a surface at grazing view.
  const bool edge_on = std::abs(normal.dot(centroid)) < kCosEdgeOn * normal.norm() * centroid.norm();
  const float depth = (scene.vertices[face[0]].z() + scene.vertices[face[1]].z() + scene.vertices[face[2]].z()) / 3;
  seen_faces[static_cast<std::size_t>(light)].push_back(
      {scene.faces.size() - 1, depth, 0.5 * normal.norm(), y * width + x, filled, edge_on});
  light_faces[static_cast<std::size_t>(light)].push_back(scene.faces.size() - 1);
  float& nearest = nearest_depth_m.at<float>(y, x);
  nearest = std::min(nearest, depth);
}

// The normal map's mean over the face's three pixels, when all three have one, the face is no
// solid's back (whose pixels show its front) and that mean faces the camera; else zero (the
// face's own normal). Hole fills take it too: where they are seen, their pixels show them.
Eigen::Vector3f NightSceneBuilder::shadingNormal(const FaceVertices& fv, double scale_x, double scale_y) const {
  if (!options.shading_normals || normals.empty() || normals.cols != width || normals.rows != height ||
      fv.with_pixel != 3 || fv.behind)
    return Eigen::Vector3f::Zero();
  Eigen::Vector3f sum = Eigen::Vector3f::Zero(), centroid = Eigen::Vector3f::Zero();
  for (int k = 0; k < 3; ++k) {
    const OpenMesh::Vec2i& p = fv.pixels[static_cast<std::size_t>(k)];
    const int x = mapPixel(p[0], scale_x, width), y = mapPixel(p[1], scale_y, height);
    const cv::Vec3f n = normals.at<cv::Vec3f>(y, x);
    sum += Eigen::Vector3f(n[0], n[1], n[2]);
    centroid += scene.vertices[fv.face[static_cast<std::size_t>(k)]];
  }
  const float length = sum.norm();
  if (!std::isfinite(length) || !(length > 1.5f)) return Eigen::Vector3f::Zero();  // invalid or disagreeing pixels
  const Eigen::Vector3f n = sum / length;
  return n.dot(centroid) < 0.f ? n : Eigen::Vector3f::Zero();
}

// Geometry, and per face the material and the light of the pixel under its vertices' mean
// pixel position.
void NightSceneBuilder::addMeshFaces() {
  const SurfaceMesh& mesh = depth_mesh.mesh;
  const std::optional<ImageVertexProperties> props = ImageVertexProperties::find(mesh);
  index_of_vertex.assign(mesh.n_vertices(), -1);
  // Pixel coordinates on the mesh are of its own grid; pixel centres map by the camera's rule.
  const double scale_x = depth_mesh.width > 0 ? static_cast<double>(width) / depth_mesh.width : 1.0;
  const double scale_y = depth_mesh.height > 0 ? static_cast<double>(height) / depth_mesh.height : 1.0;
  reserveFaceArrays(mesh.n_faces(), mesh.n_vertices());
  for (const auto f : mesh.faces()) {
    if (mesh.status(f).deleted()) continue;
    const FaceVertices fv = addFaceVertices(f, props, index_of_vertex);
    scene.faces.push_back(fv.face);
    Eigen::Vector3f rgb = Eigen::Vector3f::Constant(options.default_reflectance);
    float rough = 0.5f;
    int shown_light = -1;  // the light this face shows, if it emits
    if (fv.with_pixel > 0) {
      const int x = mapPixel(fv.u / fv.with_pixel, scale_x, width);
      const int y = mapPixel(fv.v / fv.with_pixel, scale_y, height);
      if (!reflectance_map.empty()) {
        const cv::Vec3f a = reflectance_map.at<cv::Vec3f>(y, x);
        rgb = Eigen::Vector3f(a[0], a[1], a[2]).cwiseMax(0.f).cwiseMin(1.f);
      }
      if (!roughness.empty()) rough = std::clamp(roughness.at<float>(y, x), 0.f, 1.f);
      const int light = light_index.at<int>(y, x);
      if (light >= 0 && light_on[static_cast<std::size_t>(light)]) {
        // Only the surface the light's pixels see emits. Closed solids' backs, and hole fills
        // and backdrops behind it, share its pixels: emitting, they would add area (a street
        // lamp's 0.4 m^2 became 10-30 m^2 of backdrop and solid backs) and light where none is.
        // Solid backs never emit; filled faces only where nothing nearer shows the pixel
        // (keepFacesAtLightDepth).
        if (!fv.behind) {
          shown_light = light;
          noteLightFace(fv.face, light, x, y, fv.filled);
        } else {
          ++hidden_faces_under_lights;
        }
      }
    } else {
      ++faces_without_pixel;
    }
    scene.face_reflectance.push_back(reflectanceFromLinearSrgb(rgb));
    if (!roughness.empty()) scene.face_roughness.push_back(rough);
    light_of_face.push_back(shown_light);
    if (options.shading_normals && !normals.empty()) {
      scene.face_shading_normal.push_back(shadingNormal(fv, scale_x, scale_y));
      faces_with_shading_normal += scene.face_shading_normal.back().squaredNorm() > 0.f;
    }
  }
}

// Room in the scene's per-face and per-vertex arrays for a mesh of `mesh_faces` and
// `mesh_vertices`, and a sixteenth more for the light proxies after it: they are not copied to
// grow.
void NightSceneBuilder::reserveFaceArrays(std::size_t mesh_faces, std::size_t mesh_vertices) {
  const std::size_t faces = mesh_faces + mesh_faces / 16 + 1024;
  const std::size_t vertices = mesh_vertices + mesh_vertices / 16 + 1024;
  scene.vertices.reserve(scene.vertices.size() + vertices);
  scene.faces.reserve(scene.faces.size() + faces);
  scene.face_reflectance.reserve(scene.face_reflectance.size() + faces);
  if (!roughness.empty()) scene.face_roughness.reserve(scene.face_roughness.size() + faces);
  light_of_face.reserve(light_of_face.size() + faces);
  if (options.shading_normals && !normals.empty())
    scene.face_shading_normal.reserve(scene.face_shading_normal.size() + faces);
}

// Removes the faces for which `drop` holds (they stay dark) and counts them.
template <typename Drop>
void NightSceneBuilder::dropFaces(std::vector<SeenFace>& faces, const Drop& drop, std::int64_t& count) {
  const auto first = std::partition(faces.begin(), faces.end(), [&](const SeenFace& f) { return !drop(f); });
  for (auto it = first; it != faces.end(); ++it) light_of_face[it->face] = -1;
  count += std::distance(first, faces.end());
  faces.erase(first, faces.end());
}

// A light's pixels also see the faces its silhouette stretches toward the background
// (pixels of mixed depth): a street lamp's head 0.5 m deep showed faces over 5 m of depth
// behind it. Only faces within a robust band around the light's median depth emit:
// median +- max(3 MAD, 0.25 m). A flat light seen at grazing (depth spread evenly over its
// width w: MAD = w / 4) keeps all of its faces.
void NightSceneBuilder::keepFacesAtLightDepth() {
  seen_area_m2.assign(record.tree.lights.size(), 0.0);
  for (std::size_t i = 0; i < seen_faces.size(); ++i) {
    std::vector<SeenFace>& faces = seen_faces[i];
    // A filled face behind a nearer face of the same pixel (a backdrop or a hole fill behind
    // the lamp) is hidden; one that fills a hole in the seen surface (a lamp's faces removed as
    // spurious and filled again) is what the pixel sees. Tolerance: 2 % of the depth + 5 cm,
    // below the 0.2 m of the thinnest slab behind a surface.
    dropFaces(faces, [&](const SeenFace& face) {
      const float nearest = nearest_depth_m.ptr<float>()[face.pixel];
      return face.filled && face.depth_m > nearest * 1.02f + 0.05f;
    }, hidden_faces_under_lights);
    // A flux light (a compact lamp) loses its edge-on faces, mostly its silhouette stretched
    // toward the background, unless it has no other faces (1080p street: 23.4 -> 9.5 m^2 of
    // street-light faces, the record says 5.0). A luminance light keeps them.
    const auto is_edge_on = [](const SeenFace& f) { return f.edge_on; };
    if (record.instantiation.lights[i].unit == StrengthUnit::FluxLm && !std::all_of(faces.begin(), faces.end(), is_edge_on))
      dropFaces(faces, is_edge_on, faces_seen_edge_on);
    if (faces.empty()) continue;
    std::vector<double> depths(faces.size());
    for (std::size_t k = 0; k < faces.size(); ++k) depths[k] = faces[k].depth_m;
    const LightDepthBand band = lightDepthBand(std::move(depths));
    dropFaces(faces, [&](const SeenFace& face) { return !band.contains(face.depth_m); }, faces_off_light_depth);
    for (const SeenFace& face : faces) seen_area_m2[i] += face.area_m2;
  }
}

// A proxy lies this share of the depth in front of its light's nearest face, and moves at most
// kProxyMaxMoveM toward the camera for them (a face farther in front is left there, dark).
constexpr double kProxyClearance = 0.002, kProxyMaxMoveM = 1.0;

// The factor (<= 1) that scales light i's proxy plane {p : normal . p = plane} toward the
// camera so that, along every pixel ray of the light, it lies in front of the nearest face
// showing that pixel.
double NightSceneBuilder::proxyScaleInFrontOfFaces(std::size_t i, const Eigen::Vector3d& normal, double plane) const {
  const PinholeCamera& camera = scene.camera;
  double scale = 1.0;
  for (const PixelRun& run : record.tree.lights[i].runs)
    for (int c = run.first_col; c <= run.last_col; ++c) {
      const float nearest = nearest_depth_m.at<float>(run.row, c);
      if (!std::isfinite(nearest)) continue;
      for (const double du : {-0.5, 0.5})
        for (const double dv : {-0.5, 0.5}) {
          const Eigen::Vector3d ray((c + du - camera.cx) / camera.fx, (run.row + dv - camera.cy) / camera.fy, 1.0);
          const double depth = plane / normal.dot(ray);  // the plane's z along the ray
          if (!(depth > 0) || !std::isfinite(depth)) continue;
          const double limit = std::max(nearest * (1.0 - kProxyClearance), depth - kProxyMaxMoveM);
          if (limit < depth) scale = std::min(scale, limit / depth);
        }
    }
  return std::max(scale, 1e-3);
}

// Adds light i's proxy faces (see addEmitters); returns their area, 0 when the record has no
// usable plane.
double NightSceneBuilder::addProxy(std::size_t i) {
  const double min_incidence_cosine = std::cos(85.0 * 3.14159265358979 / 180.0);
  if (!lights_match || i >= record.geometry.size()) return 0;  // the runs are pixels of scene.camera's grid
  const LightGeometry& geometry = record.geometry[i];
  if (!geometry.positioned() || !geometry.centroid_m.allFinite() || !(geometry.centroid_m.z() > 0) ||
      !geometry.normal.allFinite() || !(geometry.normal.norm() > 0.5))
    return 0;
  const PinholeCamera& camera = scene.camera;
  const double distance = geometry.centroid_m.norm();
  const Eigen::Vector3d centre = geometry.centroid_m * (1.0 - (0.01 + 0.002 * distance) / distance);
  const auto corner = [&](const PixelRun& run, bool right, bool below) {
    const double u = right ? run.last_col + 0.5 : run.first_col - 0.5, v = below ? run.row + 0.5 : run.row - 0.5;
    return Eigen::Vector3d((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
  };
  Eigen::Vector3d normal = geometry.normal.normalized();
  for (const PixelRun& run : record.tree.lights[i].runs)
    for (const bool right : {false, true})
      for (const bool below : {false, true}) {
        const Eigen::Vector3d ray = corner(run, right, below);
        if (std::abs(normal.dot(ray)) < min_incidence_cosine * ray.norm()) normal = -centre.normalized();
      }
  // The emitting quads, and half way back to the centroid a black plate behind them: emitters
  // are two-sided, and a lamp's back, unlike a mesh face's (backed by the lamp's solid or the
  // surface behind), would light the wall behind it. Both move toward the camera, along the
  // pixels' rays, until the quads lie in front of the light's own faces (kProxyClearance of
  // their depth): faces left in front would hide the proxy and trap its light between them.
  const double record_plane = normal.dot(centre);
  const double plane = record_plane * proxyScaleInFrontOfFaces(i, normal, record_plane);
  const double plate = plane + (normal.dot(0.5 * (centre + geometry.centroid_m)) - record_plane);
  std::vector<std::array<std::uint32_t, 3>> faces;
  double area = 0;
  const std::size_t first_vertex = scene.vertices.size();
  for (const PixelRun& run : record.tree.lights[i].runs) {
    const auto first = static_cast<std::uint32_t>(scene.vertices.size());
    std::array<Eigen::Vector3d, 8> q;
    int k = 0;
    for (const double offset : {plane, plate})
      for (const auto& [right, below] : {std::pair{false, false}, {true, false}, {true, true}, {false, true}}) {
        const Eigen::Vector3d ray = corner(run, right, below);
        q[static_cast<std::size_t>(k++)] = ray * (offset / normal.dot(ray));
      }
    if (!std::all_of(q.begin(), q.end(), [](const Eigen::Vector3d& p) { return p.allFinite(); })) continue;
    for (const Eigen::Vector3d& p : q) scene.vertices.push_back(p.cast<float>());
    area += 0.5 * ((q[1] - q[0]).cross(q[2] - q[0]).norm() + (q[2] - q[0]).cross(q[3] - q[0]).norm());
    for (const std::uint32_t base : {first, first + 4}) {
      faces.push_back({base, base + 1, base + 2});
      faces.push_back({base, base + 2, base + 3});
    }
  }
  if (!(area > 0) || !std::isfinite(area)) {
    scene.vertices.resize(first_vertex);
    return 0;
  }
  for (std::size_t f = 0; f < faces.size(); ++f) {
    scene.faces.push_back(faces[f]);
    scene.face_reflectance.push_back(Eigen::Vector3f::Zero());
    if (!roughness.empty()) scene.face_roughness.push_back(0.5f);
    light_of_face.push_back(f % 4 < 2 ? static_cast<int>(i) : -1);  // per run: 2 emitting, 2 plate
  }
  return area;
}

// One emitter per light that is on and shown by some face. A flux (street and front lights)
// is spread over the area of those faces, so the rendered light keeps its flux whatever the
// mesh made of the light's pixels; a luminance is emitted as it is.
//
// A light that is on but shows no face would lose its light: the mesh stage removes a lamp
// head a few pixels high whole (it lies in the uncertain band of its silhouette). A flux light
// whose faces cover more than `max_flux_area_ratio` times the record's area is crumpled or
// stretched toward the background, and its faces' normals send its light where the lamp does
// not (on the 960x540 street a lamp's flux lit the wall beside it instead of the road). Both
// emit from a proxy instead (their faces stay dark): the light's own pixels, each run of them
// a quad on the record's plane (its centroid and normal, with the 85 degree incidence limit
// the record's area uses; past it the plane faces the camera), moved toward the camera by
// 1 cm + 0.2 % of its distance so that it lies in front of the surface behind it. It covers
// exactly the light's pixels, so the light-id AOV and the labels still agree. A light the
// physical priors moved onto its support (light_priors.h) emits from its proxy too: its faces lie
// where its own depth put it. A light without valid depth has a record plane at a prior depth.
//
// lights_on_without_faces counts every light that is on and shows no mesh face, whether it then
// emits from its proxy or not; lights_on_not_emitting those of them without a usable record
// plane (only a record made without priors, or at another resolution), which emit nothing.
void NightSceneBuilder::addEmitters() {
  emitter_of_light.assign(record.tree.lights.size(), -1);
  proxied.assign(record.tree.lights.size(), 0);
  for (std::size_t i = 0; i < record.tree.lights.size(); ++i) {
    if (!light_on[i]) continue;
    const Light& light = record.tree.lights[i];
    const LightState& state = record.instantiation.lights[i];
    const bool flux = state.unit == StrengthUnit::FluxLm;
    const double record_area_m2 = i < record.geometry.size() ? record.geometry[i].area_m2 : 0.0;
    const bool too_large = flux && seen_area_m2[i] > options.max_flux_area_ratio * record_area_m2;
    const bool moved = i < record.geometry.size() && record.geometry[i].placement == LightPlacement::MovedToSupport;
    const bool without_faces = !(seen_area_m2[i] > 0);
    lights_on_without_faces += without_faces;
    double emitting_area_m2 = seen_area_m2[i];
    if (without_faces || too_large || moved) {
      const double area = addProxy(i);
      if (area > 0) {
        for (const SeenFace& face : seen_faces[i]) light_of_face[face.face] = -1;
        // The lamp's own faces are the lamp the proxy stands for: like an emitting face they
        // reflect nothing (lit by the proxy at centimetres, they held its light in creases).
        for (const std::size_t face : light_faces[i]) scene.face_reflectance[face].setZero();
        proxied[i] = 1;
        emitting_area_m2 = area;
        ++light_proxies;
        light_proxies_moved += !without_faces && moved;
        light_proxies_for_area += !without_faces && !moved;
        proxy_area_m2 += area;
      } else if (without_faces) {
        ++lights_on_not_emitting;
        continue;
      }
    }
    (flux ? flux_area_mesh_m2 : luminance_area_mesh_m2) += emitting_area_m2;
    (flux ? flux_area_record_m2 : luminance_area_record_m2) += record_area_m2;
    const double luminance = emittedLuminance(state, light.category, emitting_area_m2);
    if (!(luminance > 0) || !std::isfinite(luminance)) continue;
    Emitter e;
    e.radiance = xyzFromChromaticity(state.xy, luminance).cast<float>();
    e.profile = emitterProfile(emissionProfile(light.category));
    if (e.profile == EmitterProfile::TowardCamera) e.beam_exponent = static_cast<float>(kSignalBeamExponent);
    e.light_id = light.map_id;
    emitter_of_light[i] = static_cast<int>(scene.emitters.size());
    scene.emitters.push_back(e);
    ++lights_on_by_category[lightCategoryName(light.category)];
  }
}

// Each face's emitter. An emitting face reflects nothing. A lamp's luminance (10^3-10^5 cd/m^2)
// dwarfs what it could reflect, except its own light: a depth mesh crumples a small lamp into
// creases, and a path caught in one gathers the lamp's radiance at every bounce (at reflectance
// 0.8 a one-in-10^5 sample worth 2.4 times the lamp's luminance: the fireflies of the 1080p
// street).
void NightSceneBuilder::assignFaceEmitters() {
  scene.face_emitter.reserve(light_of_face.size());
  for (std::size_t f = 0; f < light_of_face.size(); ++f) {
    const int light = light_of_face[f];
    const int emitter = light >= 0 ? emitter_of_light[static_cast<std::size_t>(light)] : -1;
    scene.face_emitter.push_back(emitter);
    if (emitter >= 0) scene.face_reflectance[f].setZero();
    emitting_faces += emitter >= 0;
  }
}

// Per pixel, the light-map id of the emitting light it shows (NightScene::light_id).
void NightSceneBuilder::markLightPixels() {
  light_pixels = cv::Mat::zeros(height, width, CV_32S);
  if (!lights_match) return;
  for (std::size_t i = 0; i < record.tree.lights.size(); ++i) {
    if (emitter_of_light[i] < 0) continue;
    const int id = scene.emitters[static_cast<std::size_t>(emitter_of_light[i])].light_id;
    for (const PixelRun& run : record.tree.lights[i].runs)
      for (int c = run.first_col; c <= run.last_col; ++c) light_pixels.at<int>(run.row, c) = id;
  }
}

// RenderScene's pixel texture: per texel of the mesh's grid, what a face made from that pixel
// alone would reflect and emit (the rules of addMeshFaces, addEmitters and assignFaceEmitters:
// a lit light's pixel emits its emitter and reflects nothing, one whose light emits from a
// proxy reflects nothing either); per scene vertex made from a pixel, its texel.
void NightSceneBuilder::addPixelTexture() {
  const SurfaceMesh& mesh = depth_mesh.mesh;
  const std::optional<ImageVertexProperties> props = ImageVertexProperties::find(mesh);
  const int w = depth_mesh.width, h = depth_mesh.height;
  const std::size_t texels = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  if (!props || texels == 0 || depth_mesh.vertex_of_pixel.size() != texels) return;
  const double scale_x = static_cast<double>(width) / w, scale_y = static_cast<double>(height) / h;
  const Eigen::Vector3f default_xyz =
      reflectanceFromLinearSrgb(Eigen::Vector3f::Constant(options.default_reflectance));
  scene.texture_width = w;
  scene.texture_height = h;
  scene.texel_reflectance.assign(texels, default_xyz);
  scene.texel_emitter.assign(texels, -1);
  if (!roughness.empty()) scene.texel_roughness.assign(texels, 0.5f);
  scene.vertex_texel.assign(scene.vertices.size(), -1);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const std::size_t t = static_cast<std::size_t>(v) * static_cast<std::size_t>(w) + static_cast<std::size_t>(u);
      const int x = mapPixel(u, scale_x, width), y = mapPixel(v, scale_y, height);
      if (!reflectance_xyz.empty()) {
        const cv::Vec3f a = reflectance_xyz.at<cv::Vec3f>(y, x);
        scene.texel_reflectance[t] = Eigen::Vector3f(a[0], a[1], a[2]);
      }
      if (!roughness.empty()) scene.texel_roughness[t] = std::clamp(roughness.at<float>(y, x), 0.f, 1.f);
      const int light = light_index.at<int>(y, x);
      if (light >= 0 && light_on[static_cast<std::size_t>(light)]) {
        const bool from_proxy = proxied[static_cast<std::size_t>(light)] != 0;
        const int emitter = from_proxy ? -1 : emitter_of_light[static_cast<std::size_t>(light)];
        scene.texel_emitter[t] = emitter;
        if (emitter >= 0 || from_proxy) scene.texel_reflectance[t].setZero();
      }
      const int vertex = depth_mesh.vertex_of_pixel[t];
      if (vertex < 0) continue;
      const OpenMesh::VertexHandle vh(vertex);
      if (mesh.status(vh).deleted() ||
          static_cast<VertexOrigin>(mesh.property(props->origin, vh)) != VertexOrigin::Pixel)
        continue;
      const int index = index_of_vertex[static_cast<std::size_t>(vertex)];
      if (index >= 0) scene.vertex_texel[static_cast<std::size_t>(index)] = static_cast<std::int32_t>(t);
    }
}

// The ego car's headlights and the night sky, as the options ask.
void NightSceneBuilder::addHeadlightsAndSky() {
  if (options.headlights) {
    const double area = 0.3 * 0.15;
    scene.rectangle_lights = egoHeadlights(static_cast<float>(options.headlight_flux_lm / (3.14159265358979 * area)));
  } else {
    report.notes.push_back("ego headlights switched off");
  }
  if (options.sky_luminance_cd_m2 > 0) {
    scene.sky_radiance = xyzFromChromaticity({0.3, 0.3}, options.sky_luminance_cd_m2).cast<float>();
  }
}

void NightSceneBuilder::writeReport() {
  report.add("faces", static_cast<std::int64_t>(scene.faces.size()));
  report.add("emitting_faces", emitting_faces);
  report.add("emitters", static_cast<std::int64_t>(scene.emitters.size()));
  report.add("faces_without_pixel", faces_without_pixel);
  report.add("faces_with_shading_normal", faces_with_shading_normal);
  report.add("hidden_faces_under_lights", hidden_faces_under_lights);
  report.add("faces_off_light_depth", faces_off_light_depth);
  report.add("flux_light_faces_edge_on", faces_seen_edge_on);
  // The same count of lights without depth as the light stage's (countLightsWithoutDepth).
  const LightsWithoutDepth without_depth = countLightsWithoutDepth(record);
  report.add("lights_on_without_depth", without_depth.lit);
  report.add("lights_on_without_faces", lights_on_without_faces);
  report.add("lights_on_not_emitting", lights_on_not_emitting);
  report.add("light_proxies", light_proxies);
  report.add("light_proxies_for_area", light_proxies_for_area);
  report.add("light_proxies_moved", light_proxies_moved);
  report.add("light_proxies_area", proxy_area_m2, "m2");
  if (light_proxies > 0) {
    char note[400];
    std::snprintf(note, sizeof note,
                  "%lld lights that are on show no mesh face (%lld lights that are on have no valid depth), the faces "
                  "of %lld flux lights cover more than %g times their record's area, and %lld lights were moved onto "
                  "their support: %lld of them emit from their pixels on their record's plane",
                  static_cast<long long>(lights_on_without_faces), static_cast<long long>(without_depth.lit),
                  static_cast<long long>(light_proxies_for_area), options.max_flux_area_ratio,
                  static_cast<long long>(light_proxies_moved), static_cast<long long>(light_proxies));
    report.notes.push_back(note);
  }
  if (lights_on_not_emitting > 0)
    report.warnings.push_back(std::to_string(lights_on_not_emitting) +
                              " lights that are on show no mesh face and have no position in the light record: they "
                              "emit nothing");
  report.add("flux_lights_area_mesh", flux_area_mesh_m2, "m2");
  report.add("flux_lights_area_record", flux_area_record_m2, "m2");
  // A luminance light's flux follows its emitting area: the mesh's against the record's.
  report.add("luminance_lights_area_mesh", luminance_area_mesh_m2, "m2");
  report.add("luminance_lights_area_record", luminance_area_record_m2, "m2");
  for (const auto& [category, count] : lights_on_by_category) report.add("on_" + category, count);
  if (scene.emitters.empty()) report.warnings.push_back("no active light in view");
}

}  // namespace

NightScene buildNightScene(const DepthMesh& depth_mesh, const cv::Mat& albedo, const cv::Mat& roughness,
                           const cv::Mat& day_image, const LightRecord& record, const NightSceneOptions& options,
                           const cv::Mat& normals) {
  if (!normals.empty() && normals.type() != CV_32FC3)
    throw std::invalid_argument("buildNightScene: normals must be CV_32FC3");
  Stopwatch clock;
  NightScene out;
  out.report.name = "scene";
  NightSceneBuilder builder(depth_mesh, roughness, normals, record, options, out);
  builder.chooseResolution(albedo);
  builder.markSurfacePixels();
  builder.prepareReflectance(albedo, day_image);
  builder.mapLights();
  builder.addMeshFaces();
  builder.keepFacesAtLightDepth();
  builder.addEmitters();
  builder.assignFaceEmitters();
  builder.markLightPixels();
  builder.addPixelTexture();
  builder.addHeadlightsAndSky();
  builder.writeReport();
  out.report.seconds = clock.seconds();
  return out;
}

}  // namespace solo
