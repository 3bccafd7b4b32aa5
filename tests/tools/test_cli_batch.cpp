// `solo night --batch` end to end (docs/batch.md): outputs per scene, failures recorded with
// their reason, resuming, shards that partition the scenes, the per-scene seed, bad specs.

#include <solo/core/image_io.h>

#include <nlohmann/json.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <chrono>
#include <cstdint>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include "test_support.h"

namespace fs = std::filesystem;
using solo::test::runSolo;
using solo::test::TempDir;

namespace {

// The smallest budget `solo night` has: this checks the batch plumbing, not the images.
const std::string kFast = " --min-spp 2 --max-spp 2 --no-optimize --no-solids --no-glare";

std::string quoted(const fs::path& p) { return "\"" + p.string() + "\""; }

void synth(const fs::path& folder, int seed) {
  fs::create_directories(folder.parent_path());
  const auto r = runSolo("synth -o " + quoted(folder) + " --size 96x54 --seed " + std::to_string(seed));
  ASSERT_EQ(r.exit_code, 0) << r.output;
}

nlohmann::json readJson(const fs::path& file) { return nlohmann::json::parse(solo::test::readText(file)); }

// docs/batch.md, "Seeds", computed here from its definition: FNV-1a 64 of the name, xor the
// batch seed, SplitMix64, top 53 bits.
std::uint64_t documentedSceneSeed(std::uint64_t batch_seed, const std::string& name) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (const unsigned char c : name) h = (h ^ c) * 0x100000001b3ull;
  std::uint64_t z = (batch_seed ^ h) + 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return (z ^ (z >> 31)) >> 11;
}

void expectNightImage(const fs::path& file) {
  ASSERT_TRUE(fs::exists(file)) << file;
  const solo::ImageFileInfo info = solo::probeImage(file);
  EXPECT_EQ(info.width, 96) << file;
  EXPECT_EQ(info.height, 54) << file;
  EXPECT_EQ(info.channels, 3) << file;
  const cv::Mat image = solo::readImageRaw(file);
  double low = 0, high = 0;
  cv::minMaxLoc(image.reshape(1), &low, &high);
  EXPECT_GT(high, low) << file << ": a night image, not a constant one";
}

std::set<std::string> scenesWithStatus(const nlohmann::json& summary, const std::string& status) {
  std::set<std::string> names;
  for (const auto& s : summary["per_scene"])
    if (s["status"] == status) names.insert(s["scene"].get<std::string>());
  return names;
}

}  // namespace

