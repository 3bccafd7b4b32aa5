#pragma once
// The night conversion of a whole dataset (docs/batch.md): every scene of a list file or a
// folder, a shard of them, each converted by a child process running `EXECUTABLE night SCENE
// ...` (the solo binary), J at once, with a time limit per scene, resumable, the failures and a
// summary written as JSON into the output folder.
//
// A child process per scene: a crash, an abort or an out-of-memory kill of one scene cannot take
// the batch down, every option of the scene command (presets, config files, ...) is forwarded
// without the batch knowing it, and wait4 gives the child's peak memory.

#include <solo/pipeline/dataset_scenes.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace solo {

struct NightBatchOptions {
  std::filesystem::path list;           ///< list file of manifests, or a folder searched for them
  std::string shard = "0/1";            ///< i/N: scenes k with k % N == i (0-based)
  int jobs = 1;                         ///< scenes converted at once
  double scene_timeout_s = 0;           ///< a scene running longer is stopped and recorded failed; 0: none
  std::filesystem::path output_folder;  ///< OUT_DIR: <name>.png, <name>.report.json, failures, summary, logs/
  /// --layout: each night image goes to OUT_DIR/<the layout's night folder>/<its manifest's
  /// "name">.png (datasetNightImage), in the dataset's own folder layout, instead of OUT_DIR/<name>.png.
  std::optional<Dataset> layout;
  std::uint64_t seed = 0;               ///< the batch seed; each scene's is nightBatchSceneSeed(seed, name)
  /// The scene command's arguments, starting with the subcommand ("night"); the batch adds the
  /// scene after it and -o, --report, --seed (and --contact-sheet) at the end
  /// (forwardedSceneArguments makes them from a command line).
  std::vector<std::string> arguments;
  bool contact_sheet = false;        ///< one OUT_DIR/<name>.contact-sheet.png per scene
  std::filesystem::path executable;  ///< the solo binary each scene runs
  /// Library versions recorded in the summary; empty: pipelineDependencyVersions().
  std::vector<std::pair<std::string, std::string>> versions;
};

struct NightBatchShard {
  int index = 0, count = 1;
};

struct NightBatchScene {
  std::filesystem::path manifest;  ///< absolute
  std::string name;                ///< output name, unique in the batch
  std::uint64_t seed = 0;
  /// The night image, relative to the output folder: <name>.png, or with a layout the frame's
  /// path in the dataset's layout. Its report is <name>.report.json in the output folder.
  std::filesystem::path image;
};

/// The scenes of a batch before any runs.
struct NightBatchPlan {
  std::filesystem::path output_folder;  ///< absolute
  NightBatchShard shard;
  std::size_t scenes_in_batch = 0;        ///< every shard's
  std::size_t ground_truth_left_out = 0;  ///< manifests another one names as its ground truth
  std::vector<NightBatchScene> scenes;    ///< this shard's, sorted by name
};

enum class NightBatchStatus { NotStarted, Done, Skipped, Failed, Interrupted };

/// "not started", "done", "skipped", "failed", "interrupted": the summary's names.
std::string nightBatchStatusName(NightBatchStatus status);

/// A duration as the batch reports it: "3.31 s" below 10 s, "12.4 s" above.
std::string nightBatchSeconds(double s);

struct NightBatchSceneOutcome {
  NightBatchStatus status = NightBatchStatus::NotStarted;
  double seconds = 0;
  double peak_rss_MiB = 0;
  int exit_code = -1;                 ///< when it exited
  int signal = 0;                     ///< when a signal ended it
  std::string reason;                 ///< why it failed or was interrupted, with the last line of its log
  std::vector<std::string> log_tail;  ///< the last 10 non-blank lines of its log
};

/// What happened, for a progress display.
struct NightBatchEvent {
  enum class Kind {
    Planned,           ///< the scenes are known; nothing has run yet
    SceneSkipped,      ///< scene: its outputs are there from an earlier run
    SceneStartFailed,  ///< scene: its child process could not start (outcome's reason)
    SceneStarted,      ///< scene: its child process runs
    SceneEnded,        ///< scene: done, failed or interrupted (outcome)
    Interrupted,       ///< a signal arrived: no scene starts any more, `running` are being stopped
  };
  Kind kind = Kind::Planned;
  std::size_t scene = 0;    ///< index into the plan's scenes (the scene kinds)
  int signal = 0;           ///< Interrupted
  std::size_t running = 0;  ///< Interrupted
};

