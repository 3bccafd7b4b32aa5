// A synthetic street written as a scene folder (scene_folder.h).

#include <solo/synth/scene_folder.h>

#include <solo/core/atomic_file.h>
#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/output_path.h>
#include <solo/core/version.h>
#include <solo/geometry/prediction_noise.h>
#include <solo/geometry/triangle_mesh.h>
#include <solo/synth/day_scene.h>
#include <solo/synth/scene_raster.h>
#include <solo/synth/street_scene.h>

#include <nlohmann/json.hpp>

#include <fstream>
#include <optional>
#include <set>
#include <stdexcept>
#include <unistd.h>

namespace fs = std::filesystem;
using nlohmann::ordered_json;

namespace solo {
namespace {

cv::Mat toUint16(const cv::Mat& unit_range) {
  cv::Mat out;
  unit_range.convertTo(out, CV_MAKETYPE(CV_16U, unit_range.channels()), 65535.0);
  return out;
}

cv::Mat toUint16Ids(const cv::Mat& ids) {
  double lo = 0, hi = 0;
  cv::minMaxLoc(ids, &lo, &hi);
  CV_Assert(lo >= 0 && hi <= 65535);
  cv::Mat out;
  ids.convertTo(out, CV_16U);
  return out;
}

ordered_json cameraJson(const PinholeCamera& c) {
  return {{"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy}, {"width", c.width}, {"height", c.height}};
}

void writeJson(const fs::path& file, const ordered_json& j) { writeTextAtomically(file, j.dump(2) + "\n"); }

// Every file and folder a `solo synth` folder holds, relative to it.
const std::set<std::string> kSynthEntries = {"day.png",          "lightIds.png",       "groups.png",
                                             "scene.json",       "synth.json",         "gt",
                                             "gt/depth.exr",     "gt/normals.png",     "gt/albedo.png",
                                             "gt/roughness.png", "gt/labelIds.png",    "gt/instanceIds.png",
                                             "gt/mesh.ply",      "gt/scene.json",      "est",
                                             "est/depth.exr",    "est/normals.png",    "est/albedo.png",
                                             "est/labelIds.png", "est/instanceIds.png", "est/disparity.png",
                                             "est/camera.json"};

// True when `folder`/synth.json is the record `solo synth` writes ("generator": "solo synth ...").
bool holdsSynthRecord(const fs::path& folder) {
  const fs::path record = folder / "synth.json";
  std::error_code ec;
  if (!fs::is_regular_file(record, ec) || fs::file_size(record, ec) > (1u << 20)) return false;
  std::ifstream in(record);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  return j.is_object() && j.contains("generator") && j["generator"].is_string() &&
         j["generator"].get<std::string>().rfind("solo synth", 0) == 0;
}

// --force replaces only a folder `solo synth` made and that holds nothing else: throws otherwise.
void requireReplaceableSynthFolder(const fs::path& folder) {
  refuseWorkingFolderOrParent(folder, "-o");
  const std::string keep = ": not replaced, even with --force (remove it yourself or choose another folder)";
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(folder, ec);
  if (status.type() != fs::file_type::directory) throw InputError(folder, "exists and is not a folder" + keep);
  if (fs::is_empty(folder, ec)) return;
  if (!holdsSynthRecord(folder))
    throw InputError(folder, "is not a folder solo synth wrote (it lacks synth.json from solo synth)" + keep);
  for (auto it = fs::recursive_directory_iterator(folder); it != fs::recursive_directory_iterator(); ++it) {
    const std::string relative = it->path().lexically_relative(folder).generic_string();
    const bool expected_type = relative == "gt" || relative == "est" ? it->is_directory() && !it->is_symlink()
                                                                     : it->is_regular_file() && !it->is_symlink();
    if (!kSynthEntries.count(relative) || !expected_type)
      throw InputError(folder, "holds \"" + relative + "\", which solo synth does not write" + keep);
  }
}

// Moves the finished `staging` folder onto `target`, replacing a previous one only once the new
// one is in place: a failure leaves the previous folder as it was.
void moveFolderIntoPlace(const fs::path& staging, const fs::path& target) {
  const BlockedTerminationSignals unsplit;  // a signal waits for the swap to end
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(target, ec))) {
    fs::rename(staging, target);
    return;
  }
  const fs::path previous = fs::path(staging).concat(".previous");
  fs::rename(target, previous);
  fs::rename(staging, target, ec);
  if (ec) {
    std::error_code ignore;
    fs::rename(previous, target, ignore);
    throw InputError(target, "cannot move the finished folder into place: " + ec.message());
  }
  fs::remove_all(previous, ec);
}

// Checks the options and the folder: the street's options and the folder to write (without
// trailing separators). Throws InputError naming the option or the folder.
std::pair<StreetSceneOptions, fs::path> checkedOptions(const fs::path& folder, const SyntheticSceneOptions& o) {
  StreetSceneOptions scene_options;
  scene_options.seed = o.seed;
  scene_options.width = o.width;
  scene_options.height = o.height;
  try {
    scene_options.variant = streetVariantFromName(o.variant);
  } catch (const std::invalid_argument& e) {
    throw InputError("--variant", e.what());
  }
  if (o.width < 16 || o.height < 16 || o.width > 8192 || o.height > 8192)
    throw InputError("--size", "image size must be between 16 and 8192 pixels per side");
  if (o.day_render != "raster" && o.day_render != "path")
    throw InputError("--day-render", "expected raster or path, got \"" + o.day_render + "\"");
  if (o.day_samples < 0 || o.day_samples > 4096)
    throw InputError("--day-samples", "expected 0 (adaptive) to 4096, got " + std::to_string(o.day_samples));
  if (!o.depth_source.empty()) {
    try {
      depthSourceFromName(o.depth_source);
    } catch (const std::invalid_argument& e) {
      throw InputError("--depth-source", e.what());
    }
  }
  const fs::path output = withoutTrailingSeparators(folder);
  if (output.empty()) throw InputError("-o", "the output folder is an empty path");
  std::error_code exists_ec;
  if (fs::exists(fs::symlink_status(output, exists_ec))) {
    if (!o.force) throw InputError(output, "already exists (pass --force to replace a folder solo synth wrote)");
    requireReplaceableSynthFolder(output);
  }
  return {scene_options, output};
}

StageReport& addStage(RunReport& report, const std::string& name, double seconds) {
  report.stages.push_back({});
  report.stages.back().name = name;
  report.stages.back().seconds = seconds;
  return report.stages.back();
}

/// A simulated sensor's depth for est/depth.exr, with what synth.json records of it.
struct SensorDepth {
  cv::Mat depth_m;        ///< CV_32F full resolution, 0 = invalid
  cv::Mat disparity_png;  ///< CV_16U Cityscapes disparity (stereo only)
  ordered_json record;    ///< synth.json "depth_source"
};

/// Everything the folder holds, made in memory.
struct SyntheticStreet {
  StreetScene scene;
  TriangleMesh mesh;
  GroundTruthMaps truth;
  cv::Mat day;  ///< linear sRGB
  PredictionNoiseOptions noise;
  SimulatedPredictions est;
  std::optional<SensorDepth> sensor;  ///< set when --depth-source names one
};

// The day image, rastered or path traced, with its stage in `report`.
cv::Mat dayImage(const SyntheticStreet& street, const SyntheticSceneOptions& o, RunReport& report) {
  Stopwatch clock;
  if (o.day_render == "path") {
    DayRenderOptions day_options;
    day_options.seed = o.seed;
    day_options.progress = o.progress;
    if (o.day_samples > 0) day_options.min_samples = day_options.max_samples = o.day_samples;
    DaylightRender traced = renderDaylightPathTraced(street.scene, day_options);
    traced.report.seconds = clock.seconds();
    traced.report.notes.push_back("day image path traced: sun and sky gradient, NEE + MIS (--day-render path)");
    traced.report.metrics.insert(traced.report.metrics.begin(), Metric{"day_render", std::string("path"), ""});
    report.stages.push_back(std::move(traced.report));
    return std::move(traced.linear_rgb);
  }
  cv::Mat day = renderDaylight(street.scene, street.truth);
  addStage(report, "daylight", clock.seconds())
      .add("day_render", std::string("raster"))
      .add("samples_per_pixel", std::int64_t{1})
      .notes.push_back(
      "day image rastered: sun with one shadow ray, sky as an ambient term (--day-render path traces it)");
  return day;
}

// synth.json's record of the stereo sensor: its options, search range, reach and holes.
ordered_json stereoRecord(const StereoSensorOptions& o, const StereoDepth& stereo) {
  const StereoHoleCounts& h = stereo.holes;
  return {{"options",
           {{"baseline_m", o.baseline_m},
            {"disparity_noise_px", o.disparity_noise_px},
            {"disparity_step_px", o.disparity_step_px},
            {"min_disparity_px", o.min_disparity_px},
            {"max_disparity_width_share", o.max_disparity_width_share},
            {"texture_window_px", o.texture_window_px},
            {"texture_min_std", o.texture_min_std},
            {"texture_reach_width_share", o.texture_reach_width_share}}},
          {"max_disparity_px", stereo.max_disparity_px},
          {"texture_reach_px", stereo.texture_reach_px},
          {"holes",
           {{"no_surface", h.no_surface},
            {"left_border", h.left_border},
            {"too_close", h.too_close},
            {"occluded", h.occluded},
            {"textureless", h.textureless},
            {"too_far", h.too_far}}}};
}

// synth.json's record of the LiDAR: its options and returns.
ordered_json lidarRecord(const LidarSensorOptions& o, const LidarDepth& lidar) {
  return {{"options",
           {{"beams", o.beams},
            {"min_elevation_deg", o.min_elevation_deg},
            {"max_elevation_deg", o.max_elevation_deg},
            {"azimuth_step_deg", o.azimuth_step_deg},
            {"range_noise_m", o.range_noise_m},
            {"max_range_m", o.max_range_m}}},
          {"returns", lidar.returns}};
}

// synth.json's record of the monocular depth: its options and what it drew.
ordered_json monoRecord(const MonoSensorOptions& o, const MonoDepth& mono) {
  return {{"options",
           {{"edge_bleed_px", o.edge_bleed_px},
            {"edge_relative_jump", o.edge_relative_jump},
            {"scale_error_max", o.scale_error_max},
            {"inverse_shift_max_per_m", o.inverse_shift_max_per_m},
            {"max_depth_m", o.max_depth_m},
            {"noise_relative", o.noise_relative},
            {"noise_growth_m", o.noise_growth_m}}},
          {"scale_drawn", mono.scale},
          {"inverse_shift_drawn_per_m", mono.inverse_shift_per_m}};
}

// The day image as a camera would store it: sRGB-encoded, in [0, 1].
cv::Mat daySrgb(const cv::Mat& linear_rgb) {
  cv::Mat srgb;
  srgbEncode8(linear_rgb).convertTo(srgb, CV_32FC3, 1.0 / 255);
  return srgb;
}

// The depth of the sensor `source`, with its record for synth.json.
SensorDepth simulateSensor(DepthSource source, const SyntheticStreet& street, const SyntheticSceneOptions& o) {
  const cv::Mat& exact = street.truth.depth_m;
  const DepthSensorOptions& sensors = o.depth_sensors;
  SensorDepth sensor;
  ordered_json details;
  if (source == DepthSource::Exact) {
    sensor.depth_m = exact.clone();
  } else if (source == DepthSource::Stereo) {
    StereoDepth stereo = simulateStereoDepth(exact, street.scene.camera, daySrgb(street.day), o.seed, sensors.stereo);
    sensor.depth_m = stereo.depth_m;
    sensor.disparity_png = cityscapesDisparityPng(stereo.disparity_px);
    details = stereoRecord(sensors.stereo, stereo);
  } else if (source == DepthSource::Lidar) {
    LidarDepth lidar = simulateLidarDepth(exact, street.scene.camera, o.seed, sensors.lidar);
    sensor.depth_m = lidar.depth_m;
    details = lidarRecord(sensors.lidar, lidar);
  } else {
    MonoDepth mono = simulateMonoDepth(exact, o.seed, sensors.mono);
    sensor.depth_m = mono.depth_m;
    details = monoRecord(sensors.mono, mono);
  }
  const DepthSensorAgreement agreement = compareWithExactDepth(sensor.depth_m, exact);
  sensor.record = {{"sensor", depthSourceName(source)}, {"file", "est/depth.exr"},
                   {"valid_share", agreement.valid_share}, {"abs_rel", agreement.abs_rel}};
  if (source == DepthSource::Stereo) {
    sensor.record["disparity"] = "est/disparity.png";
    sensor.record["camera"] = "est/camera.json";
  }
  for (auto& [key, value] : details.items()) sensor.record[key] = value;
  return sensor;
}

// The street, its exact maps, its day image and the simulated predictions; a stage each in `report`.
SyntheticStreet makeSyntheticStreet(const StreetSceneOptions& scene_options, const SyntheticSceneOptions& o,
                           RunReport& report) {
  SyntheticStreet street;
  Stopwatch clock;
  street.scene = buildStreetScene(scene_options);
  street.mesh = streetSceneMesh(street.scene);
  addStage(report, "layout", clock.seconds())
      .add("boxes", static_cast<std::int64_t>(street.scene.parts.size()))
      .add("triangles", static_cast<std::int64_t>(street.mesh.faces.size()));

  clock = Stopwatch();
  street.truth = rasterizeGroundTruth(street.scene);
  std::int64_t sky = cv::countNonZero(street.truth.depth_m <= 0);
  std::int64_t light_pixels = cv::countNonZero(street.truth.lights > 0);
  addStage(report, "ground_truth", clock.seconds()).add("sky_pixels", sky).add("light_pixels", light_pixels);

  street.day = dayImage(street, o, report);

  clock = Stopwatch();
  const GroundTruthMaps& truth = street.truth;
  street.est = simulatePredictions(truth.depth_m, truth.normals, truth.albedo, truth.labels, truth.instances,
                                   street.noise, o.seed);
  addStage(report, "predictions", clock.seconds()).add("depth_scale_bias", street.est.depth_scale_bias);

  if (!o.depth_source.empty()) {
    clock = Stopwatch();
    street.sensor = simulateSensor(depthSourceFromName(o.depth_source), street, o);
    addStage(report, "depth_sensor", clock.seconds())
        .add("valid_share", street.sensor->record["valid_share"].get<double>())
        .add("abs_rel", street.sensor->record["abs_rel"].get<double>())
        .notes.push_back("est/depth.exr: the " + o.depth_source + " sensor's depth (--depth-source)");
  }
  return street;
}

// The image files and the mesh: day image, light maps, gt/ and est/.
void writeMaps(const fs::path& staging, const SyntheticStreet& street) {
  const GroundTruthMaps& truth = street.truth;
  const SimulatedPredictions& est = street.est;
  writeImage(staging / "day.png", srgbEncode8(street.day));
  writeImage(staging / "lightIds.png", toUint16Ids(truth.lights));
  writeImage(staging / "groups.png", toUint16Ids(truth.light_groups));

  writeDepth(staging / "gt/depth.exr", truth.depth_m);
  writeNormals(staging / "gt/normals.png", truth.normals);
  writeImage(staging / "gt/albedo.png", toUint16(truth.albedo));
  writeImage(staging / "gt/roughness.png", toUint16(truth.roughness));
  writeImage(staging / "gt/labelIds.png", toUint16Ids(truth.labels));
  writeImage(staging / "gt/instanceIds.png", toUint16Ids(truth.instances));
  writeMesh(staging / "gt/mesh.ply", street.mesh);

  writeDepth(staging / "est/depth.exr", street.sensor ? street.sensor->depth_m : est.depth_m);
  if (street.sensor && !street.sensor->disparity_png.empty())
    writeImage(staging / "est/disparity.png", street.sensor->disparity_png);
  writeNormals(staging / "est/normals.png", est.normals);
  writeImage(staging / "est/albedo.png", toUint16(est.albedo));
  writeImage(staging / "est/labelIds.png", toUint16Ids(est.labels));
  writeImage(staging / "est/instanceIds.png", toUint16Ids(est.instances));
}

// The manifests scene.json (estimated inputs) and gt/scene.json (ground truth).
void writeManifests(const fs::path& staging, const SyntheticStreet& street, const SyntheticSceneOptions& o) {
  const ordered_json camera = cameraJson(street.scene.camera);
  ordered_json estimated = {{"name", std::string("synthetic street, variant ") + o.variant + ", seed " +
                                         std::to_string(o.seed)},
                            {"image", "day.png"},
                            {"depth", "est/depth.exr"},
                            {"normals", "est/normals.png"},
                            {"albedo", "est/albedo.png"},
                            {"roughness", "gt/roughness.png"},
                            {"instances", "est/instanceIds.png"},
                            {"labels", "est/labelIds.png"},
                            {"lights", "lightIds.png"},
                            {"light_groups", "groups.png"},
                            {"camera", camera},
                            {"ground_truth", "gt/scene.json"}};
  writeJson(staging / "scene.json", estimated);
  ordered_json exact = {{"name", "ground truth of " + estimated["name"].get<std::string>()},
                        {"image", "../day.png"},
                        {"depth", "depth.exr"},
                        {"normals", "normals.png"},
                        {"albedo", "albedo.png"},
                        {"roughness", "roughness.png"},
                        {"instances", "instanceIds.png"},
                        {"labels", "labelIds.png"},
                        {"lights", "../lightIds.png"},
                        {"light_groups", "../groups.png"},
                        {"camera", camera}};
  writeJson(staging / "gt/scene.json", exact);
}

// est/camera.json: the stereo camera as Cityscapes' camera/*.json states it.
void writeCityscapesCamera(const fs::path& file, const PinholeCamera& c, double baseline_m) {
  const ordered_json camera = {{"extrinsic", {{"baseline", baseline_m}}},
                               {"intrinsic", {{"fx", c.fx}, {"fy", c.fy}, {"u0", c.cx}, {"v0", c.cy}}}};
  writeJson(file, camera);
}

// synth.json: the generator, the options, the mesh and the perturbations of the predictions.
void writeSynthRecord(const fs::path& staging, const SyntheticStreet& street, const SyntheticSceneOptions& o) {
  const StreetScene& scene = street.scene;
  const PredictionNoiseOptions& noise = street.noise;
  ordered_json record = {
      {"generator", "solo synth " + soloVersion()},
      {"seed", o.seed},
      {"variant", o.variant},
      {"day_render", o.day_render},
      {"day_samples", o.day_samples},
      {"width", o.width},
      {"height", o.height},
      {"camera", cameraJson(scene.camera)},
      {"sun_direction", {scene.sun_direction.x(), scene.sun_direction.y(), scene.sun_direction.z()}},
      {"mesh", {{"file", "gt/mesh.ply"}, {"boxes", scene.parts.size()}, {"triangles", street.mesh.faces.size()}}},
      {"perturbations",
       {{"depth_downscale", noise.depth_downscale},
        {"edge_bleed_px", noise.edge_bleed_px},
        {"edge_relative_jump", noise.edge_relative_jump},
        {"depth_bias_max", noise.depth_bias_max},
        {"depth_scale_bias_drawn", street.est.depth_scale_bias},
        {"depth_noise_relative", noise.depth_noise_relative},
        {"depth_noise_growth_m", noise.depth_noise_growth_m},
        {"normal_downscale", noise.normal_downscale},
        {"normal_blur_px", noise.normal_blur_px},
        {"normal_noise_deg", noise.normal_noise_deg},
        {"albedo_downscale", noise.albedo_downscale},
        {"label_jitter_px", noise.label_jitter_px},
        {"label_jitter_scale_px", noise.label_jitter_scale_px}}}};
  if (street.sensor) record["depth_source"] = street.sensor->record;
  writeJson(staging / "synth.json", record);
}

// Writes the folder into a hidden sibling first, renamed onto `output` at the end.
void writeFolder(const fs::path& output, const SyntheticStreet& street, const SyntheticSceneOptions& o) {
  const fs::path parent = output.parent_path().empty() ? fs::path(".") : output.parent_path();
  const fs::path staging = parent / ("." + output.filename().string() + ".tmp" + std::to_string(::getpid()));
  fs::remove_all(staging);
  const LiveTemporaryFolder removed_on_signal(staging);
  fs::create_directories(staging / "gt");
  fs::create_directories(staging / "est");
  try {
    writeMaps(staging, street);
    writeManifests(staging, street, o);
    if (street.sensor && !street.sensor->disparity_png.empty())
      writeCityscapesCamera(staging / "est/camera.json", street.scene.camera, o.depth_sensors.stereo.baseline_m);
    writeSynthRecord(staging, street, o);
    std::error_code exists_ec;
    if (fs::exists(fs::symlink_status(output, exists_ec))) requireReplaceableSynthFolder(output);  // still so
    moveFolderIntoPlace(staging, output);
  } catch (...) {
    std::error_code ignore;
    fs::remove_all(staging, ignore);
    throw;
  }
}

}  // namespace

SyntheticSceneResult writeSyntheticScene(const fs::path& folder, const SyntheticSceneOptions& o) {
  Stopwatch total;
  const auto [scene_options, output] = checkedOptions(folder, o);
  SyntheticSceneResult result;
  result.folder = output;
  result.manifest = output / "scene.json";
  RunReport& report = result.report;
  report.command = "synth";
  report.seed = o.seed;
  report.scene = output.string();

  const SyntheticStreet street = makeSyntheticStreet(scene_options, o, report);
  Stopwatch clock;
  writeFolder(output, street, o);
  addStage(report, "write", clock.seconds());
  report.total_seconds = total.seconds();
  return result;
}

}  // namespace solo
