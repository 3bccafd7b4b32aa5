// The batch controller without the solo binary: shard parsing, scene lists and their output
// names, the forwarded arguments, and whole batches whose scenes a shell script stands in for
// (done, failed with the log's last line, skipped on a rerun, stopped at the time limit).

#include <solo/core/error.h>
#include <solo/pipeline/night_batch.h>

#include "test_support.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

using solo::NightBatchStatus;
using solo::test::readText;
using solo::test::TempDir;
using solo::test::writeText;

std::vector<std::string> names(const solo::NightBatchPlan& plan) {
  std::vector<std::string> result;
  for (const auto& s : plan.scenes) result.push_back(s.name);
  return result;
}

// Stands in for `solo night MANIFEST -o PNG --report REPORT --seed SEED`: a manifest whose path
// holds "bad" fails with an error line, one holding "slow" sleeps, the others write both outputs.
fs::path fakeSolo(const TempDir& dir) {
  const fs::path script = dir / "fake-solo.sh";
  writeText(script,
            "#!/bin/sh\n"
            "case \"$2\" in *bad*) echo \"solo: error: $2: broken\" >&2; exit 2;; *slow*) exec sleep 20;; esac\n"
            "echo \"$*\" > \"$4\"; echo \"$8\" > \"$6\"\n");
  fs::permissions(script, fs::perms::owner_all);
  return script;
}

solo::NightBatchOptions batchOptions(const TempDir& dir, const fs::path& list) {
  solo::NightBatchOptions options;
  options.list = list;
  options.output_folder = dir / "out";
  options.seed = 7;
  options.arguments = {"night"};
  options.executable = fakeSolo(dir);
  return options;
}

}  // namespace

TEST(NightBatch, ShardsParseAndBadOnesNameTheOption) {
  const solo::NightBatchShard shard = solo::parseNightBatchShard(" 3 / 16 ");
  EXPECT_EQ(shard.index, 3);
  EXPECT_EQ(shard.count, 16);
  for (const std::string bad : {"2/2", "0/0", "1", "a/b", "-1/2"}) {
    try {
      solo::parseNightBatchShard(bad);
      ADD_FAILURE() << bad;
    } catch (const solo::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--shard"), std::string::npos) << e.what();
    }
  }
}

TEST(NightBatch, SceneSeedsDependOnTheNameAndTheBatchSeedOnly) {
  EXPECT_EQ(solo::nightBatchSceneSeed(1, "a"), solo::nightBatchSceneSeed(1, "a"));
  EXPECT_NE(solo::nightBatchSceneSeed(1, "a"), solo::nightBatchSceneSeed(2, "a"));
  EXPECT_NE(solo::nightBatchSceneSeed(1, "a"), solo::nightBatchSceneSeed(1, "b"));
  EXPECT_LT(solo::nightBatchSceneSeed(0, "berlin__0001"), std::uint64_t{1} << 53);
}

TEST(NightBatch, AListGivesSortedUniqueNamesAndSkipsCommentsAndBlankLines) {
  TempDir dir;
  fs::create_directories(dir / "set" / "berlin" / "0001");
  const fs::path list = dir / "set" / "list.txt";
  writeText(list, "# scenes\n\nmunich/0001/scene.json\n  berlin/0001  \nframes/f17.scene.json\n../other/x.json\n");
  const solo::NightBatchPlan plan = solo::collectNightBatchScenes(list, 5);
  EXPECT_EQ(names(plan), (std::vector<std::string>{"berlin__0001", "frames__f17", "munich__0001", "up__other__x"}));
  EXPECT_EQ(plan.scenes_in_batch, 4u);
  EXPECT_EQ(plan.scenes[0].manifest, fs::absolute(dir / "set" / "berlin" / "0001" / "scene.json").lexically_normal());
  EXPECT_EQ(plan.scenes[0].seed, solo::nightBatchSceneSeed(5, "berlin__0001"));

  writeText(list, "a/b/scene.json\na__b/scene.json\n");
  EXPECT_THROW(solo::collectNightBatchScenes(list, 5), solo::InputError) << "two scenes named a__b";
  writeText(list, "# nothing\n");
  EXPECT_THROW(solo::collectNightBatchScenes(list, 5), solo::InputError);
  writeText(list, "{\"depth\": \"d.png\"}\n");
  EXPECT_THROW(solo::collectNightBatchScenes(list, 5), solo::InputError) << "a manifest given as the list";
  EXPECT_THROW(solo::collectNightBatchScenes(dir / "missing.txt", 5), solo::InputError);
}

