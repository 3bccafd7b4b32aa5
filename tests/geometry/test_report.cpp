#include <solo/core/report.h>

#include <nlohmann/json.hpp>

#include "test_support.h"

TEST(Report, JsonKeepsStagesMetricsUnitsAndSkipReasons) {
  solo::RunReport r;
  r.command = "night";
  r.seed = 42;
  r.scene = "s.json";
  r.versions = {{"CGAL", "5.5.1"}};
  solo::StageReport input;
  input.name = "input";
  input.seconds = 0.25;
  input.add("depth_valid", std::int64_t{1234}).add("depth_max", 99.5, "m").add("camera_default", true);
  input.notes.push_back("no normals map given");
  input.warnings.push_back("no camera given: square pixels, 56.7 deg wide");
  solo::StageReport glare;
  glare.name = "glare";
  glare.skipped = true;
  glare.skip_reason = "no light above glare threshold";
  r.stages = {input, glare};

  const auto j = nlohmann::json::parse(solo::reportToJson(r));
  EXPECT_EQ(j["seed"], 42);
  EXPECT_EQ(j["versions"]["CGAL"], "5.5.1");
  EXPECT_EQ(j["stages"][0]["metrics"]["depth_valid"], 1234);
  EXPECT_EQ(j["stages"][0]["metrics"]["depth_max"]["value"], 99.5);
  EXPECT_EQ(j["stages"][0]["metrics"]["depth_max"]["unit"], "m");
  EXPECT_EQ(j["stages"][0]["metrics"]["camera_default"], true);
  EXPECT_EQ(j["stages"][0]["notes"][0], "no normals map given");
  EXPECT_EQ(j["stages"][1]["skipped"], true);
  EXPECT_EQ(j["stages"][1]["skip_reason"], "no light above glare threshold");

  const std::string summary = solo::reportSummary(r);
  EXPECT_NE(summary.find("seed: 42"), std::string::npos);
  EXPECT_NE(summary.find("skipped: no light above glare threshold"), std::string::npos);
  EXPECT_NE(summary.find("depth_max 99.5 m"), std::string::npos);
  // The terminal gets a count of the notes and every warning; the report has both in full.
  EXPECT_EQ(summary.find("no normals map given"), std::string::npos) << summary;
  EXPECT_NE(summary.find("(1 note)"), std::string::npos) << summary;
  EXPECT_NE(summary.find("warning: no camera given: square pixels"), std::string::npos) << summary;
  EXPECT_EQ(j["stages"][0]["warnings"][0], "no camera given: square pixels, 56.7 deg wide");
  solo::SummaryOptions verbose;
  verbose.notes = true;
  EXPECT_NE(solo::reportSummary(r, verbose).find("note: no normals map given"), std::string::npos);

  ASSERT_NE(input.find("depth_max"), nullptr);
  EXPECT_EQ(std::get<double>(*input.find("depth_max")), 99.5);
  EXPECT_EQ(input.find("missing"), nullptr);
}
