// Albedo from the day image on synthetic scenes with exact albedo: the linearised day image
// (what stands in for a missing albedo map without removal) against removeDayLight with its
// sun searched by shadow rays and with the shadows read from the image
// (DayLightRemovalOptions::shadows_from_image), by the error of linear albedo over the non-sky
// pixels, and each found sun against synth.json's (sun: degrees, -1 without a sun).
// Not a Google Benchmark: one run per scene, a table on stdout (docs/rendering.md).
// The geometry is solo night's: the refined depth (default options) meshed and cleaned.
// Run:
//   for s in 1 2 3; do build/release/tools/solo synth -o /tmp/dl/s$s --seed $s --day-render path; done
//   build/release/tests/benchmarks/bench_day_light [--pictures DIR] [--exact-geometry | --exact-depth-mesh] /tmp/dl/s1 ...
// --exact-geometry: synth's exact mesh, normals and instances instead of solo night's.
// --exact-depth-mesh: the depth mesh of synth's exact depth (what the camera sees of the exact
// geometry, cleaned as solo night cleans it) with the exact normals and instances.
// --known-sun: the shadow-ray removal is given synth's sun (DayLightRemovalOptions::sun_direction)
// instead of searching it; the image-shadow removal searches as before.
// Errors: "fit" scales each channel of both estimates by its least-squares gain to the exact
// albedo (the shading left, not the exposure); "rule" is each estimate with the removal's own
// white balance and scale (the day image given the same rule). --pictures DIR writes each
// albedo and a side-by-side of the day image, the image-shadow removal and the truth.

#include <solo/core/image_io.h>
#include <solo/core/scene.h>
#include <solo/core/srgb.h>
#include <solo/geometry/depth_refinement.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/geometry/triangle_mesh.h>
#include <solo/pipeline/night_conversion.h>
#include <solo/render/day_light_removal.h>
#include <solo/synth/scene_raster.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <variant>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace solo;

namespace {

constexpr int kSkyLabel = 23;

std::string valueText(bool v) { return v ? "true" : "false"; }
std::string valueText(std::int64_t v) { return std::to_string(v); }
std::string valueText(double v) { return std::to_string(v); }
std::string valueText(const std::string& v) { return v; }

struct AlbedoError {
  double mae = 0, relative = 0;
};

// Mean absolute error over the mask, averaged over channels, after per-channel gains (fit) or none.
AlbedoError albedoError(const cv::Mat& estimate, const cv::Mat& truth, const cv::Mat& mask, bool fit) {
  std::array<double, 3> ee{}, et{};
  for (int y = 0; y < truth.rows; ++y)
    for (int x = 0; x < truth.cols; ++x) {
      if (!mask.at<std::uint8_t>(y, x)) continue;
      const cv::Vec3f e = estimate.at<cv::Vec3f>(y, x), t = truth.at<cv::Vec3f>(y, x);
      for (int c = 0; c < 3; ++c) {
        ee[c] += double(e[c]) * e[c];
        et[c] += double(e[c]) * t[c];
      }
    }
  std::array<double, 3> gain{1, 1, 1};
  if (fit)
    for (int c = 0; c < 3; ++c) gain[c] = ee[c] > 0 ? et[c] / ee[c] : 1;
  double abs_sum = 0, truth_sum = 0;
  std::int64_t n = 0;
  for (int y = 0; y < truth.rows; ++y)
    for (int x = 0; x < truth.cols; ++x) {
      if (!mask.at<std::uint8_t>(y, x)) continue;
      const cv::Vec3f e = estimate.at<cv::Vec3f>(y, x), t = truth.at<cv::Vec3f>(y, x);
      for (int c = 0; c < 3; ++c) {
        abs_sum += std::abs(gain[c] * e[c] - t[c]);
        truth_sum += t[c];
      }
      ++n;
    }
  AlbedoError out;
  out.mae = n ? abs_sum / (3.0 * n) : 0;
  out.relative = truth_sum > 0 ? abs_sum / truth_sum : 0;
  return out;
}

// The removal's own rule on another estimate: road and sidewalk grey, median luminance 0.2.
cv::Mat balanced(const cv::Mat& image, const cv::Mat& labels, const cv::Mat& mask) {
  std::array<std::vector<float>, 3> road;
  std::vector<float> lum;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      const int label = labels.at<int>(y, x);
      if (!mask.at<std::uint8_t>(y, x) || (label != 7 && label != 8)) continue;
      for (int c = 0; c < 3; ++c) road[c].push_back(image.at<cv::Vec3f>(y, x)[c]);
    }
  const auto median = [](std::vector<float> v) {
    if (v.empty()) return 1.f;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  cv::Vec3f gain(1, 1, 1);
  const cv::Vec3f ref(median(road[0]), median(road[1]), median(road[2]));
  for (int c = 0; c < 3; ++c) gain[c] = (ref[0] + ref[1] + ref[2]) / 3 / ref[c];
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x)
      if (mask.at<std::uint8_t>(y, x)) {
        const cv::Vec3f v = image.at<cv::Vec3f>(y, x);
        lum.push_back(0.2126f * v[0] * gain[0] + 0.7152f * v[1] * gain[1] + 0.0722f * v[2] * gain[2]);
      }
  const float scale = 0.2f / median(lum);
  cv::Mat out = image.clone();
  out.forEach<cv::Vec3f>([&](cv::Vec3f& v, const int*) {
    for (int c = 0; c < 3; ++c) v[c] = std::clamp(v[c] * gain[c] * scale, 0.f, 1.f);
  });
  return out;
}

