#include <solo/pipeline/night_batch.h>

#include <solo/core/atomic_file.h>
#include <solo/core/error.h>
#include <solo/core/option_checks.h>
#include <solo/core/scene.h>
#include <solo/pipeline/night_job.h>

#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <spawn.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <thread>


namespace fs = std::filesystem;

namespace solo {

namespace {

constexpr int kMaxBatchJobs = 256;            ///< --jobs: child processes at once
constexpr double kMaxSceneTimeoutS = 1e6;     ///< --scene-timeout: about 11.5 days
/// The batch's process id in a scene process's environment (stopWithBatchParent).
constexpr const char* kBatchParentVariable = "SOLO_BATCH_PARENT";

// FNV-1a, 64 bit: a fixed, documented hash of the scene name.
std::uint64_t fnv1a64(const std::string& text) {
  std::uint64_t h = 14695981039346656037ull;
  for (const unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

// SplitMix64's finaliser: spreads nearby inputs over the whole 64-bit range.
std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

bool isManifestName(const std::string& file_name) {
  const std::string suffix = ".scene.json";
  return file_name == "scene.json" || (file_name.size() > suffix.size() &&
                                       file_name.compare(file_name.size() - suffix.size(), suffix.size(), suffix) == 0);
}

/// Output name of a manifest from its path relative to the batch root: the folder for
/// `scene.json`, the file without `.scene.json` / `.json` otherwise, components joined by "__"
/// ("a/b/scene.json" -> "a__b", "x/street.scene.json" -> "x__street"), ".." read as "up".
std::string sceneName(const fs::path& relative, const fs::path& manifest_absolute) {
  fs::path p = relative.lexically_normal().relative_path();
  const std::string file = p.filename().string();
  const std::string scene_suffix = ".scene.json";
  if (file == "scene.json")
    p = p.parent_path();
  else if (isManifestName(file))
    p.replace_filename(file.substr(0, file.size() - scene_suffix.size()));
  else
    p.replace_extension();
  std::string name;
  for (const fs::path& part : p) {
    std::string s = part.string();
    if (s.empty() || s == ".") continue;
    if (s == "..") s = "up";
    name += (name.empty() ? "" : "__") + s;
  }
  if (name.empty()) name = manifest_absolute.parent_path().filename().string();
  if (name.empty() || name == "." || name == "..") name = "scene";
  return name;
}

std::string trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return {};
  const auto end = s.find_last_not_of(" \t\r\n");
  return s.substr(begin, end - begin + 1);
}

struct Found {
  fs::path manifest;   ///< absolute
  fs::path relative;   ///< to the batch root, for the name
  std::string origin;  ///< where it came from, for messages ("list.txt:3")
};

std::vector<Found> readList(const fs::path& list) {
  std::ifstream in(list);
  if (!in) throw InputError(list, "cannot open the scene list");
  const fs::path root = fs::absolute(list).parent_path();
  std::vector<Found> found;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string entry = trim(line);
    if (entry.empty() || entry[0] == '#') continue;
    if (line_number == 1 && entry[0] == '{')
      throw InputError(list, "this is a scene manifest, not a list of manifests: convert it with `solo night " +
                                 list.string() + "`, or put its path in a list file");
    fs::path path = entry;
    fs::path absolute = path.is_absolute() ? path : root / path;
    if (fs::is_directory(absolute)) {  // a scene folder stands for its scene.json
      path /= "scene.json";
      absolute /= "scene.json";
    }
    fs::path relative = path.is_absolute() ? path.lexically_relative(root) : path;
    if (relative.empty() || *relative.begin() == "..") relative = path.is_absolute() ? path.relative_path() : path;
    found.push_back({absolute.lexically_normal(), relative, list.string() + ":" + std::to_string(line_number)});
  }
  return found;
}

/// Every manifest file under `root`, hidden folders not entered.
std::vector<Found> findManifests(const fs::path& folder, const fs::path& root) {
  std::vector<Found> found;
  std::error_code ec;
  fs::recursive_directory_iterator it(root, fs::directory_options::skip_permission_denied, ec);
  if (ec) throw InputError(folder, "cannot search the folder: " + ec.message());
  for (; it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (ec) throw InputError(folder, "cannot search the folder: " + ec.message());
    const std::string file = it->path().filename().string();
    if (it->is_directory(ec) && !file.empty() && file[0] == '.') {
      it.disable_recursion_pending();  // hidden folders (.git, ...) hold no scenes
      continue;
    }
    if (it->is_regular_file(ec) && isManifestName(file))
      found.push_back({it->path(), it->path().lexically_relative(root), it->path().string()});
  }
  return found;
}

// A `solo synth` folder holds gt/scene.json besides scene.json: the ground truth of the scene,
// not a scene to convert. Manifests that another found manifest names as its "ground_truth"
// are left out.
std::vector<Found> searchFolder(const fs::path& folder, std::size_t& ground_truth_skipped) {
  std::vector<Found> found = findManifests(folder, fs::absolute(folder).lexically_normal());
  std::error_code ec;
  std::set<fs::path> ground_truths;
  for (const Found& f : found) {
    try {
      if (const auto truth = readSceneManifest(f.manifest).ground_truth)
        ground_truths.insert(fs::weakly_canonical(*truth, ec));
    } catch (const InputError&) {
      // A broken manifest is still a scene of the batch: it fails, with its reason, when run.
    }
  }
  const auto before = found.size();
  found.erase(
      std::remove_if(found.begin(), found.end(),
                     [&](const Found& f) { return ground_truths.count(fs::weakly_canonical(f.manifest, ec)) > 0; }),
      found.end());
  ground_truth_skipped = before - found.size();
  return found;
}

/// Named scenes from the found manifests, sorted by name; two with one name are an error.
std::vector<NightBatchScene> nameScenes(const std::vector<Found>& found, const fs::path& list_or_dir,
                                        std::uint64_t batch_seed) {
  std::vector<NightBatchScene> scenes;
  std::map<std::string, std::string> origin_of_name;
  for (const Found& f : found) {
    const std::string name = sceneName(f.relative, f.manifest);
    const auto [it, inserted] = origin_of_name.emplace(name, f.origin);
    if (!inserted)
      throw InputError(list_or_dir, "scenes " + it->second + " and " + f.origin + " both get the output name \"" +
                                        name + "\" (listed twice, or rename one)");
    scenes.push_back({f.manifest, name, nightBatchSceneSeed(batch_seed, name), name + ".png"});
  }
  std::sort(scenes.begin(), scenes.end(),
            [](const NightBatchScene& a, const NightBatchScene& b) { return a.name < b.name; });
  return scenes;
}

/// A manifest's "name", read for --layout (the rest of the manifest is the scene's to check).
std::string manifestName(const fs::path& manifest, Dataset layout) {
  const std::string needs = "--layout " + datasetName(layout) + " needs the manifest's \"name\"";
  std::ifstream in(manifest);
  if (!in) throw InputError(manifest, "cannot open the manifest (" + needs + ")");
  nlohmann::json j;
  try {
    in >> j;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(manifest, "not valid JSON (" + needs + "): " + e.what());
  }
  if (!j.is_object() || !j.contains("name") || !j.at("name").is_string())
    throw InputError(manifest, "no \"name\": " + needs + ", the frame's path " + datasetLayout(layout).name_form +
                                   " (solo scenes " + datasetName(layout) + " writes it)");
  return j.at("name").get<std::string>();
}

/// With a layout, each scene's night image at its frame's path in the dataset's layout; two
/// scenes with one night image are an error.
void placeInLayout(std::vector<NightBatchScene>& scenes, Dataset layout, const fs::path& list_or_dir) {
  std::map<fs::path, std::string> scene_of_image;
  for (NightBatchScene& scene : scenes) {
    scene.image = datasetNightImage(layout, manifestName(scene.manifest, layout), scene.manifest);
    const auto [it, inserted] = scene_of_image.emplace(scene.image, scene.manifest.string());
    if (!inserted)
      throw InputError(list_or_dir, "scenes " + it->second + " and " + scene.manifest.string() +
                                        " both get the night image " + scene.image.string() + " (one frame listed twice)");
  }
}

/// The last lines of a child's log, blank lines dropped.
std::vector<std::string> tailLines(const fs::path& file, std::size_t count) {
  std::ifstream in(file, std::ios::binary);
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    line = trim(line);
    if (!line.empty()) lines.push_back(line);
  }
  if (lines.size() > count) lines.erase(lines.begin(), lines.end() - static_cast<std::ptrdiff_t>(count));
  return lines;
}

// A killed child leaves its hidden temporary files (writeAtomically: ".<stem>.tmp<pid>_<n><ext>"
// beside the target); they never look finished, but a rerun of that scene removes them.
void removeStaleTemporaries(const fs::path& target) {
  const std::string prefix = "." + target.stem().string() + ".tmp";
  const std::string ext = target.extension().string();
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(target.parent_path(), ec)) {
    const std::string file = entry.path().filename().string();
    if (file.size() > prefix.size() + ext.size() && file.rfind(prefix, 0) == 0 &&
        file.compare(file.size() - ext.size(), ext.size(), ext) == 0) {
      const std::string middle = file.substr(prefix.size(), file.size() - prefix.size() - ext.size());
      if (std::regex_match(middle, std::regex(R"(\d+_\d+)"))) fs::remove(entry.path(), ec);
    }
  }
}

