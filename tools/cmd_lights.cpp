#include "commands.h"

#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/lighting/light_overlay.h>
#include <solo/lighting/light_record.h>
#include <solo/lighting/light_stage.h>

#include <iostream>

namespace fs = std::filesystem;

namespace solo::tools {


int runLights(const LightsOptions& options) {
  validateLightStageOptions(options.stage);
  Stopwatch total;
  const fs::path scene_file = options.scene ? *options.scene : defaultScene();
  RunReport report;
  report.command = "lights";
  report.scene = scene_file.string();
  report.seed = options.stage.instantiation.seed;
  report.versions = dependencyVersions();

  const Scene scene = loadScene(scene_file);
  LightRecord record;
  if (options.from_record) {
    // An edited record: validate it against the scene and write it back normalised.
    Stopwatch clock;
    record = readLightRecord(*options.from_record);
    if (record.tree.width != scene.width() || record.tree.height != scene.height())
      throw InputError(*options.from_record, "made for a " + std::to_string(record.tree.width) + "x" +
                                                 std::to_string(record.tree.height) + " image, the scene is " +
                                                 std::to_string(scene.width()) + "x" + std::to_string(scene.height()));
    StageReport stage;
    stage.name = "lights";
    stage.seconds = clock.seconds();
    std::int64_t on = 0;
    for (const LightState& s : record.instantiation.lights) on += s.on;
    stage.add("lights", static_cast<std::int64_t>(record.tree.lights.size())).add("lights_on", on);
    stage.notes.push_back("lights read from " + options.from_record->string() + " (no sampling)");
    report.stages.push_back(stage);
  } else {
    LightStageOptions stage_options = options.stage;
    if (stage_options.illuminant_table.empty()) stage_options.illuminant_table = defaultIlluminantTable();
    LightStageResult result = runLightStage(scene, cv::Mat(), stage_options);
    record = std::move(result.record);
    report.stages.push_back(std::move(result.report));
  }

  writeLightRecord(options.output, record);
  if (options.overlay) writeImage(*options.overlay, drawLightOverlay(scene.image, record.tree, record.instantiation.lights));
  report.total_seconds = total.seconds();
  if (options.report) writeReportJson(*options.report, report);
  std::cout << reportSummary(report) << "lights: " << options.output.string() << "\n";
  if (options.overlay) std::cout << "overlay: " << options.overlay->string() << "\n";
  return 0;
}

}  // namespace solo::tools
