// One night conversion from files to files (night_job.h).

#include <solo/pipeline/night_job.h>

#include <solo/core/atomic_file.h>
#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/output_path.h>
#include <solo/core/version.h>
#include <solo/lighting/light_category.h>
#include <solo/lighting/light_overlay.h>
#include <solo/pipeline/data_dir.h>
#include <solo/post/colour_encoding.h>
#include <solo/post/night_statistics.h>
#include <solo/render/contact_sheet.h>
#include <solo/render/ray_caster.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <variant>

namespace fs = std::filesystem;

namespace solo {

namespace {

// The removed-face marks of a mesh made from a downsampled depth map, at the image's size.
cv::Mat removedAtImageSize(const DepthMesh& mesh, cv::Size image_size) {
  if (mesh.removed_spurious.empty() || mesh.removed_spurious.size() == image_size) return mesh.removed_spurious;
  cv::Mat resized;
  cv::resize(mesh.removed_spurious, resized, image_size, 0, 0, cv::INTER_NEAREST);
  return resized;
}

// The number of lights the conversion proposed from the labels (its "light_proposals" stage),
// or -1 when the lights came from the scene's light map or a light record.
std::int64_t proposedLightCount(const std::vector<StageReport>& stages) {
  for (const StageReport& stage : stages) {
    if (stage.name != "light_proposals") continue;
    const MetricValue* lights = stage.find("lights");
    return lights && std::holds_alternative<std::int64_t>(*lights) ? std::get<std::int64_t>(*lights) : 0;
  }
  return -1;
}

// The contact sheet: day, raw and refined depth on one colour scale, the faces the mesh stage
// cut, the lights on and off (proposed ones framed in magenta), the night image.
cv::Mat contactSheet(const Scene& scene, const DepthRefinementResult& refined, const DepthMesh& mesh,
                     const LightRecord& record, std::int64_t proposed_lights, const cv::Mat& night_rgb8) {
  cv::Mat day;
  scene.image.convertTo(day, CV_8UC3, 255.0);
  const auto [near_m, far_m] = depthDisplayRange({refined.upsampled_depth_m, refined.depth_m});
  char range[64];
  std::snprintf(range, sizeof range, ", log %.3g-%.3g m", near_m, far_m);
  cv::Mat lights;
  std::string lights_label = proposed_lights >= 0
                                 ? "lights: proposed from labels (" + std::to_string(proposed_lights) + ")"
                                 : std::string("lights: bright on, dim off");
  if (record.tree.width == scene.width() && record.tree.height == scene.height() &&
      record.instantiation.lights.size() == record.tree.lights.size()) {
    LightOverlayOptions overlay;
    overlay.proposed = proposed_lights >= 0;
    lights = drawLightOverlay(scene.image, record.tree, record.instantiation.lights, overlay);
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

// The render's AOV files beside render_exr: albedo, normal, depth, light ids.
std::vector<fs::path> renderAovFiles(const fs::path& render_exr) {
  const std::string stem = fs::path(render_exr).replace_extension().string();
  return {stem + ".albedo.exr", stem + ".normal.exr", stem + ".depth.exr", stem + ".lightid.npy"};
}

// Refuses, before any work, an unsupported output format, or an output that is an input of
// this run: the manifest, a map it names, or the light record (`-o S/day.png` would overwrite
// the day image).
void checkOutputs(const NightJobOptions& job, const NightConversionOptions& o, const fs::path& scene_file,
                  const fs::path& report_file) {
  const std::string ext = lowercaseExtension(job.output);
  if (ext != ".png" && ext != ".tif" && ext != ".tiff" && ext != ".jpg" && ext != ".jpeg" && ext != ".exr")
    throw InputError(job.output, "unsupported output format \"" + job.output.extension().string() +
                                     "\" (use .png, .tif, .jpg or .exr)");
  if (job.contact_sheet) {
    const std::string sheet_ext = lowercaseExtension(*job.contact_sheet);
    if (sheet_ext != ".png" && sheet_ext != ".jpg" && sheet_ext != ".tif")
      throw InputError(*job.contact_sheet, "unsupported contact sheet format \"" +
                                               job.contact_sheet->extension().string() + "\" (use .png)");
  }
  std::vector<fs::path> inputs = manifestFiles(readSceneManifest(scene_file));
  if (o.light_record) inputs.push_back(*o.light_record);
  refuseOutputThatIsAnInput(job.output, inputs, "-o");
  refuseOutputThatIsAnInput(report_file, inputs, "--report");
  if (job.render_exr) {
    refuseOutputThatIsAnInput(*job.render_exr, inputs, "--render-exr");
    for (const fs::path& aov : renderAovFiles(*job.render_exr)) refuseOutputThatIsAnInput(aov, inputs, "--render-exr");
  }
  if (job.contact_sheet) refuseOutputThatIsAnInput(*job.contact_sheet, inputs, "--contact-sheet");
  if (job.text_file) refuseOutputThatIsAnInput(job.text_file->first, inputs, "--write-config");
}

void writeRenderExr(const fs::path& render_exr, const RenderOutput& rendered) {
  writeImage(render_exr, rendered.radiance);
  const std::vector<fs::path> aovs = renderAovFiles(render_exr);
  writeImage(aovs[0], rendered.albedo);
  writeImage(aovs[1], rendered.normal);
  writeDepth(aovs[2], rendered.depth_m);
  writeImage(aovs[3], rendered.light_id);
}

}  // namespace

StageReport sceneInputReport(const Scene& scene, double seconds) {
  StageReport stage = describeScene(scene);
  stage.seconds = seconds;
  if (!scene.lights.empty()) {
    const LightCensus census = countLights(scene.lights);
    stage.add("light_instances", census.total_instances());
    for (int c = kFirstLightCategory; c <= kLastLightCategory; ++c)
      if (census.instances[c] > 0)
        stage.add(std::string("lights_") + lightCategoryName(static_cast<LightCategory>(c)), census.instances[c]);
  }
  return stage;
}

std::vector<std::pair<std::string, std::string>> pipelineDependencyVersions() {
  auto list = geometryDependencyVersions();
  for (auto& v : renderDependencyVersions()) list.push_back(v);
  list.push_back({"nlohmann_json", std::to_string(NLOHMANN_JSON_VERSION_MAJOR) + "." +
                                       std::to_string(NLOHMANN_JSON_VERSION_MINOR) + "." +
                                       std::to_string(NLOHMANN_JSON_VERSION_PATCH)});
  return list;
}

void writeDevelopedImage(const fs::path& file, const cv::Mat& encoded, const cv::Mat& linear_rgb, bool sixteen_bit) {
  const std::string ext = lowercaseExtension(file);
  if (ext == ".exr") {
    writeImage(file, linear_rgb);
  } else if (ext == ".png" || ext == ".tif" || ext == ".tiff") {
    writeImage(file, quantiseEncoded(encoded, sixteen_bit ? 16 : 8));
  } else if (ext == ".jpg" || ext == ".jpeg") {
    if (sixteen_bit) throw InputError(file, "JPEG holds 8 bits only: use .png or .tif for --16bit");
    writeImage(file, quantiseEncoded(encoded, 8));
  } else {
    throw InputError(file, "unsupported output format \"" + ext + "\" (use .png, .tif, .jpg or .exr)");
  }
}

NightJobResult runNightJob(const NightJobOptions& job, const NightConversionOptions& o,
                           const NightConversionCallbacks& callbacks) {
  const Stopwatch total;
  const fs::path scene_file = job.scene ? *job.scene : defaultScene();
  NightJobResult result;
  result.report_file = job.report ? *job.report : fs::path(job.output).replace_extension(".report.json");
  validateNightConversionOptions(o);
  checkOutputs(job, o, scene_file, result.report_file);

  RunReport& report = result.report;
  report.command = "night";
  report.scene = scene_file.string();
  report.seed = o.seed;
  report.preset = job.preset;
  report.versions = job.versions.empty() ? pipelineDependencyVersions() : job.versions;

  if (callbacks.stage_started) callbacks.stage_started("input");
  const Stopwatch clock;
  const Scene scene = loadScene(scene_file);
  report.stages.push_back(sceneInputReport(scene, clock.seconds()));

  NightConversionResult converted = runNightConversion(scene, o, callbacks);
  const std::int64_t proposed_lights = proposedLightCount(converted.stages);
  for (StageReport& stage : converted.stages) report.stages.push_back(std::move(stage));
  const PostProcessResult& developed = converted.developed;
  writeDevelopedImage(job.output, developed.encoded, developed.linear_rgb, job.sixteen_bit);
  // realism: the statistics of the written image (docs/evaluation.md, `solo eval night`).
  const Stopwatch realism_clock;
  const NightStatistics realism = computeNightStatistics(developed.encoded, ChannelOrder::Rgb);
  report.stages.push_back(nightStatisticsReport(realism, realism_clock.seconds()));
  if (job.render_exr) writeRenderExr(*job.render_exr, converted.rendered);
  if (job.contact_sheet)
    writeImage(*job.contact_sheet, contactSheet(scene, converted.refined, converted.mesh, converted.record,
                                                proposed_lights, quantiseEncoded(developed.encoded, 8)));
  if (job.text_file) writeTextAtomically(job.text_file->first, job.text_file->second);
  report.total_seconds = total.seconds();
  writeReportJson(result.report_file, report);
  return result;
}

}  // namespace solo