volatile std::sig_atomic_t g_interrupt_signal = 0;
extern "C" void onInterrupt(int signal) { g_interrupt_signal = signal; }

// Ctrl-C or Slurm's SIGTERM: start nothing more, stop the running scenes, write the summary.
// Installed for the lifetime of the object.
class InterruptHandler {
 public:
  InterruptHandler() {
    struct sigaction action {};
    action.sa_handler = onInterrupt;
    sigemptyset(&action.sa_mask);
    g_interrupt_signal = 0;
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
  }
  ~InterruptHandler() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  InterruptHandler(const InterruptHandler&) = delete;
  InterruptHandler& operator=(const InterruptHandler&) = delete;

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

struct Running {
  std::size_t scene = 0;  ///< index into the shard's scenes
  std::chrono::steady_clock::time_point start;
  bool timed_out = false;  ///< stopped by --scene-timeout (SIGTERM, SIGKILL 10 s later)
  std::chrono::steady_clock::time_point terminated;
};

/// The shard's scenes run by child processes, `jobs` at once, and their outcomes.
class BatchRun {
 public:
  BatchRun(const NightBatchOptions& options, const NightBatchPlan& plan, const NightBatchProgress& progress)
      : options_(options), plan_(plan), progress_(progress), outcomes_(plan.scenes.size()) {}

