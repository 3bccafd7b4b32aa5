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

struct LightGeometry {
  std::int64_t pixels_with_depth = 0;  ///< pixels of the light with valid depth
  /// Of those, pixels whose depth lies off the light's (beyond median +- max(3 MAD, 0.25 m)):
  /// mixed pixels of its silhouette. They count in neither the area nor the centroid.
  std::int64_t pixels_off_depth = 0;
  double area_m2 = 0;                  ///< emitting surface area, square metres
  Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();  ///< area-weighted, camera frame
  Eigen::Vector3d normal = Eigen::Vector3d(0, 0, -1);    ///< unit, toward the camera
  NormalSource normal_source = NormalSource::FacingCamera;
  bool valid() const { return pixels_with_depth > 0; }
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

/// Normals at `size`: bilinear resampling, renormalised; invalid (zero) pixels are ignored
/// like resampleDepthIgnoringInvalid does. CV_32FC3 in and out; empty stays empty.
cv::Mat resampleNormals(const cv::Mat& normals, cv::Size size);

/// Bilinear resampling of a depth map to `size` ignoring invalid (0) pixels: the weighted
/// average of the valid neighbours (cv::resize of depth * valid over cv::resize of valid);
/// 0 where no neighbour is valid. CV_32F metres in and out.
cv::Mat resampleDepthIgnoringInvalid(const cv::Mat& depth_m, cv::Size size);

}  // namespace solo
