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

LightStageResult runLightStage(const Scene& scene, const cv::Mat& depth_m, const LightStageOptions& options) {
  validateLightStageOptions(options);
  Stopwatch total;
  LightStageResult result;
  StageReport& report = result.report;
  report.name = "lights";
  LightRecord& record = result.record;
  record.scene = scene.manifest.file.string();
  record.seed = options.instantiation.seed;
  record.ablation = options.instantiation.ablation;
  record.illuminant_table = options.illuminant_table.string();
  const cv::Size size(scene.width(), scene.height());
  record.tree.width = size.width;
  record.tree.height = size.height;
  if (scene.lights.empty()) {
    record.tree.groups.push_back(LightGroup{});
    report.skipped = true;
    report.skip_reason = "the scene has no light map (\"lights\"): no scene lights to switch on";
    report.seconds = total.seconds();
    return result;
  }

  Stopwatch clock;
  const std::filesystem::path light_source = scene.manifest.lights ? *scene.manifest.lights : "lights";
  record.tree = buildLightGroups(resampleLabels(scene.lights, size), resampleLabels(scene.instances, size),
                                 resampleLabels(scene.light_groups, size), light_source);
  report.add("grouping_seconds", clock.seconds(), "s");
  if (scene.instances.empty()) report.notes.push_back("no instance map: no vehicle groups");
  if (scene.light_groups.empty()) report.notes.push_back("no window-group map: windows draw one by one");

  clock = Stopwatch();
  const cv::Mat depth = depth_m.empty() ? resampleDepthIgnoringInvalid(scene.depth_m, size) : depth_m;
  CV_Assert(depth.size() == size && depth.type() == CV_32F);
  record.geometry = measureLightGeometry(record.tree, depth, scene.camera, options.geometry,
                                         resampleNormals(scene.normals, size));
  if (scene.normals.empty()) report.notes.push_back("no normal map: light normals from plane fits to the depth");
  report.add("geometry_seconds", clock.seconds(), "s");

  clock = Stopwatch();
  const IlluminantTable table = readIlluminantTable(options.illuminant_table);
  record.instantiation = instantiateLights(record.tree, table, options.instantiation,
                                           inferredChromaticities(record.tree, scene.image));
  report.add("instantiation_seconds", clock.seconds(), "s");

  std::int64_t on = 0, never = 0, without_depth = 0, planar = 0, from_map = 0;
  double area_on = 0;
  for (std::size_t i = 0; i < record.tree.lights.size(); ++i) {
    const LightState& s = record.instantiation.lights[i];
    on += s.on;
    never += !s.emits;
    without_depth += !record.geometry[i].valid();
    planar += record.geometry[i].normal_source == NormalSource::PlaneFit;
    from_map += record.geometry[i].normal_source == NormalSource::NormalMap;
    if (s.on) area_on += record.geometry[i].area_m2;
  }
  report.add("lights", static_cast<std::int64_t>(record.tree.lights.size()))
      .add("groups", static_cast<std::int64_t>(record.tree.groups.size()) - 1)
      .add("root_lights", static_cast<std::int64_t>(record.tree.groups[0].lights.size()))
      .add("lights_on", on)
      .add("lights_never_emitting", never)
      .add("lights_without_depth", without_depth)
      .add("lights_with_plane_normal", planar)
      .add("lights_with_map_normal", from_map)
      .add("area_on_m2", area_on, "m2")
      .add("illuminant_samples", static_cast<std::int64_t>(table.samples.size()));
  if (options.instantiation.ablation)
    report.notes.push_back("ablation: every light on, white E, " +
                           std::to_string(options.instantiation.ablation_luminance_cd_m2) + " cd/m2");
  if (never > 0)
    report.notes.push_back(std::to_string(never) + " lights of categories without illuminant samples never emit");
  if (without_depth > 0)
    report.notes.push_back(std::to_string(without_depth) + " lights have no valid depth: no area or position");
  report.seconds = total.seconds();
  return result;
}

}  // namespace solo
