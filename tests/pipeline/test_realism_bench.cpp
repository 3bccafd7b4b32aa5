// The realism benchmark's pieces that need no night conversion, on hand-made rows: the median
// row, the targets a row misses, realism.csv's header and rows, the markdown table's marks, and
// the options refused before anything is written.

#include <solo/core/error.h>
#include <solo/pipeline/realism_bench.h>

#include "test_support.h"

#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <vector>

namespace {

using solo::RealismRow;

/// A row meeting every target: values in the columns missedTargets reads, plus a size.
RealismRow goodRow(const std::string& scene, double mean) {
  RealismRow row{scene, "default", "2", {}, ""};
  row.values = {{"width_px", 160.0}, {"height_px", 90.0},   {"mean", mean},        {"clipped", 0.001},
                {"bright", 0.002},   {"noise", 0.8},        {"chroma_noise", 0.5}, {"cast_cb", -10.0},
                {"cast_cr", 5.0},    {"night_to_day", 0.3}, {"road_cd_m2", 1.0}};
  return row;
}

/// Sets column `key` of `row` (which has it) to `value`.
void set(RealismRow& row, const std::string& key, std::optional<double> value) {
  for (auto& [k, v] : row.values)
    if (k == key) v = value;
}

TEST(RealismBench, MedianOfAnOddCountIsTheMiddleValueAndTheSizeHasNone) {
  const std::vector<RealismRow> rows = {goodRow("a", 50), goodRow("b", 30), goodRow("c", 40)};
  const RealismRow median = solo::medianRow(rows);
  EXPECT_EQ(median.scene, "MEDIAN");
  EXPECT_EQ(median.variant, "");
  EXPECT_EQ(median.street_seed, "");
  ASSERT_EQ(median.values.size(), rows.front().values.size());
  for (std::size_t k = 0; k < median.values.size(); ++k) EXPECT_EQ(median.values[k].first, rows[0].values[k].first);
  EXPECT_FALSE(median.get("width_px"));
  EXPECT_FALSE(median.get("height_px"));
  EXPECT_EQ(median.get("mean"), 40.0);
  EXPECT_EQ(median.get("noise"), 0.8);
}

TEST(RealismBench, MedianOfAnEvenCountIsTheMeanOfTheMiddleTwoOverTheValuesPresent) {
  std::vector<RealismRow> rows = {goodRow("a", 50), goodRow("b", 30), goodRow("c", 40), goodRow("d", 10)};
  set(rows[3], "mean", std::nullopt);  // d has no mean: the median of 30, 40, 50
  set(rows[0], "clipped", 0.003);      // clipped 0.003, 0.001, 0.001, 0.001
  const RealismRow median = solo::medianRow(rows);
  EXPECT_EQ(median.get("mean"), 40.0);
  EXPECT_EQ(median.get("clipped"), 0.001);
  set(rows[3], "mean", 20.0);  // 20, 30, 40, 50
  EXPECT_EQ(solo::medianRow(rows).get("mean"), 35.0);
  for (RealismRow& r : rows) set(r, "road_cd_m2", std::nullopt);  // no road anywhere: no median
  EXPECT_FALSE(solo::medianRow(rows).get("road_cd_m2"));
}

TEST(RealismBench, MissedTargetsNameEachStatisticOutsideItsRangeOrWithoutValue) {
  EXPECT_TRUE(solo::missedTargets(goodRow("a", 50)).empty());
  RealismRow row = goodRow("a", 71);
  set(row, "clipped", 0.0051);
  set(row, "cast_cr", 0.0);              // cast_cr not > 0
  set(row, "road_cd_m2", std::nullopt);  // road without value
  EXPECT_EQ(solo::missedTargets(row), (std::vector<std::string>{"mean", "clipped", "cast", "road_cd_m2"}));
  RealismRow edges = goodRow("b", 30);
  set(edges, "noise", 1.5);         // noise at its upper bound
  set(edges, "night_to_day", 0.5);  // night_to_day at its upper bound
  set(edges, "road_cd_m2", 0.3);    // road at its lower bound
  EXPECT_TRUE(solo::missedTargets(edges).empty());
}

TEST(RealismBench, CsvHasTheNamesSeedsPresetEveryColumnAndTheMissedTargets) {
  RealismRow missing = goodRow("street-s2-default", 25.5);
  set(missing, "bright", std::nullopt);
  RealismRow embedded{"default-scene", "embedded", "", goodRow("x", 45).values, "11"};
  missing.night_seed = "12";
  const std::string csv = solo::realismCsv({embedded, missing}, 7, "draft");
  EXPECT_EQ(csv,
            "scene,variant,street_seed,seed,night_seed,preset,width_px,height_px,mean,clipped,bright,noise,"
            "chroma_noise,cast_cb,cast_cr,night_to_day,road_cd_m2,missed_targets\n"
            "default-scene,embedded,,7,11,draft,160,90,45,0.001,0.002,0.8,0.5,-10,5,0.3,1,\n"
            "street-s2-default,default,2,7,12,draft,160,90,25.5,0.001,,0.8,0.5,-10,5,0.3,1,mean;bright\n");
}

TEST(RealismBench, TableMarksMissedCellsAndNamesTheMedianRow) {
  std::vector<RealismRow> rows = {goodRow("default-scene", 45), goodRow("street-s2-default", 80)};
  rows.push_back(solo::medianRow(rows));
  const std::string table = solo::realismTable(rows);
  EXPECT_NE(table.find("| *target* | | 30-70 |"), std::string::npos) << table;
  EXPECT_NE(table.find("| default-scene | 160x90 | 45.0 |"), std::string::npos) << table;
  EXPECT_NE(table.find("| street-s2-default | 160x90 | 80.0 ✗ |"), std::string::npos) << table;
  EXPECT_NE(table.find("| **median** |  | 62.5 |"), std::string::npos) << table;
  EXPECT_NE(table.find("| -10.0 / +5.0 |"), std::string::npos) << table;
}

TEST(RealismBench, RefusesABadStreetSizePresetOrOutputBeforeWriting) {
  solo::test::TempDir dir;
  solo::RealismBenchOptions o;
  o.output = dir / "out";
  o.width = 15;
  EXPECT_THROW(solo::runRealismBench(o), solo::InputError);
  o.width = 960;
  o.height = 4097;
  EXPECT_THROW(solo::runRealismBench(o), solo::InputError);
  o.height = 540;
  o.preset = "no-such-preset";
  EXPECT_THROW(solo::runRealismBench(o), solo::InputError);
  EXPECT_FALSE(std::filesystem::exists(o.output));
}

}  // namespace
