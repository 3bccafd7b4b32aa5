// `solo depth`: outputs, report, switches and errors.

#include <solo/core/image_io.h>

#include <nlohmann/json.hpp>

#include "test_support.h"

using solo::test::runSolo;
using solo::test::TempDir;

namespace {

const std::string kScene = "\"" + (std::filesystem::path(SOLO_PROJECT_DATA_DIR) / "default" / "scene.json").string() + "\"";

TEST(CliDepth, WritesRefinedDepthNormalsMaskAndReport) {
  TempDir dir;
  const auto r = runSolo("depth " + kScene + " -o \"" + (dir / "refined.exr").string() + "\" --report \"" +
                         (dir / "r.json").string() + "\"");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat depth = solo::readDepth(dir / "refined.exr", 0);
  EXPECT_EQ(depth.size(), cv::Size(960, 540)) << "the image resolution, not the estimate's";
  const cv::Mat normals = solo::readNormals(dir / "refined.normals.exr");
  EXPECT_EQ(normals.size(), depth.size());
  const cv::Mat mask = solo::readLabels(dir / "refined.uncertain.png");
  EXPECT_GT(cv::countNonZero(mask), 0);
  const auto j = nlohmann::json::parse(solo::test::readText(dir / "r.json"));
  EXPECT_EQ(j["command"], "depth");
  std::vector<std::string> names;
  for (const auto& stage : j["stages"]) names.push_back(stage["name"]);
  EXPECT_EQ(names,
            (std::vector<std::string>{"input", "upsample", "complete", "filter", "uncertain", "optimize", "refine"}));
  EXPECT_EQ(j["stages"][6]["metrics"]["uncertain_pixels"], cv::countNonZero(mask));
}

TEST(CliDepth, SwitchedOffStepsAreReportedAsSkipped) {
  TempDir dir;
  const auto r = runSolo("depth " + kScene + " -o \"" + (dir / "d.pfm").string() +
                         "\" --no-optimize --no-uncertain --no-complete");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(solo::test::readText(dir / "d.report.json"));
  EXPECT_EQ(j["stages"][2]["name"], "complete");
  EXPECT_EQ(j["stages"][2]["skip_reason"], "switched off");
  EXPECT_TRUE(j["stages"][4]["skipped"].get<bool>());
  EXPECT_EQ(j["stages"][5]["skip_reason"], "switched off");
}

TEST(CliDepth, TheObjectiveIsChosenByNameAndReported) {
  TempDir dir;
  const auto optimizeStage = [&](const std::string& extra, const std::string& name) {
    const auto r = runSolo("depth " + kScene + " -o \"" + (dir / (name + ".exr")).string() + "\" " + extra);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const auto j = nlohmann::json::parse(solo::test::readText(dir / (name + ".report.json")));
    return j["stages"][5]["metrics"];
  };
  const auto chosen = optimizeStage("", "default");
  EXPECT_EQ(chosen["tangent_stencil"], "one_sided");
  EXPECT_EQ(chosen["tangent_loss"], "cauchy");
  EXPECT_EQ(chosen["data_units"], "footprints");
  EXPECT_EQ(chosen["data_weight"], 3.0);
  // The paper's, with the paper's tangent graph given after it: both hold.
  const auto paper = optimizeStage("--tangent-model paper --objective paper", "paper");
  EXPECT_EQ(paper["tangent_stencil"], "central");
  EXPECT_EQ(paper["tangent_loss"], "squared");
  EXPECT_EQ(paper["data_units"], "metres");
  EXPECT_EQ(paper["data_weight"], 1.0);
  EXPECT_EQ(paper["tangent_model"], "paper_graph");
  const cv::Mat a = solo::readDepth(dir / "default.exr", 0), b = solo::readDepth(dir / "paper.exr", 0);
  EXPECT_GT(cv::norm(a, b, cv::NORM_INF), 1e-3) << "the two objectives refine differently";
  const auto bad = runSolo("depth " + kScene + " -o \"" + (dir / "x.exr").string() + "\" --objective smooth");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("--objective"), std::string::npos) << bad.output;
}

TEST(CliDepth, AMissingSceneIsAnErrorNamingItAndWritesNothing) {
  TempDir dir;
  const auto r = runSolo("depth \"" + (dir / "none.json").string() + "\" -o \"" + (dir / "out.exr").string() + "\"");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("none.json"), std::string::npos) << r.output;
  EXPECT_TRUE(solo::test::listFolder(dir.path()).empty());
}

}  // namespace
