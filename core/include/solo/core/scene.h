#pragma once
// The scene: the contract every stage reads. docs/scene-format.md is its authoritative
// description. A scene is a JSON manifest whose paths are relative to the manifest.

#include "solo/core/camera.h"
#include "solo/core/image_io.h"
#include "solo/core/report.h"

#include <opencv2/core.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace solo {

/// Light-source categories in a light map are 1..kLightCategoryCount (see the lighting
/// module for their names); a light map value is categoryId * 1000 + k.
constexpr int kLightCategoryCount = 15;

/// The manifest as written, paths resolved against the manifest's folder.
struct SceneManifest {
  std::filesystem::path file;  ///< the manifest itself
  std::filesystem::path image;
  std::filesystem::path depth;
  std::optional<double> depth_scale_m_per_unit;  ///< "scale"; required for integer depth files
  std::optional<std::filesystem::path> normals, albedo, roughness;
  std::optional<std::filesystem::path> instances;     ///< Cityscapes instanceIds
  std::optional<std::filesystem::path> labels;        ///< Cityscapes labelIds
  std::optional<std::filesystem::path> lights;        ///< light-source instance ids
  std::optional<std::filesystem::path> light_groups;  ///< building-floor window groups
  std::optional<std::filesystem::path> ground_truth;  ///< the exact scene's manifest (`solo synth`)

  /// Camera: inline intrinsics (resolution 0 = "the image's"), or a Cityscapes camera JSON.
  std::optional<PinholeCamera> camera;
  std::optional<std::filesystem::path> camera_file;

  std::vector<std::string> warnings;  ///< unknown keys and the like
};

/// Parses and type-checks a manifest. Does not open the maps. Throws InputError naming
/// the manifest for malformed JSON, a missing required key or a key of the wrong type;
/// unknown keys are kept as warnings.
SceneManifest readSceneManifest(const std::filesystem::path& manifest_file);

/// The manifest file itself and every file it names (maps, camera file, ground-truth manifest),
/// resolved against the manifest's folder: the inputs an output must never overwrite.
std::vector<std::filesystem::path> manifestFiles(const SceneManifest& manifest);

/// The "ground_truth" manifest a synthetic scene names, resolved against its folder. Throws
/// InputError naming the manifest when it cannot be read or names none (not a synthetic scene).
std::filesystem::path groundTruthManifest(const std::filesystem::path& manifest_file);

/// Size and encoding of one loaded map, for the report.
struct MapRecord {
  std::string name;  ///< "depth", "normals", ...
  std::filesystem::path file;
  ImageFileInfo info;
};

/// A loaded, validated scene. Maps keep their own resolution; upsampling to the image
/// resolution is a pipeline stage, not a reading step. Optional maps are empty Mats.
struct Scene {
  SceneManifest manifest;
  cv::Mat image;         ///< CV_32FC3 RGB, sRGB-encoded, [0, 1]
  cv::Mat depth_m;       ///< CV_32F metres, 0 = invalid
  cv::Mat normals;       ///< CV_32FC3 unit, camera frame, (0,0,0) = invalid
  cv::Mat albedo;        ///< CV_32FC3 [0, 1]
  cv::Mat roughness;     ///< CV_32F [0, 1]
  cv::Mat instances;     ///< CV_32S Cityscapes instanceIds
  cv::Mat labels;        ///< CV_32S Cityscapes labelIds (given, or derived from instances)
  cv::Mat lights;        ///< CV_32S categoryId * 1000 + k, 0 = no light
  cv::Mat light_groups;  ///< CV_32S group id, 0 = none

  PinholeCamera camera;  ///< scaled to the image resolution
  bool camera_is_default = false;

  DepthReadStats depth_stats;
  std::optional<NormalReadStats> normal_stats;
  std::vector<MapRecord> maps;
  std::vector<std::string> warnings;

  int width() const { return image.cols; }
  int height() const { return image.rows; }
};

/// Reads the manifest and every map it names, validates them, scales the intrinsics to
/// the image resolution (ACDC intrinsics with a warning when none are given) and derives
/// labelIds from instanceIds when only the latter is given.
Scene loadScene(const std::filesystem::path& manifest_file);

/// What the input stage reports: map sizes and encodings, invalid and renormalised
/// counts, the camera, warnings.
StageReport describeScene(const Scene& scene);

/// Cityscapes class of an instanceIds value: id / 1000 for things (>= 1000), else id.
inline int cityscapesClassOfInstance(int instance_id) {
  return instance_id >= 1000 ? instance_id / 1000 : instance_id;
}

}  // namespace solo
