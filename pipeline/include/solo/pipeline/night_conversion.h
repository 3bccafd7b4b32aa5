#pragma once
// The night conversion after the scene is read: refine -> mesh -> lights -> night scene ->
// render -> denoise -> post. `solo night`, `solo bench` and the Cycles exporter run this one
// sequence, so a preset measured by a benchmark is the preset users run.

#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/geometry/depth_mesh.h>
#include <solo/geometry/depth_refinement.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/lighting/light_record.h>
#include <solo/lighting/light_proposals.h>
#include <solo/lighting/light_stage.h>
#include <solo/post/exposure.h>
#include <solo/post/post_process.h>
#include <solo/render/night_scene.h>
#include <solo/render/path_tracer.h>
#include <solo/render/render_denoise.h>
#include <solo/render/render_upsample.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace solo {

/// A mesh_downsample or render_downsample that resolveDownsample chooses from the image size.
inline constexpr int kAutoDownsample = 0;
/// The image size above which kAutoDownsample downsamples: 1 megapixel (1280x720 stays whole,
/// 1920x1080 and Cityscapes' 2048x1024 are halved, 3840x2160 divided by 3).
inline constexpr double kAutoDownsampleMaxPixels = 1.0e6;

/// Every setting of the night conversion, composed of the stage option structs. A
/// default-constructed value is the `default` preset (night_presets.h); where the conversion
/// wants other values than a stage's own defaults, the constructor sets them (and says why).
struct NightConversionOptions {
  NightConversionOptions();

  /// Seeds the light draw, the render and the sensor noise (copied into lights.instantiation,
  /// render and post.noise_options when the conversion runs).
  std::uint64_t seed = 0;

  /// The least share of the depth map's pixels that must hold a depth. Depth completion
  /// (refinement.completion) densifies anything above it, projected LiDAR's 2-5 % included;
  /// below it the depth is too sparse to say where surfaces are, and the conversion refuses
  /// the scene, naming the share. 0 to 1.
  double min_depth_share = 0.01;

  /// Depth refinement (filter, uncertain regions, optimisation) on; false: upsampling and
  /// completion only.
  bool refine = true;
  DepthRefinementOptions refinement;

  /// The mesh is made from the refined depth downsampled by this factor (1: every pixel a
  /// vertex; downsample_depth.h). 1 to 8, or kAutoDownsample (resolveDownsample).
  int mesh_downsample = kAutoDownsample;
  DepthMeshCleanupOptions mesh;

  /// An (edited) light record to use instead of a new draw; none: draw from the light map.
  std::optional<std::filesystem::path> light_record;
  /// A scene without a light map gets proposed lights (street lights, traffic lights, vehicle
  /// lamps, windows; lighting/light_proposals.h) from its labels, day image and depth; the
  /// report's "light_proposals" stage says so. false: such a scene has only the headlights.
  bool propose_lights = true;
  LightProposalOptions proposals;
  /// The light draw; an empty illuminant_table is the bundled table (data_dir.h).
  LightStageOptions lights;

  NightSceneOptions night_scene;

  /// The path tracer. Its seed and progress are set by the conversion (seed; progress from
  /// the callbacks).
  PathTracerOptions render;
  /// Adaptive sampling to the sensor noise: a pixel stops once its standard error is below
  /// render.noise_factor x the sensor noise's sigma there (render.relative_error is then
  /// ignored); only with post.noise on. docs/rendering.md.
  bool noise_target = true;
  /// The path tracer renders at the image size divided by this factor; after denoising the
  /// render is upsampled with the image's texture (render_upsample.h). 1 to 8, or
  /// kAutoDownsample (resolveDownsample).
  int render_downsample = kAutoDownsample;
  RenderDenoiseOptions denoise;
  RenderUpsampleOptions upsample;

  /// Luminance exposed to sensor white, cd/m^2; <= 0: the night camera meters the scene.
  double sensor_white_cd_m2 = 0;
  NightCameraOptions camera;
  /// Glare, sensor noise (its ISO comes from the camera), adaptation and colour encoding.
  PostProcessOptions post;
};

/// The factor `requested` stands for at an image of width x height pixels: itself when >= 1;
/// for kAutoDownsample the smallest factor f with (width / f) x (height / f) <= 
/// kAutoDownsampleMaxPixels (at most 8).
int resolveDownsample(int requested, int width, int height);

/// What a caller hears while the conversion runs; every member may be empty.
struct NightConversionCallbacks {
  std::function<void(const std::string& stage)> stage_started;  ///< "refine", "mesh", ...
  bool render_progress = true;  ///< the path tracer's progress bar (on a terminal)
};

struct NightConversionResult {
  DepthRefinementResult refined;
  DepthMesh mesh;
  LightRecord record;
  RenderOutput rendered;          ///< at the image size (upsampled after render_downsample)
  PostProcessResult developed;    ///< the night image
  double sensor_white_cd_m2 = 0;  ///< the exposure used (metered or given)
  std::vector<StageReport> stages;  ///< refine steps, mesh, lights, scene, render, denoise, post
};

/// Throws InputError naming the setting for a value the conversion cannot run with (negative
/// samples, a downsample factor outside 1..8, non-finite numbers, ...), before any work.
void validateNightConversionOptions(const NightConversionOptions& options);

/// The scene the depth refinement and the mesh stage see: `scene` with each street light an
/// instance of its own in the instance map (streetLightsAsPoles; the light map outlines a lamp
/// better than an estimated segmentation does). `changed` receives the pixels changed.
Scene sceneForRefinement(const Scene& scene, std::int64_t* changed = nullptr);

/// The stages before the render (refine, mesh, lights, night scene): fills result.refined,
/// .mesh, .record and appends to result.stages; returns the scene to render. The Cycles
/// exporter (tests/benchmarks/blender) stops here.
NightScene runNightSceneStages(const Scene& scene, const NightConversionOptions& options,
                               const NightConversionCallbacks& callbacks, NightConversionResult& result);

/// Throws InputError naming the depth file when less than options.min_depth_share of the depth
/// map's pixels hold a depth (too sparse for depth completion).
void requireDenseDepth(const Scene& scene, const NightConversionOptions& options);

/// The whole conversion of a loaded scene; checks the options and requireDenseDepth first.
NightConversionResult runNightConversion(const Scene& scene, const NightConversionOptions& options,
                                         const NightConversionCallbacks& callbacks = {});

}  // namespace solo
