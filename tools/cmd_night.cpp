// `solo night`: the whole pipeline on one scene. input -> refine -> mesh -> lights ->
// scene -> render -> post, each stage reporting its time and figures into one run report.

#include "commands.h"
#include "night_pipeline.h"
#include "night_presets.h"

#include <solo/core/atomic_file.h>
#include <solo/geometry/depth_refinement.h>
#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/output_path.h>
#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/lighting/light_overlay.h>
#include <solo/post/colour_encoding.h>
#include <solo/render/contact_sheet.h>
#include <solo/post/night_statistics.h>

#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <iostream>

namespace fs = std::filesystem;

namespace solo::tools {

StageReport inputStage(const Scene& scene, double seconds);

namespace {

void say(const std::string& line) { std::cerr << line << std::flush; }

// The removed-face marks of a mesh made from a downsampled depth map, at the image's size.
cv::Mat removedAtImageSize(const DepthMesh& mesh, cv::Size image_size) {
  if (mesh.removed_spurious.empty() || mesh.removed_spurious.size() == image_size) return mesh.removed_spurious;
  cv::Mat resized;
  cv::resize(mesh.removed_spurious, resized, image_size, 0, 0, cv::INTER_NEAREST);
  return resized;
}

// The contact sheet: day, raw and refined depth on one colour scale, the faces the mesh stage
// cut, the lights on and off, the night image.
cv::Mat contactSheet(const Scene& scene, const DepthRefinementResult& refined, const DepthMesh& mesh,
                     const LightRecord& record, const cv::Mat& night_rgb8) {
  cv::Mat day;
  scene.image.convertTo(day, CV_8UC3, 255.0);
  const auto [near_m, far_m] = depthDisplayRange({refined.upsampled_depth_m, refined.depth_m});
  char range[64];
  std::snprintf(range, sizeof range, ", log %.3g-%.3g m", near_m, far_m);
  cv::Mat lights;
  std::string lights_label = "lights: bright on, dim off";
  if (record.tree.width == scene.width() && record.tree.height == scene.height() &&
      record.instantiation.lights.size() == record.tree.lights.size()) {
    lights = drawLightOverlay(scene.image, record.tree, record.instantiation.lights);
  } else {
    scene.image.convertTo(lights, CV_8UC3, 127.5);
    lights_label = "lights: none at this resolution";
  }
  return composeContactSheet({
      {"day", day},
      {std::string("raw depth") + range, colourizeDepth(refined.upsampled_depth_m, near_m, far_m)},
      {std::string("refined depth") + range, colourizeDepth(refined.depth_m, near_m, far_m)},
      {"cut faces: red jump, yellow uncertain, cyan instance", drawRemovedFaces(day, removedAtImageSize(mesh, day.size()))},
      {lights_label, lights},
      {"night", night_rgb8},
  });
}

// Refuses, before any work, an output that is an input of this run: the manifest, a map it
// names, or the light record (`-o S/day.png` would overwrite the day image).
void refuseOutputsThatAreInputs(const NightOptions& o, const fs::path& scene_file, const fs::path& report_file) {
  std::vector<fs::path> inputs = manifestFiles(readSceneManifest(scene_file));
  if (o.lights_record) inputs.push_back(*o.lights_record);
  refuseOutputThatIsAnInput(o.output, inputs, "-o");
  refuseOutputThatIsAnInput(report_file, inputs, "--report");
  if (o.render_exr) {
    const std::string stem = fs::path(*o.render_exr).replace_extension().string();
    for (const std::string& aov : {std::string(), std::string(".albedo.exr"), std::string(".normal.exr"),
                                   std::string(".depth.exr"), std::string(".lightid.npy")})
      refuseOutputThatIsAnInput(aov.empty() ? *o.render_exr : fs::path(stem + aov), inputs, "--render-exr");
  }
  if (o.contact_sheet) refuseOutputThatIsAnInput(*o.contact_sheet, inputs, "--contact-sheet");
  if (o.write_config) refuseOutputThatIsAnInput(*o.write_config, inputs, "--write-config");
}

}  // namespace

int runNight(const NightOptions& o) {
  Stopwatch total;
  const fs::path scene_file = o.scene ? *o.scene : defaultScene();
  const fs::path report_file = o.report ? *o.report : fs::path(o.output).replace_extension(".report.json");
  const std::string ext = fs::path(o.output).extension().string();
  if (ext != ".png" && ext != ".tif" && ext != ".tiff" && ext != ".jpg" && ext != ".jpeg" && ext != ".exr")
    throw InputError(o.output, "unsupported output format \"" + ext + "\" (use .png, .tif, .jpg or .exr)");
  if (o.contact_sheet) {
    const std::string sheet_ext = o.contact_sheet->extension().string();
    if (sheet_ext != ".png" && sheet_ext != ".jpg" && sheet_ext != ".tif")
      throw InputError(*o.contact_sheet, "unsupported contact sheet format \"" + sheet_ext + "\" (use .png)");
  }
  lightSamplerOption(o);  // unknown names fail before any work
  samplerOption(o);
  refuseOutputsThatAreInputs(o, scene_file, report_file);

  RunReport report;
  report.command = "night";
  report.scene = scene_file.string();
  report.seed = o.seed;
  report.preset = o.preset;
  const std::string config_text = o.write_config ? nightConfigText(o) : std::string();  // throws before any work
  report.versions = dependencyVersions();

  // input
  say("input ... ");
  Stopwatch clock;
  const Scene scene = loadScene(scene_file);
  report.stages.push_back(inputStage(scene, clock.seconds()));

  NightPipelineExtras extras;
  extras.say = say;
  NightPipelineResult result = runNightPipeline(scene, o, extras);
  for (StageReport& stage : result.stages) report.stages.push_back(std::move(stage));
  const DepthRefinementResult& refined = result.refined;
  const DepthMesh& mesh = result.mesh;
  const LightRecord& record = result.record;
  const RenderOutput& rendered = result.rendered;
  const PostProcessResult& developed = result.developed;

  writePostOutput(o.output, developed.encoded, developed.linear_rgb, o.sixteen_bit);
  // realism: the statistics of the written image (docs/evaluation.md, `solo eval night`).
  Stopwatch realism_clock;
  const NightStatistics realism = computeNightStatistics(developed.encoded, ChannelOrder::Rgb);
  report.stages.push_back(nightStatisticsReport(realism, realism_clock.seconds()));
  if (o.render_exr) {
    writeImage(*o.render_exr, rendered.radiance);
    const fs::path stem = fs::path(*o.render_exr).replace_extension();
    writeImage(stem.string() + ".albedo.exr", rendered.albedo);
    writeImage(stem.string() + ".normal.exr", rendered.normal);
    writeDepth(stem.string() + ".depth.exr", rendered.depth_m);
    writeImage(stem.string() + ".lightid.npy", rendered.light_id);
  }
  if (o.contact_sheet)
    writeImage(*o.contact_sheet,
               contactSheet(scene, refined, mesh, record, quantiseEncoded(developed.encoded, 8)));
  // With the outputs, not before: a run that fails leaves no file behind.
  if (o.write_config) writeTextAtomically(*o.write_config, config_text);
  report.total_seconds = total.seconds();
  writeReportJson(report_file, report);
  std::cout << reportSummary(report) << "night image: " << o.output.string() << "\nreport: " << report_file.string()
            << "\n";
  return 0;
}

}  // namespace solo::tools
