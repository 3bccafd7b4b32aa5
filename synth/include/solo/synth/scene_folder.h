#pragma once
// A synthetic street written as a scene folder (docs/scene-format.md), as `solo synth` writes
// it: the day image, the light and window-group maps, the exact maps and mesh under gt/, the
// simulated network predictions under est/, the manifests scene.json (estimated inputs, naming
// the ground truth) and gt/scene.json, and synth.json recording how the folder was made. The
// folder is written under a hidden sibling name and renamed into place at the end: a run that
// fails leaves no folder, and a replaced folder stays as it was until the new one is complete.

#include <solo/core/report.h>
#include <solo/synth/depth_sensor.h>

#include <cstdint>
#include <filesystem>
#include <string>

namespace solo {

struct SyntheticSceneOptions {
  std::uint64_t seed = 1;             ///< the street's layout, the day image and the predictions' noise
  int width = 960, height = 540;      ///< pixels, 16 to 8192 per side
  std::string variant = "default";    ///< streetVariantName; recorded as given
  std::string day_render = "raster";  ///< "raster" (1 ray + 1 shadow ray per pixel) or "path" (path traced sun and sky)
  /// The path-traced day image's samples per pixel, 1 to 4096; 0 = adaptive, 4 to 16 (a noisy
  /// image; a real day photo's noise is that of about 256).
  int day_samples = 0;
  /// est/depth.exr: "" for the half-resolution prediction (geometry/prediction_noise.h), or a
  /// depthSourceName ("exact", "mono", "stereo", "lidar") for that sensor's depth at full
  /// resolution, 0 = invalid (depth_sensor.h); recorded in synth.json with its agreement
  /// with the exact depth. "stereo" also writes est/disparity.png and est/camera.json.
  std::string depth_source;
  DepthSensorOptions depth_sensors;   ///< the simulated sensors, used as depth_source says
  bool progress = false;              ///< the path-traced day image's progress on stderr
  /// Replace an existing folder, only one this function wrote that holds nothing else.
  bool force = false;
};

struct SyntheticSceneResult {
  std::filesystem::path folder;    ///< as written: the given folder without trailing separators
  std::filesystem::path manifest;  ///< folder/scene.json
  /// command "synth": a stage per step (layout, ground truth, day image, predictions, the depth
  /// sensor when one is chosen, write)
  RunReport report;
};

/// Writes the synthetic street of `options` into `folder`. Throws InputError naming the option
/// (--variant, --size, --day-render, -o) or the folder for a bad option or a folder that exists
/// and may not be replaced; a run that fails leaves the folder as it was.
SyntheticSceneResult writeSyntheticScene(const std::filesystem::path& folder, const SyntheticSceneOptions& options);

}  // namespace solo
