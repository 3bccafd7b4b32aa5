// `solo depth SCENE -o refined.exr [--report r.json]`: the depth refinement stage alone.

#include "commands.h"
#include <solo/pipeline/night_conversion.h>

#include <solo/geometry/depth_refinement.h>
#include <solo/core/image_io.h>
#include <solo/core/report.h>
#include <solo/core/scene.h>

#include <iostream>

namespace fs = std::filesystem;

namespace solo::tools {


namespace {

/// <folder>/<stem>.<what><extension>
fs::path besides(const fs::path& output, const std::string& what, const std::string& extension) {
  return output.parent_path() / (output.stem().string() + "." + what + extension);
}

}  // namespace

int runDepth(const DepthOptions& options) {
  Stopwatch total;
  const fs::path report_file = options.report ? *options.report : besides(options.output, "report", ".json");
  const fs::path normals_file = besides(options.output, "normals", options.output.extension().string());
  const fs::path uncertain_file = besides(options.output, "uncertain", ".png");

  RunReport report;
  report.command = "depth";
  report.scene = options.scene.string();
  report.versions = dependencyVersions();

  Stopwatch clock;
  const Scene scene = loadScene(options.scene);
  report.stages.push_back(sceneInputReport(scene, clock.seconds()));

  const DepthRefinementResult result = refineDepth(sceneForRefinement(scene), options.refinement);
  for (const StageReport& step : result.steps) report.stages.push_back(step);
  report.stages.push_back(result.report);

  writeDepth(options.output, result.depth_m);
  writeNormals(normals_file, result.depth_normals);
  writeImage(uncertain_file, result.uncertain);
  report.notes.push_back("wrote " + options.output.string() + ", " + normals_file.string() + ", " +
                         uncertain_file.string());
  report.total_seconds = total.seconds();
  writeReportJson(report_file, report);
  std::cout << reportSummary(report) << "refined depth: " << options.output.string() << "\nnormals: "
            << normals_file.string() << "\nuncertain mask: " << uncertain_file.string()
            << "\nreport: " << report_file.string() << "\n";
  return 0;
}

}  // namespace solo::tools
