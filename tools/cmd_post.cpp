// `solo post`: the camera-like post-process applied to a linear XYZ render (white point E).

#include "commands.h"

#include <solo/pipeline/night_job.h>

#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/output_path.h>
#include <solo/core/report.h>
#include <solo/post/colour_encoding.h>
#include <solo/post/post_process.h>

#include <algorithm>
#include <cmath>
#include <cctype>
#include <iostream>
#include <stdexcept>
#include <vector>

namespace fs = std::filesystem;

namespace solo::tools {
namespace {

/// A 3-channel CV_32F image from any file readImageRaw reads: alpha dropped, integer files
/// divided by their largest code.
cv::Mat readThreeChannels(const fs::path& file, StageReport* report) {
  ImageFileInfo info;
  cv::Mat raw = readImageRaw(file, &info);
  if (raw.channels() != 3 && raw.channels() != 4)
    throw InputError(file, "expected 3 channels (X, Y, Z) or 4 with alpha, found " + std::to_string(raw.channels()));
  if (raw.channels() == 4) {
    std::vector<cv::Mat> planes;
    cv::split(raw, planes);
    planes.pop_back();
    cv::merge(planes, raw);
  }
  double max_code = 0;
  if (info.pixel_type == "uint8") max_code = 255;
  if (info.pixel_type == "uint16") max_code = 65535;
  if (max_code > 0) {
    raw /= max_code;
    if (report)
      report->notes.push_back(file.string() + " holds " + info.pixel_type +
                              " codes: divided by " + std::to_string(static_cast<int>(max_code)) +
                              " (an integer file cannot hold values above its white)");
  }
  return raw;
}

}  // namespace

int runPost(const PostOptions& o) {
  Stopwatch total;
  PostProcessOptions options;
  options.glare = o.glare;
  options.glare_options.size = o.glare_size;
  options.glare_options.threshold = o.glare_threshold;
  if (o.glare_method == "auto") options.glare_options.method = GlareMethod::Automatic;
  else if (o.glare_method == "direct") options.glare_options.method = GlareMethod::Direct;
  else if (o.glare_method == "fft") options.glare_options.method = GlareMethod::Fft;
  else if (o.glare_method == "tiled") options.glare_options.method = GlareMethod::TiledFft;
  else throw InputError("--glare-method", "expected auto, direct, fft or tiled, got \"" + o.glare_method + "\"");
  if (!std::isfinite(o.glare_threshold)) throw InputError("--glare-threshold", "must be a number (-1: what clips)");
  if (!(o.glare_scatter > 0 && o.glare_scatter <= 1)) throw InputError("--glare-scatter", "must be in (0, 1]");
  options.glare_options.scatter_fraction = o.glare_scatter;
  if (o.glare_size < 2 || o.glare_size > 11) throw InputError("--glare-size", "must be between 2 and 11");

  options.exposure_options.stops = o.stops;
  if (o.shutter_s || o.f_number) {
    CameraExposure camera;
    camera.iso = o.iso;
    if (o.shutter_s) camera.shutter_s = *o.shutter_s;
    if (o.f_number) camera.f_number = *o.f_number;
    if (!(camera.shutter_s > 0)) throw InputError("--shutter", "must be a positive time in seconds");
    if (!(camera.f_number > 0)) throw InputError("--f-number", "must be positive");
    options.exposure_options.camera = camera;
  }
  options.noise = o.noise;
  options.noise_options.iso = o.iso;
  options.noise_options.std_scale = o.noise_scale;
  options.noise_options.seed = o.seed;
  try {
    noiseCalibrationAtIso(o.iso);
  } catch (const std::invalid_argument& e) {
    throw InputError("--iso", e.what());
  }
  if (!(o.noise_scale >= 0)) throw InputError("--noise-scale", "must be 0 or more");
  options.noise_options.demosaic = o.demosaic;
  if (!(o.chroma_denoise_px >= 0 && o.chroma_denoise_px <= 100))
    throw InputError("--chroma-denoise", "must be a Gaussian sigma of 0 to 100 px");
  options.noise_options.chroma_denoise_sigma_px = o.chroma_denoise_px;
  if (!(o.chroma_denoise_strength >= 0 && o.chroma_denoise_strength <= 1))
    throw InputError("--chroma-denoise-strength", "must be between 0 and 1");
  options.noise_options.chroma_denoise_strength = o.chroma_denoise_strength;
  options.adaptation = o.adaptation;
  if (o.curve == "gamma2.2") options.encoding_options.curve = TransferCurve::Gamma22;
  else if (o.curve == "srgb") options.encoding_options.curve = TransferCurve::Srgb;
  else if (o.curve == "linear") options.encoding_options.curve = TransferCurve::Linear;
  else throw InputError("--curve", "expected gamma2.2, srgb or linear, got \"" + o.curve + "\"");
  if (o.negatives == "desaturate") options.encoding_options.negatives = NegativeHandling::Desaturate;
  else if (o.negatives == "clip") options.encoding_options.negatives = NegativeHandling::Clip;
  else throw InputError("--negatives", "expected desaturate or clip, got \"" + o.negatives + "\"");
  if (o.highlights == "desaturate") options.encoding_options.highlights = HighlightHandling::Desaturate;
  else if (o.highlights == "clip") options.encoding_options.highlights = HighlightHandling::Clip;
  else throw InputError("--highlights", "expected desaturate or clip, got \"" + o.highlights + "\"");
  if (!(o.highlight_knee >= 0 && o.highlight_knee <= 1)) throw InputError("--highlight-knee", "must be between 0 and 1");
  options.encoding_options.highlight_knee = o.highlight_knee;
  if (!(o.white_clip >= 1 && std::isfinite(o.white_clip))) throw InputError("--white-clip", "must be a finite level >= 1");
  if (!(o.knee_point > 0 && o.knee_point < 1)) throw InputError("--knee-point", "must be between 0 and 1 (exclusive)");
  options.encoding_options.white_clip = o.white_clip;
  options.encoding_options.knee_point = o.knee_point;
  refuseOutputThatIsAnInput(o.output, {o.input}, "-o");
  if (o.report) refuseOutputThatIsAnInput(*o.report, {o.input}, "--report");

  RunReport report;
  report.command = "post";
  report.seed = o.seed;
  report.scene = o.input.string();
  report.versions = dependencyVersions();
  StageReport read;
  read.name = "read";
  Stopwatch clock;
  const cv::Mat xyz = readThreeChannels(o.input, &read);
  read.seconds = clock.seconds();
  read.add("width", static_cast<std::int64_t>(xyz.cols), "px");
  read.add("height", static_cast<std::int64_t>(xyz.rows), "px");
  report.stages.push_back(read);

  PostProcessResult result = postProcess(xyz, options);
  for (StageReport& step : result.steps) report.stages.push_back(std::move(step));

  clock = Stopwatch();
  writeDevelopedImage(o.output, result.encoded, result.linear_rgb, o.sixteen_bit);
  StageReport write;
  write.name = "write";
  write.seconds = clock.seconds();
  write.add("file", o.output.string());
  write.add("content", std::string(lowercaseExtension(o.output) == ".exr" ? "linear sRGB, float"
                                   : o.sixteen_bit                     ? "encoded sRGB, 16 bit"
                                                                       : "encoded sRGB, 8 bit"));
  report.stages.push_back(write);
  report.total_seconds = total.seconds();
  if (o.report) writeReportJson(*o.report, report);
  std::cout << reportSummary(report) << "wrote " << o.output.string() << "\n";
  return 0;
}

}  // namespace solo::tools
