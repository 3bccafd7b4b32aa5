// The night conversion's stages after the input (night_conversion.h).

#include <solo/pipeline/night_conversion.h>

#include <solo/core/error.h>
#include <solo/geometry/downsample_depth.h>
#include <solo/lighting/street_light_instances.h>
#include <solo/pipeline/data_dir.h>
#include <solo/post/sensor_noise.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <new>

namespace solo {

NightConversionOptions::NightConversionOptions() {
  // Self-intersection and manifoldness counts cost more than the rest of the mesh stage.
  mesh.evaluate = false;
  // A night image is judged beside the sensor noise it gets: 2 to 4 samples per pixel, stopped
  // at the sensor noise (noise_target), the denoiser taking the rest; power-proportional light
  // choice (docs/presets.md).
  render.min_samples = 2;
  render.max_samples = 4;
  render.relative_error = 0.1;
  render.noise_factor = 1;
  render.shadow_roulette = 0.3;
  render.light_sampler = LightSamplerKind::Power;
  // Near-field light selection removes rare bright samples beside lamps, which the image clips
  // at white and the denoiser's firefly clamp bounds anyway: on the default scene it gave the
  // same clipped error for 1.1-1.2x the render time (docs/rendering.md, "Light selection").
  render.near_field_lights = false;
  render.seed = 0;
  // The night camera: -2.2 EV night-mode compensation, sensor noise at 0.9 of the calibration at
  // the chosen ISO, a video knee up to 8x white, glare only from what clips
  // (docs/post-processing.md, docs/realism.md).
  camera.compensation_ev = -2.2;
  post.noise_options.std_scale = 0.9;
  post.glare_options.scatter_fraction = 0.02;
  post.encoding_options.white_clip = 8;
  post.encoding_options.knee_point = 0.7;
}

namespace {

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

// The camera's limits with the shortest shutter and lowest ISO kept below the longest and highest.
NightCameraOptions consistentCameraLimits(NightCameraOptions camera) {
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
/// kMeteringSamplesPerPixel) of `render_camera`'s view, or derived from sensor_white_cd_m2.
MeteredCamera meterNightCamera(const PreparedRenderScene& prepared, const PinholeCamera& render_camera,
                               const PathTracerOptions& tracer, const NightConversionOptions& o) {
  const NightCameraOptions limits = consistentCameraLimits(o.camera);
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

void announce(const NightConversionCallbacks& callbacks, const std::string& stage) {
  if (callbacks.stage_started) callbacks.stage_started(stage);
}

// refine: upsampling always (every later stage works at the image resolution).
void runRefineStage(const Scene& scene, const NightConversionOptions& o, NightConversionResult& r) {
  DepthRefinementOptions refine_options = o.refinement;
  refine_options.filter = o.refine && refine_options.filter;
  refine_options.uncertain_regions = o.refine && refine_options.uncertain_regions;
  refine_options.optimize = o.refine && refine_options.optimize;
  // The mesh is made at a reduced size: the optimisation that feeds it runs at that size too.
  refine_options.optimization_downsample = resolveDownsample(o.mesh_downsample, scene.width(), scene.height());
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
  for (const StageReport& step : r.refined.steps) r.stages.push_back(step);
  if (!o.refine) r.stages.back().notes.push_back("refinement switched off (--no-refine): upsampling and completion only");
}

// Replaces `mesh` with make()'s result, constructed where `mesh` lives: OpenMesh meshes have no
// move assignment, so assigning the result would copy every array of a 1080p mesh (about half a
// second) and then free the temporary. `mesh` is left empty when make() throws.
template <typename Make>
void buildInPlace(DepthMesh& mesh, const Make& make) {
  mesh.~DepthMesh();
  try {
    new (&mesh) DepthMesh(make());
  } catch (...) {
    new (&mesh) DepthMesh();
    throw;
  }
}

// A downsample option as the user gave it: the factor, or 0 (auto) and why it downsamples.
std::string downsampleSetting(int requested) {
  return requested == kAutoDownsample ? "0 (auto: the image is above 1 megapixel)" : std::to_string(requested);
}

void runMeshStage(const Scene& scene, const NightConversionOptions& o, NightConversionResult& r) {
  const DepthRefinementResult& refined = r.refined;
  StageReport mesh_report;
  const int factor = resolveDownsample(o.mesh_downsample, refined.depth_m.cols, refined.depth_m.rows);
  const cv::Mat mesh_depth_m = factor > 1 ? downsampleDepth(refined.depth_m, factor) : refined.depth_m;
  buildInPlace(r.mesh, [&] {
    return meshFromScene(mesh_depth_m, scene.camera, refined.maps.instances, refined.uncertain, o.mesh, mesh_report);
  });
  mesh_report.add("mesh_downsample", factor);
  if (factor > 1) {
    char note[200];
    std::snprintf(note, sizeof note, "mesh made from the refined depth downsampled %dx (%dx%d): --mesh-downsample %s",
                  factor, mesh_depth_m.cols, mesh_depth_m.rows, downsampleSetting(o.mesh_downsample).c_str());
    mesh_report.notes.push_back(note);
  }
  if (!o.mesh.evaluate)
    mesh_report.notes.push_back("mesh quality counts (self-intersections, manifoldness) not evaluated: they cost more "
                                "than the rest of the stage; --evaluate-mesh, or solo eval mesh, gives them");
  r.stages.push_back(mesh_report);
}

// lights: a new draw, or the user's edited record.
void runLightsStage(const Scene& scene, const NightConversionOptions& o, NightConversionResult& r) {
  if (o.light_record) {
    const Stopwatch clock;
    r.record = readLightRecord(*o.light_record);
    StageReport lights_report;
    lights_report.name = "lights";
    lights_report.seconds = clock.seconds();
    lights_report.add("lights", static_cast<std::int64_t>(r.record.tree.lights.size()));
    lights_report.notes.push_back("light record read from " + o.light_record->string() + " (not drawn)");
    r.stages.push_back(lights_report);
    return;
  }
  LightStageOptions light_options = o.lights;
  light_options.instantiation.seed = o.seed;
  if (light_options.illuminant_table.empty()) light_options.illuminant_table = defaultIlluminantTable();
  LightStageResult lights = runLightStage(scene, r.refined.depth_m, light_options);
  r.record = std::move(lights.record);
  r.stages.push_back(lights.report);
}

// The render camera: the image's, divided by render_downsample (at least 16 px a side).
PinholeCamera renderCamera(const PinholeCamera& image_camera, int render_downsample) {
  if (render_downsample <= 1) return image_camera;
  return image_camera.scaledTo(std::max(16, image_camera.width / render_downsample),
                               std::max(16, image_camera.height / render_downsample));
}

// render: the night camera meters a small preview before the full render, whatever the preset:
// the exposure does not depend on the render's samples, and noise_target sets its target from it.
MeteredCamera runRenderStage(const NightScene& night, const PinholeCamera& render_camera,
                             const NightConversionOptions& o, const NightConversionCallbacks& callbacks,
                             const PostProcessOptions& post, NightConversionResult& r) {
  PathTracerOptions tracer = o.render;
  tracer.seed = o.seed;
  tracer.progress = callbacks.render_progress;
  const PreparedRenderScene prepared(night.scene);  // one BVH for the preview and the render
  const MeteredCamera metered = meterNightCamera(prepared, render_camera, tracer, o);
  const std::string exposure_note = exposureNote(metered.exposure, metered.preview_size);
  // noise_target: stop where render noise is below noise_factor x the sensor noise the pixel
  // will get at that exposure.
  std::string render_note = exposure_note;
  const bool noise_target = o.noise_target && o.post.noise;
  if (noise_target) {
    PostProcessOptions at_exposure = post;
    at_exposure.noise_options.iso = metered.exposure.camera.iso;
    tracer.noise_sigma = renderNoiseSigma(metered.exposure.white_cd_m2, at_exposure);
    tracer.relative_error = 0;  // the sensor's noise is the target; max_samples still caps
    char note[128];
    std::snprintf(note, sizeof note, "noise-matched target: standard error <= %.2f x sensor noise sigma; ",
                  tracer.noise_factor);
    render_note = note + exposure_note;
  } else {
    tracer.shadow_roulette = 0;  // shadow roulette is relative to the sensor noise
  }
  r.rendered = renderPathTraced(prepared, render_camera, tracer);
  StageReport& report = r.stages.emplace_back(r.rendered.report);
  report.add("render_width", render_camera.width, "px").add("render_height", render_camera.height, "px");
  // The BVH and the exposure preview belong to the render's time.
  report.add("prepare_seconds", prepared.prepareSeconds(), "s");
  report.seconds += prepared.prepareSeconds();
  if (metered.preview_seconds > 0) {
    report.add("preview_seconds", metered.preview_seconds, "s");
    report.seconds += metered.preview_seconds;
  }
  if (!render_note.empty()) report.notes.push_back(render_note);
  if (o.noise_target && !o.post.noise)
    report.notes.push_back(
        "noise-matched target skipped: sensor noise is off (--no-noise), the relative-error target applies");
  return metered;
}

// denoise: the render's Monte Carlo noise, edge-aware, at the render's own size (before any
// upsampling: cheaper, and the upsampled pixels would not be independent) (render_denoise.h);
// then the upsampling to the image size with the image's texture (render_upsample.h).
void runDenoiseStage(const NightScene& night, const PinholeCamera& render_camera, const NightConversionOptions& o,
                     NightConversionResult& r) {
  StageReport& render_report = r.stages.back();
  StageReport denoise_report = denoiseRender(r.rendered, render_camera, o.denoise);
  if (!o.denoise.enabled) denoise_report.skip_reason = "render denoising switched off (--no-denoise)";
  const PinholeCamera& image_camera = night.scene.camera;
  const cv::Size image_size(image_camera.width, image_camera.height);
  if (r.rendered.radiance.size() != image_size) {
    const Stopwatch clock;
    UpsampleGuides guides;
    if (r.refined.depth_m.size() == image_size && night.reflectance.size() == image_size) {
      guides.reflectance = night.reflectance;
      guides.depth_m = r.refined.depth_m;
      const std::vector<std::uint8_t>& surface_pixels = night.scene.surface_pixels;
      if (surface_pixels.size() == static_cast<std::size_t>(image_size.area()))
        guides.surface = cv::Mat(image_size, CV_8U, const_cast<std::uint8_t*>(surface_pixels.data()));
      if (night.light_id.size() == image_size) guides.light_id = night.light_id;
    }
    const bool texture = o.upsample.texture && !guides.reflectance.empty();
    r.rendered = upsampleRender(r.rendered, image_size, guides, o.upsample, &render_report);
    render_report.add("upsample_seconds", clock.seconds(), "s");
    render_report.seconds += clock.seconds();
    char note[240];
    std::snprintf(note, sizeof note, "rendered at %dx%d and upsampled to %dx%d (%s): --render-downsample %s",
                  render_camera.width, render_camera.height, image_camera.width, image_camera.height,
                  texture ? "the image's texture times the render's irradiance" : "bilinear",
                  downsampleSetting(o.render_downsample).c_str());
    render_report.notes.push_back(note);
  }
  r.stages.push_back(std::move(denoise_report));
}

// post: radiance in cd/m^2 scaled so that the reference exposure (+3.25 stops) puts the sensor
// white at 1. Only what will clip (above the knee's white clip) glows; the reference lets every
// pixel glow.
void runPostStage(const MeteredCamera& metered, const NightConversionOptions& o, PostProcessOptions post,
                  NightConversionResult& r) {
  const NightCameraExposure& camera = metered.exposure;
  const double sensor_white = camera.white_cd_m2;
  const bool auto_white = !(o.sensor_white_cd_m2 > 0);
  post.noise_options.iso = camera.camera.iso;
  const double calibration = 1.0 / (sensor_white * exposureScale(post.exposure_options));
  cv::Mat xyz = r.rendered.radiance * calibration;
  r.developed = postProcess(xyz, post);
  r.sensor_white_cd_m2 = sensor_white;
  StageReport post_report = r.developed.report;
  post_report.add("sensor_white", sensor_white, "cd/m2").add("sensor_white_auto", auto_white);
  post_report.add("camera_iso", camera.camera.iso)
      .add("camera_shutter", camera.camera.shutter_s, "s")
      .add("camera_f_number", camera.camera.f_number)
      .add("camera_at_exposure_limit", camera.at_exposure_limit);
  if (auto_white) post_report.add("metered_mean_luminance", camera.metered_cd_m2, "cd/m2");
  if (!post.glare) post_report.notes.push_back("glare switched off (--no-glare)");
  if (!post.noise) post_report.notes.push_back("sensor noise switched off (--no-noise)");
  for (const StageReport& step : r.developed.steps)
    if (post.glare && step.name == "glare" && step.skipped)
      post_report.notes.push_back("no light above glare threshold: glare skipped");
  r.stages.push_back(post_report);
}

void requireInRange(double value, double low, double high, const char* setting) {
  if (!(value >= low && value <= high)) {
    char range[96];
    std::snprintf(range, sizeof range, "must be within [%g, %g], got %g", low, high, value);
    throw InputError(setting, range);
  }
}

}  // namespace

int resolveDownsample(int requested, int width, int height) {
  if (requested != kAutoDownsample) return requested;
  int factor = 1;
  for (; factor < 8; ++factor) {
    const int map_width = width / factor, map_height = height / factor;  // whole pixels
    if (static_cast<double>(map_width) * map_height <= kAutoDownsampleMaxPixels) break;
  }
  return factor;
}

void validateNightConversionOptions(const NightConversionOptions& o) {
  requireInRange(o.min_depth_share, 0, 1, "--min-depth-share");
  requireInRange(o.mesh_downsample, kAutoDownsample, 8, "--mesh-downsample");
  requireInRange(o.render_downsample, kAutoDownsample, 8, "--render-downsample");
  requireInRange(o.render.min_samples, 1, 1 << 20, "--min-spp");
  requireInRange(o.render.max_samples, 1, 1 << 20, "--max-spp");
  if (o.render.min_samples > o.render.max_samples)
    throw InputError("--min-spp", "is " + std::to_string(o.render.min_samples) + ", more than --max-spp " +
                                      std::to_string(o.render.max_samples) + " (a preset sets both; give both)");
  requireInRange(o.render.relative_error, 0, 1e6, "--relative-error");
  requireInRange(o.render.noise_factor, 0, 1e6, "--noise-factor");
  requireInRange(o.render.shadow_roulette, 0, 1, "--shadow-roulette");
  requireInRange(o.render.max_bounces, 1, 64, "--max-bounces");
  requireInRange(o.render.indirect_clamp, 0, 1e30, "--indirect-clamp");
  requireInRange(o.denoise.firefly_sigma, 0, 1e30, "--firefly-sigma");
  requireInRange(o.denoise.iterations, 1, 10, "--denoise-passes");
  requireInRange(o.denoise.fine_passes, 0, 10, "--denoise-fine-passes");
  requireInRange(o.refinement.optimization.max_iterations, 1, 100000, "--optimize-iterations");
  requireInRange(o.refinement.optimization.function_tolerance, 0, 1, "--optimize-tolerance");
  requireInRange(o.night_scene.headlight_flux_lm, 0, 1e9, "--headlight-flux");
  requireInRange(o.sensor_white_cd_m2, -1e30, 1e30, "--sensor-white");
  requireInRange(o.camera.f_number, 0.5, 64, "--camera-f-number");
  requireInRange(o.camera.max_shutter_s, 1e-4, 30, "--camera-max-shutter");
  requireInRange(o.camera.max_iso, 100, 3200, "--camera-max-iso");
  requireInRange(o.camera.compensation_ev, -6, 6, "--camera-compensation");
  requireInRange(o.post.noise_options.std_scale, 0, 10, "--noise-scale");
  requireInRange(o.post.encoding_options.white_clip, 1, 64, "--white-clip");
  requireInRange(o.post.encoding_options.knee_point, 0.05, 0.99, "--knee-point");
  requireInRange(o.post.glare_options.scatter_fraction, 1e-6, 1, "--glare-scatter");
  requireInRange(o.post.glare_options.threshold, -1e30, 1e30, "--glare-threshold");
}

void requireDenseDepth(const Scene& scene, const NightConversionOptions& o) {
  const double pixels = static_cast<double>(scene.depth_m.total());
  const double share = pixels > 0 ? static_cast<double>(scene.depth_stats.valid) / pixels : 0.0;
  if (share >= o.min_depth_share) return;
  char problem[320];
  std::snprintf(problem, sizeof problem,
                "only %.2f %% of the depth map's pixels hold a depth, below the %g %% from which depth completion "
                "can densify it (a LiDAR projected into the image covers 2-5 %%; densify it first, or lower "
                "--min-depth-share; docs/scene-format.md)",
                100.0 * share, 100.0 * o.min_depth_share);
  throw InputError(scene.manifest.depth, problem);
}

Scene sceneForRefinement(const Scene& scene, std::int64_t* changed) {
  Scene out = scene;  // cv::Mat copies share their pixels; only the instance map is new
  out.instances = streetLightsAsPoles(scene.instances, scene.lights, changed);
  return out;
}

// `scene`, or with proposed lights when it has no light map and the options ask for them.
Scene sceneWithLights(const Scene& scene, const NightConversionOptions& o, const NightConversionCallbacks& callbacks,
                      NightConversionResult& r) {
  if (!o.propose_lights || !scene.lights.empty() || o.light_record || scene.labels.empty()) return scene;
  announce(callbacks, "light_proposals");
  LightProposalResult proposed = proposeLights(scene, o.proposals);
  proposed.report.notes.insert(proposed.report.notes.begin(),
                               "the scene has no light map: " + std::to_string(proposed.proposals.size()) +
                                   " lights proposed from its labels, day image and depth (docs/lighting.md, "
                                   "\"Proposals\"; --no-propose-lights: headlights only)");
  r.stages.push_back(proposed.report);
  return withProposedLights(scene, proposed);
}

NightScene runNightSceneStages(const Scene& given_scene, const NightConversionOptions& o,
                               const NightConversionCallbacks& callbacks, NightConversionResult& r) {
  const Scene scene = sceneWithLights(given_scene, o, callbacks, r);
  announce(callbacks, "refine");
  runRefineStage(scene, o, r);
  announce(callbacks, "mesh");
  runMeshStage(scene, o, r);
  announce(callbacks, "lights");
  runLightsStage(scene, o, r);
  // scene for the renderer
  NightScene night =
      buildNightScene(r.mesh, r.refined.maps.albedo, r.refined.maps.roughness, scene.image, r.record, o.night_scene,
                      r.refined.normals);
  r.stages.push_back(night.report);
  return night;
}

NightConversionResult runNightConversion(const Scene& scene, const NightConversionOptions& o,
                                         const NightConversionCallbacks& callbacks) {
  validateNightConversionOptions(o);
  requireDenseDepth(scene, o);
  NightConversionResult r;
  const NightScene night = runNightSceneStages(scene, o, callbacks, r);
  announce(callbacks, "render");
  PostProcessOptions post = o.post;
  post.noise_options.seed = o.seed;
  const PinholeCamera image_camera = night.scene.camera;
  const PinholeCamera render_camera =
      renderCamera(image_camera, resolveDownsample(o.render_downsample, image_camera.width, image_camera.height));
  const MeteredCamera metered = runRenderStage(night, render_camera, o, callbacks, post, r);
  announce(callbacks, "denoise");
  runDenoiseStage(night, render_camera, o, r);
  announce(callbacks, "post");
  runPostStage(metered, o, post, r);
  return r;
}

}  // namespace solo
