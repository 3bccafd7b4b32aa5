#include <solo/pipeline/dataset_scenes.h>

#include <solo/core/atomic_file.h>
#include <solo/core/error.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace solo {

namespace {

// Float formats a network's depth or normals come in (metres, unit vectors).
const std::vector<std::string> kFloatExtensions = {".npy", ".exr", ".pfm", ".tif", ".tiff"};
// KITTI's depth-completion annotations store metres * 256 in 16-bit PNGs.
constexpr double kKittiDepthScale = 1.0 / 256.0;

bool endsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string withoutSuffix(const std::string& text, const std::string& suffix) {
  return endsWith(text, suffix) ? text.substr(0, text.size() - suffix.size()) : text;
}

bool isFile(const fs::path& file) {
  std::error_code ec;
  return fs::is_regular_file(file, ec);
}

bool isFolder(const fs::path& folder) {
  std::error_code ec;
  return fs::is_directory(folder, ec);
}

/// The names of a folder's subfolders, hidden ones left out, sorted; none when it is no folder.
std::vector<std::string> subfolders(const fs::path& folder) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (!name.empty() && name[0] != '.' && entry.is_directory(ec)) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

/// The names of a folder's files ending with one of `suffixes`, sorted.
std::vector<std::string> filesEndingWith(const fs::path& folder, const std::vector<std::string>& suffixes) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name[0] == '.' || !entry.is_regular_file(ec)) continue;
    for (const std::string& suffix : suffixes)
      if (endsWith(name, suffix)) {
        names.push_back(name);
        break;
      }
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::string joined(const std::vector<std::string>& items) {
  std::string text;
  for (const std::string& item : items) text += (text.empty() ? "" : ", ") + item;
  return text.empty() ? "none" : text;
}

std::optional<fs::path> existing(const fs::path& file) {
  if (isFile(file)) return file;
  return std::nullopt;
}

/// The splits to walk: the requested one, which must be among `available`, or all of them.
std::vector<std::string> chooseSplits(const std::vector<std::string>& available, const std::string& requested,
                                      const fs::path& where) {
  if (requested.empty()) return available;
  if (std::find(available.begin(), available.end(), requested) == available.end())
    throw InputError(where, "no split \"" + requested + "\" here; the splits are: " + joined(available));
  return {requested};
}

/// A frame's file in another folder laid out like the dataset: <folder>/<relative_folder>/<stem>.<ext>
/// for the first stem and float extension that exists; `looked_for` gets the pattern.
std::optional<fs::path> findInFolder(const fs::path& folder, const fs::path& relative_folder,
                                     const std::vector<std::string>& stems, std::string& looked_for) {
  looked_for.clear();
  for (const std::string& stem : stems) {
    looked_for += (looked_for.empty() ? "" : " or ") + (folder / relative_folder / stem).string() + ".{npy,exr,pfm,tif,tiff}";
    for (const std::string& extension : kFloatExtensions)
      if (auto file = existing(folder / relative_folder / (stem + extension))) return file;
  }
  return std::nullopt;
}

/// Walks one dataset's layout into a DatasetWalk.
class DatasetWalker {
 public:
  explicit DatasetWalker(const DatasetScenesOptions& options)
      : options_(options), root_(fs::absolute(options.root).lexically_normal()) {}

  DatasetWalk walk();

 private:
  void walkCityscapes();
  void addCityscapesFrame(const std::string& split, const std::string& city, const std::string& file);
  void walkKitti();
  void addKittiFrame(const std::string& date, const std::string& drive, const std::string& file,
                     const std::vector<std::string>& depth_splits);
  void walkAcdc();
  void addAcdcFrame(const fs::path& relative_folder, const std::string& file);
  /// Depth and normals from the options' folders; false (frame skipped) when the depth is missing.
  bool useOtherMaps(DatasetFrame& frame, const fs::path& relative_folder, const std::vector<std::string>& stems);
  void skip(const fs::path& image, const std::string& reason) { walk_.skipped.push_back({image, reason}); }
  /// The error for a walk that found nothing usable.
  void requireFrames(const std::string& pattern) const;

  const DatasetScenesOptions& options_;
  fs::path root_;
  DatasetWalk walk_;
};

DatasetWalk DatasetWalker::walk() {
  if (!isFolder(root_))
    throw InputError(options_.root, isFile(root_) ? "is a file, expected the dataset's top folder" : "not found");
  switch (options_.dataset) {
    case Dataset::Cityscapes:
      walkCityscapes();
      break;
    case Dataset::Kitti:
      walkKitti();
      break;
    case Dataset::Acdc:
      walkAcdc();
      break;
  }
  std::sort(walk_.frames.begin(), walk_.frames.end(),
            [](const DatasetFrame& a, const DatasetFrame& b) { return a.name < b.name; });
  std::sort(walk_.skipped.begin(), walk_.skipped.end(),
            [](const SkippedFrame& a, const SkippedFrame& b) { return a.image < b.image; });
  return walk_;
}

