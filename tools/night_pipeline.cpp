// `solo night`'s stages after the input (night_pipeline.h).

#include "night_pipeline.h"

#include <solo/geometry/downsample_depth.h>
#include <solo/core/error.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/lighting/light_stage.h>
#include <solo/lighting/street_light_instances.h>
#include <solo/post/exposure.h>
#include <solo/render/night_scene.h>
#include <solo/render/render_denoise.h>
#include <solo/post/sensor_noise.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace solo::tools {

namespace {

// A render made at a fraction of the image size, upsampled to it: radiance, albedo and normal
// bilinear, first-hit depth and light ids nearest (they are not averageable across edges).
RenderOutput upsampleRender(RenderOutput r, cv::Size size) {
  const auto resize = [&](cv::Mat& m, int interpolation) {
    if (m.empty() || m.size() == size) return;
    cv::Mat out;
    cv::resize(m, out, size, 0, 0, interpolation);
    m = out;
  };
  resize(r.radiance, cv::INTER_LINEAR);
  resize(r.albedo, cv::INTER_LINEAR);
  resize(r.normal, cv::INTER_LINEAR);
  resize(r.depth_m, cv::INTER_NEAREST);
  resize(r.light_id, cv::INTER_NEAREST);
  resize(r.emitter_coverage, cv::INTER_NEAREST);
  resize(r.samples, cv::INTER_NEAREST);
  resize(r.std_error, cv::INTER_NEAREST);
  return r;
}

/// What the night camera chose; `preview` is the metering preview's size (empty: white given).
std::string exposureNote(const NightCameraExposure& e, cv::Size preview) {
  char note[400];
  if (!preview.empty())
    std::snprintf(note, sizeof note,
                  "night camera metered a mean %.4g cd/m2 on a %dx%d preview at %d spp (lamps seen directly left "
                  "out): ISO %.0f, 1/%.0f s, f/%.1f, sensor white %.6g cd/m2%s",
                  e.metered_cd_m2, preview.width, preview.height, kMeteringSamplesPerPixel, e.camera.iso,
                  1.0 / e.camera.shutter_s, e.camera.f_number, e.white_cd_m2,
                  e.at_exposure_limit ? "; at its exposure limit, so the street stays darker than the meter's grey"
                  : e.at_bright_limit ? "; at its shortest exposure: over-exposed"
                                      : "");
  else
    std::snprintf(note, sizeof note, "sensor white given, %.6g cd/m2 (noise at ISO %.0f)", e.white_cd_m2,
                  e.camera.iso);
  return note;
}

NightCameraOptions nightCameraOptions(const NightOptions& o) {
  NightCameraOptions camera;
  camera.f_number = o.camera_f_number;
  camera.max_shutter_s = o.camera_max_shutter_s;
  camera.max_iso = o.camera_max_iso;
  camera.compensation_ev = o.camera_compensation_ev;
  camera.min_shutter_s = std::min(camera.min_shutter_s, camera.max_shutter_s);
  camera.min_iso = std::min(camera.min_iso, camera.max_iso);
  return camera;
}

struct MeteredCamera {
  NightCameraExposure exposure;
  cv::Size preview_size;  ///< empty when the white was given
  double preview_seconds = 0;
};

/// The night camera's settings: metered on a preview (meteringPreviewSize at
/// kMeteringSamplesPerPixel) of `render_camera`'s view, or derived from --sensor-white.
MeteredCamera meterNightCamera(const PreparedRenderScene& prepared, const PinholeCamera& render_camera,
                               const PathTracerOptions& tracer, const NightOptions& o) {
  const NightCameraOptions limits = nightCameraOptions(o);
  MeteredCamera m;
  if (o.sensor_white_cd_m2 > 0) {
    m.exposure = nightCameraForWhite(o.sensor_white_cd_m2, limits);
    return m;
  }
  const Stopwatch clock;
  m.preview_size = meteringPreviewSize(render_camera.width, render_camera.height);
  PathTracerOptions preview = tracer;
  preview.min_samples = preview.max_samples = kMeteringSamplesPerPixel;
  preview.progress = false;
  const RenderOutput rendered =
      renderPathTraced(prepared, render_camera.scaledTo(m.preview_size.width, m.preview_size.height), preview);
  m.exposure = nightCameraExposure(meteredMeanLuminance(rendered.radiance, rendered.emitter_coverage), limits);
  m.preview_seconds = clock.seconds();
  return m;
}

}  // namespace

