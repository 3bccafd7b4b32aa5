#include "commands.h"

#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/lighting/light_category.h>

#include <iostream>

namespace solo::tools {

/// The input stage with a census of the light map, shared by `info` and `night`.
StageReport inputStage(const Scene& scene, double seconds) {
  StageReport stage = describeScene(scene);
  stage.seconds = seconds;
  if (!scene.lights.empty()) {
    const LightCensus census = countLights(scene.lights);
    stage.add("light_instances", census.total_instances());
    for (int c = kFirstLightCategory; c <= kLastLightCategory; ++c)
      if (census.instances[c] > 0)
        stage.add(std::string("lights_") + lightCategoryName(static_cast<LightCategory>(c)), census.instances[c]);
  }
  return stage;
}

int runInfo(const InfoOptions& options) {
  Stopwatch clock;
  const Scene scene = loadScene(options.scene);
  RunReport report;
  report.command = "info";
  report.scene = options.scene.string();
  report.stages.push_back(inputStage(scene, clock.seconds()));
  report.total_seconds = clock.seconds();
  report.versions = dependencyVersions();
  if (options.json) {
    std::cout << reportToJson(report);
    return 0;
  }
  const StageReport& s = report.stages.front();
  std::cout << "scene " << options.scene.string() << "\n";
  for (const Metric& m : s.metrics) {
    std::cout << "  " << m.name << ": ";
    std::visit([](const auto& v) { std::cout << v; }, m.value);
    std::cout << (m.unit.empty() ? "" : " " + m.unit) << "\n";
  }
  for (const std::string& note : s.notes) std::cout << "  note: " << note << "\n";
  return 0;
}

}  // namespace solo::tools
