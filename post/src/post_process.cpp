#include <solo/post/post_process.h>

#include <solo/core/option_checks.h>

#include <atomic>
#include <cmath>
#include <stdexcept>
#include <variant>

namespace solo {

namespace {

StageReport sanitise(cv::Mat& image) {
  Stopwatch clock;
  StageReport report;
  report.name = "input";
  std::atomic<std::int64_t> nan{0}, inf{0}, negative{0};
  cv::parallel_for_(cv::Range(0, image.rows), [&](const cv::Range& rows) {
    std::int64_t local_nan = 0, local_inf = 0, local_negative = 0;
    for (int y = rows.start; y < rows.end; ++y) {
      float* p = image.ptr<float>(y);
      for (int i = 0; i < image.cols * 3; ++i) {
        if (std::isnan(p[i])) ++local_nan, p[i] = 0.f;
        else if (std::isinf(p[i])) ++local_inf, p[i] = 0.f;
        else if (p[i] < 0.f) ++local_negative, p[i] = 0.f;
      }
    }
    nan += local_nan;
    inf += local_inf;
    negative += local_negative;
  });
  const std::int64_t nan_count = nan.load(), inf_count = inf.load(), negative_count = negative.load();
  report.add("width", static_cast<std::int64_t>(image.cols), "px");
  report.add("height", static_cast<std::int64_t>(image.rows), "px");
  report.add("nan_values", nan_count);
  report.add("inf_values", inf_count);
  report.add("negative_values", negative_count);
  if (nan_count + inf_count + negative_count > 0)
    report.notes.push_back(std::to_string(nan_count + inf_count + negative_count) +
                           " NaN, infinite or negative channel values set to 0 (a render should have none)");
  const cv::Scalar mean = cv::mean(image);
  report.add("mean_luminance", mean[1]);
  report.seconds = clock.seconds();
  return report;
}

StageReport switchedOff(const std::string& name, const std::string& flag) {
  StageReport report;
  report.name = name;
  report.skipped = true;
  report.skip_reason = "switched off (" + flag + ")";
  return report;
}

// The glare options with a negative threshold made what will clip: the luminance the encoding's
// white clip stands for before exposure.
FogGlareOptions resolvedGlare(const PostProcessOptions& options) {
  FogGlareOptions glare = options.glare_options;
  if (glare.threshold < 0) glare.threshold = options.encoding_options.white_clip / exposureScale(options.exposure_options);
  return glare;
}

// The exposure's settings: stops, or the camera's shutter, f-number and ISO.
void validateExposureOptions(const ExposureOptions& exposure) {
  requireOptionInRange(exposure.stops, -64, 64, "--stops");
  if (!exposure.camera) return;
  requireOptionInRange(exposure.camera->shutter_s, 1e-6, 3600, "--shutter");
  requireOptionInRange(exposure.camera->f_number, 0.5, 64, "--f-number");
  requireOptionInRange(exposure.camera->iso, 100, 3200, "--iso");
}

}  // namespace

void validatePostProcessOptions(const PostProcessOptions& options) {
  const FogGlareOptions& glare = options.glare_options;
  requireOptionInRange(glare.size, 2, 11, "--glare-size");
  requireOptionInRange(glare.threshold, -1e30, 1e30, "--glare-threshold");
  requireOptionAboveAndAtMost(glare.scatter_fraction, 0, 1, "--glare-scatter");
  validateExposureOptions(options.exposure_options);
  const SensorNoiseOptions& noise = options.noise_options;
  requireOptionInRange(noise.iso, 100, 3200, "--iso");
  requireOptionInRange(noise.std_scale, 0, 1e6, "--noise-scale");
  requireOptionInRange(noise.chroma_denoise_sigma_px, 0, 100, "--chroma-denoise");
  requireOptionInRange(noise.chroma_denoise_strength, 0, 1, "--chroma-denoise-strength");
  const ColourEncodingOptions& encoding = options.encoding_options;
  requireOptionInRange(encoding.highlight_knee, 0, 1, "--highlight-knee");
  requireOptionInRange(encoding.white_clip, 1, 1e6, "--white-clip");
  if (!(encoding.knee_point > 0 && encoding.knee_point < 1))
    throw InputError("--knee-point", "must be between 0 and 1 (exclusive), got " + std::to_string(encoding.knee_point));
}

PostProcessResult postProcess(const cv::Mat& xyz_e, const PostProcessOptions& options) {
  Stopwatch total;
  if (xyz_e.empty() || xyz_e.type() != CV_32FC3)
    throw std::invalid_argument("post-processing needs a non-empty 3-channel float XYZ image");
  // Option errors surface before any work is done.
  validatePostProcessOptions(options);
  if (options.exposure) exposureStops(options.exposure_options);
  if (options.noise) noiseVarianceCounts(0, options.noise_options);
  if (options.glare) {
    fogGlowKernel(options.glare_options.size);
    if (!std::isfinite(options.glare_options.threshold))
      throw std::invalid_argument("glare threshold must be a finite luminance (or negative: what clips)");
  }
  PostProcessResult result;
  cv::Mat image = xyz_e.clone();
  result.steps.push_back(sanitise(image));

  result.steps.push_back(options.glare ? applyFogGlare(image, resolvedGlare(options)) : switchedOff("glare", "no glare"));
  result.steps.push_back(options.exposure ? applyExposure(image, options.exposure_options)
                                          : switchedOff("exposure", "no exposure"));
  // The encoded chroma noise reduction needs the image without the noise, carried through
  // the adaptation and the colour step beside it.
  const SensorNoiseOptions& noise = options.noise_options;
  const bool encoded_chroma = options.noise && noise.chroma_denoise_sigma_px > 0 && noise.chroma_denoise_strength > 0;
  cv::Mat clean = encoded_chroma ? image.clone() : cv::Mat();
  result.steps.push_back(options.noise ? applySensorNoise(image, noise) : switchedOff("noise", "no noise"));
  result.steps.push_back(options.adaptation ? applyChromaticAdaptation(image, options.adaptation_options)
                                            : switchedOff("adaptation", "no adaptation"));
  if (encoded_chroma && options.adaptation) applyChromaticAdaptation(clean, options.adaptation_options);
  ColourEncodingResult colour = encodeXyzToSrgb(image, options.encoding_options);
  result.encoded = std::move(colour.encoded);
  result.linear_rgb = std::move(colour.linear_rgb);
  result.steps.push_back(std::move(colour.report));
  if (encoded_chroma) {
    Stopwatch clock;  // the step's time includes encoding the image without the noise
    const cv::Mat clean_encoded = encodeXyzToSrgb(clean, options.encoding_options).encoded;
    StageReport chroma = reduceEncodedChromaNoise(result.encoded, clean_encoded, noise);
    chroma.seconds = clock.seconds();
    result.steps.push_back(std::move(chroma));
  } else {
    result.steps.push_back(switchedOff("chroma", options.noise ? "no chroma noise reduction" : "no noise"));
  }

  result.report.name = "post";
  for (const StageReport& step : result.steps) {
    result.report.add(step.name + ".seconds", step.seconds, "s");
    for (const Metric& m : step.metrics) result.report.add(step.name + "." + m.name, m.value, m.unit);
    if (step.skipped) result.report.notes.push_back(step.name + " skipped: " + step.skip_reason);
    for (const std::string& note : step.notes) result.report.notes.push_back(step.name + ": " + note);
  }
  result.report.seconds = total.seconds();
  return result;
}

std::function<double(double)> renderNoiseSigma(double sensor_white_cd_m2, const PostProcessOptions& options) {
  const double exposure = exposureScale(options.exposure_options);
  return sensorNoiseSigma(1.0 / (sensor_white_cd_m2 * exposure), exposure, options.noise_options);
}

}  // namespace solo
