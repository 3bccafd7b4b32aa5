// `solo night --batch LIST_OR_DIR -o OUT_DIR [--shard i/N] [--jobs J]`: `solo night` on every
// scene of a dataset (docs/batch.md).
//
// Inputs: a list file (one manifest path a line, relative to the list's folder) or a folder
// searched for `scene.json` / `*.scene.json`; the parent's command line, forwarded to each scene.
// Outputs: OUT_DIR/<name>.png and OUT_DIR/<name>.report.json per scene, the failures file and
// the batch summary (JSON), progress and a summary on the terminal. Exit 0 when every scene of
// the shard is done, 1 when one failed, 130 when interrupted.
//
// Each scene runs in a child process (/proc/self/exe with the parent's arguments minus the
// batch ones): a crash, an abort or an out-of-memory kill of one scene cannot take the batch
// down, every option (presets, config files, ...) is forwarded without this file knowing it,
// and wait4 gives the child's peak memory.

#include "commands.h"

#include <solo/core/atomic_file.h>
#include <solo/core/error.h>
#include <solo/core/scene.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <regex>
#include <set>
#include <spawn.h>
#include <sstream>
#include <sys/resource.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

extern char** environ;

namespace fs = std::filesystem;

namespace solo::tools {

namespace {

struct BatchScene {
  fs::path manifest;   ///< absolute
  std::string name;    ///< output name, unique in the batch
  std::uint64_t seed = 0;
};

struct Shard {
  int index = 0, count = 1;
};

Shard parseShard(const std::string& text) {
  static const std::regex pattern(R"(\s*(\d{1,9})\s*/\s*(\d{1,9})\s*)");
  std::smatch m;
  if (!std::regex_match(text, m, pattern))
    throw InputError("--shard", "expected i/N (0-based shard index i of N shards, e.g. 3/16), got \"" + text + "\"");
  Shard shard{std::stoi(m[1]), std::stoi(m[2])};
  if (shard.count < 1) throw InputError("--shard", "the shard count N must be at least 1, got \"" + text + "\"");
  if (shard.index >= shard.count)
    throw InputError("--shard", "the shard index i must be below N (0-based: 0 to " + std::to_string(shard.count - 1) +
                                    "), got \"" + text + "\"");
  return shard;
}

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

/// The seed of one scene: a function of the batch seed and the scene's name only, so a scene
/// gets the same image whatever the shard split, the job count or the other scenes. 53 bits,
/// so that it survives JSON readers that hold numbers as doubles and signed 64-bit fields.
std::uint64_t sceneSeed(std::uint64_t batch_seed, const std::string& name) {
  return splitmix64(batch_seed ^ fnv1a64(name)) >> 11;
}

bool isManifestName(const std::string& file_name) {
  const std::string suffix = ".scene.json";
  return file_name == "scene.json" ||
         (file_name.size() > suffix.size() && file_name.compare(file_name.size() - suffix.size(), suffix.size(), suffix) == 0);
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
  fs::path manifest;  ///< absolute
  fs::path relative;  ///< to the batch root, for the name
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

// A `solo synth` folder holds gt/scene.json besides scene.json: the ground truth of the scene,
// not a scene to convert. Manifests that another found manifest names as its "ground_truth"
// are left out.
std::vector<Found> searchFolder(const fs::path& folder, std::size_t& ground_truth_skipped) {
  const fs::path root = fs::absolute(folder).lexically_normal();
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
  found.erase(std::remove_if(found.begin(), found.end(),
                             [&](const Found& f) { return ground_truths.count(fs::weakly_canonical(f.manifest, ec)) > 0; }),
              found.end());
  ground_truth_skipped = before - found.size();
  return found;
}

/// Every scene of the batch, sorted by name, with unique names and their seeds.
std::vector<BatchScene> collectScenes(const fs::path& list_or_dir, std::uint64_t batch_seed,
                                      std::size_t& ground_truth_skipped) {
  std::error_code ec;
  ground_truth_skipped = 0;
  std::vector<Found> found;
  if (fs::is_directory(list_or_dir, ec))
    found = searchFolder(list_or_dir, ground_truth_skipped);
  else if (fs::exists(list_or_dir, ec))
    found = readList(list_or_dir);
  else
    throw InputError(list_or_dir, "not found (--batch takes a list file of scene manifests or a folder of scenes)");
  if (found.empty())
    throw InputError(list_or_dir, fs::is_directory(list_or_dir, ec)
                                      ? "no scene manifest (scene.json or *.scene.json) in this folder"
                                      : "the list names no scene manifest");
  std::vector<BatchScene> scenes;
  std::map<std::string, std::string> origin_of_name;
  for (const Found& f : found) {
    const std::string name = sceneName(f.relative, f.manifest);
    const auto [it, inserted] = origin_of_name.emplace(name, f.origin);
    if (!inserted)
      throw InputError(list_or_dir, "scenes " + it->second + " and " + f.origin + " both get the output name \"" +
                                        name + "\" (listed twice, or rename one)");
    scenes.push_back({f.manifest, name, sceneSeed(batch_seed, name)});
  }
  std::sort(scenes.begin(), scenes.end(), [](const BatchScene& a, const BatchScene& b) { return a.name < b.name; });
  return scenes;
}

// The parent's arguments minus what the batch sets per scene. Forms: "--x v", "--x=v", "-ov".
struct ForwardedArguments {
  std::vector<std::string> arguments;  ///< starting with the subcommand ("night")
  bool output_given = false;
};

ForwardedArguments forwardArguments(const std::vector<std::string>& argv) {
  const std::set<std::string> dropped = {"--batch",  "--shard",  "--jobs",          "--scene-timeout", "-o",
                                         "--output", "--report", "--contact-sheet", "--seed"};
  ForwardedArguments result;
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

// A killed child leaves its hidden temporary files (writeAtomically: ".<stem>.tmp<pid>_<n><ext>");
// they never look finished, but a rerun of that scene removes them.
void removeStaleTemporaries(const fs::path& out_dir, const std::string& name) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(out_dir, ec)) {
    const std::string file = entry.path().filename().string();
    for (const auto& [stem, ext] : {std::pair<std::string, std::string>{name, ".png"}, {name + ".report", ".json"}}) {
      const std::string prefix = "." + stem + ".tmp";
      if (file.size() > prefix.size() + ext.size() && file.rfind(prefix, 0) == 0 &&
          file.compare(file.size() - ext.size(), ext.size(), ext) == 0) {
        const std::string middle = file.substr(prefix.size(), file.size() - prefix.size() - ext.size());
        if (std::regex_match(middle, std::regex(R"(\d+_\d+)"))) fs::remove(entry.path(), ec);
      }
    }
  }
}

volatile std::sig_atomic_t g_interrupt_signal = 0;
extern "C" void onInterrupt(int signal) { g_interrupt_signal = signal; }

struct Running {
  std::size_t scene = 0;  ///< index into the shard's scenes
  std::chrono::steady_clock::time_point start;
  bool timed_out = false;  ///< stopped by --scene-timeout (SIGTERM, SIGKILL 10 s later)
  std::chrono::steady_clock::time_point terminated;
};

struct Outcome {
  std::string status = "not started";  ///< or "done", "skipped", "failed", "interrupted"
  double seconds = 0;
  double peak_rss_MiB = 0;
  int exit_code = -1;   ///< when it exited
  int signal = 0;       ///< when a signal ended it
  std::string reason;
  std::vector<std::string> log_tail;
};

std::string seconds3(double s) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(s < 10 ? 2 : 1) << s << " s";
  return out.str();
}

}  // namespace

