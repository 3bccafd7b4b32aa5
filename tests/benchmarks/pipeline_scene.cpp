#include "pipeline_scene.h"

#include <solo/pipeline/night_conversion.h>

#include <solo/core/report.h>
#include <solo/core/scene.h>

#include <cstdio>

namespace solo::bench {

RenderScene pipelineScene(const std::filesystem::path& manifest, int width, int height) {
  Stopwatch clock;
  const Scene input = loadScene(manifest);
  NightConversionOptions options;  // its defaults are the default preset (night_presets.h)
  options.seed = kPipelineLightSeed;
  // The mesh at the image resolution, also above a megapixel where the preset halves it: the
  // benchmarks measure the tracer on the full mesh.
  options.mesh_downsample = 1;
  NightConversionResult stages;
  NightConversionCallbacks quiet;
  quiet.render_progress = false;
  RenderScene scene = runNightSceneStages(input, options, quiet, stages).scene;
  std::printf("pipeline scene from %s: %dx%d mesh, %zu triangles, %zu emitters, %zu rectangle lights, light seed %llu, "
              "camera %dx%d, built in %.1f s\n",
              manifest.string().c_str(), input.width(), input.height(), scene.faces.size(), scene.emitters.size(),
              scene.rectangle_lights.size(), static_cast<unsigned long long>(kPipelineLightSeed), width, height,
              clock.seconds());
  std::fflush(stdout);
  scene.camera = scene.camera.scaledTo(width, height);
  return scene;
}

}  // namespace solo::bench
