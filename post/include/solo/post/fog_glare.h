#pragma once
// Fog glare (Blender's FOG_GLOW, as the reference uses it): bright pixels are convolved
// with a wide, peaked kernel and the glow is added to the image (output = input + glow).
// Works on linear radiance before exposure. The cost follows what the image holds: no
// bright pixel costs nothing, a few bright pixels are splatted directly, clustered ones
// are convolved by FFT over their bounding region only (plus the kernel radius), spread
// ones tile by tile; a full bright field costs one FFT of the image plus one kernel radius.

#include <solo/core/report.h>

#include <opencv2/core.hpp>

namespace solo {

/// How the convolution is computed; all give the same glow to float precision.
enum class GlareMethod {
  Automatic,  ///< cheapest by the cost model below
  Direct,     ///< splat the kernel around every bright pixel
  Fft,        ///< one FFT over the bounding region of all bright pixels
  TiledFft,   ///< one FFT per occupied tile (overlap-add)
};

struct FogGlareOptions {
  int size = 9;  ///< Blender glare size: the kernel is 2^size px wide (9: 512 px, radius 255 px)
  /// Luminance (Y, linear render units, before exposure) a pixel must exceed to glow; it
  /// contributes its colour scaled by (Y - threshold) / Y. The reference uses 0.
  double threshold = 0;
  /// Share of each bright pixel's luminance above the threshold that the glow carries (the rest
  /// stays in the pixel, which clips anyway). 1 is the reference (the glow adds the full excess
  /// again); a lens scatters a few per cent into its veiling glare (docs/post-processing.md).
  double scatter_fraction = 1;
  GlareMethod method = GlareMethod::Automatic;
};

/// The FOG_GLOW kernel, CV_32F, n x n with n = 2^size, centre at (n/2, n/2), sum 1:
/// with u, v = 2 x / n - 1, rr = (u^2 + v^2) * n / 4,
/// k = exp(-9 * rr^(1/8)) * hann(u) * hann(v), hann(t) = 0.5 + 0.5 cos(pi t).
/// Row and column 0 are zero (hann(-1) = 0): the support is the centre +- (n/2 - 1).
/// Throws std::invalid_argument for size outside [2, 11].
cv::Mat fogGlowKernel(int size);

/// Adds the glow in place to a CV_32FC3 linear XYZ image (luminance = channel 1) whose
/// values are finite and non-negative. Report "glare": bright pixel count, method, FFT
/// sizes, the share of the bright energy that lands inside the frame; skipped when no
/// pixel exceeds the threshold. Throws std::invalid_argument for a negative threshold or a
/// scatter fraction outside (0, 1].
StageReport applyFogGlare(cv::Mat& linear_xyz, const FogGlareOptions& options);

}  // namespace solo
