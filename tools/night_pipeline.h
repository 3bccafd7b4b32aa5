#pragma once
// The stages of `solo night` after the scene is read: refine -> mesh -> lights -> night scene
// -> render -> post. `solo night` and the end-to-end sweep of `solo bench accuracy` run this
// one sequence, so a preset measured by the sweep is the preset users run.

#include "commands.h"

#include <solo/geometry/depth_mesh.h>
#include <solo/geometry/depth_refinement.h>
#include <solo/geometry/mesh_holes.h>
#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/lighting/light_record.h>
#include <solo/render/light_sampler.h>
#include <solo/render/night_scene.h>
#include <solo/render/path_tracer.h>
#include <solo/post/post_process.h>
#include <solo/render/sampler.h>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace solo::tools {

/// Settings of the pipeline that `solo night` does not expose (the accuracy sweep varies them).
struct NightPipelineExtras {
  bool fill_holes = true;
  int max_fair_vertices = HoleFillOptions{}.max_fair_vertices;
  std::filesystem::path illuminant_table;  ///< empty: the bundled table
  bool progress = true;                    ///< the render's progress bar (on a terminal)
  std::function<void(const std::string&)> say;  ///< stage names as they start; may be empty
};

struct NightPipelineResult {
  DepthRefinementResult refined;
  DepthMesh mesh;
  LightRecord record;
  RenderOutput rendered;        ///< at the image size (upsampled with --render-downsample)
  PostProcessResult developed;  ///< the night image
  double sensor_white_cd_m2 = 0;  ///< the exposure used (metered or given)
  std::vector<StageReport> stages;  ///< refine steps, mesh, lights, scene, render, post
};

/// The light sampler and per-sample numbers named by the options; InputError naming the option
/// for an unknown name.
/// The scene the depth refinement and the mesh stage see: `scene` with each street light an
/// instance of its own in the instance map (streetLightsAsPoles; the light map outlines a lamp
/// better than an estimated segmentation does). `changed` receives the pixels changed.
Scene sceneForRefinement(const Scene& scene, std::int64_t* changed = nullptr);

LightSamplerKind lightSamplerOption(const NightOptions& options);
SamplerKind samplerOption(const NightOptions& options);

/// The stages before the render (refine, mesh, lights, night scene) on `scene` with `options`
/// (its preset already applied): fills result.refined, .mesh, .record and appends to
/// result.stages; returns the scene to render. The Cycles exporter (tests/benchmarks/blender)
/// stops here.
NightScene runNightSceneStages(const Scene& scene, const NightOptions& options, const NightPipelineExtras& extras,
                               NightPipelineResult& result);

/// Runs every stage after the input on `scene` with `options` (its preset already applied).
NightPipelineResult runNightPipeline(const Scene& scene, const NightOptions& options,
                                     const NightPipelineExtras& extras = {});

}  // namespace solo::tools