  /// Runs every scene (or until interrupted); returns the outcomes.
  std::vector<NightBatchSceneOutcome> run();

  fs::path failuresFile() const { return plan_.output_folder / ("failures" + shardSuffix() + ".json"); }
  fs::path summaryFile() const { return plan_.output_folder / ("batch-summary" + shardSuffix() + ".json"); }
  std::string shardText() const { return std::to_string(plan_.shard.index) + "/" + std::to_string(plan_.shard.count); }
  /// Writes this shard's failed scenes (the failures file).
  void writeFailures() const;

 private:
  /// "" for one shard, ".shard-i-of-N" otherwise: the failure and summary files are per shard.
  std::string shardSuffix() const {
    const NightBatchShard& shard = plan_.shard;
    return shard.count == 1 ? "" : ".shard-" + std::to_string(shard.index) + "-of-" + std::to_string(shard.count);
  }
  fs::path pngOf(std::size_t i) const { return plan_.output_folder / plan_.scenes[i].image; }
  fs::path reportOf(std::size_t i) const { return plan_.output_folder / (plan_.scenes[i].name + ".report.json"); }
  fs::path logDir() const { return plan_.output_folder / "logs"; }
  fs::path logOf(std::size_t i) const { return logDir() / (plan_.scenes[i].name + ".log"); }
  void notify(NightBatchEvent::Kind kind, std::size_t scene = 0) const {
    NightBatchEvent event;
    event.kind = kind;
    event.scene = scene;
    event.signal = g_interrupt_signal;
    event.running = running_.size();
    if (progress_) progress_(event, plan_, outcomes_);
  }