Eigen::Vector3f synthSun(const fs::path& dir) {
  std::ifstream in(dir / "synth.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  const auto& s = j.at("sun_direction");
  return Eigen::Vector3f(s[0].get<float>(), s[1].get<float>(), s[2].get<float>()).normalized();
}

cv::Mat linearised(const cv::Mat& srgb) {
  cv::Mat out = srgb.clone();
  out.forEach<cv::Vec3f>([](cv::Vec3f& c, const int*) {
    for (int k = 0; k < 3; ++k) c[k] = srgbToLinear(std::clamp(c[k], 0.f, 1.f));
  });
  return out;
}

enum class Geometry { SoloNight, ExactMesh, ExactDepthMesh };

// The removal's geometry for one of the three modes (file header).
DayLightGeometry removalGeometry(const fs::path& dir, const Scene& scene, const PinholeCamera& camera, Geometry mode) {
  const NightConversionOptions o;
  if (mode == Geometry::ExactDepthMesh) {
    const Scene gt = loadScene(dir / "gt" / "scene.json");
    StageReport report;
    const DepthMesh mesh = meshFromScene(gt.depth_m, gt.camera, gt.instances, cv::Mat(), o.mesh, report);
    DayLightGeometry geometry = dayLightGeometry(mesh, camera, gt.normals);
    geometry.instances = gt.instances;
    return geometry;
  }
  const DepthRefinementResult refined = refineDepth(sceneForRefinement(scene), o.refinement);
  StageReport mesh_report;
  const DepthMesh mesh =
      meshFromScene(refined.depth_m, scene.camera, refined.maps.instances, refined.uncertain, o.mesh, mesh_report);
  DayLightGeometry geometry = dayLightGeometry(mesh, camera, refined.normals);
  if (mode == Geometry::ExactMesh) {
    const TriangleMesh exact = readMesh(dir / "gt" / "mesh.ply");
    geometry.vertices.clear();
    geometry.triangles.clear();
    for (const Eigen::Vector3d& v : exact.vertices)
      for (int k = 0; k < 3; ++k) geometry.vertices.push_back(static_cast<float>(v[k]));
    for (const auto& f : exact.faces)
      for (int k = 0; k < 3; ++k) geometry.triangles.push_back(f[static_cast<std::size_t>(k)]);
    geometry.triangle_instance.assign(exact.faces.size(), 0);
    geometry.normals = readNormals(dir / "gt" / "normals.png");
    geometry.instances = readLabels(dir / "gt" / "instanceIds.png");
  }
  return geometry;
}

// One removal's errors against the truth and its sun's angle to synth's (-1 without a sun).
struct Scored {
  DayLightRemoval removal;
  AlbedoError fit, rule;
  double sun_error_deg = -1;
};

Scored score(DayLightRemoval removal, const cv::Mat& truth, const cv::Mat& mask, const Eigen::Vector3f& sun) {
  Scored s;
  s.fit = albedoError(removal.albedo, truth, mask, true);
  s.rule = albedoError(removal.albedo, truth, mask, false);
  if (removal.method == DayLightMethod::SunAndSky)
    s.sun_error_deg = std::acos(std::clamp(double(sun.dot(removal.sun_direction)), -1.0, 1.0)) * 180 / 3.14159265358979;
  s.removal = std::move(removal);
  return s;
}

void printNotes(const char* label, const DayLightRemoval& removal) {
  for (const std::string& note : removal.report.notes) std::printf("    %s: %s\n", label, note.c_str());
  if (std::getenv("SOLO_BENCH_VERBOSE"))
    for (const Metric& m : removal.report.metrics)
      std::visit([&](const auto& v) { std::printf("    %s: %s = %s\n", label, m.name.c_str(), valueText(v).c_str()); },
                 m.value);
}

// The PNGs of --pictures: each albedo alone, and the day image (the removal's rule), the
// image-shadow removal and the truth side by side at half size.
void writePictures(const fs::path& pictures, const std::string& name, const cv::Mat& day_rule, const cv::Mat& rays,
                   const cv::Mat& image, const cv::Mat& truth) {
  fs::create_directories(pictures);
  writeImage(pictures / (name + "_day_albedo.png"), srgbEncode8(day_rule));
  writeImage(pictures / (name + "_delit_albedo.png"), srgbEncode8(rays));
  writeImage(pictures / (name + "_image_shadows_albedo.png"), srgbEncode8(image));
  writeImage(pictures / (name + "_true_albedo.png"), srgbEncode8(truth));
  cv::Mat row, half;
  cv::hconcat(std::vector<cv::Mat>{day_rule, image, truth}, row);
  cv::resize(row, half, cv::Size(row.cols / 2, row.rows / 2), 0, 0, cv::INTER_AREA);
  writeImage(pictures / (name + "_side_by_side.png"), srgbEncode8(half));
}

void runScene(const fs::path& dir, const fs::path& pictures, Geometry mode, bool known_sun) {
  const Scene scene = loadScene(dir / "scene.json");
  const cv::Mat day = linearised(scene.image);
  const PinholeCamera camera = scene.camera.scaledTo(day.cols, day.rows);
  const DayLightGeometry geometry = removalGeometry(dir, scene, camera, mode);
  DayLightRemovalOptions image_options;
  image_options.shadows_from_image = true;

  const cv::Mat truth = readColorImage(dir / "gt" / "albedo.png");
  const cv::Mat labels = readLabels(dir / "gt" / "labelIds.png");
  cv::Mat mask = cv::Mat::zeros(truth.size(), CV_8U);
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x) mask.at<std::uint8_t>(y, x) = labels.at<int>(y, x) != kSkyLabel ? 1 : 0;
  const Eigen::Vector3f sun = synthSun(dir);
  DayLightRemovalOptions ray_options;
  if (known_sun) ray_options.sun_direction = sun;
  const Scored rays = score(removeDayLight(day, geometry, ray_options), truth, mask, sun);
  const Scored image = score(removeDayLight(day, geometry, image_options), truth, mask, sun);
  const cv::Mat day_rule = balanced(day, labels, mask);
  const AlbedoError day_fit = albedoError(day, truth, mask, true), day_rule_err = albedoError(day_rule, truth, mask, false);
  std::printf("%-6s %6.3f %5.2f | %-11s %6.3f %5.2f %6.1f %5.1f s | %-11s %6.3f %5.2f %6.1f %5.1f s | %6.3f %6.3f %6.3f\n",
              dir.filename().string().c_str(), day_fit.mae, day_fit.relative, dayLightMethodName(rays.removal.method),
              rays.fit.mae, rays.fit.relative, rays.sun_error_deg, rays.removal.report.seconds,
              dayLightMethodName(image.removal.method), image.fit.mae, image.fit.relative, image.sun_error_deg,
              image.removal.report.seconds, day_rule_err.mae, rays.rule.mae, image.rule.mae);
  printNotes("shadow rays", rays.removal);
  printNotes("image shadows", image.removal);
  std::fflush(stdout);
  if (!pictures.empty())
    writePictures(pictures, dir.filename().string(), day_rule, rays.removal.albedo, image.removal.albedo, truth);
}

}  // namespace

