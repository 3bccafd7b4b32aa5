// solo mesh from-depth / solo mesh clean: the mesh stage on its own (docs/mesh.md).

#include "commands.h"
#include <solo/pipeline/night_conversion.h>

#include <solo/geometry/depth_mesh.h>
#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/geometry/triangle_mesh.h>

#include <cstdio>
#include <iostream>
#include <variant>

namespace fs = std::filesystem;

namespace solo::tools {
namespace {

std::string formatMetric(const Metric& m) {
  char buffer[64];
  if (const auto* d = std::get_if<double>(&m.value)) std::snprintf(buffer, sizeof buffer, "%.6g", *d);
  else if (const auto* i = std::get_if<std::int64_t>(&m.value)) std::snprintf(buffer, sizeof buffer, "%lld", static_cast<long long>(*i));
  else if (const auto* b = std::get_if<bool>(&m.value)) std::snprintf(buffer, sizeof buffer, "%s", *b ? "yes" : "no");
  else return std::get<std::string>(m.value);
  return buffer;
}

/// The readable summary: every metric on its own line, then the notes.
void printStage(const StageReport& stage) {
  std::cout << "solo " << stage.name << "\n";
  if (stage.skipped) std::cout << "  skipped: " << stage.skip_reason << "\n";
  for (const Metric& m : stage.metrics) {
    char line[160];
    std::snprintf(line, sizeof line, "  %-38s %s%s%s\n", m.name.c_str(), formatMetric(m).c_str(),
                  m.unit.empty() ? "" : " ", m.unit.c_str());
    std::cout << line;
  }
  for (const std::string& n : stage.notes) std::cout << "  note: " << n << "\n";
  std::printf("  %-38s %.3f s\n", "total time", stage.seconds);
  std::cout.flush();
}

void writeReport(const std::optional<fs::path>& file, const std::string& command, const std::string& input,
                 const StageReport& stage) {
  if (!file) return;
  RunReport report;
  report.command = command;
  report.scene = input;
  report.versions = dependencyVersions();
  report.stages.push_back(stage);
  report.total_seconds = stage.seconds;
  writeReportJson(*file, report);
}

/// Refuses a depth map in which no 2x2 block of pixels all hold a depth: the backprojection
/// makes its faces from such blocks, so the mesh would be empty.
void requireAFaceOfDepth(const Scene& scene) {
  const cv::Mat& depth = scene.depth_m;
  for (int y = 0; y + 1 < depth.rows; ++y) {
    const float* row = depth.ptr<float>(y);
    const float* below = depth.ptr<float>(y + 1);
    for (int x = 0; x + 1 < depth.cols; ++x)
      if (row[x] > 0 && row[x + 1] > 0 && below[x] > 0 && below[x + 1] > 0) return;
  }
  throw InputError(scene.manifest.depth,
                   "no 2x2 block of valid depth pixels in the " + std::to_string(depth.cols) + "x" +
                       std::to_string(depth.rows) + " map (" + std::to_string(scene.depth_stats.valid) +
                       " valid): a mesh face needs one, the mesh would be empty");
}

}  // namespace

int runMeshFromDepth(const MeshFromDepthOptions& options) {
  const Scene scene = loadScene(options.scene);
  requireAFaceOfDepth(scene);
  cv::Mat uncertain;
  if (options.uncertain) {
    uncertain = readLabels(*options.uncertain);
    uncertain.convertTo(uncertain, CV_8U);
  }
  cv::Mat true_depth, true_normals;
  if (options.truth) {
    const Scene truth = loadScene(*options.truth);
    if (truth.depth_m.size() != scene.depth_m.size())
      throw InputError(*options.truth, "ground-truth depth is " + std::to_string(truth.depth_m.cols) + "x" +
                                           std::to_string(truth.depth_m.rows) + ", the scene's depth " +
                                           std::to_string(scene.depth_m.cols) + "x" + std::to_string(scene.depth_m.rows));
    if (truth.normals.empty()) throw InputError(*options.truth, "ground truth has no normals");
    true_depth = truth.depth_m;
    true_normals = truth.normals;
  }
  StageReport stage;
  // The instance map as solo night's mesh stage sees it: each street light an instance of its own.
  std::int64_t street_light_pixels = 0;
  const cv::Mat instances = sceneForRefinement(scene, &street_light_pixels).instances;
  DepthMesh mesh =
      meshFromScene(scene.depth_m, scene.camera, instances, uncertain, options.cleanup, stage, true_depth, true_normals,
                    scene.normals);
  stage.add("street_light_pixels_relabelled", street_light_pixels);
  const Stopwatch clock;
  const TriangleMesh triangles = toTriangleMesh(mesh.mesh);
  if (triangles.faces.empty())
    throw InputError(scene.manifest.depth, "the mesh has no face after the clean-up: nothing to write");
  writeMesh(options.output, triangles);
  stage.add("seconds_write", clock.seconds(), "s");
  stage.seconds += clock.seconds();
  printStage(stage);
  writeReport(options.report, "mesh from-depth", options.scene.string(), stage);
  return 0;
}

int runMeshClean(const MeshCleanOptions& options) {
  Stopwatch clock;
  const TriangleMesh input = readMesh(options.input);
  const double read_seconds = clock.seconds();
  StageReport stage;
  const TriangleMesh output = cleanMesh(input, options.cleanup, stage, options.input);
  stage.metrics.insert(stage.metrics.begin(), Metric{"seconds_read", read_seconds, "s"});
  clock = Stopwatch();
  if (output.faces.empty()) throw InputError(options.input, "the mesh has no face: nothing to write");
  writeMesh(options.output, output);
  stage.add("seconds_write", clock.seconds(), "s");
  stage.seconds += read_seconds + clock.seconds();
  printStage(stage);
  for (const std::string& w : stage.warnings) std::cerr << "solo: warning: " << w << "\n";
  writeReport(options.report, "mesh clean", options.input.string(), stage);
  return 0;
}

}  // namespace solo::tools
