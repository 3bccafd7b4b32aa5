#pragma once
// The render scene `solo night --seed 3 --mesh-downsample 1` builds from a scene manifest with its default preset,
// by solo night's own stages (pipeline/night_conversion.h, runNightSceneStages): refined depth, the
// cleaned mesh at the image resolution with closed solids, the light record's draw (real
// strengths and chromaticities), the two headlights. Shared by bench_render's efficiency line
// and the Cycles comparison (blender/export_blender_scene), which adds its simplifications.

#include <solo/render/render_scene.h>

#include <cstdint>
#include <filesystem>

namespace solo::bench {

/// The light record's draw (solo night's --seed; the synth scene's seed).
constexpr std::uint64_t kPipelineLightSeed = 3;

/// The scene, its camera scaled to width x height (same view, fewer pixels; the mesh keeps the
/// image resolution). Prints one line: the manifest, mesh size, triangles, lights, build time.
/// Throws (naming the file) when the manifest cannot be read.
RenderScene pipelineScene(const std::filesystem::path& manifest, int width, int height);

}  // namespace solo::bench
