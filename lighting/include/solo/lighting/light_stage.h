#pragma once
// The pipeline's "lights" stage: from a loaded scene to a light record. Resamples the
// light, instance and window-group maps to the image resolution (nearest neighbour), builds
// the group tree, measures each light's geometry on a depth map at the image resolution,
// checks it against its category's physical priors (moving implausible lights onto their
// support, placing lights without depth at a prior depth; light_priors.h), instantiates the
// lights with the illuminant table, and reports what it did.

#include "solo/lighting/light_geometry.h"
#include "solo/lighting/light_instantiation.h"
#include "solo/lighting/light_priors.h"
#include "solo/lighting/light_record.h"

#include <solo/core/report.h>
#include <solo/core/scene.h>

#include <filesystem>

namespace solo {

struct LightStageOptions {
  InstantiationOptions instantiation;
  LightGeometryOptions geometry;
  LightPriorOptions priors;          ///< the category priors every light is checked against
  GroundFitOptions ground_plane;   ///< the priors' ground plane, from the road and sidewalk
  std::filesystem::path illuminant_table;  ///< CSV (data/illuminants/night_illuminants.csv)
};

struct LightStageResult {
  LightRecord record;
  StageReport report;  ///< name "lights": counts, areas, timings; skipped when the scene has no light map
};

/// Throws InputError naming the option for a setting outside its range: the ablation's
/// luminance ("--ablation-luminance") must be above 0 and at most 1e9 cd/m^2.
void validateLightStageOptions(const LightStageOptions& options);

/// `depth_m`: CV_32F metres at the image resolution (the refined depth); empty = the
/// scene's depth resampled bilinearly ignoring invalid pixels. Throws InputError for
/// invalid options (validateLightStageOptions), a malformed light map or illuminant table.
LightStageResult runLightStage(const Scene& scene, const cv::Mat& depth_m, const LightStageOptions& options);

/// A label map (CV_32S) at `size` by nearest-neighbour resampling (pixel centres kept);
/// empty stays empty.
cv::Mat resampleLabels(const cv::Mat& labels, cv::Size size);

}  // namespace solo