TEST(CliBatch, ListConvertsEachSceneRecordsTheBrokenOneAndResumes) {
  TempDir dir;
  const fs::path scenes = dir / "scenes";
  synth(scenes / "a", 1);
  synth(scenes / "b", 2);
  fs::create_directories(scenes / "c");
  solo::test::writeText(scenes / "c" / "scene.json", R"({"image": "day.png", )");  // truncated JSON
  solo::test::writeText(scenes / "list.txt", "# three scenes, one broken\n\nc/scene.json\n  a/scene.json  \n"
                                             "# a scene folder stands for its scene.json\nb\n");
  const fs::path out = dir / "out";
  const std::string command = "night --batch " + quoted(scenes / "list.txt") + " -o " + quoted(out) + " --seed 5" + kFast;

  auto r = runSolo(command);
  EXPECT_EQ(r.exit_code, 1) << "a scene failed: non-zero exit\n" << r.output;
  expectNightImage(out / "a.png");
  expectNightImage(out / "b.png");
  EXPECT_FALSE(fs::exists(out / "c.png"));
  EXPECT_FALSE(fs::exists(out / "c.report.json"));
  for (const std::string name : {"a", "b"}) {
    const auto report = readJson(out / (name + ".report.json"));
    EXPECT_EQ(report["seed"].get<std::uint64_t>(), documentedSceneSeed(5, name)) << name;
    EXPECT_EQ(fs::path(report["scene"].get<std::string>()), scenes / name / "scene.json");
    for (const auto& stage : report["stages"])
      if (stage["name"] == "render") {
        EXPECT_EQ(stage["metrics"]["samples_per_pixel_max"], 2) << "--max-spp 2 reached the scene's process";
      }
  }

  const auto failures = readJson(out / "failures.json");
  ASSERT_EQ(failures["failures"].size(), 1u) << failures.dump(2);
  const auto& failure = failures["failures"][0];
  EXPECT_EQ(failure["scene"], "c");
  EXPECT_EQ(failure["exit_code"], 2);
  const std::string reason = failure["reason"];
  EXPECT_NE(reason.find((scenes / "c" / "scene.json").string() + ": not valid JSON"), std::string::npos) << reason;
  EXPECT_TRUE(fs::exists(out / failure["log"].get<std::string>())) << "the failed scene's log is kept";
  EXPECT_NE(r.output.find("FAILED"), std::string::npos) << r.output;

  auto summary = readJson(out / "batch-summary.json");
  EXPECT_EQ(summary["scenes"], 3);
  EXPECT_EQ(summary["done"], 2);
  EXPECT_EQ(summary["skipped_already_done"], 0);
  EXPECT_EQ(summary["failed"], 1);
  EXPECT_EQ(scenesWithStatus(summary, "done"), (std::set<std::string>{"a", "b"}));
  std::vector<std::string> order;
  for (const auto& s : summary["per_scene"]) {
    order.push_back(s["scene"]);
    if (s["status"] == "done") {
      EXPECT_GT(s["peak_rss_MiB"].get<double>(), 1.0) << "the child's peak memory from wait4";
    }
  }
  EXPECT_EQ(order, (std::vector<std::string>{"a", "b", "c"})) << "sorted, whatever the list order";

  // Rerun: finished scenes are skipped, untouched; the broken one is tried and recorded again.
  const auto a_time = fs::last_write_time(out / "a.png");
  const auto a_report_time = fs::last_write_time(out / "a.report.json");
  const auto b_time = fs::last_write_time(out / "b.png");
  r = runSolo(command);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  summary = readJson(out / "batch-summary.json");
  EXPECT_EQ(summary["done"], 0);
  EXPECT_EQ(summary["skipped_already_done"], 2);
  EXPECT_EQ(summary["failed"], 1);
  EXPECT_EQ(fs::last_write_time(out / "a.png"), a_time);
  EXPECT_EQ(fs::last_write_time(out / "a.report.json"), a_report_time);
  EXPECT_EQ(fs::last_write_time(out / "b.png"), b_time);
  EXPECT_EQ(readJson(out / "failures.json")["failures"].size(), 1u);

  // A scene killed between its image and its report (the report is written last) is not done.
  fs::remove(out / "b.report.json");
  r = runSolo(command);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  summary = readJson(out / "batch-summary.json");
  EXPECT_EQ(scenesWithStatus(summary, "done"), (std::set<std::string>{"b"}));
  EXPECT_EQ(scenesWithStatus(summary, "skipped"), (std::set<std::string>{"a"}));
  EXPECT_TRUE(fs::exists(out / "b.report.json"));
  for (const std::string& file : solo::test::listFolder(out))
    EXPECT_NE(file[0], '.') << "no temporary file left behind: " << file;
}

TEST(CliBatch, ShardsOfAFolderPartitionTheScenesAndKeepTheirSeeds) {
  TempDir dir;
  const fs::path scenes = dir / "scenes";
  // Two scenes share the folder name s1; their ground-truth manifests (gt/scene.json) are no scenes.
  synth(scenes / "x" / "s1", 1);
  synth(scenes / "y" / "s1", 2);
  synth(scenes / "z", 3);
  const fs::path out = dir / "out";
  const std::string base = "night --batch " + quoted(scenes) + " -o " + quoted(out) + " --seed 11" + kFast;
  const auto r0 = runSolo(base + " --shard 0/2 --jobs 2");
  ASSERT_EQ(r0.exit_code, 0) << r0.output;
  // A contact sheet names one file: each scene gets its own beside its image instead.
  const auto r1 = runSolo(base + " --shard 1/2 --contact-sheet " + quoted(dir / "sheet.png"));
  ASSERT_EQ(r1.exit_code, 0) << r1.output;

  // Sorted names x__s1, y__s1, z: shard 0 takes k = 0, 2, shard 1 takes k = 1.
  const auto s0 = readJson(out / "batch-summary.shard-0-of-2.json");
  const auto s1 = readJson(out / "batch-summary.shard-1-of-2.json");
  EXPECT_EQ(s0["scenes_in_batch"], 3);
  EXPECT_EQ(s0["ground_truth_manifests_left_out"], 3);
  EXPECT_EQ(scenesWithStatus(s0, "done"), (std::set<std::string>{"x__s1", "z"}));
  EXPECT_EQ(scenesWithStatus(s1, "done"), (std::set<std::string>{"y__s1"}));
  EXPECT_EQ(s0["per_scene"].size() + s1["per_scene"].size(), 3u) << "each scene in exactly one shard";
  for (const std::string name : {"x__s1", "y__s1", "z"}) {
    expectNightImage(out / (name + ".png"));
    EXPECT_EQ(readJson(out / (name + ".report.json"))["seed"].get<std::uint64_t>(), documentedSceneSeed(11, name))
        << name << ": the seed does not depend on the shard";
  }
  EXPECT_EQ(readJson(out / "failures.shard-0-of-2.json")["failures"].size(), 0u);
  EXPECT_EQ(readJson(out / "failures.shard-1-of-2.json")["failures"].size(), 0u);
  EXPECT_FALSE(fs::exists(out / "failures.json")) << "shards write their own files";
  EXPECT_TRUE(fs::exists(out / "y__s1.contact-sheet.png"));
  EXPECT_FALSE(fs::exists(out / "z.contact-sheet.png")) << "shard 0 asked for none";
  EXPECT_FALSE(fs::exists(dir / "sheet.png"));
}