LightSamplerKind lightSamplerOption(const NightOptions& o) {
  try {
    return lightSamplerFromName(o.light_sampler);
  } catch (const std::invalid_argument& e) {
    throw InputError("--light-sampler", e.what());
  }
}

SamplerKind samplerOption(const NightOptions& o) {
  try {
    return parseSamplerKind(o.sampler);
  } catch (const std::invalid_argument& e) {
    throw InputError("--sampler", e.what());
  }
}

Scene sceneForRefinement(const Scene& scene, std::int64_t* changed) {
  Scene out = scene;  // cv::Mat copies share their pixels; only the instance map is new
  out.instances = streetLightsAsPoles(scene.instances, scene.lights, changed);
  return out;
}

NightScene runNightSceneStages(const Scene& scene, const NightOptions& o, const NightPipelineExtras& extras,
                               NightPipelineResult& r) {
  const auto say = [&](const std::string& line) {
    if (extras.say) extras.say(line);
  };
  std::vector<StageReport>& stages = r.stages;

  // refine: upsampling always (every later stage works at the image resolution)
  say("refine ... ");
  DepthRefinementOptions refine_options;
  refine_options.filter = o.refine;
  refine_options.uncertain_regions = o.refine;
  refine_options.optimize = o.refine && o.optimize;
  refine_options.optimization.max_iterations = o.optimize_iterations;
  refine_options.optimization.function_tolerance = o.optimize_tolerance;
  std::int64_t street_light_pixels = 0;
  r.refined = refineDepth(sceneForRefinement(scene, &street_light_pixels), refine_options);
  if (!r.refined.steps.empty()) {
    r.refined.steps.front().add("street_light_pixels_relabelled", street_light_pixels);
    if (street_light_pixels > 0)
      r.refined.steps.front().notes.push_back(
          std::to_string(street_light_pixels) +
          " street-light pixels given an instance of their own lamp (class 17, pole) for the depth filter and "
          "the mesh: the light map outlines a lamp better than the instance map");
  }
  const DepthRefinementResult& refined = r.refined;
  for (const StageReport& step : refined.steps) stages.push_back(step);
  if (!o.refine) stages.back().notes.push_back("refinement switched off (--no-refine): upsampling only");

  // mesh
  say("mesh ... ");
  DepthMeshCleanupOptions mesh_options;
  mesh_options.close_solids = o.solids;
  mesh_options.backdrops = o.backdrops;
  mesh_options.evaluate = o.evaluate_mesh;
  mesh_options.fill_holes = extras.fill_holes;
  mesh_options.hole_filling.max_fair_vertices = extras.max_fair_vertices;
  StageReport mesh_report;
  const cv::Mat mesh_depth_m =
      o.mesh_downsample > 1 ? downsampleDepth(refined.depth_m, o.mesh_downsample) : refined.depth_m;
  r.mesh =
      meshFromScene(mesh_depth_m, scene.camera, refined.maps.instances, refined.uncertain, mesh_options, mesh_report);
  if (o.mesh_downsample > 1) {
    char note[160];
    std::snprintf(note, sizeof note, "mesh made from the refined depth downsampled %dx (%dx%d): --mesh-downsample",
                  o.mesh_downsample, mesh_depth_m.cols, mesh_depth_m.rows);
    mesh_report.notes.push_back(note);
  }
  if (!o.evaluate_mesh)
    mesh_report.notes.push_back("mesh quality counts (self-intersections, manifoldness) not evaluated: they cost more "
                                "than the rest of the stage; --evaluate-mesh, or solo eval mesh, gives them");
  stages.push_back(mesh_report);
  const DepthMesh& mesh = r.mesh;

  // lights: a new draw, or the user's edited record
  say("lights ... ");
  LightRecord& record = r.record;
  if (o.lights_record) {
    const Stopwatch clock;
    record = readLightRecord(*o.lights_record);
    StageReport lights_report;
    lights_report.name = "lights";
    lights_report.seconds = clock.seconds();
    lights_report.add("lights", static_cast<std::int64_t>(record.tree.lights.size()));
    lights_report.notes.push_back("light record read from " + o.lights_record->string() + " (not drawn)");
    stages.push_back(lights_report);
  } else {
    LightStageOptions light_options;
    light_options.instantiation.seed = o.seed;
    light_options.instantiation.ablation = o.ablation;
    light_options.illuminant_table = extras.illuminant_table.empty() ? defaultIlluminantTable() : extras.illuminant_table;
    LightStageResult lights = runLightStage(scene, refined.depth_m, light_options);
    record = std::move(lights.record);
    stages.push_back(lights.report);
  }

  // scene for the renderer
  NightSceneOptions scene_options;
  scene_options.headlights = o.headlights;
  scene_options.headlight_flux_lm = o.headlight_flux_lm;
  NightScene night = buildNightScene(mesh, refined.maps.albedo, refined.maps.roughness, scene.image, record, scene_options);
  stages.push_back(night.report);
  return night;
}

