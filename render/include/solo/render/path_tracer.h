#pragma once
// A CPU path tracer for a RenderScene: next-event estimation with multiple importance
// sampling (power heuristic) against BSDF sampling, Russian roulette, a bounce limit,
// per-pixel adaptive sampling, TBB over tiles. Deterministic for a seed whatever the
// thread count: every pixel draws from its own sample stream (sampler.h).

#include "solo/render/light_sampler.h"
#include "solo/render/render_scene.h"
#include "solo/render/sampler.h"
#include "solo/render/surface_bsdf.h"

#include <solo/core/report.h>

#include <opencv2/core.hpp>

#include <cstdint>
#include <functional>
#include <vector>
#include <memory>

namespace solo {

/// One ray as the tracer cast it, for replaying the same rays through bare Embree calls
/// (bench_render's efficiency line): closest-hit rays from t = 0 to infinity, shadow rays
/// (occlusion only) from t = 0 to t_far, metres.
struct RecordedRay {
  Eigen::Vector3f origin, direction;
  float t_far = 0.f;
  bool shadow = false;
};

/// How adaptive sampling (min_samples < max_samples) spends its samples.
enum class AdaptiveRule {
  /// relative_error is a target for the image's relative RMSE: a pilot render at a quarter of the
  /// resolution gives the image's scale, then every pixel takes, after its min_samples, a count
  /// half even, half proportional to its neighbours' per-sample standard deviation (the
  /// allocation that minimises the summed squared error for a total, hedged against spreads
  /// that min_samples underestimates; docs/rendering.md, "Adaptive sampling"). A target the
  /// pilot meets below min_samples (>= 4) spreads the min_samples budget the same way after
  /// min_samples / 2 a pixel, instead of sampling every pixel evenly. Applies when
  /// relative_error is the only target (no absolute_error, no noise_sigma); otherwise, and with
  /// relative_error 0, PixelThreshold.
  ImageError,
  /// Each pixel stops once its standard error is below its own target (max of relative_error x
  /// mean, absolute_error, noise_factor x noise_sigma), checked every 8 samples.
  PixelThreshold,
};

/// Which part of each sample's light the render keeps (PathTracerOptions::component).
enum class PathComponent {
  All,
  /// Light scattered at most once: emission the camera ray's hit shows, and light reaching that
  /// hit straight from an emitter, a headlight, the sky or the sun (next-event estimation and the
  /// first bounce's emitter and sky hits).
  Direct,
  /// Light scattered twice or more: All minus Direct, sample by sample (indirect_clamp applies).
  Indirect,
};

/// The path tracer's settings. Its defaults are the renderer's on its own (converged reference
/// renders, benchmarks, tests); the night conversion's are set once in NightConversionOptions
/// (pipeline/night_conversion.h: 2 to 8 spp to the sensor noise, power light sampling, seed 0).
struct PathTracerOptions {
  /// Per pixel before the error estimate is trusted; at least 2 are taken. The image-error rule
  /// spreads min_samples x pixels when its target needs fewer (AdaptiveRule::ImageError).
  int min_samples = 16;
  /// Camera samples stay within the outermost pixel centres (1/64 px inside): a depth mesh ends
  /// there, and the outer half of each frame pixel would otherwise see nothing behind it.
  bool film_within_pixel_centres = true;
  /// Mesh cracks: in a pixel that RenderScene::surface_pixels marks as a surface, a camera
  /// sample that hits nothing went through the gap between a near sheet's silhouette and the
  /// sheet behind it; it is not counted, so the pixel's value is the mean over the part of it
  /// that shows a surface (instead of darkened toward the black sky). A marked pixel none of
  /// whose samples hit takes the value and AOVs of its farthest neighbour that has a hit (up to
  /// kCrackFillPasses rings). Off: every sample counts, as in a plain mesh render.
  bool cover_mesh_cracks = true;
  /// A render at the size of RenderScene's pixel texture shades camera rays that hit a face
  /// made from their own pixel with that pixel's texel (render_scene.h): edges between materials
  /// and lights are the pixels' own, not the mesh quads' diagonals. Off: every hit the face's.
  bool pixel_texture = true;
  int max_samples = 256;  ///< per pixel
  AdaptiveRule adaptive_rule = AdaptiveRule::ImageError;
  /// ImageError: the target for the image's relative RMSE of Y (root of the summed squared errors
  /// over the summed squared luminance, on the pixels that see no emitter), from independent-
  /// sample variances (an upper bound with the Sobol sampler).
  /// PixelThreshold: stop a pixel when the standard error of its mean luminance (Y) is below
  /// max(relative_error * mean, absolute_error[pixel], noise_factor * noise_sigma(mean)).
  /// The standard error: with the independent sampler, sample variance / n; with the Sobol
  /// sampler (whose stratified samples make that an overestimate), the spread of the means of
  /// `error_replicates` independently scrambled point sets the samples alternate between
  /// (batch means over replicates); both are unbiased for the mean's variance. By default the
  /// replicate spread is pooled over the pixel's tile (pool_error_gain).
  double relative_error = 0.1;
  /// 1, 2, 4 or 8; used with the Sobol sampler by the PixelThreshold rule. More
  /// replicates give a less noisy error estimate but smaller, less stratified point sets; 1
  /// falls back to sample variance / n. min_samples is rounded up to a multiple of it.
  int error_replicates = 2;
  /// With replicates: a pixel's variance is its sample variance / n times the tile's
  /// stratification gain (summed replicate variances / summed sample variances / n over its
  /// 16x16 tile), which pools the tile's degrees of freedom; false: the pixel's own replicate
  /// spread (R - 1 degrees of freedom, too few to stop on: docs/rendering.md).
  bool pool_error_gain = true;
  /// Whether a pixel stops is decided from its 3x3 neighbours in the tile (their mean and
  /// per-sample variance of Y; the pixel's own sample count), not from its own samples. A pixel
  /// that stops on its own few samples stops most often when its rare bright paths have not
  /// appeared yet, so its mean is biased dark (measured: 27 % of the light lost at 4-16 spp, 47 %
  /// at 2-16, docs/rendering.md); a decision independent of its samples leaves its mean
  /// unbiased. false: the pixel's own samples (biased dark, kept for comparison).
  bool stop_on_neighbours = true;
  cv::Mat absolute_error;  ///< CV_32F per pixel, render units; empty = none
  /// Standard deviation of the noise the output will receive afterwards (the sensor noise)
  /// as a function of the pixel's mean luminance, render units; empty = none. Called from
  /// every thread: it must be thread-safe. See sensorNoiseSigma (sensor_noise.h).
  std::function<double(double mean_y)> noise_sigma;
  /// Render noise is independent of the sensor's, so the variances add: a render standard
  /// error of k sigma raises the final noise to sqrt(1 + k^2) sigma, +12 % at k = 0.5; below
  /// that, more samples buy little that can be seen.
  double noise_factor = 0.5;
  /// Shadow-ray roulette, with noise_sigma only: a next-event contribution whose largest XYZ
  /// component is below this fraction of the sensor noise at black, noise_sigma(0), casts its
  /// shadow ray with probability (that component / the threshold) and is divided by it when
  /// cast. Unbiased; a sample's variance grows by at most threshold^2 / 4 per path vertex. 0 = off.
  double shadow_roulette = 0.0;
  int max_bounces = 12;
  /// One shadow ray per path vertex, to one light chosen among the emitter sample and the
  /// rectangle lights in proportion to their unoccluded contributions (unbiased; adds only
  /// visibility variance); false: one shadow ray to each.
  bool one_shadow_ray = true;
  /// Next-event estimation samples an emitting triangle that looks large from the shading point
  /// (solid angle >= kMinSphericalSolidAngle) by solid angle, warped toward the receiver's
  /// cosine (spherical_triangle.h), which bounds the contribution next to an emitter; false:
  /// always by area.
  bool solid_angle_emitter_sampling = true;
  /// When > 0, a sample's indirect radiance (light scattered twice or more) is scaled down so
  /// that its luminance Y is at most this, render units (Cycles' "clamp indirect"). Biased
  /// (darker), but it removes the fireflies of paths that find the bright surroundings of a
  /// lamp by chance. 0 = off.
  float indirect_clamp = 0.f;
  /// The part of the light rendered: for the same seed and fixed sample counts, the Direct and
  /// Indirect images sum to the All image pixel by pixel (the same paths); for measuring where
  /// the error comes from (export_blender_scene error-sources).
  PathComponent component = PathComponent::All;
  /// Emission splitting: at a vertex whose light pick (an emitting triangle's centroid) lies
  /// within split_distance_m, the emission its bounce finds is estimated from this many BSDF
  /// directions, each casting a ray, averaged (the path goes on along the first). Next to a
  /// large emitter of many small triangles, which light sampling covers one triangle at a time,
  /// the bounce finds it as a whole; the extra directions lower that estimate's variance.
  /// Unbiased; 1 = off. On the Cycles comparison's scene, 8 within 2 m: 0.85x the error at
  /// 1.07x the time (docs/rendering.md).
  int emission_splits = 1;
  float split_distance_m = 2.f;
  int russian_roulette_after = 3;  ///< bounces before roulette starts
  LightSamplerKind light_sampler = LightSamplerKind::Hierarchy;
  /// light_sampler mixed with near-field selection (light_sampler.h): a shading point within
  /// 0.5 m of emitting triangles picks among them by distance and orientation with a
  /// probability of up to 1/2. Unbiased; false: light_sampler alone (solo night's presets).
  bool near_field_lights = true;
  /// Where the per-sample random numbers come from (sampler.h): scrambled Sobol points,
  /// stratified per pixel and dimension, or independent PCG32 values.
  SamplerKind sampler = SamplerKind::Sobol;
  DiffuseModel diffuse = DiffuseModel::Disney;
  std::uint64_t seed = 1;
  bool progress = true;  ///< a progress bar on stderr when it is a terminal
  /// When set, every ray cast is appended here (tile by tile, in the order each tile cast
  /// them; tiles in completion order). For benchmarks: it costs a store per ray.
  std::vector<RecordedRay>* ray_log = nullptr;
};

struct RenderOutput {
  cv::Mat radiance;  ///< CV_32FC3, XYZ relative to E, render units
  cv::Mat albedo;    ///< CV_32FC3 first-hit reflectance; 0 for sky
  /// CV_32FC3 first-hit reflectance averaged over the pixel's counted samples (0 for those that
  /// see sky): radiance / mean_albedo is the pixel's irradiance also where it covers several
  /// surfaces, which `albedo` (one sample's) is not.
  cv::Mat mean_albedo;
  cv::Mat normal;    ///< CV_32FC3 first-hit normal facing the camera; 0 for sky
  cv::Mat depth_m;   ///< CV_32F first-hit z-depth; 0 for sky
  cv::Mat light_id;  ///< CV_32S light id of an emitter seen directly; 0 otherwise
  /// CV_32F share of the pixel's samples whose camera ray hit an emitter (0-1): the pixels that
  /// see a light, also where it covers a sliver of the pixel (light_id is the first sample's).
  cv::Mat emitter_coverage;
  cv::Mat samples;   ///< CV_32S samples taken per pixel
  cv::Mat std_error; ///< CV_32F estimated standard error of Y per pixel
  StageReport report;
};

/// The scene's geometry prepared for rendering: the BVH (Embree), the emissive triangles and the
/// face normals, built once for several renders through different cameras (`solo night` meters
/// its exposure on a small preview first). Keeps a reference to `scene`, which must outlive it.
/// Preconditions: per-face arrays sized like faces (or empty where optional), emitter indices
/// valid.
class PreparedRenderScene {
 public:
  explicit PreparedRenderScene(const RenderScene& scene);
  ~PreparedRenderScene();
  PreparedRenderScene(const PreparedRenderScene&) = delete;
  PreparedRenderScene& operator=(const PreparedRenderScene&) = delete;

  const RenderScene& scene() const;
  double bvhBuildSeconds() const;
  double prepareSeconds() const;  ///< the whole preparation, BVH included

  struct Impl;
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

/// Renders the prepared scene through `camera` (its width and height are the output's; > 0).
/// The report's seconds are the render's alone (add prepareSeconds() for the first render).
RenderOutput renderPathTraced(const PreparedRenderScene& prepared, const PinholeCamera& camera,
                              const PathTracerOptions& options = {});

/// Prepares the scene and renders it through its own camera.
RenderOutput renderPathTraced(const RenderScene& scene, const PathTracerOptions& options = {});

}  // namespace solo