  void startScenes();
  void startScene(std::size_t i);
  fs::path contactSheetOf(std::size_t i) const {
    return plan_.output_folder / (plan_.scenes[i].name + ".contact-sheet.png");
  }
  /// Every output of the scene a run of it may have left a temporary of (a contact sheet's too,
  /// whether or not this run asks for one).
  void removeTemporariesOf(std::size_t i) const {
    for (const fs::path& output : {pngOf(i), reportOf(i), contactSheetOf(i)}) removeStaleTemporaries(output);
  }
  std::vector<std::string> sceneArguments(std::size_t i) const;
  int spawnScene(std::size_t i, std::vector<std::string> arguments, pid_t& pid) const;
  void stopChildren();
  void enforceTimeouts();
  void finishScene(pid_t pid, int status, const struct rusage& usage);
  void recordExit(std::size_t i, int status, bool timed_out);

  const NightBatchOptions& options_;
  const NightBatchPlan& plan_;
  const NightBatchProgress& progress_;
  std::vector<NightBatchSceneOutcome> outcomes_;
  std::map<pid_t, Running> running_;
  std::size_t next_ = 0;
  bool stopping_ = false;
};

void BatchRun::writeFailures() const {
  nlohmann::json failures = nlohmann::json::array();
  for (std::size_t i = 0; i < plan_.scenes.size(); ++i) {
    const NightBatchSceneOutcome& o = outcomes_[i];
    if (o.status != NightBatchStatus::Failed) continue;
    const NightBatchScene& scene = plan_.scenes[i];
    nlohmann::json f = {{"scene", scene.name},
                        {"manifest", scene.manifest.string()},
                        {"seed", scene.seed},
                        {"reason", o.reason},
                        {"log_tail", o.log_tail},
                        {"log", "logs/" + scene.name + ".log"},
                        {"seconds", o.seconds}};
    if (o.signal)
      f["signal"] = o.signal;
    else
      f["exit_code"] = o.exit_code;
    failures.push_back(f);
  }
  writeTextAtomically(failuresFile(), nlohmann::json{{"shard", shardText()}, {"failures", failures}}.dump(2) + "\n");
}

std::vector<NightBatchSceneOutcome> BatchRun::run() {
  const InterruptHandler interrupts;
  while (true) {
    if (g_interrupt_signal) stopChildren();
    startScenes();
    if (running_.empty()) break;

    int status = 0;
    struct rusage usage {};
    // With a time limit, poll: a scene past it gets SIGTERM, and SIGKILL if it ignores that.
    const pid_t pid = ::wait4(-1, &status, options_.scene_timeout_s > 0 ? WNOHANG : 0, &usage);
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;  // ECHILD: nothing left to wait for
    }
    if (pid == 0) {
      enforceTimeouts();
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    finishScene(pid, status, usage);
  }
  return outcomes_;
}

// Start scenes until every job slot is busy.
void BatchRun::startScenes() {
  std::error_code ec;
  while (!stopping_ && running_.size() < static_cast<std::size_t>(options_.jobs) && next_ < plan_.scenes.size()) {
    const std::size_t i = next_++;
    if (fs::exists(pngOf(i), ec) && fs::exists(reportOf(i), ec)) {
      outcomes_[i].status = NightBatchStatus::Skipped;
      notify(NightBatchEvent::Kind::SceneSkipped, i);
      continue;
    }
    startScene(i);
  }
}

void BatchRun::startScene(std::size_t i) {
  removeTemporariesOf(i);
  std::error_code ec;
  fs::create_directories(logDir(), ec);
  fs::create_directories(pngOf(i).parent_path(), ec);  // a layout's folders
  pid_t pid = 0;
  const int error = spawnScene(i, sceneArguments(i), pid);
  if (error != 0) {
    outcomes_[i].status = NightBatchStatus::Failed;
    outcomes_[i].reason = std::string("cannot start the child process: ") + std::strerror(error);
    notify(NightBatchEvent::Kind::SceneStartFailed, i);
    writeFailures();
    return;
  }
  Running started;
  started.scene = i;
  started.start = std::chrono::steady_clock::now();
  running_[pid] = started;
  notify(NightBatchEvent::Kind::SceneStarted, i);
}

/// The scene command: the forwarded arguments with the scene and its outputs and seed.
std::vector<std::string> BatchRun::sceneArguments(std::size_t i) const {
  const NightBatchScene& scene = plan_.scenes[i];
  std::vector<std::string> args = options_.arguments;
  // The scene goes right after the subcommand: a positional after a list-valued option
  // would be taken as one more value of it.
  const auto subcommand = std::find(args.begin(), args.end(), "night");
  args.insert(subcommand == args.end() ? args.begin() : subcommand + 1, scene.manifest.string());
  if (subcommand == args.end()) args.insert(args.begin(), "night");
  for (const std::string& a : {std::string("-o"), pngOf(i).string(), std::string("--report"), reportOf(i).string(),
                               std::string("--seed"), std::to_string(scene.seed)})
    args.push_back(a);
  if (options_.contact_sheet) {  // one contact sheet per scene, whatever file was named
    args.push_back("--contact-sheet");
    args.push_back(contactSheetOf(i).string());
  }
  return args;
}

/// Starts the executable with `arguments`, stdin from /dev/null, stdout and stderr to the
/// scene's log, SOLO_BATCH_SCENE=<name> and SOLO_BATCH_PARENT=<this pid> in its environment
/// (stopWithBatchParent). Returns posix_spawn's error (0: ok).
int BatchRun::spawnScene(std::size_t i, std::vector<std::string> arguments, pid_t& pid) const {
  std::vector<char*> child_argv;
  std::string argv0 = "solo";
  child_argv.push_back(argv0.data());
  for (std::string& a : arguments) child_argv.push_back(a.data());
  child_argv.push_back(nullptr);

  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, 0, "/dev/null", O_RDONLY, 0);
  const std::string log = logOf(i).string();
  posix_spawn_file_actions_addopen(&files, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&files, 1, 2);
  std::string scene_variable = "SOLO_BATCH_SCENE=" + plan_.scenes[i].name;
  std::string parent_variable = std::string(kBatchParentVariable) + "=" + std::to_string(::getpid());
  std::vector<char*> child_environment;
  for (char** e = environ; *e; ++e)
    if (std::strncmp(*e, "SOLO_BATCH_SCENE=", 17) != 0 &&
        std::strncmp(*e, parent_variable.c_str(), std::strlen(kBatchParentVariable) + 1) != 0)
      child_environment.push_back(*e);
  child_environment.push_back(scene_variable.data());
  child_environment.push_back(parent_variable.data());
  child_environment.push_back(nullptr);
  const std::string executable = options_.executable.string();
  const int error =
      ::posix_spawn(&pid, executable.c_str(), &files, nullptr, child_argv.data(), child_environment.data());
  posix_spawn_file_actions_destroy(&files);
  return error;
}