void DatasetWalker::requireFrames(const std::string& pattern) const {
  if (walk_.frames.empty() && walk_.skipped.empty())
    throw InputError(options_.root, "no frame found: looked for " + pattern);
  if (walk_.frames.empty())
    throw InputError(options_.root, std::to_string(walk_.skipped.size()) + " frames found but none can be used: " +
                                        walk_.skipped.front().image.filename().string() + ": " +
                                        walk_.skipped.front().reason +
                                        (options_.depth_folder ? "" : " (--depth DIR gives another depth source)"));
}

bool DatasetWalker::useOtherMaps(DatasetFrame& frame, const fs::path& relative_folder,
                                 const std::vector<std::string>& stems) {
  std::string looked_for;
  if (options_.depth_folder) {
    const auto depth = findInFolder(fs::absolute(*options_.depth_folder), relative_folder, stems, looked_for);
    if (!depth) {
      skip(frame.image, "no depth in --depth " + options_.depth_folder->string() + " (looked for " + looked_for + ")");
      return false;
    }
    frame.depth = depth->lexically_normal();
    frame.depth_scale_m_per_unit.reset();
    frame.depth_is_disparity = false;
  }
  if (options_.normals_folder)
    if (const auto normals = findInFolder(fs::absolute(*options_.normals_folder), relative_folder, stems, looked_for))
      frame.normals = normals->lexically_normal();
  return true;
}

// Cityscapes: leftImg8bit/<split>/<city>/<city>_<seq>_<frame>_leftImg8bit.png, with disparity/,
// camera/ and gtFine/ beside it under the same <split>/<city>.
void DatasetWalker::walkCityscapes() {
  const fs::path images = root_ / "leftImg8bit";
  const std::string pattern = (images / "<split>/<city>/*_leftImg8bit.png").string();
  if (!isFolder(images)) throw InputError(options_.root, "no frame found: looked for " + pattern);
  walk_.splits = chooseSplits(subfolders(images), options_.split, images);
  for (const std::string& split : walk_.splits)
    for (const std::string& city : subfolders(images / split))
      for (const std::string& file : filesEndingWith(images / split / city, {"_leftImg8bit.png"}))
        addCityscapesFrame(split, city, file);
  requireFrames(pattern);
}

void DatasetWalker::addCityscapesFrame(const std::string& split, const std::string& city, const std::string& file) {
  const fs::path relative_folder = fs::path(split) / city;
  const std::string stem = fs::path(file).stem().string();
  const std::string id = withoutSuffix(stem, "_leftImg8bit");
  DatasetFrame frame;
  frame.name = (relative_folder / stem).generic_string();
  frame.image = root_ / "leftImg8bit" / relative_folder / file;
  frame.camera_file = existing(root_ / "camera" / relative_folder / (id + "_camera.json"));
  frame.instances = existing(root_ / "gtFine" / relative_folder / (id + "_gtFine_instanceIds.png"));
  frame.labels = existing(root_ / "gtFine" / relative_folder / (id + "_gtFine_labelIds.png"));
  if (!options_.depth_folder) {
    const fs::path disparity = root_ / "disparity" / relative_folder / (id + "_disparity.png");
    if (!isFile(disparity)) return skip(frame.image, "no disparity (looked for " + disparity.string() + ")");
    if (!frame.camera_file)
      return skip(frame.image, "no camera file for its disparity's baseline (looked for " +
                                   (root_ / "camera" / relative_folder / (id + "_camera.json")).string() + ")");
    frame.depth = disparity;
    frame.depth_is_disparity = true;
  }
  if (useOtherMaps(frame, relative_folder, {stem, id})) walk_.frames.push_back(frame);
}

