#pragma once
// Exposure: multiplies linear radiance by 2^stops. The stops come either directly (the
// reference's +3.25) or from a physical camera (ISO, shutter, aperture) relative to a
// reference camera that is defined to give exactly the reference's +3.25 stops.

#include <solo/geometry/report.h>

#include <opencv2/core.hpp>

#include <optional>

namespace solo {

/// Camera settings. The reference camera {ISO 3200, 1/30 s, f/2} is +3.25 stops; every
/// doubling of ISO or shutter time adds a stop, every doubling of the f-number removes two.
struct CameraExposure {
  double iso = 3200;
  double shutter_s = 1.0 / 30.0;  ///< seconds
  double f_number = 2.0;
};

struct ExposureOptions {
  double stops = 3.25;                   ///< exposure compensation in stops (EV)
  std::optional<CameraExposure> camera;  ///< when set, replaces `stops`
};

/// The stops the options stand for. Throws std::invalid_argument for a camera with a
/// non-positive ISO, shutter or f-number, or non-finite stops.
double exposureStops(const ExposureOptions& options);
/// The linear factor 2^exposureStops(options).
double exposureScale(const ExposureOptions& options);

/// Size (pixels) of the preview render that meters the exposure before a noise-matched render
/// of width x height: a quarter of each side, or an eighth, a sixteenth ... (at most 1/64) while
/// the preview would have more than max_pixels; never below 16 x 16. A 95th percentile is
/// stable on a few thousand pixels, and the preview's cost grows with its pixel count.
cv::Size meteringPreviewSize(int width, int height, int max_pixels = 10000);

/// Samples per pixel of that preview, whatever the render's own sample settings. A pixel's mean
/// of a few heavy-tailed samples is mostly below its expectation, so the 95th percentile of a
/// few-sample render reads low: on the 1080p synthetic street (120x67 preview) 63 cd/m^2 at 8
/// spp, 76 at 16, 80 at 32, 81 at 128; at the former 4 spp of a 240x135 preview, 49 against a
/// converged 78 (docs/rendering.md). Fixed, so every preset meters the same exposure.
inline constexpr int kMeteringSamplesPerPixel = 32;

/// Auto exposure, metering the street rather than the lamps: the luminance (cd/m^2, the Y of a
/// CV_32FC3 XYZ render) that puts the `percentile` of the lit pixels where no sample saw an
/// emitter (`emitter_coverage` 0: RenderOutput::emitter_coverage, CV_32F, the same size) at
/// `level` of sensor white; 1 when no such pixel is lit. `solo night` uses 0.95 at 0.8.
/// The coverage rather than the first sample's light id, because in a small preview a lamp
/// covers a fraction of a pixel, and a pixel whose first sample missed it still carries its
/// light: on the 960x540 street the first-sample mask metered 8.22 cd/m^2 at the 120x67 preview
/// against 4.91 at full resolution (0.74 stops apart); the coverage 3.83 against 4.29.
/// Throws std::invalid_argument on other types or sizes.
double meteredSensorWhite(const cv::Mat& radiance_xyz, const cv::Mat& emitter_coverage, double percentile = 0.95,
                          double level = 0.8);

/// Multiplies every channel of a linear CV_32FC3 image by exposureScale(options) in place.
/// Report "exposure": stops, scale; skipped (image untouched) when the stops are 0.
StageReport applyExposure(cv::Mat& linear_image, const ExposureOptions& options);

}  // namespace solo