void BatchRun::stopChildren() {
  if (stopping_) return;
  stopping_ = true;
  notify(NightBatchEvent::Kind::Interrupted);
  for (const auto& [pid, r] : running_) ::kill(pid, SIGTERM);
}

/// A scene past the time limit gets SIGTERM, and SIGKILL 10 s later.
void BatchRun::enforceTimeouts() {
  const auto now = std::chrono::steady_clock::now();
  for (auto& [child, r] : running_) {
    if (!r.timed_out && std::chrono::duration<double>(now - r.start).count() > options_.scene_timeout_s) {
      r.timed_out = true;
      r.terminated = now;
      ::kill(child, SIGTERM);
    } else if (r.timed_out && now - r.terminated > std::chrono::seconds(10)) {
      ::kill(child, SIGKILL);
    }
  }
}

/// How an ended child's scene went: done, failed (with the reason) or interrupted.
void BatchRun::recordExit(std::size_t i, int status, bool timed_out) {
  NightBatchSceneOutcome& o = outcomes_[i];
  std::error_code ec;
  if (WIFEXITED(status)) {
    o.exit_code = WEXITSTATUS(status);
    if (o.exit_code == 0 && fs::exists(pngOf(i), ec) && fs::exists(reportOf(i), ec)) {
      o.status = NightBatchStatus::Done;
    } else {
      o.status = NightBatchStatus::Failed;
      o.reason = o.exit_code == 0 ? "exited with status 0 without writing " + pngOf(i).filename().string() + " and " +
                                        reportOf(i).filename().string()
                                  : "exited with status " + std::to_string(o.exit_code);
    }
  } else if (WIFSIGNALED(status)) {
    o.signal = WTERMSIG(status);
    o.status = stopping_ && (o.signal == SIGTERM || o.signal == SIGINT) ? NightBatchStatus::Interrupted
                                                                        : NightBatchStatus::Failed;
    o.reason = "killed by signal " + std::to_string(o.signal) + " (" + ::strsignal(o.signal) + ")";
    if (o.signal == SIGKILL && !timed_out) o.reason += ", perhaps out of memory";
  }
  if (timed_out) {
    o.status = NightBatchStatus::Failed;
    std::ostringstream reason;
    reason << "timed out: stopped after " << nightBatchSeconds(o.seconds) << " (--scene-timeout "
           << options_.scene_timeout_s << " s)";
    o.reason = reason.str();
    removeTemporariesOf(i);
  }
}

