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
#include <cctype>
#include <iostream>
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
  PostProcessOptions options = o.post;
  // --iso is the sensor's: the noise calibration's and the camera's.
  if (options.exposure_options.camera) options.exposure_options.camera->iso = options.noise_options.iso;
  validatePostProcessOptions(options);
  refuseOutputThatIsAnInput(o.output, {o.input}, "-o");
  if (o.report) refuseOutputThatIsAnInput(*o.report, {o.input}, "--report");

  RunReport report;
  report.command = "post";
  report.seed = options.noise_options.seed;
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
