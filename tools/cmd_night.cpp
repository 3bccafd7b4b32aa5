// `solo night`: one scene through the night conversion (pipeline/night_job.h), its progress on
// stderr and its summary on stdout.

#include "commands.h"

#include <solo/core/report.h>

#include <iostream>

namespace solo::tools {

int runNight(const NightOptions& o) {
  NightJobOptions job = o.job;
  job.preset = o.preset;
  job.versions = dependencyVersions();
  if (o.write_config) job.text_file = std::make_pair(*o.write_config, nightConfigText(o));  // throws before any work
  NightConversionCallbacks callbacks;
  bool line_open = false;  // a "stage ... " line waits for its end
  callbacks.stage_started = [&line_open](const std::string& stage) {
    if (stage == "render") {
      std::cerr << "render\n" << std::flush;
      line_open = false;
    } else if (stage != "denoise" && stage != "post") {
      std::cerr << stage << " ... " << std::flush;
      line_open = true;
    }
  };
  NightJobResult result;
  try {
    result = runNightJob(job, o.conversion, callbacks);
  } catch (...) {
    if (line_open) std::cerr << "\n";  // the error goes on a line of its own
    throw;
  }
  SummaryOptions summary;
  summary.notes = o.verbose;
  std::cout << reportSummary(result.report, summary) << "night image: " << job.output.string()
            << "\nreport: " << result.report_file.string() << "\n";
  return 0;
}

}  // namespace solo::tools
