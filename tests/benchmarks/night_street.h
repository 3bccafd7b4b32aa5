#pragma once
// The benchmarks' synthetic night street: solo synth's box street with every light switched on
// at a typical luminance for its category, and the two ego headlights. Shared by bench_render
// and the Cycles comparison (blender/export_blender_scene) so both measure the same scene.

#include <solo/render/render_scene.h>

namespace solo::bench {

struct NightStreetOptions {
  int width = 480, height = 270;  ///< pixels
  /// Front and street lights carry the reference's directional profile g(v, n); the Cycles
  /// comparison turns it off because Cycles cannot express it.
  bool profiled_emitters = true;
  /// Headlight half-angle, radians; < 0 keeps egoHeadlights' default cone.
  float headlight_spread_rad = -1.f;
};

RenderScene nightStreet(const NightStreetOptions& options);

}  // namespace solo::bench
