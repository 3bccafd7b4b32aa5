#pragma once
// 3D geometry of each light from a metric z-depth map at the image resolution (the scene's
// depth upsampled, later the refined depth) and the pinhole camera: the pixels with depth,
// the emitting area in square metres, the centroid and the mean normal in the camera frame
// (x right, y down, z forward, metres).
//
// A pixel (u, v) at z-depth z sees the surface patch of area z^2 / (fx fy |n . r|) with the
// unnormalised ray r = ((u - cx) / fx, (v - cy) / fy, 1) and the surface normal n: the
// pixel's solid angle times the squared distance over the cosine of incidence. n is the
// light's mean normal: the normalised mean of a normal map's valid pixels when one is given
// (predicted normals are far steadier than normals of noisy depth); else a plane fitted to
// the backprojected points (area-weighted PCA, one refit without points farther than 3
// robust sigmas), oriented toward the camera; a light whose points do not span a plane
// (fewer than 3, or collinear) faces the camera.

#include "solo/lighting/light_groups.h"

#include <solo/core/camera.h>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace solo {

struct LightGeometryOptions {
  /// Incidence angles beyond this count as this when computing areas (a patch seen exactly
  /// edge-on would have infinite area), degrees.
  double max_incidence_deg = 85.0;
};

enum class NormalSource { NormalMap, PlaneFit, FacingCamera };
/// "normal_map", "plane_fit", "facing_camera".
const char* normalSourceName(NormalSource source);
/// Inverse; throws std::invalid_argument.
NormalSource normalSourceFromName(const std::string& name);

/// Where a light's geometry comes from (docs/lighting.md, "Physical priors"): its own depth
/// ("measured"), its own depth moved onto its supporting surface because the measured position
/// was implausible for its category ("moved_to_support"), or, for a light without valid depth,
/// the depth of its supporting surface around it ("support_depth") or its category's prior
/// distance along its pixels' rays ("prior_distance").
enum class LightPlacement { Measured, MovedToSupport, SupportDepth, PriorDistance };
/// "measured", "moved_to_support", "support_depth", "prior_distance".
const char* lightPlacementName(LightPlacement placement);
/// Inverse; throws std::invalid_argument.
LightPlacement lightPlacementFromName(const std::string& name);

struct LightGeometry {
  std::int64_t pixels_with_depth = 0;  ///< pixels of the light with valid depth
  /// Of those, pixels whose depth lies off the light's (beyond median +- max(3 MAD, 0.25 m)):
  /// mixed pixels of its silhouette. They count in neither the area nor the centroid.
  std::int64_t pixels_off_depth = 0;
  double area_m2 = 0;                  ///< emitting surface area, square metres
  Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();  ///< area-weighted, camera frame
  Eigen::Vector3d normal = Eigen::Vector3d(0, 0, -1);    ///< unit, toward the camera
  NormalSource normal_source = NormalSource::FacingCamera;
  LightPlacement placement = LightPlacement::Measured;
  /// The checks of its category's priors it fails where it is placed (LightPriorCheck bits,
  /// light_priors.h); 0 = plausible or not checked.
  std::uint32_t implausible = 0;
  /// Has valid depth under it.
  bool valid() const { return pixels_with_depth > 0; }
  /// Has a position, area and normal: measured, or placed at a prior depth.
  bool positioned() const {
    return valid() || placement == LightPlacement::SupportDepth || placement == LightPlacement::PriorDistance;
  }
};

/// The depth band of one light: median +- max(3 MAD, 0.25 m) of its depths (the upper median
/// for an even count). What lies outside it belongs to the light's silhouette, mixed pixels or
/// faces stretched toward the background. A flat light seen at grazing spreads its depth evenly
/// over its width w (MAD = w / 4) and lies wholly inside. Used by measureLightGeometry for the
/// light's pixels and by the night scene for its faces.
struct LightDepthBand {
  double median_m = 0, half_width_m = 0;
  bool contains(double depth_m) const { return std::abs(depth_m - median_m) <= half_width_m; }
};
/// `depths_m` must not be empty.
LightDepthBand lightDepthBand(std::vector<double> depths_m);

/// One entry per tree.lights (same order). `depth_m`: CV_32F metres at the tree's
/// resolution, 0 = invalid; `camera` at the same resolution; `normals`: CV_32FC3 unit
/// camera-frame normals at the same resolution, (0,0,0) = invalid, or empty.
std::vector<LightGeometry> measureLightGeometry(const LightGroupTree& tree, const cv::Mat& depth_m,
                                                const PinholeCamera& camera, const LightGeometryOptions& options = {},
                                                const cv::Mat& normals = cv::Mat());

/// The geometry of a light whose pixels all lie at z-depth `depth_m` (a placement at a prior
/// depth, for a light without valid depth): area and centroid as measureLightGeometry computes
/// them, the normal from the normal map's pixels under the light when there are any, else
/// `fallback_normal` (turned toward the camera) when it is not zero, else facing the camera.
/// pixels_with_depth stays 0 and placement Measured (the caller says how it
/// was placed). `normals`: as for measureLightGeometry, or empty. A depth that is not positive
/// and finite gives the default (no position).
LightGeometry lightGeometryAtDepth(const Light& light, double depth_m, const PinholeCamera& camera,
                                   const LightGeometryOptions& options = {}, const cv::Mat& normals = cv::Mat(),
                                   const Eigen::Vector3d& fallback_normal = Eigen::Vector3d::Zero());

/// Normals at `size`: bilinear resampling, renormalised; invalid (zero) pixels are ignored
/// like resampleDepthIgnoringInvalid does. CV_32FC3 in and out; empty stays empty.
cv::Mat resampleNormals(const cv::Mat& normals, cv::Size size);

/// Bilinear resampling of a depth map to `size` ignoring invalid (0) pixels: the weighted
/// average of the valid neighbours (cv::resize of depth * valid over cv::resize of valid);
/// 0 where no neighbour is valid. CV_32F metres in and out.
cv::Mat resampleDepthIgnoringInvalid(const cv::Mat& depth_m, cv::Size size);

}  // namespace solo
