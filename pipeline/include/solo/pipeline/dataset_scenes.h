#pragma once
// Scene manifests for a dataset as it comes (docs/datasets.md): `solo scenes cityscapes|kitti|acdc
// ROOT -o DIR` walks the dataset's own folder layout and writes one manifest per frame, naming the
// dataset's files in place (no copies), and the list file `solo night --batch` reads. Each manifest's
// "name" is the frame's path in the dataset's layout, so `solo night --batch --layout DATASET` writes
// the night images in that layout too, with the day image's file name: the dataset's labels apply
// to them unchanged.

#include <solo/core/scene.h>

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace solo {

enum class Dataset { Cityscapes, Kitti, Acdc };

/// "cityscapes", "kitti", "acdc".
std::string datasetName(Dataset dataset);

/// The dataset of a name ("cityscapes", "kitti", "acdc"). Throws InputError naming `what` (the
/// option or argument it came from) for any other.
Dataset parseDataset(const std::string& name, const std::string& what);

/// Where the night images of a dataset go in its own layout: OUT/<night_folder>/<frame name>.png.
struct DatasetLayout {
  std::string night_folder;  ///< "leftImg8bit_night", "kitti_raw_night", "rgb_anon_night"
  int name_parts = 0;        ///< path components of a frame name
  std::string name_form;     ///< the frame name's form, for messages: "<split>/<city>/<stem>"
};
DatasetLayout datasetLayout(Dataset dataset);

/// The night image of a frame named `name` (a manifest's "name") relative to the batch's output
/// folder: <night_folder>/<name>.png. Throws InputError naming `manifest` when the name is not a
/// relative path of the layout's form (its number of parts, no "." or "..").
std::filesystem::path datasetNightImage(Dataset layout, const std::string& name, const std::filesystem::path& manifest);

struct DatasetScenesOptions {
  Dataset dataset = Dataset::Cityscapes;
  std::filesystem::path root;  ///< the dataset's top folder
  std::string split;           ///< one split ("train", "val", ...); empty: every split
  /// Another depth per frame (a monocular network's output, float metres): <folder>/<frame's
  /// folder>/<day image stem or frame id>.{npy,exr,pfm,tif,tiff}. Replaces the dataset's own.
  std::optional<std::filesystem::path> depth_folder;
  /// Normals per frame, found the same way (camera frame, docs/scene-format.md).
  std::optional<std::filesystem::path> normals_folder;
  std::filesystem::path output_folder;  ///< <name>.scene.json per frame and scenes.txt
};

/// One frame of a dataset: the files its manifest names (absolute paths).
struct DatasetFrame {
  std::string name;  ///< its path in the dataset layout, e.g. "train/aachen/aachen_000000_000019_leftImg8bit"
  std::filesystem::path image;
  std::filesystem::path depth;
  std::optional<double> depth_scale_m_per_unit;  ///< integer depth files (KITTI: 1/256)
  bool depth_is_disparity = false;               ///< a Cityscapes disparity (needs the camera file)
  std::optional<std::filesystem::path> normals, instances, labels;
  std::optional<std::filesystem::path> camera_file;
  CameraFileFormat camera_format = CameraFileFormat::Cityscapes;
};

/// A frame left out, and why (no depth, no camera for its disparity).
struct SkippedFrame {
  std::filesystem::path image;
  std::string reason;
};

/// What a walk of a dataset found.
struct DatasetWalk {
  std::vector<DatasetFrame> frames;   ///< sorted by name
  std::vector<SkippedFrame> skipped;  ///< sorted by image
  std::vector<std::string> splits;    ///< the splits walked
  std::vector<std::string> notes;     ///< what was left out on purpose (ACDC's night condition)
};

/// Every frame of the dataset's layout (docs/datasets.md) with its depth, camera, labels and, with
/// the options' folders, depth and normals from elsewhere. Throws InputError: the root missing, a
/// split that does not exist (naming those that do), no frame found (naming the pattern looked
/// for), frames found but none with a depth, ACDC without a depth folder.
DatasetWalk findDatasetFrames(const DatasetScenesOptions& options);

/// A frame's scene manifest (JSON text): "name", "comment", "image", "depth", "camera" and the
/// labels, normals when there are some.
std::string datasetFrameManifest(const DatasetFrame& frame, Dataset dataset);

struct DatasetScenesResult {
  DatasetWalk walk;
  std::filesystem::path list;                  ///< output_folder/scenes.txt
  std::vector<std::filesystem::path> manifests;  ///< output_folder/<name>.scene.json, one per frame
};

/// findDatasetFrames, then writes output_folder/<name>.scene.json for each frame and the list
/// output_folder/scenes.txt (their paths relative to it, one a line), each atomically.
DatasetScenesResult writeDatasetScenes(const DatasetScenesOptions& options);

}  // namespace solo
