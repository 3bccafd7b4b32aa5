// `solo night`: the whole pipeline on one scene. input -> refine -> mesh -> lights ->
// scene -> render -> post, each stage reporting its time and figures into one run report.

#include "commands.h"

#include <solo/geometry/depth_refinement.h>
#include <solo/geometry/error.h>
#include <solo/geometry/image_io.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/geometry/report.h>
#include <solo/geometry/scene.h>
#include <solo/lighting/light_stage.h>
#include <solo/render/night_scene.h>
#include <solo/render/path_tracer.h>
#include <solo/render/post_process.h>

#include <iostream>

namespace fs = std::filesystem;

namespace solo::tools {

StageReport inputStage(const Scene& scene, double seconds);

namespace {

void say(const std::string& line) { std::cerr << line << std::flush; }

// Auto exposure: the luminance that the 95th percentile of the lit, non-emitting pixels
// reaches at 80 % of sensor white, like a camera metering the street rather than the lamps.
double autoSensorWhite(const cv::Mat& radiance, const cv::Mat& light_id) {
  std::vector<float> y;
  y.reserve(radiance.total());
  for (int r = 0; r < radiance.rows; ++r)
    for (int c = 0; c < radiance.cols; ++c) {
      const float v = radiance.at<cv::Vec3f>(r, c)[1];
      if (light_id.at<int>(r, c) == 0 && v > 0.f) y.push_back(v);
    }
  if (y.empty()) return 1.0;
  const auto k = static_cast<std::ptrdiff_t>(0.95 * static_cast<double>(y.size() - 1));
  std::nth_element(y.begin(), y.begin() + k, y.end());
  return std::max(1e-6, static_cast<double>(y[static_cast<std::size_t>(k)]) / 0.8);
}

}  // namespace

int runNight(const NightOptions& o) {
  Stopwatch total;
  const fs::path scene_file = o.scene ? *o.scene : defaultScene();
  const fs::path report_file = o.report ? *o.report : fs::path(o.output).replace_extension(".report.json");
  const std::string ext = fs::path(o.output).extension().string();
  if (ext != ".png" && ext != ".tif" && ext != ".tiff" && ext != ".jpg" && ext != ".jpeg" && ext != ".exr")
    throw InputError(o.output, "unsupported output format \"" + ext + "\" (use .png, .tif, .jpg or .exr)");
  LightSamplerKind sampler_kind;
  try {
    sampler_kind = lightSamplerFromName(o.light_sampler);
  } catch (const std::invalid_argument& e) {
    throw InputError("--light-sampler", e.what());
  }

  RunReport report;
  report.command = "night";
  report.scene = scene_file.string();
  report.seed = o.seed;
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
  tracer.min_samples = o.min_samples;
  tracer.max_samples = o.max_samples;
  tracer.relative_error = o.relative_error;
  const RenderOutput rendered = renderPathTraced(night.scene, tracer);
  report.stages.push_back(rendered.report);

  // post: radiance in cd/m^2 scaled so that the reference exposure (+3.25 stops) puts
  // sensor_white at 1. Only what will clip glows (the reference lets every pixel glow).
  PostProcessOptions post;
  post.glare = o.glare;
  post.noise = o.noise;
  post.noise_options.seed = o.seed;
  const bool auto_white = !(o.sensor_white_cd_m2 > 0);
  const double sensor_white = auto_white ? autoSensorWhite(rendered.radiance, rendered.light_id) : o.sensor_white_cd_m2;
  const double calibration = 1.0 / (sensor_white * exposureScale(post.exposure_options));
  post.glare_options.threshold = o.glare_threshold >= 0 ? o.glare_threshold : 1.0 / exposureScale(post.exposure_options);
  cv::Mat xyz = rendered.radiance * calibration;
  const PostProcessResult developed = postProcess(xyz, post);
  StageReport post_report = developed.report;
  post_report.add("sensor_white", sensor_white, "cd/m2").add("sensor_white_auto", auto_white);
  if (!o.glare) post_report.notes.push_back("glare switched off (--no-glare)");
  if (!o.noise) post_report.notes.push_back("sensor noise switched off (--no-noise)");
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
  report.total_seconds = total.seconds();
  writeReportJson(report_file, report);
  std::cout << reportSummary(report) << "night image: " << o.output.string() << "\nreport: " << report_file.string()
            << "\n";
  return 0;
}

}  // namespace solo::tools