NightPipelineResult runNightPipeline(const Scene& scene, const NightOptions& o, const NightPipelineExtras& extras) {
  NightPipelineResult r;
  const NightScene night = runNightSceneStages(scene, o, extras, r);
  std::vector<StageReport>& stages = r.stages;

  // render
  if (extras.say) extras.say("render\n");
  PathTracerOptions tracer;
  tracer.seed = o.seed;
  tracer.light_sampler = lightSamplerOption(o);
  tracer.sampler = samplerOption(o);
  tracer.progress = extras.progress;
  tracer.min_samples = o.min_samples;
  tracer.max_samples = o.max_samples;
  tracer.relative_error = o.relative_error;
  tracer.max_bounces = o.max_bounces;
  tracer.indirect_clamp = static_cast<float>(o.indirect_clamp_cd_m2);
  const PinholeCamera image_camera = night.scene.camera;
  const PinholeCamera render_camera =
      o.render_downsample > 1 ? image_camera.scaledTo(std::max(16, image_camera.width / o.render_downsample),
                                                      std::max(16, image_camera.height / o.render_downsample))
                              : image_camera;
  const PreparedRenderScene prepared(night.scene);  // one BVH for the preview and the render
  // The night camera meters a small preview before the full render, whatever the preset: the
  // exposure does not depend on the render's samples, and --noise-target sets its target from it.
  const bool auto_white = !(o.sensor_white_cd_m2 > 0);
  const MeteredCamera metered = meterNightCamera(prepared, render_camera, tracer, o);
  const NightCameraExposure& camera = metered.exposure;
  const double preview_seconds = metered.preview_seconds;
  const double sensor_white = camera.white_cd_m2;
  const std::string exposure_note = exposureNote(camera, metered.preview_size);
  PostProcessOptions post;
  post.glare = o.glare;
  post.noise = o.noise;
  post.noise_options.seed = o.seed;
  post.noise_options.iso = camera.camera.iso;
  post.noise_options.std_scale = o.noise_scale;
  // --noise-target: stop where render noise is below noise_factor x the sensor noise the pixel
  // will get at that exposure.
  std::string render_note = exposure_note;
  if (o.noise_target && o.noise) {
    tracer.noise_sigma = renderNoiseSigma(sensor_white, post);
    tracer.noise_factor = o.noise_factor;
    tracer.shadow_roulette = o.shadow_roulette;
    tracer.relative_error = 0;  // the sensor's noise is the target now; max_samples still caps
    char note[128];
    std::snprintf(note, sizeof note, "noise-matched target: standard error <= %.2f x sensor noise sigma; ", o.noise_factor);
    render_note = note + exposure_note;
  }
  r.rendered = renderPathTraced(prepared, render_camera, tracer);
  RenderOutput& rendered = r.rendered;
  stages.push_back(rendered.report);
  stages.back().add("render_width", render_camera.width, "px").add("render_height", render_camera.height, "px");
  // The BVH and the exposure preview belong to the render's time.
  stages.back().add("prepare_seconds", prepared.prepareSeconds(), "s");
  stages.back().seconds += prepared.prepareSeconds();
  if (preview_seconds > 0) {
    stages.back().add("preview_seconds", preview_seconds, "s");
    stages.back().seconds += preview_seconds;
  }
  if (!render_note.empty()) stages.back().notes.push_back(render_note);
  if (o.noise_target && !o.noise)
    stages.back().notes.push_back(
        "noise-matched target skipped: sensor noise is off (--no-noise), the relative-error target applies");
  StageReport& render_report = stages.back();

  // denoise: the render's Monte Carlo noise, edge-aware, at the render's own size (before any
  // upsampling: cheaper, and the upsampled pixels would not be independent) (render_denoise.h)
  RenderDenoiseOptions denoise;
  denoise.enabled = o.denoise;
  StageReport denoise_report = denoiseRender(rendered, render_camera, denoise);
  if (!o.denoise) denoise_report.skip_reason = "render denoising switched off (--no-denoise)";

  if (o.render_downsample > 1) {
    rendered = upsampleRender(std::move(rendered), cv::Size(image_camera.width, image_camera.height));
    char note[160];
    std::snprintf(note, sizeof note, "rendered at %dx%d and upsampled to %dx%d (bilinear): --render-downsample %d",
                  render_camera.width, render_camera.height, image_camera.width, image_camera.height,
                  o.render_downsample);
    render_report.notes.push_back(note);
  }
  stages.push_back(std::move(denoise_report));

  // post: radiance in cd/m^2 scaled so that the reference exposure (+3.25 stops) puts
  // sensor_white at 1. Only what will clip (above the knee's white clip) glows; the reference
  // lets every pixel glow.
  post.glare_options.scatter_fraction = o.glare_scatter;
  post.encoding_options.white_clip = o.white_clip;
  post.encoding_options.knee_point = o.knee_point;
  const double calibration = 1.0 / (sensor_white * exposureScale(post.exposure_options));
  post.glare_options.threshold =
      o.glare_threshold >= 0 ? o.glare_threshold : o.white_clip / exposureScale(post.exposure_options);
  cv::Mat xyz = rendered.radiance * calibration;
  r.developed = postProcess(xyz, post);
  const PostProcessResult& developed = r.developed;
  r.sensor_white_cd_m2 = sensor_white;
  StageReport post_report = developed.report;
  post_report.add("sensor_white", sensor_white, "cd/m2").add("sensor_white_auto", auto_white);
  post_report.add("camera_iso", camera.camera.iso)
      .add("camera_shutter", camera.camera.shutter_s, "s")
      .add("camera_f_number", camera.camera.f_number)
      .add("camera_at_exposure_limit", camera.at_exposure_limit);
  if (auto_white) post_report.add("metered_mean_luminance", camera.metered_cd_m2, "cd/m2");
  if (!o.glare) post_report.notes.push_back("glare switched off (--no-glare)");
  if (!o.noise) post_report.notes.push_back("sensor noise switched off (--no-noise)");
  for (const StageReport& step : developed.steps)
    if (o.glare && step.name == "glare" && step.skipped)
      post_report.notes.push_back("no light above glare threshold: glare skipped");
  stages.push_back(post_report);

  return r;
}

}  // namespace solo::tools
