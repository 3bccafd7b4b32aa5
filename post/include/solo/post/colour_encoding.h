#pragma once
// XYZ (D65-relative) to display sRGB: the 3x3 matrix to linear sRGB, a deliberate
// treatment of colours outside the sRGB gamut and of highlights above white, then the
// transfer curve and quantisation.

#include <solo/core/report.h>

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

/// What happens to colours with a linear sRGB channel above 1 (highlights: lamps, lit
/// windows, their glare) when they are encoded.
enum class HighlightHandling {
  /// Move toward the grey of equal luminance, as a camera's highlights do: luminance and hue
  /// line kept, white once the luminance reaches 1; a smooth shoulder (highlight_knee).
  Desaturate,
  Clip,  ///< clip each channel at 1 (rotates hues: a saturated red lamp turns magenta or orange)
};

struct ColourEncodingOptions {
  TransferCurve curve = TransferCurve::Gamma22;
  NegativeHandling negatives = NegativeHandling::Desaturate;
  HighlightHandling highlights = HighlightHandling::Desaturate;
  /// Desaturate only: the share of a colour's chroma headroom (from its luminance Y up to 1)
  /// its largest channel may use before desaturation starts, in [0, 1]. Below it a colour is
  /// unchanged; above it the desaturation eases in with a continuous slope. 1 = a hard
  /// shoulder (every colour inside [0, 1]^3 unchanged).
  double highlight_knee = 0.8;
  /// Luminance roll-off of a video camera's knee: the linear luminance that encodes to full
  /// white (>= 1). 1 = none, everything above sensor white clips (the reference). Above it the
  /// image's luminance is compressed in the gamma-2.2 domain from `knee_point` up, with a
  /// straight slope that reaches 1 at white_clip (luminanceRolloff); the colour keeps its
  /// chromaticity, and the highlight handling above then treats channels still above 1.
  double white_clip = 1;
  double knee_point = 0.8;  ///< gamma-2.2-encoded luminance where the knee starts, in (0, 1)
};

/// The knee of a video camera on a linear luminance y >= 0: with e = y^(1/2.2), e is kept up to
/// `knee_point` and above it becomes knee_point + (e - knee_point) (1 - knee_point) /
/// (white_clip^(1/2.2) - knee_point), capped at 1; the result is decoded back to linear. Monotone
/// and continuous; the identity when white_clip is 1 (then only clipping at 1). Throws
/// std::invalid_argument for white_clip < 1 or non-finite, or knee_point outside (0, 1).
double luminanceRolloff(double y, double white_clip, double knee_point);

/// Linear sRGB from XYZ relative to D65 (Y = 1 white), derived from the sRGB primaries
/// and the D65 white (0.95047, 1, 1.08883): D65 white maps to (1, 1, 1).
cv::Matx33d xyzToLinearSrgbMatrix();
/// The Y row of its inverse: luminance weights of linear sRGB (sum 1).
cv::Vec3d linearSrgbLuminanceWeights();

/// One linear value through the curve, clamped to [0, 1] first.
float encodeTransfer(float linear, TransferCurve curve);
/// Inverse of encodeTransfer on [0, 1].
float decodeTransfer(float encoded, TransferCurve curve);

/// The Desaturate highlight treatment of one linear sRGB colour (channels >= 0, any size):
/// c -> Y + t (c - Y) with Y its luminance, t = s(u) / u, u = (max(c) - Y) / (1 - Y) the share
/// of the chroma headroom the colour uses and s the shoulder: s(u) = u up to `knee`, then
/// knee + (1 - knee)(1 - exp(-(u - knee) / (1 - knee))), which tends to 1. The result lies in
/// [0, 1]^3, has the luminance Y and the HSV hue of c, and is (1, 1, 1) once Y >= 1.
/// Throws std::invalid_argument for a knee outside [0, 1].
cv::Vec3f desaturateHighlight(const cv::Vec3f& linear_rgb, double knee);

struct ColourEncodingResult {
  cv::Mat linear_rgb;  ///< CV_32FC3 linear sRGB, no negative channel, not clipped above 1
  /// CV_32FC3 in [0, 1] after the highlight handling and the transfer curve.
  cv::Mat encoded;
  StageReport report;  ///< "colour": out-of-gamut, over-range and desaturated-highlight pixel counts
};

/// xyz_d65: CV_32FC3 XYZ relative to D65 (after adaptation), any finite values. Throws
/// std::invalid_argument for a highlight knee outside [0, 1] or an invalid white clip / knee point.
ColourEncodingResult encodeXyzToSrgb(const cv::Mat& xyz_d65, const ColourEncodingOptions& options);

/// CV_8UC3 or CV_16UC3 codes round(value * max) of an encoded image in [0, 1].
cv::Mat quantiseEncoded(const cv::Mat& encoded, int bits);

}  // namespace solo
