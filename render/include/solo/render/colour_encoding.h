#pragma once
// XYZ (D65-relative) to display sRGB: the 3x3 matrix to linear sRGB, a deliberate
// treatment of colours outside the sRGB gamut, then the transfer curve and quantisation.

#include <solo/geometry/report.h>

#include <opencv2/core.hpp>

namespace solo {

/// Transfer curve from linear to encoded values.
enum class TransferCurve {
  Gamma22,  ///< pure power 1/2.2 (the reference)
  Srgb,     ///< IEC 61966-2-1 piecewise curve (linear segment below 0.0031308)
  Linear,   ///< no curve (for inspection)
};

/// What happens to colours with a negative linear sRGB channel (outside the gamut, e.g.
/// a saturated sodium or traffic-light colour).
enum class NegativeHandling {
  Desaturate,  ///< move toward the grey of equal luminance until the lowest channel is 0: keeps Y and hue
  Clip,        ///< set negative channels to 0 (raises luminance, shifts hue)
};

struct ColourEncodingOptions {
  TransferCurve curve = TransferCurve::Gamma22;
  NegativeHandling negatives = NegativeHandling::Desaturate;
};

/// Linear sRGB from XYZ relative to D65 (Y = 1 white), derived from the sRGB primaries
/// and the D65 white (0.95047, 1, 1.08883): D65 white maps to (1, 1, 1).
cv::Matx33d xyzToLinearSrgbMatrix();
/// The Y row of its inverse: luminance weights of linear sRGB (sum 1).
cv::Vec3d linearSrgbLuminanceWeights();

/// One linear value through the curve, clamped to [0, 1] first.
float encodeTransfer(float linear, TransferCurve curve);
/// Inverse of encodeTransfer on [0, 1].
float decodeTransfer(float encoded, TransferCurve curve);

struct ColourEncodingResult {
  cv::Mat linear_rgb;  ///< CV_32FC3 linear sRGB, no negative channel, not clipped above 1
  cv::Mat encoded;     ///< CV_32FC3 in [0, 1] after the transfer curve (channels above 1 clipped)
  StageReport report;  ///< "colour": out-of-gamut and over-range pixel counts
};

/// xyz_d65: CV_32FC3 XYZ relative to D65 (after adaptation), any finite values.
ColourEncodingResult encodeXyzToSrgb(const cv::Mat& xyz_d65, const ColourEncodingOptions& options);

/// CV_8UC3 or CV_16UC3 codes round(value * max) of an encoded image in [0, 1].
cv::Mat quantiseEncoded(const cv::Mat& encoded, int bits);

}  // namespace solo
