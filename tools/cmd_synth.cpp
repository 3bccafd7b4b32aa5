#include "commands.h"

#include <solo/geometry/atomic_file.h>
#include <solo/geometry/error.h>
#include <solo/geometry/image_io.h>
#include <solo/geometry/prediction_noise.h>
#include <solo/geometry/report.h>
#include <solo/geometry/triangle_mesh.h>
#include <solo/geometry/version.h>
#include <solo/render/day_scene.h>
#include <solo/render/scene_raster.h>
#include <solo/render/street_scene.h>

#include <nlohmann/json.hpp>

#include <iostream>
#include <unistd.h>

namespace fs = std::filesystem;
using nlohmann::ordered_json;

namespace solo::tools {
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

}  // namespace

int runSynth(const SynthOptions& o) {
  Stopwatch total;
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
  if (fs::exists(o.output) && !o.force)
    throw InputError(o.output, "already exists (pass --force to replace it)");

  RunReport report;
  report.command = "synth";
  report.seed = o.seed;
  report.scene = o.output.string();
  report.versions = dependencyVersions();
  auto stage = [&](const std::string& name, double seconds) -> StageReport& {
    report.stages.push_back({});
    report.stages.back().name = name;
    report.stages.back().seconds = seconds;
    return report.stages.back();
  };

  Stopwatch clock;
  const StreetScene scene = buildStreetScene(scene_options);
  const TriangleMesh mesh = streetSceneMesh(scene);
  stage("layout", clock.seconds()).add("boxes", static_cast<std::int64_t>(scene.parts.size()))
      .add("triangles", static_cast<std::int64_t>(mesh.faces.size()));

  clock = Stopwatch();
  const GroundTruthMaps truth = rasterizeGroundTruth(scene);
  std::int64_t sky = cv::countNonZero(truth.depth_m <= 0);
  std::int64_t light_pixels = cv::countNonZero(truth.lights > 0);
  stage("ground_truth", clock.seconds()).add("sky_pixels", sky).add("light_pixels", light_pixels);

  clock = Stopwatch();
  cv::Mat day;
  if (o.day_render == "path") {
    DayRenderOptions day_options;
    day_options.seed = o.seed;
    day_options.progress = true;
    DaylightRender traced = renderDaylightPathTraced(scene, day_options);
    day = std::move(traced.linear_rgb);
    traced.report.seconds = clock.seconds();
    traced.report.notes.push_back("day image path traced: sun and sky gradient, NEE + MIS (--day-render path)");
    report.stages.push_back(std::move(traced.report));
  } else {
    day = renderDaylight(scene, truth);
    stage("daylight", clock.seconds()).add("samples_per_pixel", std::int64_t{1}).notes.push_back(
        "day image rastered: sun with one shadow ray, sky as an ambient term (--day-render path traces it)");
  }

  clock = Stopwatch();
  PredictionNoiseOptions noise;
  const SimulatedPredictions est =
      simulatePredictions(truth.depth_m, truth.normals, truth.albedo, truth.labels, truth.instances, noise, o.seed);
  stage("predictions", clock.seconds()).add("depth_scale_bias", est.depth_scale_bias);

  // Everything goes to a hidden sibling folder first, renamed into place at the end.
  clock = Stopwatch();
  const fs::path parent = o.output.parent_path().empty() ? fs::path(".") : o.output.parent_path();
  const fs::path staging = parent / ("." + o.output.filename().string() + ".tmp" + std::to_string(::getpid()));
  fs::remove_all(staging);
  fs::create_directories(staging / "gt");
  fs::create_directories(staging / "est");
  try {
    writeImage(staging / "day.png", srgbEncode8(day));
    writeImage(staging / "lightIds.png", toUint16Ids(truth.lights));
    writeImage(staging / "groups.png", toUint16Ids(truth.light_groups));

    writeDepth(staging / "gt/depth.exr", truth.depth_m);
    writeNormals(staging / "gt/normals.png", truth.normals);
    writeImage(staging / "gt/albedo.png", toUint16(truth.albedo));
    writeImage(staging / "gt/roughness.png", toUint16(truth.roughness));
    writeImage(staging / "gt/labelIds.png", toUint16Ids(truth.labels));
    writeImage(staging / "gt/instanceIds.png", toUint16Ids(truth.instances));
    writeMesh(staging / "gt/mesh.ply", mesh);

    writeDepth(staging / "est/depth.exr", est.depth_m);
    writeNormals(staging / "est/normals.png", est.normals);
    writeImage(staging / "est/albedo.png", toUint16(est.albedo));
    writeImage(staging / "est/labelIds.png", toUint16Ids(est.labels));
    writeImage(staging / "est/instanceIds.png", toUint16Ids(est.instances));

    const ordered_json camera = cameraJson(scene.camera);
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

    ordered_json record = {
        {"generator", "solo synth " + soloVersion()},
        {"seed", o.seed},
        {"variant", o.variant},
        {"day_render", o.day_render},
        {"width", o.width},
        {"height", o.height},
        {"camera", camera},
        {"sun_direction", {scene.sun_direction.x(), scene.sun_direction.y(), scene.sun_direction.z()}},
        {"mesh", {{"file", "gt/mesh.ply"}, {"boxes", scene.parts.size()}, {"triangles", mesh.faces.size()}}},
        {"perturbations",
         {{"depth_downscale", noise.depth_downscale},
          {"edge_bleed_px", noise.edge_bleed_px},
          {"edge_relative_jump", noise.edge_relative_jump},
          {"depth_bias_max", noise.depth_bias_max},
          {"depth_scale_bias_drawn", est.depth_scale_bias},
          {"depth_noise_relative", noise.depth_noise_relative},
          {"depth_noise_growth_m", noise.depth_noise_growth_m},
          {"normal_downscale", noise.normal_downscale},
          {"normal_blur_px", noise.normal_blur_px},
          {"normal_noise_deg", noise.normal_noise_deg},
          {"albedo_downscale", noise.albedo_downscale},
          {"label_jitter_px", noise.label_jitter_px},
          {"label_jitter_scale_px", noise.label_jitter_scale_px}}}};
    writeJson(staging / "synth.json", record);
    if (fs::exists(o.output)) fs::remove_all(o.output);
    fs::rename(staging, o.output);
  } catch (...) {
    std::error_code ignore;
    fs::remove_all(staging, ignore);
    throw;
  }
  stage("write", clock.seconds());
  report.total_seconds = total.seconds();
  std::cout << reportSummary(report) << "scene: " << (o.output / "scene.json").string() << "\n";
  return 0;
}

}  // namespace solo::tools
