#include "solo/lighting/light_stage.h"

#include "solo/lighting/illuminant_table.h"
#include "solo/lighting/light_groups.h"

#include <solo/core/option_checks.h>

#include <opencv2/imgproc.hpp>

namespace solo {

cv::Mat resampleLabels(const cv::Mat& labels, cv::Size size) {
  if (labels.empty() || labels.size() == size) return labels;
  cv::Mat out(size, CV_32S);
  // Nearest source pixel centre: x_src = (x + 0.5) * w_src / w - 0.5, rounded.
  for (int y = 0; y < size.height; ++y) {
    const int sy = std::min(labels.rows - 1, static_cast<int>((y + 0.5) * labels.rows / size.height));
    for (int x = 0; x < size.width; ++x) {
      const int sx = std::min(labels.cols - 1, static_cast<int>((x + 0.5) * labels.cols / size.width));
      out.at<int>(y, x) = labels.at<int>(sy, sx);
    }
  }
  return out;
}

void validateLightStageOptions(const LightStageOptions& options) {
  requireOptionAboveAndAtMost(options.instantiation.ablation_luminance_cd_m2, 0, 1e9, "--ablation-luminance");
}

namespace {

// How many of the priors' lines a report's notes list; the record holds every light's placement.
constexpr std::size_t kMaxPriorNotes = 20;

// The record's provenance and an empty tree at the image size.
void startRecord(const Scene& scene, const LightStageOptions& options, cv::Size size, LightRecord& record) {
  record.scene = scene.manifest.file.string();
  record.seed = options.instantiation.seed;
  record.ablation = options.instantiation.ablation;
  record.illuminant_table = options.illuminant_table.string();
  record.tree.width = size.width;
  record.tree.height = size.height;
}

// The ground plane, its source and the priors' verdicts in the report.
void reportPriors(const LightPriorSummary& summary, const GroundPlaneFit& ground, bool enabled, StageReport& report) {
  if (!enabled) {
    report.notes.push_back("physical priors off: lights stay as measured, lights without depth have no position");
    return;
  }
  report.add("ground_plane", std::string(ground.fitted ? "road_sidewalk_fit" : "camera_height_prior"))
      .add("camera_height_m", ground.offset_m, "m")
      .add("ground_plane_inliers", ground.inliers)
      .add("lights_checked", summary.total.checked)
      .add("lights_moved_to_support", summary.total.moved)
      .add("lights_implausible", summary.total.flagged)
      .add("lights_placed_at_support_depth", summary.total.support_depth)
      .add("lights_placed_at_prior_distance", summary.total.prior_distance);
  for (int c = kFirstLightCategory; c <= kLastLightCategory; ++c) {
    const LightPriorCounts& counts = summary.by_category[static_cast<std::size_t>(c)];
    const std::string name = lightCategoryName(static_cast<LightCategory>(c));
    if (counts.moved > 0) report.add("moved_" + name, counts.moved);
    if (counts.flagged > 0) report.add("implausible_" + name, counts.flagged);
  }
  if (!ground.fitted)
    report.notes.push_back("ground plane from the camera height prior (" + std::to_string(kCameraHeightPriorM) +
                           " m, level camera): " + std::to_string(ground.points) +
                           " road and sidewalk points (labelIds 7, 8) with depth gave no plausible plane");
  for (std::size_t k = 0; k < summary.lines.size() && k < kMaxPriorNotes; ++k) report.notes.push_back(summary.lines[k]);
  if (summary.lines.size() > kMaxPriorNotes)
    report.notes.push_back(std::to_string(summary.lines.size() - kMaxPriorNotes) +
                           " more lights moved, flagged or placed: the record's \"placement\" and \"implausible\"");
}

// Each light's geometry measured on the depth, then checked against its category's priors.
void measureGeometry(const Scene& scene, const cv::Mat& depth_m, const cv::Mat& instances,
                     const LightStageOptions& options, LightRecord& record, StageReport& report) {
  const cv::Size size(record.tree.width, record.tree.height);
  const cv::Mat depth = depth_m.empty() ? resampleDepthIgnoringInvalid(scene.depth_m, size) : depth_m;
  CV_Assert(depth.size() == size && depth.type() == CV_32F);
  const cv::Mat normals = resampleNormals(scene.normals, size);
  record.geometry = measureLightGeometry(record.tree, depth, scene.camera, options.geometry, normals);
  if (scene.normals.empty()) report.notes.push_back("no normal map: light normals from plane fits to the depth");

  LightPriorInputs inputs;
  inputs.depth_m = depth;
  inputs.labels = resampleLabels(scene.labels, size);
  inputs.instances = instances;
  inputs.normals = normals;
  inputs.camera = scene.camera;
  if (options.priors.enabled) inputs.ground = fitGroundPlaneToRoad(depth, inputs.labels, scene.camera, options.ground_plane);
  const LightPriorSummary summary =
      applyLightPriors(record.tree, record.geometry, inputs, options.priors, options.geometry);
  reportPriors(summary, inputs.ground, options.priors.enabled, report);
}

// The record's counts, areas and what the user should know about them.
void reportCounts(const LightRecord& record, const IlluminantTable& table, const LightStageOptions& options,
                  StageReport& report) {
  std::int64_t on = 0, never = 0, planar = 0, from_map = 0, lit_without_position = 0;
  double area_on = 0;
  for (std::size_t i = 0; i < record.tree.lights.size(); ++i) {
    const LightState& s = record.instantiation.lights[i];
    on += s.on;
    never += !s.emits;
    planar += record.geometry[i].normal_source == NormalSource::PlaneFit;
    from_map += record.geometry[i].normal_source == NormalSource::NormalMap;
    lit_without_position += lightIsLit(s) && !record.geometry[i].positioned();
    if (s.on) area_on += record.geometry[i].area_m2;
  }
  const LightsWithoutDepth without_depth = countLightsWithoutDepth(record);
  report.add("lights", static_cast<std::int64_t>(record.tree.lights.size()))
      .add("groups", static_cast<std::int64_t>(record.tree.groups.size()) - 1)
      .add("root_lights", static_cast<std::int64_t>(record.tree.groups[0].lights.size()))
      .add("lights_on", on)
      .add("lights_never_emitting", never)
      .add("lights_without_depth", without_depth.all)
      .add("lights_on_without_depth", without_depth.lit)
      .add("lights_on_without_position", lit_without_position)
      .add("lights_with_plane_normal", planar)
      .add("lights_with_map_normal", from_map)
      .add("area_on_m2", area_on, "m2")
      .add("illuminant_samples", static_cast<std::int64_t>(table.samples.size()));
  if (options.instantiation.ablation)
    report.notes.push_back("ablation: every light on, white E, " +
                           std::to_string(options.instantiation.ablation_luminance_cd_m2) + " cd/m2");
  if (never > 0)
    report.notes.push_back(std::to_string(never) + " lights of categories without illuminant samples never emit");
  if (without_depth.all > 0)
    report.notes.push_back(std::to_string(without_depth.all) + " lights have no valid depth (" +
                           std::to_string(without_depth.lit) +
                           " of them on): placed at their support's depth or their category's prior distance");
  if (lit_without_position > 0)
    report.warnings.push_back(std::to_string(lit_without_position) +
                              " lights that are on have no position (no valid depth, priors off): they emit nothing");
}

}  // namespace

LightStageResult runLightStage(const Scene& scene, const cv::Mat& depth_m, const LightStageOptions& options) {
  validateLightStageOptions(options);
  Stopwatch total;
  LightStageResult result;
  StageReport& report = result.report;
  report.name = "lights";
  LightRecord& record = result.record;
  const cv::Size size(scene.width(), scene.height());
  startRecord(scene, options, size, record);
  if (scene.lights.empty()) {
    record.tree.groups.push_back(LightGroup{});
    report.skipped = true;
    report.skip_reason = "the scene has no light map (\"lights\"): no scene lights to switch on";
    report.seconds = total.seconds();
    return result;
  }

  Stopwatch clock;
  const std::filesystem::path light_source = scene.manifest.lights ? *scene.manifest.lights : "lights";
  const cv::Mat instances = resampleLabels(scene.instances, size);
  record.tree = buildLightGroups(resampleLabels(scene.lights, size), instances,
                                 resampleLabels(scene.light_groups, size), light_source);
  report.add("grouping_seconds", clock.seconds(), "s");
  if (scene.instances.empty()) report.notes.push_back("no instance map: no vehicle groups");
  if (scene.light_groups.empty()) report.notes.push_back("no window-group map: windows draw one by one");

  clock = Stopwatch();
  measureGeometry(scene, depth_m, instances, options, record, report);
  report.add("geometry_seconds", clock.seconds(), "s");

  clock = Stopwatch();
  const IlluminantTable table = readIlluminantTable(options.illuminant_table);
  record.instantiation = instantiateLights(record.tree, table, options.instantiation,
                                           inferredChromaticities(record.tree, scene.image));
  report.add("instantiation_seconds", clock.seconds(), "s");

  reportCounts(record, table, options, report);
  report.seconds = total.seconds();
  return result;
}

}  // namespace solo
