#pragma once
// Bradford chromatic adaptation: moves XYZ colours from one reference white to another
// (the renderer's white point E to D65, where sRGB's white lies).

#include <solo/core/report.h>

#include <opencv2/core.hpp>

namespace solo {

/// Reference whites as XYZ with Y = 1.
inline const cv::Vec3d kWhitePointE{1.0, 1.0, 1.0};
inline const cv::Vec3d kWhitePointD65{0.95047, 1.0, 1.08883};

/// The Bradford cone-response matrix (rows: rho, gamma, beta).
cv::Matx33d bradfordConeMatrix();

/// The 3x3 matrix A with xyz_destination = A * xyz_source that maps source_white to
/// destination_white through the Bradford cone space: A = M^-1 diag(M d / M s) M.
/// Throws std::invalid_argument for a white with a non-positive cone response.
cv::Matx33d bradfordAdaptation(const cv::Vec3d& source_white_xyz, const cv::Vec3d& destination_white_xyz);

struct ChromaticAdaptationOptions {
  cv::Vec3d source_white = kWhitePointE;         ///< white of the render (the reference renders to E)
  cv::Vec3d destination_white = kWhitePointD65;  ///< white of the output space (sRGB: D65)
};

/// Applies the adaptation in place to a CV_32FC3 XYZ image.
/// Report "adaptation": the matrix entries; skipped when the two whites are equal.
StageReport applyChromaticAdaptation(cv::Mat& xyz, const ChromaticAdaptationOptions& options);

}  // namespace solo
