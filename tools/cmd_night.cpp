// `solo night`: the whole pipeline on one scene. input -> refine -> mesh -> lights ->
// scene -> render -> post, each stage reporting its time and figures into one run report.

#include "commands.h"
#include "night_presets.h"

#include <solo/geometry/atomic_file.h>
#include <solo/geometry/depth_refinement.h>
#include <solo/geometry/error.h>
#include <solo/geometry/image_io.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/geometry/report.h>
#include <solo/geometry/scene.h>
#include <solo/lighting/light_overlay.h>
#include <solo/lighting/light_stage.h>
#include <solo/render/colour_encoding.h>
#include <solo/render/contact_sheet.h>
#include <solo/render/exposure.h>
#include <solo/render/night_scene.h>
#include <solo/render/path_tracer.h>
#include <solo/render/post_process.h>
#include <solo/render/sensor_noise.h>

#include <cstdio>
#include <iostream>

namespace fs = std::filesystem;

namespace solo::tools {

StageReport inputStage(const Scene& scene, double seconds);

namespace {

void say(const std::string& line) { std::cerr << line << std::flush; }

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
      {"cut faces: red jump, yellow uncertain, cyan instance", drawRemovedFaces(day, mesh.removed_spurious)},
      {lights_label, lights},
      {"night", night_rgb8},
  });
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
  LightSamplerKind sampler_kind;
  try {
    sampler_kind = lightSamplerFromName(o.light_sampler);
  } catch (const std::invalid_argument& e) {
    throw InputError("--light-sampler", e.what());
  }
  SamplerKind sample_kind;
  try {
    sample_kind = parseSamplerKind(o.sampler);
  } catch (const std::invalid_argument& e) {
    throw InputError("--sampler", e.what());
  }

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

  // refine: upsampling always (every later stage works at the image resolution)
  say("refine ... ");
  DepthRefinementOptions refine_options;
  refine_options.filter = o.refine;
  refine_options.uncertain_regions = o.refine;
  refine_options.optimize = o.refine && o.optimize;
  refine_options.optimization.max_iterations = o.optimize_iterations;
  refine_options.optimization.function_tolerance = o.optimize_tolerance;
  const DepthRefinementResult refined = refineDepth(scene, refine_options);
  for (const StageReport& step : refined.steps) report.stages.push_back(step);
  if (!o.refine) report.stages.back().notes.push_back("refinement switched off (--no-refine): upsampling only");

  // mesh
  say("mesh ... ");
  DepthMeshCleanupOptions mesh_options;
  mesh_options.close_solids = o.solids;
  mesh_options.evaluate = o.evaluate_mesh;
  StageReport mesh_report;
  const DepthMesh mesh =
      meshFromScene(refined.depth_m, scene.camera, refined.maps.instances, refined.uncertain, mesh_options, mesh_report);
  if (!o.evaluate_mesh)
    mesh_report.notes.push_back("mesh quality counts (self-intersections, manifoldness) not evaluated: they cost more "
                                "than the rest of the stage; --evaluate-mesh, or solo eval mesh, gives them");
  report.stages.push_back(mesh_report);

  // lights: a new draw, or the user's edited record
  say("lights ... ");
  LightRecord record;
  if (o.lights_record) {
    clock = Stopwatch();
    record = readLightRecord(*o.lights_record);
    StageReport lights_report;
    lights_report.name = "lights";
    lights_report.seconds = clock.seconds();
    lights_report.add("lights", static_cast<std::int64_t>(record.tree.lights.size()));
    lights_report.notes.push_back("light record read from " + o.lights_record->string() + " (not drawn)");
    report.stages.push_back(lights_report);
  } else {
    LightStageOptions light_options;
    light_options.instantiation.seed = o.seed;
    light_options.instantiation.ablation = o.ablation;
    light_options.illuminant_table = defaultIlluminantTable();
    LightStageResult lights = runLightStage(scene, refined.depth_m, light_options);
    record = std::move(lights.record);
    report.stages.push_back(lights.report);
  }

  // scene for the renderer
  NightSceneOptions scene_options;
  scene_options.headlights = o.headlights;
  scene_options.headlight_flux_lm = o.headlight_flux_lm;
  NightScene night = buildNightScene(mesh, refined.maps.albedo, refined.maps.roughness, scene.image, record, scene_options);
  report.stages.push_back(night.report);

  // render
  say("render\n");
  PathTracerOptions tracer;
  tracer.seed = o.seed;
  tracer.light_sampler = sampler_kind;
  tracer.sampler = sample_kind;
  tracer.min_samples = o.min_samples;
  tracer.max_samples = o.max_samples;
  tracer.relative_error = o.relative_error;
  // --noise-target: stop where render noise is below noise_factor x the sensor noise the pixel
  // will get. That needs the exposure first, so auto exposure meters a quarter-resolution
  // preview at min_samples spp (about 1/16 of a min_samples render) before the full render.
  double preview_white = 0;
  std::string noise_target_note;
  if (o.noise_target && o.noise) {
    Stopwatch preview_clock;
    preview_white = o.sensor_white_cd_m2;
    const PinholeCamera full_camera = night.scene.camera;
    if (!(preview_white > 0)) {
      night.scene.camera = full_camera.scaledTo(std::max(16, full_camera.width / 4), std::max(16, full_camera.height / 4));
      PathTracerOptions preview = tracer;
      preview.max_samples = preview.min_samples;
      preview.progress = false;
      const RenderOutput metered = renderPathTraced(night.scene, preview);
      night.scene.camera = full_camera;
      preview_white = meteredSensorWhite(metered.radiance, metered.light_id);
    }
    const double exposure = exposureScale(PostProcessOptions{}.exposure_options);
    tracer.noise_sigma = sensorNoiseSigma(1.0 / (preview_white * exposure), exposure, PostProcessOptions{}.noise_options);
    tracer.noise_factor = o.noise_factor;
    tracer.relative_error = 0;  // the sensor's noise is the target now; max_samples still caps
    char note[256];
    if (o.sensor_white_cd_m2 > 0)
      std::snprintf(note, sizeof note,
                    "noise-matched target: standard error <= %.2f x sensor noise sigma; sensor white given, %.6g cd/m2",
                    o.noise_factor, preview_white);
    else
      std::snprintf(note, sizeof note,
                    "noise-matched target: standard error <= %.2f x sensor noise sigma; exposure metered on a %dx%d "
                    "preview at %d spp (%.2f s), sensor white %.6g cd/m2",
                    o.noise_factor, std::max(16, full_camera.width / 4), std::max(16, full_camera.height / 4),
                    std::max(2, o.min_samples), preview_clock.seconds(), preview_white);
    noise_target_note = note;
  }
  const RenderOutput rendered = renderPathTraced(night.scene, tracer);
  report.stages.push_back(rendered.report);
  if (!noise_target_note.empty()) report.stages.back().notes.push_back(noise_target_note);
  if (o.noise_target && !o.noise)
    report.stages.back().notes.push_back(
        "noise-matched target skipped: sensor noise is off (--no-noise), the relative-error target applies");

  // post: radiance in cd/m^2 scaled so that the reference exposure (+3.25 stops) puts
  // sensor_white at 1. Only what will clip glows (the reference lets every pixel glow).
  PostProcessOptions post;
  post.glare = o.glare;
  post.noise = o.noise;
  post.noise_options.seed = o.seed;
  const bool auto_white = !(o.sensor_white_cd_m2 > 0);
  const double sensor_white = preview_white > 0 ? preview_white  // the exposure the noise target was set for
                              : auto_white      ? meteredSensorWhite(rendered.radiance, rendered.light_id)
                                                : o.sensor_white_cd_m2;
  const double calibration = 1.0 / (sensor_white * exposureScale(post.exposure_options));
  post.glare_options.threshold = o.glare_threshold >= 0 ? o.glare_threshold : 1.0 / exposureScale(post.exposure_options);
  cv::Mat xyz = rendered.radiance * calibration;
  const PostProcessResult developed = postProcess(xyz, post);
  StageReport post_report = developed.report;
  post_report.add("sensor_white", sensor_white, "cd/m2").add("sensor_white_auto", auto_white);
  if (!o.glare) post_report.notes.push_back("glare switched off (--no-glare)");
  if (!o.noise) post_report.notes.push_back("sensor noise switched off (--no-noise)");
  for (const StageReport& step : developed.steps)
    if (o.glare && step.name == "glare" && step.skipped)
      post_report.notes.push_back("no light above glare threshold: glare skipped");
  report.stages.push_back(post_report);

  writePostOutput(o.output, developed.encoded, developed.linear_rgb, o.sixteen_bit);
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
