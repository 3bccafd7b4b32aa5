#pragma once
// Simulated depth sensors: what a stereo matcher, a 64-beam LiDAR or a monocular network would
// report for a scene whose exact z-depth is known. Each is seeded and deterministic, and writes
// depth in metres with 0 = invalid, at the resolution of the exact depth it is given, so tests
// and benchmarks cover Cityscapes-like (stereo disparity), KITTI-like (projected LiDAR) and
// network depth without real data (docs/synthetic-scenes.md, "Depth sources").

#include <solo/core/camera.h>

#include <opencv2/core.hpp>

#include <cstdint>
#include <string>

namespace solo {

/// Where a depth map comes from: the exact depth, a monocular network, a stereo pair, a LiDAR.
enum class DepthSource { Exact, Mono, Stereo, Lidar };

/// "exact", "mono", "stereo", "lidar".
std::string depthSourceName(DepthSource source);
/// The inverse of depthSourceName; throws std::invalid_argument listing the names otherwise.
DepthSource depthSourceFromName(const std::string& name);

/// A rectified stereo pair matched by a semi-global matcher, as Cityscapes' disparity maps.
struct StereoSensorOptions {
  /// Cityscapes' stereo baseline (camera/*.json "extrinsic.baseline"), metres.
  static constexpr double kCityscapesBaselineM = 0.209313;
  double baseline_m = kCityscapesBaselineM;
  /// Matching noise, Gaussian in disparity with a constant sigma, pixels: depth noise grows as
  /// z^2 * sigma / (baseline * fx). Sub-pixel SGM accuracy is typically 0.1-0.2 px.
  double disparity_noise_px = 0.15;
  /// Disparities are stored in steps of this, pixels: Cityscapes PNGs hold p = d * 256 + 1.
  double disparity_step_px = 1.0 / 256;
  /// Below this disparity the match is too uncertain and is dropped (far regions), pixels.
  double min_disparity_px = 1.0;
  /// The matcher's search range as a share of the image width; above it a pixel is too close to
  /// match, and the left band this wide has no partner in the right image. 128 px of 2048 (an
  /// assumed SGM range: Cityscapes does not publish its matcher's).
  double max_disparity_width_share = 128.0 / 2048;
  /// Side of the square window over which the day image's local texture is measured, pixels.
  int texture_window_px = 9;
  /// A window whose standard deviation of the sRGB channel mean is below this (about 2.5/255)
  /// is flat: nothing to match there.
  double texture_min_std = 0.01;
  /// How far into a flat region the matcher's aggregation still carries a disparity from the
  /// nearest textured window, as a share of the image width (64 px of 2048); flat pixels
  /// further than this are textureless and invalid.
  double texture_reach_width_share = 64.0 / 2048;
};

/// Why a stereo pixel is invalid, counted per cause (a pixel counts once, under the first cause
/// in this order that applies).
struct StereoHoleCounts {
  std::int64_t no_surface = 0;   ///< exact depth 0 (sky)
  std::int64_t left_border = 0;  ///< in the left band of width max disparity
  std::int64_t too_close = 0;    ///< disparity above the search range
  std::int64_t occluded = 0;     ///< not visible from the right camera
  std::int64_t textureless = 0;  ///< the day image is flat around it
  std::int64_t too_far = 0;      ///< noisy disparity below the minimum
};

struct StereoDepth {
  cv::Mat depth_m;              ///< CV_32F z-depth, metres: baseline * fx / disparity; 0 = invalid
  cv::Mat disparity_px;         ///< CV_32F disparity, pixels, multiples of disparity_step_px; 0 = invalid
  double max_disparity_px = 0;  ///< the search range used (the left band's width), pixels
  double texture_reach_px = 0;  ///< the reach into flat regions used, pixels
  StereoHoleCounts holes;
};

/// Simulates a rectified stereo pair whose left camera is `camera`, the right one `baseline_m`
/// to its right (+x), matched left to right.
///
/// Inputs:
///   depth_m  CV_32F exact z-depth, metres, 0 = no surface (sky)
///   camera   pinhole intrinsics at depth_m's resolution (fx in pixels gives the disparities)
///   day_srgb CV_32FC3 day image, sRGB-encoded in [0, 1], same size: its local texture decides
///            where matching fails
///   seed     the disparity noise's random stream
///   options  the sensor (StereoSensorOptions)
/// Outputs:
///   the disparity d = baseline * fx / z plus Gaussian noise of options.disparity_noise_px,
///   rounded to options.disparity_step_px, and depth baseline * fx / d, 0 where invalid: no
///   surface, the left band of width max disparity, disparities above the search range, pixels
///   occluded in the right view (a scanline test on the exact disparities: pixel x is occluded
///   when some x' > x lands at or left of it in the right image, x' - d(x') <= x - d(x)),
///   textureless pixels (flat windows further than the reach from a textured one), and noisy
///   disparities below options.min_disparity_px.
StereoDepth simulateStereoDepth(const cv::Mat& depth_m, const PinholeCamera& camera, const cv::Mat& day_srgb,
                                std::uint64_t seed, const StereoSensorOptions& options = {});

/// A Cityscapes disparity PNG of `disparity_px` (CV_32F, 0 = invalid): CV_16U p = d * 256 + 1
/// rounded, 0 where invalid or where p would not fit in 16 bits (d > 255.99 px).
cv::Mat cityscapesDisparityPng(const cv::Mat& disparity_px);

/// A spinning 64-beam LiDAR at the camera centre, its axis along the camera's -y (up), beams
/// evenly spread over the Velodyne HDL-64E's vertical field, projected into the camera as KITTI
/// projects its scans.
struct LidarSensorOptions {
  int beams = 64;                    ///< lasers, evenly spaced in elevation (HDL-64E: 64)
  double min_elevation_deg = -24.8;  ///< lowest beam, degrees above the horizontal (HDL-64E datasheet)
  double max_elevation_deg = 2.0;    ///< highest beam, degrees (HDL-64E datasheet)
  double azimuth_step_deg = 0.09;    ///< horizontal step between firings (HDL-64E at 10 Hz: about 0.09)
  double range_noise_m = 0.02;       ///< Gaussian range noise sigma, metres (HDL-64E: < 2 cm)
  double max_range_m = 120.0;        ///< no return beyond this range, metres (HDL-64E: 120 m)
};

struct LidarDepth {
  cv::Mat depth_m;           ///< CV_32F sparse z-depth, metres; 0 where no return projects
  std::int64_t returns = 0;  ///< returns inside the image (several may share a pixel: the nearest is kept)
};

/// Simulates one revolution of a LiDAR at the camera centre, its azimuth zero along the optical
/// axis, its elevations measured from the camera's x-z plane (the camera frame is the sensor
/// frame: no offset, no rotation).
///
/// Inputs:
///   depth_m  CV_32F exact z-depth, metres, 0 = no surface (sky)
///   camera   pinhole intrinsics at depth_m's resolution
///   seed     the range noise's random stream
///   options  the sensor (LidarSensorOptions)
/// Outputs:
///   a sparse CV_32F z-depth map, metres, the size of depth_m: every firing (beam b at
///   elevation min + b * (max - min) / (beams - 1), azimuth k * azimuth_step_deg) whose ray
///   projects into the image reads the exact depth z at the nearest pixel, giving range
///   r = z / cos(angle to the optical axis); the noisy range r + N(0, range_noise_m) up to
///   max_range_m is written as its z-depth at that pixel (the nearest return wins). Rays that
///   meet no surface (z = 0) or leave the image give nothing.
LidarDepth simulateLidarDepth(const cv::Mat& depth_m, const PinholeCamera& camera, std::uint64_t seed,
                              const LidarSensorOptions& options = {});

/// A monocular network's dense depth: right up to an affine error in inverse depth, and
/// smoothed across depth edges. The edge bleeding, the scale draw and the per-pixel noise are
/// simulatePredictions' depth perturbation (geometry/prediction_noise.h) at full resolution.
struct MonoSensorOptions {
  int edge_bleed_px = 3;                   ///< band around depth edges blended across, pixels
  double edge_relative_jump = 0.05;        ///< a relative depth jump above this is an edge
  double scale_error_max = 0.1;            ///< global depth scale drawn from 1 +- this
  double inverse_shift_max_per_m = 0.001;  ///< global inverse-depth shift drawn from +- this, 1/m (5 % at 50 m)
  double max_depth_m = 1000;     ///< depths the shift pushes beyond this (or behind the camera) are this, metres
  double noise_relative = 0.01;  ///< per-pixel relative noise sigma at 0 m ...
  double noise_growth_m = 50;    ///< ... growing as (1 + z / this), metres
};

struct MonoDepth {
  cv::Mat depth_m;                 ///< CV_32F z-depth, metres; 0 only where the exact depth is 0
  double scale = 1;                ///< the depth scale drawn
  double inverse_shift_per_m = 0;  ///< the inverse-depth shift drawn, 1/m
};

/// Simulates a monocular network's metric depth.
///
/// Inputs:
///   depth_m  CV_32F exact z-depth, metres, 0 = no surface (sky)
///   seed     the random streams (scale, shift, noise)
///   options  the error model (MonoSensorOptions)
/// Outputs:
///   z_est = 1 / (1 / (scale * z_blended * (1 + noise)) + inverse_shift) with scale drawn from
///   1 +- scale_error_max and inverse_shift from +- inverse_shift_max_per_m, z_blended the depth
///   blended across edges within edge_bleed_px, the inverse depth floored at 1 / max_depth_m;
///   0 exactly where the exact depth is 0.
MonoDepth simulateMonoDepth(const cv::Mat& depth_m, std::uint64_t seed, const MonoSensorOptions& options = {});

/// The three simulated sensors' options together, as a scene folder takes them.
struct DepthSensorOptions {
  StereoSensorOptions stereo;
  LidarSensorOptions lidar;
  MonoSensorOptions mono;
};

/// How a simulated depth map compares with the exact one.
struct DepthSensorAgreement {
  double valid_share = 0;  ///< share of all pixels with a depth > 0
  double abs_rel = 0;      ///< mean |est - exact| / exact over pixels where both are > 0
};

/// Compares `estimate_m` with `exact_m` (both CV_32F metres, 0 = invalid, same size).
DepthSensorAgreement compareWithExactDepth(const cv::Mat& estimate_m, const cv::Mat& exact_m);

}  // namespace solo
