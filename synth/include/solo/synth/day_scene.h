#pragma once
// Daytime mode of the path tracer for `solo synth`: the street scene's boxes under a sun (a
// distant disc light) and a sky gradient, rendered with next-event estimation and MIS toward
// both (path_tracer.h). The sky is the horizon-to-zenith gradient the raster day image
// (scene_raster.h) paints in its sky pixels, so the light the scene receives is the sky it
// shows; the sun's illuminance puts a white surface facing the sun at the raster's 2.6.
// Units: the raster's relative radiance (linear sRGB, about 1 = exposed white).

#include "solo/render/path_tracer.h"
#include "solo/synth/street_scene.h"

#include <solo/core/report.h>

#include <opencv2/core.hpp>

#include <cstdint>

namespace solo {

struct DayRenderOptions {
  /// Irradiance on a surface facing the sun: pi x 2.6, so that its radiance albedo E / pi
  /// equals the raster's albedo x 2.6.
  double sun_illuminance = 3.14159265358979 * 2.6;
  float sun_angular_radius_rad = 0.00465f;
  Eigen::Vector3f sky_horizon_rgb{0.75f, 0.83f, 0.95f};  ///< linear sRGB radiance at and below the horizon
  Eigen::Vector3f sky_zenith_rgb{0.25f, 0.45f, 0.85f};   ///< linear sRGB radiance at the zenith
  int min_samples = 4, max_samples = 16;                 ///< per pixel
  double relative_error = 0.05;
  int max_bounces = 4;
  std::uint64_t seed = 1;
  bool progress = false;
};

/// The scene's boxes with their albedo (as XYZ reflectance) and roughness (so the GGX lobe is
/// on), the sun along scene.sun_direction, the sky gradient about up = -y; no emitters.
RenderScene streetDayScene(const StreetScene& scene, const DayRenderOptions& options = {});

struct DaylightRender {
  cv::Mat linear_rgb;  ///< CV_32FC3 linear sRGB, encode with srgbEncode8
  StageReport report;  ///< the path tracer's report
};

/// Path traces streetDayScene and converts XYZ (relative to E) back to linear sRGB.
DaylightRender renderDaylightPathTraced(const StreetScene& scene, const DayRenderOptions& options = {});

}  // namespace solo