int main(int argc, char** argv) {
  fs::path pictures;
  Geometry mode = Geometry::SoloNight;
  bool known_sun = false;
  std::vector<fs::path> scenes;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--pictures" && i + 1 < argc)
      pictures = argv[++i];
    else if (arg == "--exact-geometry")
      mode = Geometry::ExactMesh;
    else if (arg == "--exact-depth-mesh")
      mode = Geometry::ExactDepthMesh;
    else if (arg == "--known-sun")
      known_sun = true;
    else
      scenes.emplace_back(arg);
  }
  if (scenes.empty()) {
    std::fprintf(stderr, "usage: bench_day_light [--pictures DIR] [--exact-geometry | --exact-depth-mesh] [--known-sun] "
                         "SCENE_DIR...\n");
    return 2;
  }
  std::printf("%-6s %12s | %-11s %25s | %-11s %25s | %20s\n", "", "day", "shadow rays", "", "image shadows", "",
              "rule MAE");
  std::printf("%-6s %6s %5s | %-11s %6s %5s %6s %7s | %-11s %6s %5s %6s %7s | %6s %6s %6s\n", "scene", "fit", "rel",
              "method", "fit", "rel", "sun", "time", "method", "fit", "rel", "sun", "time", "day", "rays", "image");
  for (const fs::path& dir : scenes) runScene(dir, pictures, mode, known_sun);
  return 0;
}
