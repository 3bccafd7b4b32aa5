// Simulated depth sensors: stereo, LiDAR and monocular depth from exact depth (depth_sensor.h).

#include <solo/synth/depth_sensor.h>

#include <solo/geometry/prediction_noise.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace solo {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180;

// Salts of the sensors' random streams: each sensor draws from its own.
constexpr std::uint64_t kStereoSalt = 101;
constexpr std::uint64_t kLidarSalt = 102;
constexpr std::uint64_t kMonoShiftSalt = 103;

// A reproducible stream for `seed` and `salt`.
std::mt19937_64 stream(std::uint64_t seed, std::uint64_t salt) {
  std::seed_seq sequence{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                         static_cast<std::uint32_t>(salt)};
  return std::mt19937_64(sequence);
}

// The exact disparity baseline * fx / z of every pixel, pixels; 0 where z is 0.
cv::Mat exactDisparities(const cv::Mat& depth_m, double baseline_fx_px_m) {
  cv::Mat disparity(depth_m.size(), CV_64F, cv::Scalar(0));
  for (int y = 0; y < depth_m.rows; ++y)
    for (int x = 0; x < depth_m.cols; ++x) {
      const float z = depth_m.at<float>(y, x);
      if (z > 0) disparity.at<double>(y, x) = baseline_fx_px_m / z;
    }
  return disparity;
}

// 255 where pixel x of the left image is hidden from the right camera: some pixel x' > x on its
// row lands at or left of it in the right image (x' - d(x') <= x - d(x)), so a nearer surface
// covers it there. One right-to-left scan per row keeps the smallest x' - d(x') seen so far.
cv::Mat occludedInRightView(const cv::Mat& disparity_px) {
  cv::Mat occluded(disparity_px.size(), CV_8U, cv::Scalar(0));
  for (int y = 0; y < disparity_px.rows; ++y) {
    double leftmost_right_x = std::numeric_limits<double>::infinity();
    for (int x = disparity_px.cols - 1; x >= 0; --x) {
      const double d = disparity_px.at<double>(y, x);
      if (d <= 0) continue;  // no surface: hides nothing
      const double right_x = x - d;
      if (leftmost_right_x <= right_x) occluded.at<uchar>(y, x) = 255;
      leftmost_right_x = std::min(leftmost_right_x, right_x);
    }
  }
  return occluded;
}