void BatchRun::finishScene(pid_t pid, int status, const struct rusage& usage) {
  const auto it = running_.find(pid);
  if (it == running_.end()) return;
  const std::size_t i = it->second.scene;
  const bool timed_out = it->second.timed_out;
  NightBatchSceneOutcome& o = outcomes_[i];
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - it->second.start).count();
  o.peak_rss_MiB = static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: kibibytes
  running_.erase(it);
  recordExit(i, status, timed_out);
  std::error_code ec;
  if (o.status == NightBatchStatus::Done) {
    fs::remove(logOf(i), ec);  // the report holds everything the log said
  } else {
    o.log_tail = tailLines(logOf(i), 10);
    if (!o.log_tail.empty()) o.reason += ": " + o.log_tail.back();
    if (o.status == NightBatchStatus::Failed) writeFailures();
  }
  notify(NightBatchEvent::Kind::SceneEnded, i);
}

/// The counts and the largest peak memory of the outcomes.
void tally(NightBatchResult& result) {
  for (const NightBatchSceneOutcome& o : result.outcomes) {
    result.done += o.status == NightBatchStatus::Done;
    result.skipped += o.status == NightBatchStatus::Skipped;
    result.failed += o.status == NightBatchStatus::Failed;
    result.interrupted += o.status == NightBatchStatus::Interrupted || o.status == NightBatchStatus::NotStarted;
    result.peak_rss_MiB = std::max(result.peak_rss_MiB, o.peak_rss_MiB);
  }
}

nlohmann::json perSceneJson(const NightBatchResult& result) {
  nlohmann::json per_scene = nlohmann::json::array();
  for (std::size_t i = 0; i < result.plan.scenes.size(); ++i) {
    const NightBatchScene& scene = result.plan.scenes[i];
    const NightBatchSceneOutcome& o = result.outcomes[i];
    nlohmann::json s = {{"scene", scene.name},
                        {"manifest", scene.manifest.string()},
                        {"seed", scene.seed},
                        {"image", scene.image.generic_string()},
                        {"status", nightBatchStatusName(o.status)}};
    if (o.status == NightBatchStatus::Done || o.status == NightBatchStatus::Failed ||
        o.status == NightBatchStatus::Interrupted) {
      s["seconds"] = o.seconds;
      s["peak_rss_MiB"] = o.peak_rss_MiB;
    }
    if (!o.reason.empty()) s["reason"] = o.reason;
    per_scene.push_back(s);
  }
  return per_scene;
}