using NightBatchProgress = std::function<void(const NightBatchEvent& event, const NightBatchPlan& plan,
                                              const std::vector<NightBatchSceneOutcome>& outcomes)>;

struct NightBatchResult {
  NightBatchPlan plan;
  std::vector<NightBatchSceneOutcome> outcomes;  ///< one per plan.scenes; failures have status Failed
  std::size_t done = 0, skipped = 0, failed = 0;
  std::size_t interrupted = 0;  ///< interrupted or not started
  double total_seconds = 0;
  double peak_rss_MiB = 0;              ///< the largest scene's
  int interrupt_signal = 0;             ///< SIGINT or SIGTERM when the batch was interrupted, else 0
  std::filesystem::path failures_file;  ///< this shard's failed scenes (JSON)
  std::filesystem::path summary_file;   ///< the batch summary (JSON): counts, per-scene status
};

/// Throws InputError for a bad shard ("--shard"), jobs outside 1 to 256 ("--jobs"), a scene
/// timeout that is not a number of seconds from 0 to 1e6 ("--scene-timeout"), or a batch
/// started by a batch's scene (SOLO_BATCH_SCENE set: its options would recurse).
void checkNightBatchOptions(const NightBatchOptions& options);

/// "i/N" (0-based shard i of N). Throws InputError("--shard", ...) for anything else.
NightBatchShard parseNightBatchShard(const std::string& text);

/// The seed of a scene: a function of the batch seed and the scene's name only, so a scene gets
/// the same image whatever the shard split, the job count or the other scenes.
/// SplitMix64(batch_seed xor FNV-1a-64(name)) >> 11: 53 bits, exact in JSON readers.
std::uint64_t nightBatchSceneSeed(std::uint64_t batch_seed, const std::string& name);

/// Every scene of a list file (one manifest a line, relative to the list's folder; blank and
/// `#` lines skipped; a folder stands for its scene.json) or of a folder searched for
/// scene.json / *.scene.json (ground-truth manifests left out), sorted by output name, with
/// their seeds and night images (with a `layout`, from each manifest's "name"); the shard fields
/// left at one shard. Throws InputError when none is found, two get one name or one night image,
/// or, with a layout, a manifest cannot be read or has no "name" of the layout's form.
NightBatchPlan collectNightBatchScenes(const std::filesystem::path& list_or_dir, std::uint64_t batch_seed,
                                       const std::optional<Dataset>& layout = std::nullopt);

/// A command line (argv, the program first) as the scene command's arguments: without the
/// program and without the options the batch sets (--batch, --shard, --jobs, --scene-timeout,
/// --layout, -o/--output, --report, --contact-sheet, --seed; as "--x v", "--x=v" or "-ov").
struct ForwardedSceneArguments {
  std::vector<std::string> arguments;
  bool output_given = false;  ///< the command line had -o / --output
};
ForwardedSceneArguments forwardedSceneArguments(const std::vector<std::string>& argv);

/// Runs the batch: checks the options (checkNightBatchOptions, the output folder), collects the
/// shard's scenes, skips those done before, runs the others, and writes the failures file (after
/// each failure and at the end) and the summary. SIGINT and SIGTERM, while it runs, start no
/// more scenes and stop the running ones. Throws InputError before any scene runs for bad
/// options or scene lists.
NightBatchResult runNightBatch(const NightBatchOptions& options, const NightBatchProgress& progress = {});

/// In a batch's scene process (SOLO_BATCH_PARENT=<the batch's pid> in its environment): asks the
/// kernel for SIGTERM when the batch process dies (even by SIGKILL), and sends it at once when
/// the batch died before that request took effect (the process was already reparented). Call
/// after removeTemporariesOnSignals, so the scene removes its temporaries. Does nothing outside a
/// batch.
void stopWithBatchParent();

}  // namespace solo
