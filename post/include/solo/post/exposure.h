#pragma once
// Exposure: multiplies linear radiance by 2^stops. The stops come either directly (the
// reference's +3.25) or from a physical camera (ISO, shutter, aperture) relative to a
// reference camera that is defined to give exactly the reference's +3.25 stops.

#include <solo/core/report.h>

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
/// spp, 76 at 16, 80 at 32, 81 at 128; at 4 spp of a 240x135 preview, 49 against a converged 78
/// (docs/rendering.md). Fixed, so every preset meters the same exposure.
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

/// The camera whose auto exposure `solo night` imitates: a fixed-aperture video camera (a
/// dashcam or action camera of the kind night driving datasets are recorded with) that meters
/// the frame's mean luminance to the reflected-light meter's grey and, at night, runs out of
/// exposure: the shutter cannot stay open longer than one video frame and the gain stops at the
/// highest ISO. From then on a darker street gives a darker image, and lamps clip. Sources of
/// each constant: docs/post-processing.md, "Night camera".
struct NightCameraOptions {
  double f_number = 2.8;               ///< fixed aperture (action cameras: f/2.8)
  double min_shutter_s = 1.0 / 8000.0;  ///< shortest exposure time, seconds
  double max_shutter_s = 1.0 / 30.0;    ///< longest: one frame of 30 fps video, seconds
  double min_iso = 100;
  double max_iso = 3200;                ///< highest gain (the top of the noise calibration)
  double meter_constant = 12.5;         ///< reflected-light meter calibration K (ISO 2720), cd s / m^2
  double saturation_exposure = 78;      ///< H_sat * S in lux s: ISO 12232 saturation-based speed
  double lens_factor = 0.65;            ///< q of ISO 12232: image-plane illuminance = q L / N^2
  /// Exposure compensation of the camera's night mode, EV: the meter aims at 2^ev times the
  /// exposure that puts the mean at the meter's grey (a negative value keeps night scenes dark).
  double compensation_ev = 0;
};

/// What the camera chose for one frame.
struct NightCameraExposure {
  CameraExposure camera;        ///< ISO, shutter time and f-number
  double metered_cd_m2 = 0;     ///< the mean luminance the meter read
  double white_cd_m2 = 0;       ///< scene luminance that reaches sensor white at these settings
  bool at_exposure_limit = false;  ///< longest shutter and highest ISO: the frame is under-exposed
  bool at_bright_limit = false;    ///< shortest shutter and lowest ISO: the frame is over-exposed
};

/// The auto exposure of the camera above for a frame whose metered mean luminance is
/// `metered_cd_m2`: the exposure that puts it at the meter's grey, N^2 / t = L S / K, times
/// 2^compensation_ev, reached
/// by lengthening the shutter at the lowest ISO first and then raising the ISO, each within its
/// limits. White is the saturation luminance of ISO 12232, L_white = H_sat N^2 / (q S t); at the
/// meter's grey (no compensation) a frame's mean sits at K q / H_sat = 10.4 % of white. A metered luminance of 0
/// (nothing lit) takes the exposure limit. Throws std::invalid_argument for a negative or
/// non-finite luminance and for options that are not positive, finite and ordered.
NightCameraExposure nightCameraExposure(double metered_cd_m2, const NightCameraOptions& options = {});

/// The settings of the same camera that expose `white_cd_m2` (> 0) to sensor white: the longest
/// shutter and the ISO that L_white = H_sat N^2 / (q S t) asks for, clamped to the ISO range
/// (white_cd_m2 is kept even where the ISO clamps: the flags are set instead). For a fixed
/// exposure (`solo night --sensor-white`): the sensor noise follows this ISO.
NightCameraExposure nightCameraForWhite(double white_cd_m2, const NightCameraOptions& options = {});

/// The meter of that camera: the mean luminance (cd/m^2, the Y of a CV_32FC3 XYZ render) of the
/// pixels where no sample saw an emitter (`emitter_coverage` 0; CV_32F, the same size), as a
/// camera's matrix metering discounts the light sources in the frame. 0 when there is no such
/// pixel. Throws std::invalid_argument on other types or sizes.
double meteredMeanLuminance(const cv::Mat& radiance_xyz, const cv::Mat& emitter_coverage);

/// Multiplies every channel of a linear CV_32FC3 image by exposureScale(options) in place.
/// Report "exposure": stops, scale; skipped (image untouched) when the stops are 0.
StageReport applyExposure(cv::Mat& linear_image, const ExposureOptions& options);

}  // namespace solo
