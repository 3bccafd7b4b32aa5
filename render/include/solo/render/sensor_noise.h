#pragma once
// Heteroscedastic Gaussian sensor noise in a 10-bit raw-like space: an exposed linear
// value v (1 = sensor white) becomes the raw level I = black + v (white - black) counts,
// gets Gaussian noise of variance scale^2 (beta1 I + beta2), is rounded to whole counts,
// clipped to [0, white] and mapped back. beta1 and beta2 come from a phone sensor's
// calibration table by ISO (the reference: ISO 3200, standard deviation x3).

#include <solo/geometry/report.h>

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
  double std_scale = 3.0;  ///< multiplies the standard deviation (the reference: 3)
  int black_level = 64;    ///< raw counts
  int white_level = 1023;  ///< raw counts (10 bit)
  bool quantise = true;    ///< round to whole raw counts
  bool clip = true;        ///< clip raw values to [0, white_level]
  std::uint64_t seed = 0;
};

/// Variance of the added noise in raw counts^2 at raw level `raw_counts` (black level
/// included): std_scale^2 * max(0, beta1 * I + beta2), I clamped to [0, white_level].
/// Rounding adds 1/12 count^2 on top when quantise is on.
double noiseVarianceCounts(double raw_counts, const SensorNoiseOptions& options);

/// Noise variance in the render's linear units for a pixel value `render_value` (before
/// exposure) that the exposure multiplies by `exposure_scale`: what a renderer's adaptive
/// sampling can aim its Monte Carlo variance at (rounding excluded).
double noiseVarianceRenderUnits(double render_value, double exposure_scale, const SensorNoiseOptions& options);
/// The same for every pixel and channel of a CV_32FC3 render: CV_32FC3 variances.
cv::Mat noiseVarianceRenderUnits(const cv::Mat& render, double exposure_scale, const SensorNoiseOptions& options);

/// The noise's standard deviation in the renderer's units as a function of a pixel's
/// luminance Y, for a render that is multiplied by `render_to_input` before the
/// post-process and by `exposure_scale` in it: sqrt(noiseVarianceRenderUnits(Y
/// render_to_input, exposure_scale)) / render_to_input. For the path tracer's noise-matched
/// stopping rule (PathTracerOptions::noise_sigma). Throws std::invalid_argument for invalid
/// options or scales <= 0.
std::function<double(double)> sensorNoiseSigma(double render_to_input, double exposure_scale,
                                               const SensorNoiseOptions& options);

/// Adds the noise in place to an exposed linear CV_32FC3 image (1 = sensor white).
/// Seeded per row, so the result depends on the seed only, not on the thread count.
/// Report "noise": ISO, beta1, beta2, the standard deviation at the black level and at
/// mid grey (linear 0.18), clipped pixel counts.
StageReport applySensorNoise(cv::Mat& exposed_linear, const SensorNoiseOptions& options);

}  // namespace solo
