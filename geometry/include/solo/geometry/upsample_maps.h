#pragma once
// Step 1 of depth refinement: bring every estimated map to the day image's resolution.
// Depth and normals bilinearly (invalid samples excluded, normals renormalised), albedo and
// roughness by joint bilateral upsampling guided by the day image, label maps by nearest
// neighbour. Maps already at the image resolution are passed through unchanged.

#include "solo/core/report.h"
#include "solo/core/scene.h"

#include <opencv2/core.hpp>

namespace solo {

struct UpsampleOptions {
  /// Off: maps of another resolution are resized by nearest neighbour (no interpolation).
  bool enabled = true;
  /// An output pixel is valid when at least this share of its bilinear weight falls on valid
  /// input samples (depth > 0, non-zero normals); 0.5 keeps the valid region's outline.
  double min_valid_weight = 0.5;
  /// Joint bilateral upsampling of albedo and roughness: colour sigma in sRGB [0, 1] units of
  /// the guide, spatial sigma in input (low-resolution) pixels.
  double material_sigma_color = 0.1;
  double material_sigma_space_px = 1;
};

/// The scene's maps at the image resolution (empty Mats stay empty).
struct UpsampledMaps {
  cv::Mat depth_m;    ///< CV_32F metres, 0 = invalid
  cv::Mat normals;    ///< CV_32FC3 unit, camera frame, (0,0,0) = invalid
  cv::Mat albedo;     ///< CV_32FC3 [0, 1]
  cv::Mat roughness;  ///< CV_32F [0, 1]
  cv::Mat instances;  ///< CV_32S Cityscapes instanceIds
  cv::Mat labels;     ///< CV_32S Cityscapes labelIds
  StageReport report; ///< "upsample": what was resized from which size, time
};

/// Valid-weighted bilinear resize of a CV_32F map (0 = invalid) to `size`: each output pixel
/// is the bilinear average of the valid samples around it, 0 when less than
/// `min_valid_weight` of the bilinear weight is valid. Pixel centres are aligned
/// (x_in = (x_out + 0.5) * in / out - 0.5), like PinholeCamera::scaledTo.
cv::Mat resizeValidBilinear(const cv::Mat& map, cv::Size size, double min_valid_weight = 0.5);

/// The same for CV_32FC3 normals ((0,0,0) = invalid), renormalised to unit length.
cv::Mat resizeNormalsBilinear(const cv::Mat& normals, cv::Size size, double min_valid_weight = 0.5);

/// Joint bilateral upsampling (Kopf et al. 2007) of a CV_32F or CV_32FC3 map to the guide's
/// size: each output pixel p averages the input samples q within 2 sigma_space (input pixels)
/// of its position with weights exp(-|p - q|^2 / 2 sigma_space^2) exp(-|I(p) - I(q)|^2 /
/// 2 sigma_color^2), I the guide (CV_32FC3, [0, 1]) at p and area-averaged over q's footprint.
cv::Mat jointBilateralUpsample(const cv::Mat& map, const cv::Mat& guide, double sigma_color, double sigma_space_px);

/// Upsamples depth, normals, albedo, roughness, instances and labels of `scene` to the
/// image resolution.
UpsampledMaps upsampleMaps(const Scene& scene, const UpsampleOptions& options = {});

}  // namespace solo
