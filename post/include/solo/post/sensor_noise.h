#pragma once
// Camera-like sensor noise on an exposed linear XYZ image (white E, 1 = sensor white), the
// noise a camera's output carries: the image seen through an RGGB Bayer mosaic of a camera
// whose raw RGB is linear sRGB with white E at (1, 1, 1), heteroscedastic Gaussian noise per
// photosite in a 10-bit raw space (level I = black + v (white - black) counts, variance
// scale^2 (beta1 I + beta2), rounded to whole counts, clipped to [0, white]), bilinear
// demosaicking, and the camera's chroma noise reduction (the noise's colour-difference
// channels smoothed, its luminance left; once in linear camera RGB and once after the
// transfer curve, reduceEncodedChromaNoise). Only the noise is added: the image's own values,
// above white included, pass through unchanged. beta1 and beta2 come from a phone sensor's
// calibration table by ISO (docs/post-processing.md).

#include <solo/core/report.h>
#include <solo/post/colour_encoding.h>

#include <opencv2/core.hpp>

#include <cstdint>
#include <functional>
#include <vector>

namespace solo {

/// Shot (beta1) and read (beta2, negative) terms of variance = beta1 * I + beta2, I in raw counts.
struct NoiseCalibration {
  double iso = 0;
  double beta1 = 0;
  double beta2 = 0;
};

/// The reference's calibration at ISO 100 ... 3200: the middle of each range over the Bayer
/// channels (docs/post-processing.md lists the values).
const std::vector<NoiseCalibration>& referenceNoiseCalibration();

/// beta1 and beta2 at any ISO in [100, 3200], linear in ISO between the listed ones.
/// Throws std::invalid_argument outside the calibrated range.
NoiseCalibration noiseCalibrationAtIso(double iso);

struct SensorNoiseOptions {
  double iso = 3200;
  /// Multiplies the standard deviation. 0.4 puts the final 8-bit luma noise statistic of a
  /// night image's mid-tones (encoded luma 30-45) at 0.9-1.0 codes at ISO 3200, as in real
  /// night photos (docs/post-processing.md; the reference's renderer used 3 for its own
  /// radiance scale).
  double std_scale = 0.4;
  int black_level = 64;    ///< raw counts
  int white_level = 1023;  ///< raw counts (10 bit)
  bool quantise = true;    ///< round to whole raw counts
  bool clip = true;        ///< the noisy raw stays in [0, white_level]: a saturated photosite has no noise
  bool demosaic = true;    ///< RGGB mosaic and bilinear demosaicking; false: every pixel samples R, G and B
  /// Chroma noise reduction: Gaussian standard deviation in pixels applied to the noise's
  /// colour differences B - Y and R - Y (Y: linear sRGB luminance); 0 = none.
  double chroma_denoise_sigma_px = 2.0;
  double chroma_denoise_strength = 1.0;  ///< share of the colour differences replaced by their smoothed version, [0, 1]
  std::uint64_t seed = 0;
};

/// Linear camera RGB from exposed XYZ relative to white E: linear sRGB after Bradford E to
/// D65, so white E gives (1, 1, 1) (a white-balanced raw).
cv::Matx33d cameraRgbFromXyzE();

/// Variance of one photosite's raw noise in counts^2 at raw level `raw_counts` (black level
/// included): std_scale^2 * max(0, beta1 * I + beta2), I clamped to [0, white_level].
/// Rounding adds 1/12 count^2 on top when quantise is on. Throws std::invalid_argument for
/// invalid options.
double noiseVarianceCounts(double raw_counts, const SensorNoiseOptions& options);

/// Ratio of the final luminance noise variance of a grey pixel to one photosite's variance:
/// sum over R, G, B of w_c^2 times the mean over the four Bayer phases of the squared
/// demosaicking weights (9/16, 5/8, 9/16 bilinear; 1 without demosaicking), w the linear sRGB
/// luminance weights. The chroma noise reduction leaves luminance unchanged.
double lumaVarianceFactor(const SensorNoiseOptions& options);

/// Variance of the final luminance noise (linear sRGB luminance, averaged over the Bayer
/// phases) for a grey pixel of value `render_value` (before exposure) that the exposure
/// multiplies by `exposure_scale`, in the render's linear units: what a renderer's adaptive
/// sampling can aim its Monte Carlo variance at (rounding excluded).
double noiseVarianceRenderUnits(double render_value, double exposure_scale, const SensorNoiseOptions& options);
/// The same for every pixel of a CV_32FC3 XYZ (white E) render, from each pixel's camera R,
/// G and B levels: CV_32FC1 luminance noise variances, render units.
cv::Mat noiseVarianceRenderUnits(const cv::Mat& render, double exposure_scale, const SensorNoiseOptions& options);

/// The final luminance noise's standard deviation in the renderer's units as a function of
/// a grey pixel's luminance Y, for a render that is multiplied by `render_to_input` before
/// the post-process and by `exposure_scale` in it: sqrt(noiseVarianceRenderUnits(Y
/// render_to_input, exposure_scale)) / render_to_input. For the path tracer's noise-matched
/// stopping rule (PathTracerOptions::noise_sigma). Throws std::invalid_argument for invalid
/// options or scales <= 0.
std::function<double(double)> sensorNoiseSigma(double render_to_input, double exposure_scale,
                                               const SensorNoiseOptions& options);

/// The luma noise statistic of ../shared/docs/realism.md (robust sigma of the 4-neighbour
/// high-pass of Y' = 0.299 R' + 0.587 G' + 0.114 B', in 8-bit codes) that a flat grey image
/// at exposed linear level `exposed_linear` (1 = sensor white, after exposure) gets from
/// this noise after the colour step with `curve` and 8-bit quantisation, at the image's own
/// resolution (no resize). First order in the noise: valid while the noise is small against
/// the level. Throws std::invalid_argument for invalid options or a level outside (0, 1).
double predictedLumaNoise8Bit(double exposed_linear, const SensorNoiseOptions& options,
                              TransferCurve curve = TransferCurve::Gamma22);

/// Adds the noise in place to an exposed linear CV_32FC3 XYZ image (white E, 1 = sensor
/// white). Seeded per row, so the result depends on the seed only, not on the thread count.
/// Report "noise": ISO, beta1, beta2, the photosite standard deviation at the black level and
/// at mid grey (linear 0.18), the predicted luminance sigma there, the added luminance and
/// chroma sigma measured on the image, clipped photosite counts.
StageReport applySensorNoise(cv::Mat& exposed_linear, const SensorNoiseOptions& options);

/// The camera's chroma noise reduction in the encoded image, where a camera's JPEG engine
/// applies it (Y'CbCr, after the transfer curve). The curve turns the luminance noise of a
/// saturated colour into colour differences, since its slope differs between the colour's
/// bright and dark channels; the linear reduction of applySensorNoise cannot reach those. The
/// noise `noisy_encoded - clean_encoded` (CV_32FC3 encoded RGB of the image with and without
/// the sensor noise) is split into Y' = 0.299 R' + 0.587 G' + 0.114 B' and B' - Y', R' - Y';
/// the colour differences are replaced by (1 - strength) x themselves + strength x their
/// Gaussian-smoothed version (options.chroma_denoise_sigma_px, chroma_denoise_strength), Y' is
/// kept; noisy_encoded becomes clean + the reduced noise within [0, 1], in place, except where
/// the noise is 0 (saturated or black-clipped pixels keep their value). Only the noise is smoothed,
/// so the image's own colours do not bleed across edges. Report "chroma": the noise's
/// colour-difference standard deviation before and after (8-bit codes).
StageReport reduceEncodedChromaNoise(cv::Mat& noisy_encoded, const cv::Mat& clean_encoded,
                                     const SensorNoiseOptions& options);

}  // namespace solo