/// The batch summary file's content.
std::string summaryText(const NightBatchOptions& options, const NightBatchResult& result, const std::string& shard) {
  nlohmann::json versions = nlohmann::json::object();
  for (const auto& [library, version] : options.versions.empty() ? pipelineDependencyVersions() : options.versions)
    versions[library] = version;
  const nlohmann::json summary = {{"command", "night --batch"},
                                  {"list", options.list.string()},
                                  {"output_folder", result.plan.output_folder.string()},
                                  {"shard", shard},
                                  {"jobs", options.jobs},
                                  {"layout", options.layout ? datasetName(*options.layout) : "flat"},
                                  {"seed", options.seed},
                                  {"scenes_in_batch", result.plan.scenes_in_batch},
                                  {"ground_truth_manifests_left_out", result.plan.ground_truth_left_out},
                                  {"scenes", result.plan.scenes.size()},
                                  {"done", result.done},
                                  {"skipped_already_done", result.skipped},
                                  {"failed", result.failed},
                                  {"interrupted", result.interrupted},
                                  {"total_seconds", result.total_seconds},
                                  {"peak_rss_MiB", result.peak_rss_MiB},
                                  {"failures_file", result.failures_file.filename().string()},
                                  {"per_scene", perSceneJson(result)},
                                  {"versions", versions}};
  return summary.dump(2) + "\n";
}

/// The output folder, absolute; created. Throws InputError when it is a file or cannot be made.
fs::path prepareOutputFolder(const fs::path& output_folder) {
  fs::path out_dir = fs::absolute(output_folder);
  std::error_code ec;
  if (fs::exists(out_dir, ec) && !fs::is_directory(out_dir, ec))
    throw InputError(output_folder, "exists and is not a folder (with --batch, -o is the output folder)");
  return out_dir;
}

}  // namespace

std::string nightBatchStatusName(NightBatchStatus status) {
  switch (status) {
    case NightBatchStatus::NotStarted:
      return "not started";
    case NightBatchStatus::Done:
      return "done";
    case NightBatchStatus::Skipped:
      return "skipped";
    case NightBatchStatus::Failed:
      return "failed";
    case NightBatchStatus::Interrupted:
      return "interrupted";
  }
  return "not started";
}

std::string nightBatchSeconds(double s) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(s < 10 ? 2 : 1) << s << " s";
  return out.str();
}

NightBatchShard parseNightBatchShard(const std::string& text) {
  static const std::regex pattern(R"(\s*(\d{1,9})\s*/\s*(\d{1,9})\s*)");
  std::smatch m;
  if (!std::regex_match(text, m, pattern))
    throw InputError("--shard", "expected i/N (0-based shard index i of N shards, e.g. 3/16), got \"" + text + "\"");
  NightBatchShard shard{std::stoi(m[1]), std::stoi(m[2])};
  if (shard.count < 1) throw InputError("--shard", "the shard count N must be at least 1, got \"" + text + "\"");
  if (shard.index >= shard.count)
    throw InputError("--shard", "the shard index i must be below N (0-based: 0 to " + std::to_string(shard.count - 1) +
                                    "), got \"" + text + "\"");
  return shard;
}

std::uint64_t nightBatchSceneSeed(std::uint64_t batch_seed, const std::string& name) {
  return splitmix64(batch_seed ^ fnv1a64(name)) >> 11;
}

void checkNightBatchOptions(const NightBatchOptions& options) {
  parseNightBatchShard(options.shard);
  if (options.jobs < 1) throw InputError("--jobs", "must be at least 1, got " + std::to_string(options.jobs));
  if (options.jobs > kMaxBatchJobs)
    throw InputError("--jobs", "must be at most " + std::to_string(kMaxBatchJobs) + ", got " + std::to_string(options.jobs));
  requireOptionInRange(options.scene_timeout_s, 0, kMaxSceneTimeoutS, "--scene-timeout");
  // A scene's child that reads --batch again (from a config file, say) would recurse.
  if (const char* scene = std::getenv("SOLO_BATCH_SCENE"))
    throw InputError("--batch", std::string("given to a batch's scene (") + scene +
                                    "): a config file that sets batch cannot be forwarded to the scenes");
  if (options.executable.empty()) throw InputError("executable", "no program to run the scenes with");
}