TEST(CliBatch, BadBatchSpecificationsAreClearErrorsWithoutOutput) {
  TempDir dir;
  solo::test::writeText(dir / "list.txt", "missing/scene.json\n");
  const fs::path out = dir / "out";
  const std::string base = "night --batch " + quoted(dir / "list.txt") + " -o " + quoted(out);
  for (const auto& [shard, problem] : std::vector<std::pair<std::string, std::string>>{
           {"2/2", "--shard: the shard index i must be below N (0-based: 0 to 1), got \"2/2\""},
           {"0/0", "--shard: the shard count N must be at least 1"},
           {"1", "--shard: expected i/N"},
           {"a/b", "--shard: expected i/N"},
           {"=-1/2", "--shard: expected i/N"}}) {
    const auto r = runSolo(base + " --shard" + (shard[0] == '=' ? "" : " ") + shard);
    EXPECT_EQ(r.exit_code, 2) << shard << "\n" << r.output;
    EXPECT_NE(r.output.find(problem), std::string::npos) << shard << "\n" << r.output;
  }
  auto r = runSolo(base + " --jobs 0");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--jobs: must be at least 1"), std::string::npos) << r.output;
  r = runSolo("night --batch " + quoted(dir / "nothing.txt") + " -o " + quoted(out));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find((dir / "nothing.txt").string() + ": not found"), std::string::npos) << r.output;
  r = runSolo("night --batch " + quoted(dir / "list.txt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--batch: needs -o OUT_DIR"), std::string::npos) << r.output;
  r = runSolo(base + " --report r.json");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--report: cannot be used with --batch"), std::string::npos) << r.output;
  r = runSolo("night --shard 0/2 -o " + quoted(out));
  EXPECT_NE(r.exit_code, 0) << "--shard needs --batch\n" << r.output;
  fs::create_directories(dir / "empty");
  r = runSolo("night --batch " + quoted(dir / "empty") + " -o " + quoted(out));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("no scene manifest"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out)) << "no output folder for a batch that cannot start";
}

TEST(CliBatch, ASceneOverTheTimeLimitIsStoppedRecordedAndTheBatchGoesOn) {
  TempDir dir;
  const fs::path scenes = dir / "scenes";
  synth(scenes / "small", 1);
  // A 1920x1080 scene takes well over 10 s with any settings (its mesh stage alone takes
  // several seconds); the 96x54 one well under a second.
  fs::create_directories(scenes);
  const auto big = runSolo("synth -o " + quoted(scenes / "big") + " --size 1920x1080 --seed 3");
  ASSERT_EQ(big.exit_code, 0) << big.output;
  const fs::path out = dir / "out";
  const auto start = std::chrono::steady_clock::now();
  const auto r = runSolo("night --batch " + quoted(scenes) + " -o " + quoted(out) + " --scene-timeout 4" + kFast);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_LT(seconds, 30.0) << "the big scene was stopped, not waited for";
  expectNightImage(out / "small.png");
  EXPECT_FALSE(fs::exists(out / "big.png"));
  EXPECT_FALSE(fs::exists(out / "big.report.json"));
  const auto failures = readJson(out / "failures.json");
  ASSERT_EQ(failures["failures"].size(), 1u) << failures.dump(2);
  const auto& failure = failures["failures"][0];
  EXPECT_EQ(failure["scene"], "big");
  const std::string reason = failure["reason"];
  EXPECT_EQ(reason.rfind("timed out: stopped after ", 0), 0u) << reason;
  EXPECT_NE(reason.find("--scene-timeout 4 s"), std::string::npos) << reason;
  EXPECT_GE(failure["seconds"].get<double>(), 4.0);
  const auto summary = readJson(out / "batch-summary.json");
  EXPECT_EQ(scenesWithStatus(summary, "done"), (std::set<std::string>{"small"}));
  EXPECT_EQ(scenesWithStatus(summary, "failed"), (std::set<std::string>{"big"}));
  for (const std::string& file : solo::test::listFolder(out))
    EXPECT_NE(file[0], '.') << "no temporary file left behind: " << file;
}

