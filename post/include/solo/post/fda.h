#pragma once
// Fourier domain adaptation (FDA, Yang and Soatto 2020), the 2D baseline the paper
// compares against: per channel, the low-frequency amplitudes of the source image are
// replaced by the target's while the source phase is kept.

#include <solo/core/report.h>

#include <opencv2/core.hpp>

namespace solo {

struct FdaOptions {
  /// Band size: frequencies with |fy| < b and |fx| < b (cycles per image, b = floor(min(H, W)
  /// * beta)) take the target's amplitude. beta = 0 keeps the source; beta >= 0.5 + 1/min(H,W)
  /// on a square image replaces every amplitude. The FDA paper's 0.01 (its L) is the default.
  double beta = 0.01;
};

struct FdaResult {
  cv::Mat image;       ///< CV_32FC3, the source's size, not clamped (values may leave [0, 1])
  StageReport report;  ///< "fda": band half-size, swapped frequencies, share of values outside [0, 1]
};

/// Throws InputError("--beta", ...) unless 0 <= beta <= 1 (NaN fails): the option check the
/// library and `solo fda` share, made before any image is read.
void validateFdaOptions(const FdaOptions& options);

/// source, target: CV_32FC3 (any values; images as read, e.g. sRGB-encoded in [0, 1]).
/// A target of another size is resized to the source's (area averaging when shrinking,
/// bilinear when enlarging) and the report notes it. Throws std::invalid_argument for
/// empty or non-CV_32FC3 images, InputError for beta outside [0, 1] (validateFdaOptions).
FdaResult fourierDomainAdaptation(const cv::Mat& source, const cv::Mat& target, const FdaOptions& options);

}  // namespace solo