NightBatchPlan collectNightBatchScenes(const fs::path& list_or_dir, std::uint64_t batch_seed,
                                       const std::optional<Dataset>& layout) {
  std::error_code ec;
  NightBatchPlan plan;
  std::vector<Found> found;
  if (fs::is_directory(list_or_dir, ec))
    found = searchFolder(list_or_dir, plan.ground_truth_left_out);
  else if (fs::exists(list_or_dir, ec))
    found = readList(list_or_dir);
  else
    throw InputError(list_or_dir, "not found (--batch takes a list file of scene manifests or a folder of scenes)");
  if (found.empty())
    throw InputError(list_or_dir, fs::is_directory(list_or_dir, ec)
                                      ? "no scene manifest (scene.json or *.scene.json) in this folder"
                                      : "the list names no scene manifest");
  plan.scenes = nameScenes(found, list_or_dir, batch_seed);
  if (layout) placeInLayout(plan.scenes, *layout, list_or_dir);
  plan.scenes_in_batch = plan.scenes.size();
  return plan;
}

ForwardedSceneArguments forwardedSceneArguments(const std::vector<std::string>& argv) {
  const std::set<std::string> dropped = {"--batch",  "--shard",  "--jobs",          "--scene-timeout", "--layout",
                                         "-o",       "--output", "--report",        "--contact-sheet", "--seed"};
  ForwardedSceneArguments result;
  for (std::size_t i = 1; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    const std::string key = a.substr(0, a.find('='));
    const bool short_output = a.size() > 2 && a.rfind("-o", 0) == 0 && a[2] != '-';
    if (key == "-o" || key == "--output" || short_output) result.output_given = true;
    if (dropped.count(key) || short_output) {
      if (key == a && !short_output) ++i;  // the value is the next argument
      continue;
    }
    result.arguments.push_back(a);
  }
  return result;
}

NightBatchResult runNightBatch(const NightBatchOptions& options, const NightBatchProgress& progress) {
  const auto batch_start = std::chrono::steady_clock::now();
  checkNightBatchOptions(options);
  const NightBatchShard shard = parseNightBatchShard(options.shard);
  const fs::path out_dir = prepareOutputFolder(options.output_folder);

  NightBatchResult result;
  result.plan = collectNightBatchScenes(options.list, options.seed, options.layout);
  NightBatchPlan& plan = result.plan;
  plan.output_folder = out_dir;
  plan.shard = shard;
  std::vector<NightBatchScene> in_shard;
  for (std::size_t k = 0; k < plan.scenes.size(); ++k)
    if (static_cast<int>(k % static_cast<std::size_t>(shard.count)) == shard.index) in_shard.push_back(plan.scenes[k]);
  plan.scenes = std::move(in_shard);

  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) throw InputError(options.output_folder, "cannot create the output folder: " + ec.message());
  if (progress) progress(NightBatchEvent{}, plan, std::vector<NightBatchSceneOutcome>(plan.scenes.size()));

  BatchRun batch(options, plan, progress);
  result.failures_file = batch.failuresFile();
  result.summary_file = batch.summaryFile();
  result.outcomes = batch.run();
  result.interrupt_signal = g_interrupt_signal;
  tally(result);
  result.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - batch_start).count();
  batch.writeFailures();
  writeTextAtomically(result.summary_file, summaryText(options, result, batch.shardText()));
  return result;
}

void stopWithBatchParent() {
  const char* parent_text = std::getenv(kBatchParentVariable);
  if (!parent_text) return;
  char* end = nullptr;
  const long parent = std::strtol(parent_text, &end, 10);
  if (end == parent_text || *end != '\0' || parent <= 1) return;
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);
  // The batch may have died between the spawn and the request: then this process has another
  // parent already, and no death signal will come.
  if (::getppid() != static_cast<pid_t>(parent)) ::raise(SIGTERM);
}

}  // namespace solo
