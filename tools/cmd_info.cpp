#include "commands.h"

#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/pipeline/night_job.h>

#include <iostream>

namespace solo::tools {

int runInfo(const InfoOptions& options) {
  Stopwatch clock;
  const Scene scene = loadScene(options.scene);
  RunReport report;
  report.command = "info";
  report.scene = options.scene.string();
  report.stages.push_back(sceneInputReport(scene, clock.seconds()));
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
