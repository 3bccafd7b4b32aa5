// `solo fda`: the Fourier domain adaptation baseline, a day photo toward a night photo.

#include "commands.h"

#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/output_path.h>
#include <solo/core/report.h>
#include <solo/post/colour_encoding.h>
#include <solo/post/fda.h>

#include <iostream>

namespace solo::tools {

int runFda(const FdaCommandOptions& o) {
  Stopwatch total;
  FdaOptions options;
  options.beta = o.beta;
  validateFdaOptions(options);
  refuseOutputThatIsAnInput(o.output, {o.source, o.target}, "-o");
  if (o.report) refuseOutputThatIsAnInput(*o.report, {o.source, o.target}, "--report");
  RunReport report;
  report.command = "fda";
  report.scene = o.source.string();
  report.versions = dependencyVersions();
  const cv::Mat source = readColorImage(o.source);
  const cv::Mat target = readColorImage(o.target);
  FdaResult result = fourierDomainAdaptation(source, target, options);
  const std::string ext = lowercaseExtension(o.output);
  if (ext == ".exr") {
    writeImage(o.output, result.image);  // unclamped, as encoded in the inputs
  } else {
    if (ext != ".png" && ext != ".tif" && ext != ".tiff" && ext != ".jpg" && ext != ".jpeg")
      throw InputError(o.output, "unsupported output format \"" + ext + "\" (use .png, .tif, .jpg or .exr)");
    cv::Mat clamped = cv::max(cv::min(result.image, 1.0), 0.0);
    writeImage(o.output, quantiseEncoded(clamped, o.sixteen_bit && ext != ".jpg" && ext != ".jpeg" ? 16 : 8));
  }
  report.stages.push_back(std::move(result.report));
  report.total_seconds = total.seconds();
  if (o.report) writeReportJson(*o.report, report);
  std::cout << reportSummary(report) << "wrote " << o.output.string() << "\n";
  return 0;
}

}  // namespace solo::tools
