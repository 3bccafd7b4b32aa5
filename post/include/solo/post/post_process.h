#pragma once
// The camera-like finish of a night render, in the reference's order on linear XYZ
// relative to white point E: input check -> fog glare (linear radiance) -> exposure ->
// sensor noise (raw-like linear space) -> Bradford E to D65 -> XYZ to linear sRGB with
// out-of-gamut handling -> transfer curve (gamma 2.2) -> chroma noise reduction of the
// encoded noise. Every step can be switched off and says why when it does not run.

#include <solo/core/error.h>
#include <solo/core/report.h>
#include <solo/post/chromatic_adaptation.h>
#include <solo/post/colour_encoding.h>
#include <solo/post/exposure.h>
#include <solo/post/fog_glare.h>
#include <solo/post/sensor_noise.h>

#include <opencv2/core.hpp>

#include <functional>
#include <vector>

namespace solo {

/// FogGlareOptions whose threshold is -1: in postProcess, only the pixels that will clip glow.
inline FogGlareOptions glareAboveWhatClips() {
  FogGlareOptions glare;
  glare.threshold = -1;
  return glare;
}

/// The camera model's settings. Its defaults are the stages' own (the reference's glare
/// scatter 1, no video knee), except that only what clips glows; the night camera's are set
/// once in NightConversionOptions (pipeline/night_conversion.h).
struct PostProcessOptions {
  bool glare = true;
  /// A negative glare_options.threshold is what will clip: encoding_options.white_clip over
  /// the exposure's scale (only pixels that clip glow; the reference's 0 makes every pixel glow).
  FogGlareOptions glare_options = glareAboveWhatClips();
  bool exposure = true;
  ExposureOptions exposure_options;
  bool noise = true;
  SensorNoiseOptions noise_options;
  bool adaptation = true;
  ChromaticAdaptationOptions adaptation_options;
  ColourEncodingOptions encoding_options;  ///< the colour step always runs: it makes the output
};

struct PostProcessResult {
  cv::Mat encoded;     ///< CV_32FC3 RGB in [0, 1] after the transfer curve: the displayable image
  /// CV_32FC3 linear sRGB before the curve (no negatives, not clipped above 1), so without the
  /// encoded chroma noise reduction, which works after the curve
  cv::Mat linear_rgb;
  /// One report per step in order: input, glare, exposure, noise, adaptation, colour, chroma.
  std::vector<StageReport> steps;
  /// "post": total time, every step's metrics as "<step>.<metric>", a note per skipped step.
  StageReport report;
};

/// Refuses options outside their documented ranges (docs/pipeline.md, "Option checks"),
/// whether or not their step is on: InputError naming the `solo post` flag (--stops,
/// --shutter, --f-number, --iso, --glare-size, ...) with the range and the value.
void validatePostProcessOptions(const PostProcessOptions& options);

/// xyz_e: CV_32FC3 linear XYZ relative to white E (the renderer's output, 1 = the
/// reference exposure's unit radiance), any size. Non-finite and negative values are set to
/// 0 and counted (step "input"). Throws std::invalid_argument for an empty or non-CV_32FC3
/// image, and InputError for invalid options (validatePostProcessOptions), before any work.
PostProcessResult postProcess(const cv::Mat& xyz_e, const PostProcessOptions& options);

/// The standard deviation of the sensor noise the post-process adds, in render units
/// (cd/m^2), as a function of a pixel's luminance Y, for a render whose auto-exposure white is
/// `sensor_white_cd_m2` (> 0): the noise-matched target of PathTracerOptions::noise_sigma.
/// Uses the options' exposure and noise settings.
std::function<double(double)> renderNoiseSigma(double sensor_white_cd_m2, const PostProcessOptions& options = {});

}  // namespace solo
