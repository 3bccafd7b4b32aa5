#pragma once
// One night conversion from files to files, as `solo night` runs it: the scene manifest read,
// the conversion run, the night image (and on request the linear render with its AOVs and a
// contact sheet) written, and the run report written last. A run that fails leaves no output.

#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/pipeline/night_conversion.h>

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace solo {

struct NightJobOptions {
  std::optional<std::filesystem::path> scene;  ///< manifest; none: the embedded default scene
  /// .png (8-bit, or 16 with sixteen_bit), .tif, .jpg, .exr (linear sRGB).
  std::filesystem::path output = "night.png";
  std::optional<std::filesystem::path> report;      ///< none: <output stem>.report.json
  std::optional<std::filesystem::path> render_exr;  ///< the linear XYZ render; its AOVs beside it
  bool sixteen_bit = false;
  std::optional<std::filesystem::path> contact_sheet;  ///< PNG grid of the stages' pictures
  /// A text file written with the outputs, only when the conversion succeeded (the command
  /// line's effective configuration); checked like the other outputs.
  std::optional<std::pair<std::filesystem::path, std::string>> text_file;
  std::string preset;  ///< recorded in the report
  /// Library versions recorded in the report; empty: pipelineDependencyVersions().
  std::vector<std::pair<std::string, std::string>> versions;
};

struct NightJobResult {
  RunReport report;
  std::filesystem::path report_file;
};

/// Runs the job. Throws InputError naming the file or option for bad input (an unsupported
/// output format, an output that is one of the run's inputs, an unreadable map), before any
/// output is written.
NightJobResult runNightJob(const NightJobOptions& job, const NightConversionOptions& options,
                           const NightConversionCallbacks& callbacks = {});

/// The input stage of a run report: what describeScene reads, with a census of the light map.
StageReport sceneInputReport(const Scene& scene, double seconds);

/// Versions of the libraries the pipeline was built against (compile-time), name -> version.
std::vector<std::pair<std::string, std::string>> pipelineDependencyVersions();

/// Writes a developed (post-processed) image by extension: .png/.tif 8-bit (16-bit on
/// request) of the encoded image, .jpg 8-bit, .exr float linear sRGB. Atomic. Throws
/// InputError for another extension, or --16bit with JPEG.
void writeDevelopedImage(const std::filesystem::path& file, const cv::Mat& encoded, const cv::Mat& linear_rgb,
                         bool sixteen_bit);

}  // namespace solo
