#pragma once
// Exact per-pixel ground truth of a StreetScene by casting one ray through each pixel
// centre with Embree, and a daytime image lit by the sun and the sky.

#include "solo/synth/street_scene.h"

#include <opencv2/core.hpp>

namespace solo {

struct GroundTruthMaps {
  cv::Mat depth_m;       ///< CV_32F z-depth, metres; 0 = sky (no hit)
  cv::Mat normals;       ///< CV_32FC3 unit, camera frame, toward the camera; 0 = sky
  cv::Mat albedo;        ///< CV_32FC3 linear reflectance; 0 = sky
  cv::Mat roughness;     ///< CV_32F; 0 = sky
  cv::Mat labels;        ///< CV_32S Cityscapes labelIds; sky = 23
  cv::Mat instances;     ///< CV_32S Cityscapes instanceIds; sky = 23
  cv::Mat lights;        ///< CV_32S light ids; 0 = none
  cv::Mat light_groups;  ///< CV_32S window groups; 0 = none
  cv::Mat part;          ///< CV_32S index into scene.parts; -1 = sky
};

/// Ray casts every pixel centre (u, v) = (x, y). Multithreaded over rows; deterministic.
GroundTruthMaps rasterizeGroundTruth(const StreetScene& scene);

struct DaylightOptions {
  double sun_irradiance = 2.6;  ///< relative units: a white surface facing the sun is exposed near 1
  double sky_irradiance = 0.55;
  double exposure = 1.0;
};

/// Day image, CV_32FC3 linear RGB: albedo * (sun * cos * visibility + sky * (1 + n.up) / 2),
/// shadows from one occlusion ray toward the sun per pixel, a horizon-to-zenith gradient in
/// the sky. Encode with srgbEncode8 for a PNG.
cv::Mat renderDaylight(const StreetScene& scene, const GroundTruthMaps& truth, const DaylightOptions& options = {});

/// Linear RGB in [0, 1] to 8-bit sRGB (the IEC 61966-2-1 curve), clamped.
cv::Mat srgbEncode8(const cv::Mat& linear_rgb);

}  // namespace solo