TEST(NightBatch, ForwardedArgumentsLeaveOutWhatTheBatchSetsPerScene) {
  const solo::ForwardedSceneArguments forwarded =
      solo::forwardedSceneArguments({"solo", "night", "--batch", "list", "-oout", "--shard=1/2", "--jobs", "2",
                                     "--max-spp", "4", "--seed", "3", "--contact-sheet", "s.png", "--no-glare"});
  EXPECT_TRUE(forwarded.output_given);
  EXPECT_EQ(forwarded.arguments, (std::vector<std::string>{"night", "--max-spp", "4", "--no-glare"}));
  EXPECT_FALSE(solo::forwardedSceneArguments({"solo", "night", "--batch", "list"}).output_given);
}

TEST(NightBatch, ScenesRunRecordTheirFailuresAndARerunSkipsTheDoneOnes) {
  TempDir dir;
  const fs::path list = dir / "list.txt";
  writeText(list, "good/scene.json\nbad/scene.json\nfine.scene.json\n");
  const solo::NightBatchOptions options = batchOptions(dir, list);
  std::vector<std::string> events;
  const auto progress = [&](const solo::NightBatchEvent& e, const solo::NightBatchPlan& plan,
                            const std::vector<solo::NightBatchSceneOutcome>& outcomes) {
    if (e.kind == solo::NightBatchEvent::Kind::SceneEnded)
      events.push_back(plan.scenes[e.scene].name + " " + solo::nightBatchStatusName(outcomes[e.scene].status));
  };

  const solo::NightBatchResult first = solo::runNightBatch(options, progress);
  EXPECT_EQ(first.done, 2u);
  EXPECT_EQ(first.failed, 1u);
  EXPECT_EQ(first.interrupt_signal, 0);
  EXPECT_EQ(events, (std::vector<std::string>{"bad failed", "fine done", "good done"}));
  const solo::NightBatchSceneOutcome& bad = first.outcomes[0];
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.reason.find("exited with status 2: solo: error: "), std::string::npos) << bad.reason;
  const fs::path out = fs::absolute(dir / "out");
  const std::string seed = std::to_string(solo::nightBatchSceneSeed(7, "good"));
  EXPECT_EQ(readText(out / "good.report.json"), seed + "\n");
  EXPECT_EQ(readText(out / "good.png"), "night " +
                                            fs::absolute(dir / "good" / "scene.json").lexically_normal().string() +
                                            " -o " + (out / "good.png").string() + " --report " +
                                            (out / "good.report.json").string() + " --seed " + seed + "\n");
  EXPECT_TRUE(fs::exists(out / "logs" / "bad.log"));
  EXPECT_FALSE(fs::exists(out / "logs" / "good.log")) << "a done scene's log is removed";
  EXPECT_NE(readText(first.failures_file).find("\"scene\": \"bad\""), std::string::npos);
  EXPECT_EQ(first.summary_file, out / "batch-summary.json");

  events.clear();
  const solo::NightBatchResult second = solo::runNightBatch(options, progress);
  EXPECT_EQ(second.skipped, 2u);
  EXPECT_EQ(second.failed, 1u);
  EXPECT_EQ(events, (std::vector<std::string>{"bad failed"}));
}

TEST(NightBatch, AShardTakesEveryNthSceneAndASlowSceneIsStoppedAtTheTimeLimit) {
  TempDir dir;
  const fs::path list = dir / "list.txt";
  writeText(list, "a.scene.json\nb.scene.json\nc-slow.scene.json\nd.scene.json\n");
  solo::NightBatchOptions options = batchOptions(dir, list);
  options.shard = "0/2";
  options.jobs = 2;
  options.scene_timeout_s = 0.3;
  const solo::NightBatchResult result = solo::runNightBatch(options);
  EXPECT_EQ(names(result.plan), (std::vector<std::string>{"a", "c-slow"}));
  EXPECT_EQ(result.plan.scenes_in_batch, 4u);
  EXPECT_EQ(result.done, 1u);
  ASSERT_EQ(result.failed, 1u);
  EXPECT_EQ(result.outcomes[1].status, NightBatchStatus::Failed);
  EXPECT_EQ(result.outcomes[1].reason.rfind("timed out: stopped after ", 0), 0u) << result.outcomes[1].reason;
  EXPECT_EQ(result.failures_file.filename(), "failures.shard-0-of-2.json");
}