// 255 where the matcher finds nothing to lock onto: the standard deviation of the day image's
// channel mean over a window_px square is below min_std there and within reach_px around it.
cv::Mat texturelessMask(const cv::Mat& day_srgb, int window_px, double min_std, double reach_px) {
  cv::Mat grey;
  cv::transform(day_srgb, grey, cv::Matx13f(1.f / 3, 1.f / 3, 1.f / 3));
  cv::Mat mean, mean_of_squares;
  const cv::Size window(window_px, window_px);
  cv::boxFilter(grey, mean, CV_32F, window, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
  cv::boxFilter(grey.mul(grey), mean_of_squares, CV_32F, window, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
  const cv::Mat variance = mean_of_squares - mean.mul(mean);
  const cv::Mat flat = variance < min_std * min_std;
  if (cv::countNonZero(flat) == static_cast<int>(flat.total())) return flat;  // nothing textured anywhere
  cv::Mat distance_px;                                                        // to the nearest textured pixel
  cv::distanceTransform(flat, distance_px, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  return distance_px > reach_px;
}

// The stereo pixel's fate: its noisy disparity, or the first reason it has none.
struct StereoPixel {
  double disparity_px = 0;
  std::int64_t StereoHoleCounts::*hole = nullptr;  ///< null when valid
};

// What the matcher reports at (x, y) for a noisy, quantised disparity `measured_px`.
StereoPixel judgeStereoPixel(int x, double exact_px, double measured_px, bool occluded, bool textureless,
                             double max_disparity_px, const StereoSensorOptions& o) {
  if (exact_px <= 0) return {0, &StereoHoleCounts::no_surface};
  if (x < max_disparity_px) return {0, &StereoHoleCounts::left_border};
  if (measured_px > max_disparity_px) return {0, &StereoHoleCounts::too_close};
  if (occluded) return {0, &StereoHoleCounts::occluded};
  if (textureless) return {0, &StereoHoleCounts::textureless};
  if (measured_px < o.min_disparity_px) return {0, &StereoHoleCounts::too_far};
  return {measured_px, nullptr};
}

// The longest disparity a Cityscapes PNG holds: (65535 - 1) / 256 px.
constexpr double kMaxPngDisparityPx = 65534.0 / 256;

// One firing's unit direction in the camera frame (x right, y down, z forward).
cv::Vec3d lidarRay(double elevation_rad, double azimuth_rad) {
  return {std::cos(elevation_rad) * std::sin(azimuth_rad), -std::sin(elevation_rad),
          std::cos(elevation_rad) * std::cos(azimuth_rad)};
}

// Writes the return of `ray` with noise `noise_m` into `sparse`: true when one lands in the image.
bool fireLidarRay(const cv::Vec3d& ray, double noise_m, const cv::Mat& depth_m, const PinholeCamera& camera,
                  const LidarSensorOptions& o, cv::Mat& sparse) {
  if (ray[2] <= 1e-6) return false;  // behind the camera or along its image plane
  const long u = std::lround(camera.fx * ray[0] / ray[2] + camera.cx);
  const long v = std::lround(camera.fy * ray[1] / ray[2] + camera.cy);
  if (u < 0 || v < 0 || u >= depth_m.cols || v >= depth_m.rows) return false;
  const float z = depth_m.at<float>(static_cast<int>(v), static_cast<int>(u));
  if (z <= 0) return false;  // sky: no echo
  const double range_m = z / ray[2] + noise_m;
  if (range_m <= 0 || range_m > o.max_range_m) return false;
  float& out = sparse.at<float>(static_cast<int>(v), static_cast<int>(u));
  const float z_m = static_cast<float>(range_m * ray[2]);
  if (out <= 0 || z_m < out) out = z_m;
  return true;
}

// Applies the inverse-depth shift to every valid pixel, flooring the inverse depth at 1 / max_depth_m.
void shiftInverseDepth(cv::Mat& depth_m, double shift_per_m, double max_depth_m) {
  const double min_inverse_per_m = 1 / max_depth_m;
  for (int y = 0; y < depth_m.rows; ++y)
    for (int x = 0; x < depth_m.cols; ++x) {
      float& z = depth_m.at<float>(y, x);
      if (z <= 0) continue;
      z = static_cast<float>(1 / std::max(min_inverse_per_m, 1 / static_cast<double>(z) + shift_per_m));
    }
}

}  // namespace

std::string depthSourceName(DepthSource source) {
  switch (source) {
    case DepthSource::Exact:
      return "exact";
    case DepthSource::Mono:
      return "mono";
    case DepthSource::Stereo:
      return "stereo";
    case DepthSource::Lidar:
      return "lidar";
  }
  return "exact";
}

DepthSource depthSourceFromName(const std::string& name) {
  for (DepthSource source : {DepthSource::Exact, DepthSource::Mono, DepthSource::Stereo, DepthSource::Lidar})
    if (depthSourceName(source) == name) return source;
  throw std::invalid_argument("expected exact, mono, stereo or lidar, got \"" + name + "\"");
}

StereoDepth simulateStereoDepth(const cv::Mat& depth_m, const PinholeCamera& camera, const cv::Mat& day_srgb,
                                std::uint64_t seed, const StereoSensorOptions& o) {
  CV_Assert(depth_m.type() == CV_32F && day_srgb.type() == CV_32FC3 && day_srgb.size() == depth_m.size());
  CV_Assert(o.baseline_m > 0 && camera.fx > 0 && o.disparity_step_px > 0 && o.texture_window_px >= 1);
  const double baseline_fx_px_m = o.baseline_m * camera.fx;
  const cv::Mat exact = exactDisparities(depth_m, baseline_fx_px_m);
  const cv::Mat occluded = occludedInRightView(exact);
  StereoDepth out;
  out.max_disparity_px = std::min(o.max_disparity_width_share * depth_m.cols, kMaxPngDisparityPx);
  out.texture_reach_px = o.texture_reach_width_share * depth_m.cols;
  const cv::Mat textureless = texturelessMask(day_srgb, o.texture_window_px, o.texture_min_std, out.texture_reach_px);
  out.depth_m = cv::Mat(depth_m.size(), CV_32F, cv::Scalar(0));
  out.disparity_px = cv::Mat(depth_m.size(), CV_32F, cv::Scalar(0));
  std::mt19937_64 rng = stream(seed, kStereoSalt);
  std::normal_distribution<double> unit(0, 1);
  for (int y = 0; y < depth_m.rows; ++y)
    for (int x = 0; x < depth_m.cols; ++x) {
      const double noise_px = o.disparity_noise_px * unit(rng);  // drawn for every pixel, valid or not
      const double exact_px = exact.at<double>(y, x);
      const double measured_px = std::round((exact_px + noise_px) / o.disparity_step_px) * o.disparity_step_px;
      const StereoPixel pixel = judgeStereoPixel(x, exact_px, measured_px, occluded.at<uchar>(y, x) != 0,
                                                 textureless.at<uchar>(y, x) != 0, out.max_disparity_px, o);
      if (pixel.hole) {
        ++(out.holes.*pixel.hole);
        continue;
      }
      out.disparity_px.at<float>(y, x) = static_cast<float>(pixel.disparity_px);
      out.depth_m.at<float>(y, x) = static_cast<float>(baseline_fx_px_m / pixel.disparity_px);
    }
  return out;
}

cv::Mat cityscapesDisparityPng(const cv::Mat& disparity_px) {
  CV_Assert(disparity_px.type() == CV_32F);
  cv::Mat png(disparity_px.size(), CV_16U, cv::Scalar(0));
  for (int y = 0; y < disparity_px.rows; ++y)
    for (int x = 0; x < disparity_px.cols; ++x) {
      const double d = disparity_px.at<float>(y, x);
      if (d > 0 && d <= kMaxPngDisparityPx)
        png.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(std::lround(d * 256 + 1));
    }
  return png;
}

LidarDepth simulateLidarDepth(const cv::Mat& depth_m, const PinholeCamera& camera, std::uint64_t seed,
                              const LidarSensorOptions& o) {
  CV_Assert(depth_m.type() == CV_32F && camera.fx > 0 && camera.fy > 0);
  CV_Assert(o.beams >= 1 && o.azimuth_step_deg > 0);
  LidarDepth out;
  out.depth_m = cv::Mat(depth_m.size(), CV_32F, cv::Scalar(0));
  std::mt19937_64 rng = stream(seed, kLidarSalt);
  std::normal_distribution<double> unit(0, 1);
  // Only the forward half of the revolution can reach the image: azimuths within +-90 degrees.
  const int half_steps = static_cast<int>(std::ceil(90 / o.azimuth_step_deg));
  const double elevation_step_deg = o.beams > 1 ? (o.max_elevation_deg - o.min_elevation_deg) / (o.beams - 1) : 0;
  for (int beam = 0; beam < o.beams; ++beam) {
    const double elevation_rad = (o.min_elevation_deg + beam * elevation_step_deg) * kDegToRad;
    for (int k = -half_steps; k <= half_steps; ++k) {
      const double noise_m = o.range_noise_m * unit(rng);  // drawn for every firing, hit or not
      const cv::Vec3d ray = lidarRay(elevation_rad, k * o.azimuth_step_deg * kDegToRad);
      if (fireLidarRay(ray, noise_m, depth_m, camera, o, out.depth_m)) ++out.returns;
    }
  }
  return out;
}

MonoDepth simulateMonoDepth(const cv::Mat& depth_m, std::uint64_t seed, const MonoSensorOptions& o) {
  CV_Assert(depth_m.type() == CV_32F && o.max_depth_m > 0);
  // simulatePredictions' depth perturbation at full resolution; its other maps are not used,
  // so they get 1x1 placeholders.
  PredictionNoiseOptions noise;
  noise.depth_downscale = 1;
  noise.edge_bleed_px = o.edge_bleed_px;
  noise.edge_relative_jump = o.edge_relative_jump;
  noise.depth_bias_max = o.scale_error_max;
  noise.depth_noise_relative = o.noise_relative;
  noise.depth_noise_growth_m = o.noise_growth_m;
  const cv::Mat placeholder_rgb(1, 1, CV_32FC3, cv::Scalar::all(0));
  const cv::Mat placeholder_ids(1, 1, CV_32S, cv::Scalar(0));
  SimulatedPredictions predicted =
      simulatePredictions(depth_m, placeholder_rgb, placeholder_rgb, placeholder_ids, placeholder_ids, noise, seed);
  CV_Assert(predicted.depth_m.size() == depth_m.size());

  MonoDepth out;
  out.scale = predicted.depth_scale_bias;
  std::mt19937_64 rng = stream(seed, kMonoShiftSalt);
  out.inverse_shift_per_m =
      std::uniform_real_distribution<double>(-o.inverse_shift_max_per_m, o.inverse_shift_max_per_m)(rng);
  out.depth_m = predicted.depth_m;
  if (o.inverse_shift_max_per_m > 0) shiftInverseDepth(out.depth_m, out.inverse_shift_per_m, o.max_depth_m);
  return out;
}

DepthSensorAgreement compareWithExactDepth(const cv::Mat& estimate_m, const cv::Mat& exact_m) {
  CV_Assert(estimate_m.type() == CV_32F && exact_m.type() == CV_32F && estimate_m.size() == exact_m.size());
  std::int64_t valid = 0, compared = 0;
  double abs_rel_sum = 0;
  for (int y = 0; y < exact_m.rows; ++y)
    for (int x = 0; x < exact_m.cols; ++x) {
      const float estimate = estimate_m.at<float>(y, x), exact = exact_m.at<float>(y, x);
      if (estimate <= 0) continue;
      ++valid;
      if (exact <= 0) continue;
      ++compared;
      abs_rel_sum += std::abs(static_cast<double>(estimate) - exact) / exact;
    }
  DepthSensorAgreement agreement;
  agreement.valid_share = exact_m.empty() ? 0 : static_cast<double>(valid) / exact_m.total();
  agreement.abs_rel = compared > 0 ? abs_rel_sum / compared : 0;
  return agreement;
}

}  // namespace solo