TEST(CliBatch, ARerunRemovesEveryKindOfTemporaryOfItsScenesAndNoOtherFile) {
  TempDir dir;
  synth(dir / "scenes" / "small", 1);
  const fs::path out = dir / "out";
  fs::create_directories(out);
  // What killed runs leave: the hidden temporaries of the image, the report and the contact sheet.
  const std::vector<std::string> stale = {".small.tmp4242_0.png", ".small.report.tmp4242_1.json",
                                          ".small.contact-sheet.tmp4242_2.png"};
  // Not the scene's: another name, and a file that only looks alike.
  const std::vector<std::string> kept = {".smaller.tmp4242_0.png", ".small.tmpx_0.png", "notes.txt"};
  for (const std::string& name : stale) solo::test::writeText(out / name, "partial");
  for (const std::string& name : kept) solo::test::writeText(out / name, "keep");
  const auto r = runSolo("night --batch " + quoted(dir / "scenes") + " -o " + quoted(out) + kFast);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expectNightImage(out / "small.png");
  for (const std::string& name : stale) EXPECT_FALSE(fs::exists(out / name)) << name;
  for (const std::string& name : kept) EXPECT_TRUE(fs::exists(out / name)) << name;
}

namespace {

/// The pids of the processes whose parent is `parent` (from /proc).
std::vector<pid_t> childrenOf(pid_t parent) {
  std::vector<pid_t> children;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator("/proc", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(entry.path() / "stat");
    std::string line;
    if (!std::getline(stat, line)) continue;
    const std::size_t close = line.rfind(')');  // the command name may hold spaces
    if (close == std::string::npos) continue;
    std::istringstream fields(line.substr(close + 2));
    char state = 0;
    long ppid = 0;
    fields >> state >> ppid;
    if (ppid == parent) children.push_back(static_cast<pid_t>(std::stol(name)));
  }
  return children;
}

/// True while `pid` is a live process (not gone, not a zombie waiting to be reaped).
bool running(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return false;
  const std::size_t close = line.rfind(')');
  return close != std::string::npos && close + 2 < line.size() && line[close + 2] != 'Z' && line[close + 2] != 'X';
}

}  // namespace

TEST(CliBatch, KillingOnlyTheBatchProcessStopsItsScenes) {
  TempDir dir;
  synth(dir / "scenes" / "a", 1);
  synth(dir / "scenes" / "b", 2);
  const fs::path out = dir / "out";
  // The default preset: each scene runs long enough to be caught running.
  const std::string command = std::string("exec \"") + SOLO_BINARY + "\" night --batch " + quoted(dir / "scenes") +
                              " -o " + quoted(out) + " --jobs 2 > /dev/null 2>&1";
  const pid_t batch = ::fork();
  if (batch == 0) {
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  std::vector<pid_t> scenes;
  const auto start = std::chrono::steady_clock::now();
  while (scenes.size() < 2 && std::chrono::steady_clock::now() - start < std::chrono::seconds(20)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    scenes = childrenOf(batch);
  }
  ASSERT_FALSE(scenes.empty()) << "the batch started its scenes";
  ::kill(batch, SIGKILL);
  int status = 0;
  ASSERT_EQ(::waitpid(batch, &status, 0), batch);
  const auto killed = std::chrono::steady_clock::now();
  bool any_running = true;
  while (any_running && std::chrono::steady_clock::now() - killed < std::chrono::seconds(5)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    any_running = std::any_of(scenes.begin(), scenes.end(), running);
  }
  EXPECT_FALSE(any_running) << "every scene process stops within 5 s of its batch's death";
  for (const pid_t scene : scenes)
    if (running(scene)) ::kill(scene, SIGKILL);  // leave nothing behind whatever the outcome
  for (const std::string& file : solo::test::listFolder(out))
    EXPECT_NE(file[0], '.') << "the stopped scenes removed their temporaries: " << file;
}