int runNightBatch(const NightBatchOptions& batch, const NightOptions& night) {
  const auto batch_start = std::chrono::steady_clock::now();
  const Shard shard = parseShard(batch.shard);
  if (batch.jobs < 1) throw InputError("--jobs", "must be at least 1, got " + std::to_string(batch.jobs));
  // A scene's child that reads --batch again (from a config file, say) would recurse.
  if (const char* scene = std::getenv("SOLO_BATCH_SCENE"))
    throw InputError("--batch", std::string("given to a batch's scene (") + scene +
                                    "): a config file that sets batch cannot be forwarded to the scenes");
  const ForwardedArguments forwarded = forwardArguments(batch.arguments);
  if (night.job.scene)
    throw InputError(*night.job.scene, "a scene and --batch were both given: list the scene in the batch instead");
  if (!forwarded.output_given) throw InputError("--batch", "needs -o OUT_DIR, the folder for the outputs");
  // Options naming one file would make every scene write it (from the command line or a config file).
  if (night.job.report)
    throw InputError("--report", "cannot be used with --batch: each scene's report is OUT_DIR/<name>.report.json");
  if (night.job.render_exr)
    throw InputError("--render-exr", "cannot be used with --batch: it names one file for every scene");
  if (night.write_config)
    throw InputError("--write-config", "cannot be used with --batch: write the configuration with a one-scene run");
  const fs::path out_dir = fs::absolute(night.job.output);
  std::error_code ec;
  if (fs::exists(out_dir, ec) && !fs::is_directory(out_dir, ec))
    throw InputError(night.job.output, "exists and is not a folder (with --batch, -o is the output folder)");

  std::size_t ground_truth_skipped = 0;
  const std::vector<BatchScene> all = collectScenes(*batch.list, night.conversion.seed, ground_truth_skipped);
  std::vector<BatchScene> scenes;
  for (std::size_t k = 0; k < all.size(); ++k)
    if (static_cast<int>(k % static_cast<std::size_t>(shard.count)) == shard.index) scenes.push_back(all[k]);

  fs::create_directories(out_dir, ec);
  if (ec) throw InputError(night.job.output, "cannot create the output folder: " + ec.message());
  const std::string shard_suffix =
      shard.count == 1 ? "" : ".shard-" + std::to_string(shard.index) + "-of-" + std::to_string(shard.count);
  const fs::path failures_file = out_dir / ("failures" + shard_suffix + ".json");
  const fs::path summary_file = out_dir / ("batch-summary" + shard_suffix + ".json");
  const fs::path log_dir = out_dir / "logs";
  const std::string shard_text = std::to_string(shard.index) + "/" + std::to_string(shard.count);

  std::cout << "batch: " << all.size() << " scenes in " << batch.list->string();
  if (ground_truth_skipped > 0)
    std::cout << " (" << ground_truth_skipped << " ground-truth manifests left out)";
  if (shard.count > 1) std::cout << ", shard " << shard_text << ": " << scenes.size() << " of them";
  std::cout << "; " << batch.jobs << (batch.jobs == 1 ? " job" : " jobs") << "; outputs in " << out_dir.string()
            << "\n" << std::flush;

  std::vector<Outcome> outcomes(scenes.size());
  const auto png_of = [&](std::size_t i) { return out_dir / (scenes[i].name + ".png"); };
  const auto report_of = [&](std::size_t i) { return out_dir / (scenes[i].name + ".report.json"); };
  const auto contact_sheet_of = [&](std::size_t i) { return out_dir / (scenes[i].name + ".contact-sheet.png"); };
  const auto log_of = [&](std::size_t i) { return log_dir / (scenes[i].name + ".log"); };
  const auto progress = [&](std::size_t i) {
    std::ostringstream s;
    s << "[" << i + 1 << "/" << scenes.size() << "] " << scenes[i].name;
    return s.str();
  };

  const auto failure_json = [&](std::size_t i) {
    const Outcome& o = outcomes[i];
    nlohmann::json f = {{"scene", scenes[i].name},
                        {"manifest", scenes[i].manifest.string()},
                        {"seed", scenes[i].seed},
                        {"reason", o.reason},
                        {"log_tail", o.log_tail},
                        {"log", "logs/" + scenes[i].name + ".log"},
                        {"seconds", o.seconds}};
    if (o.signal) f["signal"] = o.signal;
    else f["exit_code"] = o.exit_code;
    return f;
  };
  const auto write_failures = [&] {
    nlohmann::json failures = nlohmann::json::array();
    for (std::size_t i = 0; i < scenes.size(); ++i)
      if (outcomes[i].status == "failed") failures.push_back(failure_json(i));
    writeTextAtomically(failures_file,
                        nlohmann::json{{"shard", shard_text}, {"failures", failures}}.dump(2) + "\n");
  };

  // Ctrl-C or Slurm's SIGTERM: start nothing more, stop the running scenes, write the summary.
  struct sigaction action {}, old_int {}, old_term {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  g_interrupt_signal = 0;
  sigaction(SIGINT, &action, &old_int);
  sigaction(SIGTERM, &action, &old_term);

  std::map<pid_t, Running> running;
  std::size_t next = 0;
  bool stopping = false;
  const auto stop_children = [&] {
    if (stopping) return;
    stopping = true;
    std::cout << "batch: interrupted (signal " << g_interrupt_signal << "), stopping " << running.size()
              << " running scene(s)\n" << std::flush;
    for (const auto& [pid, r] : running) ::kill(pid, SIGTERM);
  };

  while (true) {
    if (g_interrupt_signal) stop_children();
    // Start scenes until every job slot is busy.
    while (!stopping && running.size() < static_cast<std::size_t>(batch.jobs) && next < scenes.size()) {
      const std::size_t i = next++;
      if (fs::exists(png_of(i), ec) && fs::exists(report_of(i), ec)) {
        outcomes[i].status = "skipped";
        std::cout << progress(i) << ": already done, skipped\n";
        continue;
      }
      removeStaleTemporaries(out_dir, scenes[i].name);
      fs::create_directories(log_dir, ec);
      std::vector<std::string> args = forwarded.arguments;
      // The scene goes right after the subcommand: a positional after a list-valued option
      // would be taken as one more value of it.
      const auto subcommand = std::find(args.begin(), args.end(), "night");
      args.insert(subcommand == args.end() ? args.begin() : subcommand + 1, scenes[i].manifest.string());
      if (subcommand == args.end()) args.insert(args.begin(), "night");
      for (const std::string& a : {std::string("-o"), png_of(i).string(), std::string("--report"), report_of(i).string(),
                                   std::string("--seed"), std::to_string(scenes[i].seed)})
        args.push_back(a);
      if (night.job.contact_sheet) {  // one contact sheet per scene, whatever file was named
        args.push_back("--contact-sheet");
        args.push_back(contact_sheet_of(i).string());
      }
      std::vector<char*> child_argv;
      std::string argv0 = "solo";
      child_argv.push_back(argv0.data());
      for (std::string& a : args) child_argv.push_back(a.data());
      child_argv.push_back(nullptr);

      posix_spawn_file_actions_t files;
      posix_spawn_file_actions_init(&files);
      posix_spawn_file_actions_addopen(&files, 0, "/dev/null", O_RDONLY, 0);
      const std::string log = log_of(i).string();
      posix_spawn_file_actions_addopen(&files, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      posix_spawn_file_actions_adddup2(&files, 1, 2);
      std::string scene_variable = "SOLO_BATCH_SCENE=" + scenes[i].name;
      std::vector<char*> child_environment;
      for (char** e = environ; *e; ++e)
        if (std::strncmp(*e, "SOLO_BATCH_SCENE=", 17) != 0) child_environment.push_back(*e);
      child_environment.push_back(scene_variable.data());
      child_environment.push_back(nullptr);
      pid_t pid = 0;
      const int error =
          ::posix_spawn(&pid, "/proc/self/exe", &files, nullptr, child_argv.data(), child_environment.data());
      posix_spawn_file_actions_destroy(&files);
      if (error != 0) {
        outcomes[i].status = "failed";
        outcomes[i].reason = std::string("cannot start the child process: ") + std::strerror(error);
        std::cout << progress(i) << ": FAILED, " << outcomes[i].reason << "\n" << std::flush;
        write_failures();
        continue;
      }
      Running started;
      started.scene = i;
      started.start = std::chrono::steady_clock::now();
      running[pid] = started;
      std::cout << progress(i) << ": started\n" << std::flush;
    }
    if (running.empty()) break;

    int status = 0;
    struct rusage usage {};
    // With a time limit, poll: a scene past it gets SIGTERM, and SIGKILL if it ignores that.
    const pid_t pid = ::wait4(-1, &status, batch.scene_timeout_s > 0 ? WNOHANG : 0, &usage);
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;  // ECHILD: nothing left to wait for
    }
    if (pid == 0) {
      const auto now = std::chrono::steady_clock::now();
      for (auto& [child, r] : running) {
        if (!r.timed_out && std::chrono::duration<double>(now - r.start).count() > batch.scene_timeout_s) {
          r.timed_out = true;
          r.terminated = now;
          ::kill(child, SIGTERM);
        } else if (r.timed_out && now - r.terminated > std::chrono::seconds(10)) {
          ::kill(child, SIGKILL);
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    const std::size_t i = it->second.scene;
    const bool timed_out = it->second.timed_out;
    Outcome& o = outcomes[i];
    o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - it->second.start).count();
    o.peak_rss_MiB = static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: kibibytes
    running.erase(it);
    if (WIFEXITED(status)) {
      o.exit_code = WEXITSTATUS(status);
      if (o.exit_code == 0 && fs::exists(png_of(i), ec) && fs::exists(report_of(i), ec)) {
        o.status = "done";
      } else {
        o.status = "failed";
        o.reason = o.exit_code == 0 ? "exited with status 0 without writing " + png_of(i).filename().string() + " and " +
                                          report_of(i).filename().string()
                                    : "exited with status " + std::to_string(o.exit_code);
      }
    } else if (WIFSIGNALED(status)) {
      o.signal = WTERMSIG(status);
      o.status = stopping && (o.signal == SIGTERM || o.signal == SIGINT) ? "interrupted" : "failed";
      o.reason = "killed by signal " + std::to_string(o.signal) + " (" + ::strsignal(o.signal) + ")";
      if (o.signal == SIGKILL && !timed_out) o.reason += ", perhaps out of memory";
    }
    if (timed_out) {
      o.status = "failed";
      std::ostringstream reason;
      reason << "timed out: stopped after " << seconds3(o.seconds) << " (--scene-timeout " << batch.scene_timeout_s
             << " s)";
      o.reason = reason.str();
      removeStaleTemporaries(out_dir, scenes[i].name);
    }
    std::ostringstream line;
    line << progress(i) << ": ";
    if (o.status == "done") {
      line << "done in " << seconds3(o.seconds) << ", peak memory " << static_cast<long>(o.peak_rss_MiB) << " MiB";
      fs::remove(log_of(i), ec);  // the report holds everything the log said
    } else {
      o.log_tail = tailLines(log_of(i), 10);
      if (!o.log_tail.empty()) o.reason += ": " + o.log_tail.back();
      line << (o.status == "failed" ? "FAILED, " : "interrupted, ") << o.reason << " (log: logs/" << scenes[i].name
           << ".log)";
      if (o.status == "failed") write_failures();
    }
    std::cout << line.str() << "\n" << std::flush;
  }

  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);

  std::size_t done = 0, skipped = 0, failed = 0, interrupted = 0;
  double peak_MiB = 0;
  nlohmann::json per_scene = nlohmann::json::array();
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const Outcome& o = outcomes[i];
    done += o.status == "done";
    skipped += o.status == "skipped";
    failed += o.status == "failed";
    interrupted += o.status == "interrupted" || o.status == "not started";
    peak_MiB = std::max(peak_MiB, o.peak_rss_MiB);
    nlohmann::json s = {{"scene", scenes[i].name},
                        {"manifest", scenes[i].manifest.string()},
                        {"seed", scenes[i].seed},
                        {"status", o.status}};
    if (o.status == "done" || o.status == "failed" || o.status == "interrupted") {
      s["seconds"] = o.seconds;
      s["peak_rss_MiB"] = o.peak_rss_MiB;
    }
    if (!o.reason.empty()) s["reason"] = o.reason;
    per_scene.push_back(s);
  }
  nlohmann::json versions = nlohmann::json::object();
  for (const auto& [library, version] : dependencyVersions()) versions[library] = version;
  const double total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - batch_start).count();
  write_failures();
  const nlohmann::json summary = {{"command", "night --batch"},
                                  {"list", batch.list->string()},
                                  {"output_folder", out_dir.string()},
                                  {"shard", shard_text},
                                  {"jobs", batch.jobs},
                                  {"seed", night.conversion.seed},
                                  {"scenes_in_batch", all.size()},
                                  {"ground_truth_manifests_left_out", ground_truth_skipped},
                                  {"scenes", scenes.size()},
                                  {"done", done},
                                  {"skipped_already_done", skipped},
                                  {"failed", failed},
                                  {"interrupted", interrupted},
                                  {"total_seconds", total_seconds},
                                  {"peak_rss_MiB", peak_MiB},
                                  {"failures_file", failures_file.filename().string()},
                                  {"per_scene", per_scene},
                                  {"versions", versions}};
  writeTextAtomically(summary_file, summary.dump(2) + "\n");

  std::cout << "batch summary (shard " << shard_text << "): " << scenes.size() << " scenes, " << done << " done, "
            << skipped << " skipped (already done), " << failed << " failed";
  if (interrupted) std::cout << ", " << interrupted << " interrupted or not started";
  std::cout << "; " << seconds3(total_seconds) << "; peak memory of a scene " << static_cast<long>(peak_MiB)
            << " MiB\n";
  if (failed) std::cout << "failures: " << failures_file.string() << "\n";
  std::cout << "summary: " << summary_file.string() << "\n" << std::flush;
  if (g_interrupt_signal) return 128 + g_interrupt_signal;
  return failed > 0 ? 1 : 0;
}

}  // namespace solo::tools
