// `solo night --batch LIST_OR_DIR -o OUT_DIR [--shard i/N] [--jobs J]`: `solo night` on every
// scene of a dataset (docs/batch.md), run by the library (pipeline/night_batch.h).
//
// Inputs: a list file (one manifest path a line, relative to the list's folder) or a folder
// searched for `scene.json` / `*.scene.json`; the parent's command line, forwarded to each scene.
// Outputs: OUT_DIR/<name>.png (with --layout DATASET at the frame's path in the dataset's
// layout, e.g. OUT_DIR/leftImg8bit_night/<split>/<city>/<stem>.png) and OUT_DIR/<name>.report.json
// per scene, the failures file and the batch summary (JSON), progress and a summary on the
// terminal. Exit 0 when every scene of the shard is done, 1 when one failed, 130 when interrupted.
//
// Each scene runs in a child process: this binary (/proc/self/exe) with the parent's arguments
// minus the batch ones.

#include "commands.h"

#include <solo/core/error.h>
#include <solo/pipeline/night_batch.h>

#include <iostream>

namespace solo::tools {

namespace {

std::string shardText(const NightBatchShard& shard) {
  return std::to_string(shard.index) + "/" + std::to_string(shard.count);
}

// Options naming one file would make every scene write it (from the command line or a config file).
void refuseSingleSceneOptions(const NightOptions& night, bool output_given) {
  if (night.job.scene)
    throw InputError(*night.job.scene, "a scene and --batch were both given: list the scene in the batch instead");
  if (!output_given) throw InputError("--batch", "needs -o OUT_DIR, the folder for the outputs");
  if (night.job.report)
    throw InputError("--report", "cannot be used with --batch: each scene's report is OUT_DIR/<name>.report.json");
  if (night.job.render_exr)
    throw InputError("--render-exr", "cannot be used with --batch: it names one file for every scene");
  if (night.write_config)
    throw InputError("--write-config", "cannot be used with --batch: write the configuration with a one-scene run");
}

void printPlan(const NightBatchPlan& plan, const solo::NightBatchOptions& options) {
  std::cout << "batch: " << plan.scenes_in_batch << " scenes in " << options.list.string();
  if (plan.ground_truth_left_out > 0)
    std::cout << " (" << plan.ground_truth_left_out << " ground-truth manifests left out)";
  if (plan.shard.count > 1)
    std::cout << ", shard " << shardText(plan.shard) << ": " << plan.scenes.size() << " of them";
  std::cout << "; " << options.jobs << (options.jobs == 1 ? " job" : " jobs") << "; outputs in "
            << plan.output_folder.string() << "\n"
            << std::flush;
}

/// One terminal line per scene event: "[k/n] name: ...".
void printSceneEvent(const NightBatchEvent& event, const NightBatchPlan& plan, const NightBatchSceneOutcome& o) {
  const std::string& name = plan.scenes[event.scene].name;
  std::cout << "[" << event.scene + 1 << "/" << plan.scenes.size() << "] " << name << ": ";
  switch (event.kind) {
    case NightBatchEvent::Kind::SceneSkipped:
      std::cout << "already done, skipped";
      break;
    case NightBatchEvent::Kind::SceneStartFailed:
      std::cout << "FAILED, " << o.reason;
      break;
    case NightBatchEvent::Kind::SceneStarted:
      std::cout << "started";
      break;
    default:  // SceneEnded
      if (o.status == NightBatchStatus::Done)
        std::cout << "done in " << nightBatchSeconds(o.seconds) << ", peak memory " << static_cast<long>(o.peak_rss_MiB)
                  << " MiB";
      else
        std::cout << (o.status == NightBatchStatus::Failed ? "FAILED, " : "interrupted, ") << o.reason << " (log: logs/"
                  << name << ".log)";
  }
  std::cout << "\n" << std::flush;
}

void printProgress(const NightBatchEvent& event, const NightBatchPlan& plan,
                   const std::vector<NightBatchSceneOutcome>& outcomes, const solo::NightBatchOptions& options) {
  if (event.kind == NightBatchEvent::Kind::Planned) return printPlan(plan, options);
  if (event.kind == NightBatchEvent::Kind::Interrupted) {
    std::cout << "batch: interrupted (signal " << event.signal << "), stopping " << event.running
              << " running scene(s)\n"
              << std::flush;
    return;
  }
  printSceneEvent(event, plan, outcomes[event.scene]);
}

void printSummary(const NightBatchResult& r) {
  std::cout << "batch summary (shard " << shardText(r.plan.shard) << "): " << r.plan.scenes.size() << " scenes, "
            << r.done << " done, " << r.skipped << " skipped (already done), " << r.failed << " failed";
  if (r.interrupted) std::cout << ", " << r.interrupted << " interrupted or not started";
  std::cout << "; " << nightBatchSeconds(r.total_seconds) << "; peak memory of a scene "
            << static_cast<long>(r.peak_rss_MiB) << " MiB\n";
  if (r.failed) std::cout << "failures: " << r.failures_file.string() << "\n";
  std::cout << "summary: " << r.summary_file.string() << "\n" << std::flush;
}

}  // namespace

int runNightBatch(const NightBatchOptions& batch, const NightOptions& night) {
  solo::NightBatchOptions options;
  options.list = *batch.list;
  options.shard = batch.shard;
  options.jobs = batch.jobs;
  options.scene_timeout_s = batch.scene_timeout_s;
  if (!batch.layout.empty()) options.layout = parseDataset(batch.layout, "--layout");
  options.output_folder = night.job.output;
  options.seed = night.conversion.seed;
  options.contact_sheet = night.job.contact_sheet.has_value();
  options.executable = "/proc/self/exe";
  options.versions = dependencyVersions();
  checkNightBatchOptions(options);  // the batch's own options first, then the scene options it refuses
  const ForwardedSceneArguments forwarded = forwardedSceneArguments(batch.arguments);
  refuseSingleSceneOptions(night, forwarded.output_given);
  options.arguments = forwarded.arguments;

  const NightBatchResult result =
      solo::runNightBatch(options, [&options](const NightBatchEvent& event, const NightBatchPlan& plan,
                                              const std::vector<NightBatchSceneOutcome>& outcomes) {
        printProgress(event, plan, outcomes, options);
      });
  printSummary(result);
  if (result.interrupt_signal) return 128 + result.interrupt_signal;
  return result.failed > 0 ? 1 : 0;
}

}  // namespace solo::tools
