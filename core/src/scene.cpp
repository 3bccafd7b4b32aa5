#include "solo/core/scene.h"
#include "solo/core/scene_from_arrays.h"

#include "solo/core/error.h"
#include "solo/core/input_file.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <set>

namespace fs = std::filesystem;
using nlohmann::json;

namespace solo {
namespace {

const std::set<std::string> kKnownKeys = {"image",     "depth",  "normals", "albedo",       "roughness",
                                          "instances", "labels", "lights",  "light_groups", "camera",
                                          "name",      "comment", "ground_truth"};

std::string typeName(const json& v) { return v.type_name(); }

fs::path resolve(const fs::path& manifest, const std::string& relative) {
  fs::path p(relative);
  return p.is_absolute() ? p : manifest.parent_path() / p;
}

fs::path pathValue(const fs::path& manifest, const json& j, const std::string& key) {
  const json& v = j.at(key);
  if (!v.is_string()) throw InputError(manifest, "\"" + key + "\" must be a path string, found " + typeName(v));
  if (v.get<std::string>().empty()) throw InputError(manifest, "\"" + key + "\" is an empty path");
  return resolve(manifest, v.get<std::string>());
}

double numberValue(const fs::path& manifest, const json& obj, const std::string& where, const std::string& key) {
  if (!obj.contains(key)) throw InputError(manifest, "\"" + where + "\" lacks \"" + key + "\"");
  const json& v = obj.at(key);
  if (!v.is_number()) throw InputError(manifest, "\"" + where + "\".\"" + key + "\" must be a number, found " + typeName(v));
  return v.get<double>();
}

/// A whole number of pixels from 1 to kMaxCameraSide; anything else (a fraction, a value an
/// int cannot hold) is refused naming the manifest.
int intValue(const fs::path& manifest, const json& obj, const std::string& where, const std::string& key) {
  constexpr long long kMaxCameraSide = 65536;
  const json& v = obj.at(key);
  // An unsigned JSON value above LLONG_MAX reads as a negative long long: refused too.
  const bool in_range = v.is_number_integer() && v.get<long long>() >= 1 && v.get<long long>() <= kMaxCameraSide;
  if (!in_range)
    throw InputError(manifest, "\"" + where + "\".\"" + key + "\" must be a whole number of pixels from 1 to " +
                                   std::to_string(kMaxCameraSide) + ", found " + v.dump());
  return v.get<int>();
}

void warnUnknown(const json& obj, const std::set<std::string>& known, const std::string& where,
                 std::vector<std::string>& warnings) {
  for (const auto& item : obj.items())
    if (!known.count(item.key())) warnings.push_back("unknown key \"" + where + item.key() + "\" ignored");
}

void checkAspect(const std::string& name, const cv::Mat& map, const cv::Mat& image, std::vector<std::string>& warnings) {
  if (map.empty() || map.size() == image.size()) return;
  const double a = static_cast<double>(map.cols) / map.rows, b = static_cast<double>(image.cols) / image.rows;
  if (std::abs(a / b - 1.0) > 0.01)
    warnings.push_back(name + " is " + sizeText(map) + ", a different aspect ratio than the " + sizeText(image) +
                       " image: it will be stretched when upsampled");
}

/// The "depth" key: a path, or {"file", "scale"} / {"file", "disparity": true}.
void readDepthKey(const fs::path& manifest_file, const json& j, SceneManifest& m) {
  if (!j.contains("depth")) throw InputError(manifest_file, "required key \"depth\" is missing");
  const json& depth = j.at("depth");
  if (depth.is_string()) {
    m.depth = pathValue(manifest_file, j, "depth");
    return;
  }
  if (!depth.is_object())
    throw InputError(manifest_file, "\"depth\" must be a path or {\"file\", \"scale\"}, found " + typeName(depth));
  if (!depth.contains("file")) throw InputError(manifest_file, "\"depth\" object lacks \"file\"");
  m.depth = pathValue(manifest_file, depth, "file");
  if (depth.contains("scale")) {
    const double scale = numberValue(manifest_file, depth, "depth", "scale");
    if (!(scale > 0) || !std::isfinite(scale))
      throw InputError(manifest_file, "\"depth\".\"scale\" must be a positive number of metres per unit");
    m.depth_scale_m_per_unit = scale;
  }
  if (depth.contains("disparity")) {
    if (!depth.at("disparity").is_boolean())
      throw InputError(manifest_file, "\"depth\".\"disparity\" must be true or false, found " +
                                          typeName(depth.at("disparity")));
    m.depth_is_disparity = depth.at("disparity").get<bool>();
  }
  if (m.depth_is_disparity && m.depth_scale_m_per_unit)
    throw InputError(manifest_file, "\"depth\" has both \"disparity\" and \"scale\": a Cityscapes disparity "
                                    "is converted with the camera's baseline and fx, not scaled");
  warnUnknown(depth, {"file", "scale", "disparity"}, "depth.", m.warnings);
}

/// An optional "width" and "height" pair of a camera object, as a resolution-only camera.
std::optional<PinholeCamera> cameraResolution(const fs::path& manifest_file, const json& c) {
  if (!c.contains("width") && !c.contains("height")) return std::nullopt;
  if (c.contains("width") != c.contains("height"))
    throw InputError(manifest_file, "\"camera\" needs both \"width\" and \"height\" or neither");
  PinholeCamera resolution;
  resolution.width = intValue(manifest_file, c, "camera", "width");
  resolution.height = intValue(manifest_file, c, "camera", "height");
  return resolution;
}

/// The "camera" key: a Cityscapes camera JSON (path or {"file", "width", "height"}), a KITTI
/// calibration ({"kitti", "matrix"}), or inline intrinsics.
void readCameraKey(const fs::path& manifest_file, const json& j, SceneManifest& m) {
  if (!j.contains("camera") || j.at("camera").is_null()) return;
  const json& c = j.at("camera");
  if (c.is_string()) {
    m.camera_file = pathValue(manifest_file, j, "camera");
  } else if (c.is_object() && c.contains("file")) {
    m.camera_file = pathValue(manifest_file, c, "file");
    m.camera = cameraResolution(manifest_file, c);  // resolution only; intrinsics come from the file
    warnUnknown(c, {"file", "width", "height"}, "camera.", m.warnings);
  } else if (c.is_object() && c.contains("kitti")) {
    m.camera_file = pathValue(manifest_file, c, "kitti");
    m.camera_file_format = CameraFileFormat::Kitti;
    if (c.contains("matrix")) {
      if (!c.at("matrix").is_string() || c.at("matrix").get<std::string>().empty())
        throw InputError(manifest_file, "\"camera\".\"matrix\" must name a KITTI projection matrix (\"P_rect_02\", \"P2\")");
      m.kitti_matrix = c.at("matrix").get<std::string>();
    }
    warnUnknown(c, {"kitti", "matrix"}, "camera.", m.warnings);
  } else if (c.is_object()) {
    PinholeCamera k;
    k.fx = numberValue(manifest_file, c, "camera", "fx");
    k.fy = numberValue(manifest_file, c, "camera", "fy");
    k.cx = numberValue(manifest_file, c, "camera", "cx");
    k.cy = numberValue(manifest_file, c, "camera", "cy");
    if (const auto resolution = cameraResolution(manifest_file, c)) {
      k.width = resolution->width;
      k.height = resolution->height;
    }
    m.camera = k;
    warnUnknown(c, {"fx", "fy", "cx", "cy", "width", "height"}, "camera.", m.warnings);
  } else {
    throw InputError(manifest_file, "\"camera\" must be an object of intrinsics or a path, found " + typeName(c));
  }
}

}  // namespace

SceneManifest readSceneManifest(const fs::path& manifest_file) {
  SceneManifest m;
  m.file = manifest_file;
  requireRegularFile(manifest_file, "scene manifest");
  std::ifstream in(manifest_file);
  if (!in) throw InputError(manifest_file, "cannot open for reading");
  json j;
  try {
    in >> j;
  } catch (const json::exception& e) {
    throw InputError(manifest_file, std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) throw InputError(manifest_file, "scene manifest must be a JSON object, found " + typeName(j));
  warnUnknown(j, kKnownKeys, "", m.warnings);

  if (!j.contains("image")) throw InputError(manifest_file, "required key \"image\" is missing");
  m.image = pathValue(manifest_file, j, "image");
  readDepthKey(manifest_file, j, m);

  auto optionalPath = [&](const char* key, std::optional<fs::path>& out) {
    if (j.contains(key) && !j.at(key).is_null()) out = pathValue(manifest_file, j, key);
  };
  optionalPath("normals", m.normals);
  optionalPath("albedo", m.albedo);
  optionalPath("roughness", m.roughness);
  optionalPath("instances", m.instances);
  optionalPath("labels", m.labels);
  optionalPath("lights", m.lights);
  optionalPath("light_groups", m.light_groups);
  optionalPath("ground_truth", m.ground_truth);
  for (const char* text_key : {"name", "comment"})
    if (j.contains(text_key) && !j.at(text_key).is_string())
      throw InputError(manifest_file, std::string("\"") + text_key + "\" must be a string");

  readCameraKey(manifest_file, j, m);
  if (m.depth_is_disparity && (!m.camera_file || m.camera_file_format != CameraFileFormat::Cityscapes))
    throw InputError(manifest_file, "\"depth\" is a disparity map: it needs a Cityscapes camera file (\"camera\": "
                                    "\"..._camera.json\") giving \"extrinsic\".\"baseline\" and \"intrinsic\".\"fx\"");
  return m;
}

namespace {

/// Every light id is 0 or categoryId * 1000 + k with categoryId in 1..kLightCategoryCount.
void checkLightIds(const cv::Mat& lights, const fs::path& file) {
  for (int y = 0; y < lights.rows; ++y)
    for (int x = 0; x < lights.cols; ++x) {
      const int id = lights.at<int>(y, x);
      const int category = id / 1000;
      if (id != 0 && (category < 1 || category > kLightCategoryCount))
        throw InputError(file, "light id " + std::to_string(id) + " at pixel (" + std::to_string(x) + ", " +
                                   std::to_string(y) + ") has category " + std::to_string(category) +
                                   ", expected categoryId * 1000 + k with categoryId in 1.." +
                                   std::to_string(kLightCategoryCount));
    }
}

/// The manifest's depth in metres: a depth file as stored (scaled), or a Cityscapes disparity
/// converted with its camera file's baseline and fx.
cv::Mat readManifestDepth(const SceneManifest& m, DepthReadStats& stats, ImageFileInfo& info) {
  if (!m.depth_is_disparity) return readDepth(m.depth, m.depth_scale_m_per_unit.value_or(0.0), &stats, &info);
  const std::optional<double> baseline_m = readCityscapesBaseline(*m.camera_file);
  if (!baseline_m)
    throw InputError(m.file, "\"depth\" is a disparity map, but its camera file " + m.camera_file->string() +
                                 " gives no \"extrinsic\".\"baseline\" (metres) to turn it into depth");
  if (!(*baseline_m > 0) || !std::isfinite(*baseline_m))
    throw InputError(*m.camera_file, "\"extrinsic\".\"baseline\" must be a positive number of metres");
  const PinholeCamera camera = readCityscapesCamera(*m.camera_file);
  if (!(camera.fx > 0) || !std::isfinite(camera.fx))
    throw InputError(*m.camera_file, "\"intrinsic\".\"fx\" must be a positive number of pixels");
  cv::Mat depth_m = readCityscapesDisparityDepth(m.depth, *baseline_m, camera.fx, &stats, &info);
  if (m.camera && m.camera->width > 0 && (m.camera->width != info.width || m.camera->height != info.height))
    throw InputError(m.depth, "disparity map is " + sizeText(info.width, info.height) + " but the camera's fx is for " +
                                  sizeText(m.camera->width, m.camera->height) +
                                  ": a disparity is in pixels of the resolution its camera file describes");
  return depth_m;
}

/// Reads the manifest's maps into `s`, each file's header into s.maps; labels derived from the
/// instances when only those are given.
void readSceneMaps(const SceneManifest& m, Scene& s) {
  ImageFileInfo info;
  s.image = readColorImage(m.image, &info);
  s.maps.push_back({"image", m.image, info});
  s.depth_m = readManifestDepth(m, s.depth_stats, info);
  s.maps.push_back({"depth", m.depth, info});
  if (s.depth_stats.valid == 0) throw InputError(m.depth, "depth has no valid pixel (all 0, NaN, inf or negative)");

  if (m.normals) {
    NormalReadStats stats;
    s.normals = readNormals(*m.normals, &stats, &info);
    s.normal_stats = stats;
    s.maps.push_back({"normals", *m.normals, info});
  }
  if (m.albedo) {
    s.albedo = readColorImage(*m.albedo, &info);
    s.maps.push_back({"albedo", *m.albedo, info});
  }
  if (m.roughness) {
    s.roughness = readScalarMap(*m.roughness, &info);
    s.maps.push_back({"roughness", *m.roughness, info});
  }
  auto labelMap = [&](const char* name, const std::optional<fs::path>& file, cv::Mat& out) {
    if (!file) return;
    out = readLabels(*file, &info);
    s.maps.push_back({name, *file, info});
    double lo = 0, hi = 0;
    cv::minMaxLoc(out, &lo, &hi);
    if (lo < 0) throw InputError(*file, std::string(name) + " holds negative ids");
  };
  labelMap("instances", m.instances, s.instances);
  labelMap("labels", m.labels, s.labels);
  labelMap("lights", m.lights, s.lights);
  labelMap("light_groups", m.light_groups, s.light_groups);
  if (!s.lights.empty()) checkLightIds(s.lights, *m.lights);
  if (s.labels.empty() && !s.instances.empty()) {
    s.labels = s.instances.clone();
    s.labels.forEach<int>([](int& v, const int*) { v = cityscapesClassOfInstance(v); });
    s.warnings.push_back("labelIds derived from instanceIds");
  }
}

/// The scene's camera: validated where it was stated (a camera file, the manifest, else
/// defaultSceneCamera), then scaled to the image resolution. Sets s.camera and s.camera_is_default.
void setSceneCamera(const SceneManifest& m, Scene& s) {
  PinholeCamera camera;
  fs::path camera_source = m.file;
  if (m.camera_file) {
    camera = m.camera_file_format == CameraFileFormat::Kitti ? readKittiCalibration(*m.camera_file, m.kitti_matrix)
                                                             : readCityscapesCamera(*m.camera_file);
    camera_source = *m.camera_file;
    if (m.camera && m.camera->width > 0) {
      camera.width = m.camera->width;
      camera.height = m.camera->height;
    }
  } else if (m.camera) {
    camera = *m.camera;
  } else {
    camera = defaultSceneCamera(s.image.cols, s.image.rows);
    s.camera_is_default = true;
    s.warnings.push_back(defaultCameraWarning(camera));
  }
  setCameraForImage(camera, camera_source, s);
}

// Sets every NaN or infinite value of a float map to 0; returns how many there were. A single
// NaN reflectance would spread through the renderer's sums and turn the night image black.
std::int64_t zeroNonFinite(cv::Mat& map) {
  std::int64_t count = 0;
  if (map.empty() || map.depth() != CV_32F) return 0;
  for (int y = 0; y < map.rows; ++y) {
    float* row = map.ptr<float>(y);
    for (int i = 0; i < map.cols * map.channels(); ++i)
      if (!std::isfinite(row[i])) {
        row[i] = 0.f;
        ++count;
      }
  }
  return count;
}

}  // namespace

Scene loadScene(const fs::path& manifest_file) {
  Scene s;
  s.manifest = readSceneManifest(manifest_file);
  s.warnings = s.manifest.warnings;
  readSceneMaps(s.manifest, s);
  for (const auto& [name, map] : {std::pair<const char*, cv::Mat*>{"day image", &s.image},
                                  {"albedo", &s.albedo}, {"roughness", &s.roughness}})
    if (const std::int64_t repaired = zeroNonFinite(*map); repaired > 0)
      s.warnings.push_back(std::to_string(repaired) + " NaN or infinite values of the " + name + " set to 0");
  setSceneCamera(s.manifest, s);
  if (!s.normals.empty()) s.normal_stats->back_facing = countBackFacingNormals(s.normals, s.camera);

  for (const auto& [name, map] : {std::pair<const char*, const cv::Mat*>{"depth", &s.depth_m},
                                  {"normals", &s.normals}, {"albedo", &s.albedo}, {"roughness", &s.roughness},
                                  {"instances", &s.instances}, {"labels", &s.labels}, {"lights", &s.lights},
                                  {"light_groups", &s.light_groups}})
    checkAspect(name, *map, s.image, s.warnings);
  if (s.normal_stats && s.normal_stats->renormalised > 0)
    s.warnings.push_back(std::to_string(s.normal_stats->renormalised) + " normals were not unit length: renormalised");
  return s;
}

StageReport describeScene(const Scene& s) {
  StageReport r;
  r.name = "input";
  r.add("image_size", sizeText(s.width(), s.height()), "px");
  const DepthReadStats& d = s.depth_stats;
  r.add("depth_valid", d.valid).add("depth_invalid", d.invalid());
  r.add("depth_zero", d.zero).add("depth_nan", d.nan).add("depth_inf", d.inf).add("depth_negative", d.negative);
  r.add("depth_min", d.min_m, "m").add("depth_max", d.max_m, "m");
  if (s.normal_stats) {
    r.add("normals_valid", s.normal_stats->valid).add("normals_invalid", s.normal_stats->invalid);
    r.add("normals_renormalised", s.normal_stats->renormalised).add("normals_back_facing", s.normal_stats->back_facing);
  }
  r.add("camera_fx", s.camera.fx, "px").add("camera_fy", s.camera.fy, "px");
  r.add("camera_cx", s.camera.cx, "px").add("camera_cy", s.camera.cy, "px");
  r.add("camera_default", s.camera_is_default);
  for (const MapRecord& map : s.maps)
    r.add(map.name + "_file", map.info.format + " " + sizeText(map.info.width, map.info.height) + " " +
                                  std::to_string(map.info.channels) + "ch " + map.info.pixel_type);
  for (const char* optional_map : {"normals", "albedo", "roughness", "instances", "labels", "lights", "light_groups"}) {
    bool present = false;
    for (const MapRecord& map : s.maps) present |= map.name == optional_map;
    if (!present) r.notes.push_back(std::string("no ") + optional_map + " map given");
  }
  for (const std::string& w : s.warnings) r.warnings.push_back(w);
  return r;
}

std::vector<fs::path> manifestFiles(const SceneManifest& m) {
  std::vector<fs::path> files = {m.file, m.image, m.depth};
  for (const auto* optional : {&m.normals, &m.albedo, &m.roughness, &m.instances, &m.labels, &m.lights,
                               &m.light_groups, &m.ground_truth, &m.camera_file})
    if (*optional) files.push_back(**optional);
  return files;
}

PinholeCamera defaultSceneCamera(int width, int height) {
  const PinholeCamera acdc = PinholeCamera::acdc();
  // fx as PinholeCamera::scaledTo computes it (f * s), so a 16:9 image gets what scaling the
  // ACDC intrinsics gave; (width / 2) / tan(kDefaultHorizontalFovRad / 2) in exact arithmetic.
  const double f = acdc.fx * (static_cast<double>(width) / acdc.width);
  return {f, f, (width - 1) / 2.0, (height - 1) / 2.0, width, height};
}

std::optional<double> readCityscapesBaseline(const fs::path& file) {
  requireRegularFile(file, "camera");
  std::ifstream in(file);
  if (!in) throw InputError(file, "cannot open for reading");
  json j;
  try {
    in >> j;
  } catch (const json::exception& e) {
    throw InputError(file, std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object() || !j.contains("extrinsic") || !j.at("extrinsic").is_object()) return std::nullopt;
  const json& extrinsic = j.at("extrinsic");
  if (!extrinsic.contains("baseline") || !extrinsic.at("baseline").is_number()) return std::nullopt;
  return extrinsic.at("baseline").get<double>();
}

cv::Mat readCityscapesDisparityDepth(const fs::path& file, double baseline_m, double fx_px, DepthReadStats* stats,
                                     ImageFileInfo* info) {
  ImageFileInfo local;
  const cv::Mat stored = readImageRaw(file, &local);
  if (stored.channels() != 1)
    throw InputError(file, "a Cityscapes disparity map has one channel, found " + std::to_string(stored.channels()));
  if (local.pixel_type != "uint16")
    throw InputError(file, "a Cityscapes disparity map is a 16-bit PNG, found " + local.pixel_type);
  cv::Mat depth(stored.rows, stored.cols, CV_32F);
  DepthReadStats s;
  double lo = INFINITY, hi = -INFINITY;
  for (int y = 0; y < stored.rows; ++y) {
    const float* src = stored.ptr<float>(y);
    float* dst = depth.ptr<float>(y);
    for (int x = 0; x < stored.cols; ++x) {
      const double p = src[x];
      dst[x] = 0.f;
      if (p == 0) {
        ++s.zero;  // no disparity
      } else if (p == 1) {
        ++s.inf;  // disparity 0: infinitely far
      } else {
        const double depth_m = baseline_m * fx_px / ((p - 1.0) / 256.0);
        dst[x] = static_cast<float>(depth_m);
        ++s.valid;
        lo = std::min(lo, depth_m);
        hi = std::max(hi, depth_m);
      }
    }
  }
  s.min_m = s.valid ? lo : 0;
  s.max_m = s.valid ? hi : 0;
  if (stats) *stats = s;
  if (info) *info = local;
  return depth;
}

namespace {

/// The numbers after "<key>:" on a line of a KITTI calibration file; empty when no line has it.
std::vector<double> kittiCalibrationValues(const fs::path& file, const std::string& key) {
  std::ifstream in(file);
  if (!in) throw InputError(file, "cannot open for reading");
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string name = line.substr(0, colon);
    name.erase(0, name.find_first_not_of(" \t"));
    if (name != key) continue;
    std::istringstream numbers(line.substr(colon + 1));
    std::vector<double> values;
    std::string token;
    while (numbers >> token) {
      try {
        std::size_t used = 0;
        values.push_back(std::stod(token, &used));
        if (used != token.size()) throw std::invalid_argument(token);
      } catch (const std::exception&) {
        throw InputError(file, "\"" + key + ":\" holds \"" + token + "\", not a number");
      }
    }
    return values;
  }
  return {};
}

}  // namespace

PinholeCamera readKittiCalibration(const fs::path& file, const std::string& matrix) {
  requireRegularFile(file, "KITTI calibration");
  std::string key = matrix.empty() ? "P_rect_02" : matrix;
  std::vector<double> p = kittiCalibrationValues(file, key);
  if (p.empty() && matrix.empty()) p = kittiCalibrationValues(file, key = "P2");
  if (p.empty())
    throw InputError(file, matrix.empty() ? "no \"P_rect_02:\" (calib_cam_to_cam.txt) or \"P2:\" (object calib) line: "
                                            "not a KITTI calibration file"
                                          : "no \"" + matrix + ":\" line");
  if (p.size() != 12)
    throw InputError(file, "\"" + key + ":\" must hold the 12 numbers of a 3x4 projection matrix, found " +
                               std::to_string(p.size()));
  PinholeCamera camera;
  camera.fx = p[0];
  camera.cx = p[2];
  camera.fy = p[5];
  camera.cy = p[6];
  if (key.rfind("P_rect_", 0) == 0) {  // raw data: S_rect_XX is the rectified image size
    const std::vector<double> size = kittiCalibrationValues(file, "S_rect_" + key.substr(7));
    if (size.size() == 2 && size[0] >= 1 && size[1] >= 1) {
      camera.width = static_cast<int>(std::lround(size[0]));
      camera.height = static_cast<int>(std::lround(size[1]));
    }
  }
  return camera;
}

fs::path groundTruthManifest(const fs::path& manifest_file) {
  const SceneManifest m = readSceneManifest(manifest_file);
  if (!m.ground_truth)
    throw InputError(manifest_file, "has no \"ground_truth\" entry: not a synthetic scene (`solo synth` writes one)");
  return *m.ground_truth;
}


std::string defaultCameraWarning(const PinholeCamera& camera) {
  std::ostringstream warning;
  warning << "no camera given: square pixels with ACDC's horizontal field of view of " << std::fixed
          << std::setprecision(1) << kDefaultHorizontalFovRad * 180.0 / std::acos(-1.0) << " degrees (fx = fy = "
          << std::setprecision(2) << camera.fx << " px), principal point at the image centre";
  return warning.str();
}

void setCameraForImage(PinholeCamera camera, const fs::path& source, Scene& s) {
  if (camera.width <= 0) {
    camera.width = s.image.cols;
    camera.height = s.image.rows;
  }
  validateCamera(camera, source);
  if (camera.width != s.image.cols || camera.height != s.image.rows) {
    const double a = static_cast<double>(camera.width) / camera.height;
    const double b = static_cast<double>(s.image.cols) / s.image.rows;
    if (std::abs(a / b - 1.0) > 0.01)
      s.warnings.push_back("camera intrinsics are for " + sizeText(camera.width, camera.height) +
                           ", a different aspect ratio than the image: scaled per axis");
    camera = camera.scaledTo(s.image.cols, s.image.rows);
  }
  s.camera = camera;
}

std::int64_t countBackFacingNormals(const cv::Mat& normals, const PinholeCamera& camera) {
  const PinholeCamera at_map = camera.scaledTo(normals.cols, normals.rows);
  std::int64_t back_facing = 0;
  for (int y = 0; y < normals.rows; ++y)
    for (int x = 0; x < normals.cols; ++x) {
      const cv::Vec3f n = normals.at<cv::Vec3f>(y, x);
      const double along_ray = n[0] * (x - at_map.cx) / at_map.fx + n[1] * (y - at_map.cy) / at_map.fy + n[2];
      if ((n[0] != 0 || n[1] != 0 || n[2] != 0) && along_ray > 0) ++back_facing;
    }
  return back_facing;
}

}  // namespace solo