// KITTI raw data, <date>/calib_cam_to_cam.txt and <date>/<drive>/image_02/data/<frame>.png, with
// the depth-completion annotations either merged into the drive folders
// (<date>/<drive>/proj_depth/groundtruth/image_02/<frame>.png) or unpacked beside the dates as
// <split>/<drive>/proj_depth/groundtruth/image_02/<frame>.png (split: train, val).
void DatasetWalker::walkKitti() {
  const std::string pattern = (root_ / "<date>/<drive>/image_02/data/*.png").string() + " beside " +
                              (root_ / "<date>/calib_cam_to_cam.txt").string();
  std::vector<std::string> depth_splits;
  for (const std::string& folder : subfolders(root_)) {
    if (isFile(root_ / folder / "calib_cam_to_cam.txt")) continue;  // a date of the raw data
    bool annotated = false;
    for (const std::string& drive : subfolders(root_ / folder)) annotated |= isFolder(root_ / folder / drive / "proj_depth");
    if (annotated) depth_splits.push_back(folder);
  }
  if (!options_.split.empty() && depth_splits.empty())
    throw InputError(options_.root, "no split \"" + options_.split + "\": no depth-completion split folders here (" +
                                        (root_ / "<split>/<drive>/proj_depth").string() + ")");
  walk_.splits = chooseSplits(depth_splits, options_.split, root_);
  for (const std::string& date : subfolders(root_)) {
    if (!isFile(root_ / date / "calib_cam_to_cam.txt")) continue;
    for (const std::string& drive : subfolders(root_ / date)) {
      if (!options_.split.empty() && !isFolder(root_ / options_.split / drive)) continue;
      for (const std::string& file : filesEndingWith(root_ / date / drive / "image_02" / "data", {".png"}))
        addKittiFrame(date, drive, file, walk_.splits);
    }
  }
  requireFrames(pattern);
}

void DatasetWalker::addKittiFrame(const std::string& date, const std::string& drive, const std::string& file,
                                  const std::vector<std::string>& depth_splits) {
  const fs::path relative_folder = fs::path(date) / drive / "image_02" / "data";
  const std::string stem = fs::path(file).stem().string();
  DatasetFrame frame;
  frame.name = (relative_folder / stem).generic_string();
  frame.image = root_ / relative_folder / file;
  frame.camera_file = root_ / date / "calib_cam_to_cam.txt";
  frame.camera_format = CameraFileFormat::Kitti;
  if (!options_.depth_folder) {
    const fs::path annotation = fs::path("proj_depth") / "groundtruth" / "image_02" / file;
    std::vector<fs::path> candidates;
    if (options_.split.empty()) candidates.push_back(root_ / date / drive / annotation);
    for (const std::string& split : depth_splits) candidates.push_back(root_ / split / drive / annotation);
    for (const fs::path& candidate : candidates)
      if (isFile(candidate)) {
        frame.depth = candidate;
        break;
      }
    if (frame.depth.empty())
      return skip(frame.image, "no depth annotation (looked for " + candidates.front().string() +
                                   (candidates.size() > 1 ? " and in the split folders" : "") + ")");
    frame.depth_scale_m_per_unit = kKittiDepthScale;
  }
  if (useOtherMaps(frame, relative_folder, {stem})) walk_.frames.push_back(frame);
}

// ACDC: rgb_anon/<condition>/<split>/<sequence>/<sequence>_frame_<n>_rgb_anon.png (the _ref splits:
// *_rgb_ref_anon.png), labels in gt/ under the same path. Its night condition is already night.
void DatasetWalker::walkAcdc() {
  const fs::path images = root_ / "rgb_anon";
  const std::string pattern = (images / "<condition>/<split>/<sequence>/*_rgb_anon.png").string();
  if (!isFolder(images)) throw InputError(options_.root, "no frame found: looked for " + pattern);
  if (!options_.depth_folder)
    throw InputError("--depth", "ACDC has no depth maps: give --depth DIR with one depth file per frame "
                                "(DIR/<condition>/<split>/<sequence>/<stem>.npy, .exr or .pfm; docs/datasets.md)");
  std::vector<std::string> conditions;
  std::set<std::string> splits;
  for (const std::string& condition : subfolders(images)) {
    if (condition == "night") {
      walk_.notes.push_back("condition \"night\" left out: its images are night images already");
      continue;
    }
    conditions.push_back(condition);
    for (const std::string& split : subfolders(images / condition)) splits.insert(split);
  }
  walk_.splits = chooseSplits({splits.begin(), splits.end()}, options_.split, images);
  for (const std::string& condition : conditions)
    for (const std::string& split : walk_.splits)
      for (const std::string& sequence : subfolders(images / condition / split))
        for (const std::string& file :
             filesEndingWith(images / condition / split / sequence, {"_rgb_anon.png", "_rgb_ref_anon.png"}))
          addAcdcFrame(fs::path(condition) / split / sequence, file);
  requireFrames(pattern);
}

void DatasetWalker::addAcdcFrame(const fs::path& relative_folder, const std::string& file) {
  const std::string stem = fs::path(file).stem().string();
  const std::string id = withoutSuffix(withoutSuffix(stem, "_rgb_anon"), "_rgb_ref_anon");
  DatasetFrame frame;
  frame.name = (relative_folder / stem).generic_string();
  frame.image = root_ / "rgb_anon" / relative_folder / file;
  frame.labels = existing(root_ / "gt" / relative_folder / (id + "_gt_labelIds.png"));
  if (useOtherMaps(frame, relative_folder, {stem, id})) walk_.frames.push_back(frame);
}

