#pragma once
// The scene: the contract every stage reads. docs/scene-format.md is its authoritative
// description. A scene is a JSON manifest whose paths are relative to the manifest.

#include "solo/core/camera.h"
#include "solo/core/image_io.h"
#include "solo/core/report.h"

#include <opencv2/core.hpp>

#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace solo {

/// Light-source categories in a light map are 1..kLightCategoryCount (see the lighting
/// module for their names); a light map value is categoryId * 1000 + k.
constexpr int kLightCategoryCount = 15;

/// What a manifest's camera file is: a Cityscapes camera JSON ("camera": path or {"file"}) or a
/// KITTI calibration text file ("camera": {"kitti": path}).
enum class CameraFileFormat { Cityscapes, Kitti };

/// The manifest as written, paths resolved against the manifest's folder.
struct SceneManifest {
  std::filesystem::path file;  ///< the manifest itself
  std::filesystem::path image;
  std::filesystem::path depth;
  std::optional<double> depth_scale_m_per_unit;  ///< "scale"; required for integer depth files
  /// "disparity": true: the depth file is a Cityscapes disparity PNG, turned into metres with
  /// the camera file's baseline and fx (readCityscapesDisparityDepth).
  bool depth_is_disparity = false;
  std::optional<std::filesystem::path> normals, albedo, roughness;
  std::optional<std::filesystem::path> instances;     ///< Cityscapes instanceIds
  std::optional<std::filesystem::path> labels;        ///< Cityscapes labelIds
  std::optional<std::filesystem::path> lights;        ///< light-source instance ids
  std::optional<std::filesystem::path> light_groups;  ///< building-floor window groups
  std::optional<std::filesystem::path> ground_truth;  ///< the exact scene's manifest (`solo synth`)

  /// Camera: inline intrinsics (resolution 0 = "the image's"), or a camera file (Cityscapes
  /// camera JSON or KITTI calibration), with `camera` then holding only a resolution, if any.
  std::optional<PinholeCamera> camera;
  std::optional<std::filesystem::path> camera_file;
  CameraFileFormat camera_file_format = CameraFileFormat::Cityscapes;
  std::string kitti_matrix;  ///< "matrix" of a KITTI camera: "P_rect_02", "P2", ...; empty: the left colour camera

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

/// Horizontal field of view of the camera a scene without one gets: ACDC's, 2 atan(960 / 1780)
/// (56.7 degrees; fx = 1780 px at 1920 px wide).
inline const double kDefaultHorizontalFovRad = 2.0 * std::atan(960.0 / 1780.0);

/// The camera of a scene that names none, for a width x height image: square pixels with
/// kDefaultHorizontalFovRad, fx = fy = 1780 * (width / 1920) = (width / 2) / tan(fov / 2), and the
/// principal point at the image centre ((width - 1) / 2, (height - 1) / 2). A 1920x1080 image gets
/// ACDC's intrinsics exactly.
PinholeCamera defaultSceneCamera(int width, int height);

/// The stereo baseline of a Cityscapes camera JSON ("extrinsic"."baseline", metres); nullopt when
/// the file has none. Throws InputError naming the file when it cannot be read or is not JSON.
std::optional<double> readCityscapesBaseline(const std::filesystem::path& file);

/// Metric z-depth (CV_32F, metres, 0 = invalid) from a Cityscapes disparity map: a 16-bit PNG
/// whose value p > 0 stores the disparity (p - 1) / 256 px, so depth = baseline * fx / ((p - 1) /
/// 256). p = 0 (no disparity) is invalid and counted as zero; p = 1 (disparity 0, infinitely far)
/// is invalid and counted as inf. fx is in pixels of the disparity map's resolution.
cv::Mat readCityscapesDisparityDepth(const std::filesystem::path& file, double baseline_m, double fx_px,
                                     DepthReadStats* stats = nullptr, ImageFileInfo* info = nullptr);

/// The rectified camera of a KITTI calibration file: the 3x4 projection `matrix` (empty: the
/// left colour camera, `P_rect_02` of a raw-data calib_cam_to_cam.txt or `P2` of an
/// object-benchmark calib file): fx = P[0], cx = P[2], fy = P[5], cy = P[6]. Its resolution is
/// `S_rect_XX` of the same camera when the file has one, else left 0 ("the image's"). Throws
/// InputError naming the file when the matrix is missing or malformed.
PinholeCamera readKittiCalibration(const std::filesystem::path& file, const std::string& matrix = "");

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
/// the image resolution (defaultSceneCamera with a warning when none are given) and derives
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