const char* datasetTitle(Dataset dataset) {
  switch (dataset) {
    case Dataset::Cityscapes:
      return "Cityscapes";
    case Dataset::Kitti:
      return "KITTI";
    case Dataset::Acdc:
      return "ACDC";
  }
  return "";
}

}  // namespace

std::string datasetName(Dataset dataset) {
  switch (dataset) {
    case Dataset::Cityscapes:
      return "cityscapes";
    case Dataset::Kitti:
      return "kitti";
    case Dataset::Acdc:
      return "acdc";
  }
  return "";
}

Dataset parseDataset(const std::string& name, const std::string& what) {
  for (const Dataset d : {Dataset::Cityscapes, Dataset::Kitti, Dataset::Acdc})
    if (name == datasetName(d)) return d;
  throw InputError(what, "unknown dataset \"" + name + "\": expected cityscapes, kitti or acdc");
}

DatasetLayout datasetLayout(Dataset dataset) {
  switch (dataset) {
    case Dataset::Cityscapes:
      return {"leftImg8bit_night", 3, "<split>/<city>/<city>_<seq>_<frame>_leftImg8bit"};
    case Dataset::Kitti:
      return {"kitti_raw_night", 5, "<date>/<drive>/image_02/data/<frame>"};
    case Dataset::Acdc:
      return {"rgb_anon_night", 4, "<condition>/<split>/<sequence>/<stem>"};
  }
  return {};
}

fs::path datasetNightImage(Dataset layout, const std::string& name, const fs::path& manifest) {
  const DatasetLayout l = datasetLayout(layout);
  const fs::path relative(name);
  int parts = 0;
  bool safe = !name.empty() && relative.is_relative() && !relative.has_root_name();
  for (const fs::path& part : relative) {
    ++parts;
    safe &= !part.empty() && part != "." && part != "..";
  }
  if (!safe || parts != l.name_parts)
    throw InputError(manifest, "--layout " + datasetName(layout) + ": \"name\" must be the frame's path " + l.name_form +
                                   " (solo scenes " + datasetName(layout) + " writes it), found \"" + name + "\"");
  return fs::path(l.night_folder) / (name + ".png");
}

DatasetWalk findDatasetFrames(const DatasetScenesOptions& options) { return DatasetWalker(options).walk(); }

std::string datasetFrameManifest(const DatasetFrame& frame, Dataset dataset) {
  nlohmann::ordered_json j;
  j["name"] = frame.name;
  j["comment"] = std::string(datasetTitle(dataset)) + " frame, written by `solo scenes " + datasetName(dataset) + "`";
  j["image"] = frame.image.string();
  if (frame.depth_is_disparity)
    j["depth"] = {{"file", frame.depth.string()}, {"disparity", true}};
  else if (frame.depth_scale_m_per_unit)
    j["depth"] = {{"file", frame.depth.string()}, {"scale", *frame.depth_scale_m_per_unit}};
  else
    j["depth"] = frame.depth.string();
  if (frame.camera_file) {
    if (frame.camera_format == CameraFileFormat::Kitti)
      j["camera"] = {{"kitti", frame.camera_file->string()}};
    else
      j["camera"] = frame.camera_file->string();
  }
  if (frame.normals) j["normals"] = frame.normals->string();
  if (frame.instances) j["instances"] = frame.instances->string();
  if (frame.labels) j["labels"] = frame.labels->string();
  return j.dump(2) + "\n";
}

DatasetScenesResult writeDatasetScenes(const DatasetScenesOptions& options) {
  DatasetScenesResult result;
  result.walk = findDatasetFrames(options);
  const fs::path out = fs::absolute(options.output_folder).lexically_normal();
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw InputError(options.output_folder, "exists and is not a folder (-o is the folder for the manifests)");
  std::ostringstream list;
  list << "# solo scenes " << datasetName(options.dataset) << " " << fs::absolute(options.root).string() << ": "
       << result.walk.frames.size() << " frames\n";
  for (const DatasetFrame& frame : result.walk.frames) {
    const fs::path relative = frame.name + ".scene.json";
    const fs::path manifest = out / relative;
    fs::create_directories(manifest.parent_path(), ec);
    if (ec) throw InputError(manifest.parent_path(), "cannot create the folder: " + ec.message());
    writeTextAtomically(manifest, datasetFrameManifest(frame, options.dataset));
    result.manifests.push_back(manifest);
    list << relative.generic_string() << "\n";
  }
  result.list = out / "scenes.txt";
  writeTextAtomically(result.list, list.str());
  return result;
}

}  // namespace solo
