// `solo eval` end to end: JSON values, CSV rows appended under one header, the table, errors.

#include <solo/core/image_io.h>
#include <solo/geometry/triangle_mesh.h>

#include <nlohmann/json.hpp>

#include "test_support.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

using solo::test::readText;
using solo::test::runSolo;
using solo::test::TempDir;

namespace {

std::string quoted(const std::filesystem::path& p) { return "\"" + p.string() + "\""; }

/// The hand-computed case of test_depth_metrics: gt 2, 4, 5, 10 and pred 1, 4, 4, 12 give
/// AbsRel 0.225, SqRel 0.275, RMSE sqrt 1.5, delta1 0.5; a 5th pixel without ground truth.
void writeDepthPair(const TempDir& dir) {
  solo::writeImage(dir / "gt.pfm", cv::Mat(std::vector<float>{2, 4, 5, 10, 0}, true).reshape(1, 1));
  solo::writeImage(dir / "pred.pfm", cv::Mat(std::vector<float>{1, 4, 4, 12, 3}, true).reshape(1, 1));
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

/// A CSV file without quoted cells as rows of column -> cell, checking every row has as many
/// cells as the header.
std::vector<std::map<std::string, std::string>> readCsv(const std::filesystem::path& file) {
  const std::vector<std::string> text = lines(readText(file));
  const auto split = [](const std::string& line) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream in(line);
    while (std::getline(in, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    return cells;
  };
  std::vector<std::map<std::string, std::string>> rows;
  if (text.empty()) return rows;
  const std::vector<std::string> header = split(text[0]);
  for (std::size_t i = 1; i < text.size(); ++i) {
    const std::vector<std::string> cells = split(text[i]);
    EXPECT_EQ(cells.size(), header.size()) << text[i];
    std::map<std::string, std::string> row;
    for (std::size_t c = 0; c < std::min(cells.size(), header.size()); ++c) row[header[c]] = cells[c];
    rows.push_back(row);
  }
  return rows;
}

}  // namespace

TEST(CliEval, DepthJsonHasTheHandComputedValues) {
  TempDir dir;
  writeDepthPair(dir);
  const auto r =
      runSolo("eval depth --pred " + quoted(dir / "pred.pfm") + " --gt " + quoted(dir / "gt.pfm") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["command"], "eval depth");
  EXPECT_EQ(j["metrics"]["valid_pixels"], 4);
  EXPECT_EQ(j["metrics"]["ground_truth_invalid"], 1);
  EXPECT_DOUBLE_EQ(j["metrics"]["abs_rel"].get<double>(), 0.225);
  EXPECT_DOUBLE_EQ(j["metrics"]["sq_rel_m"].get<double>(), 0.275);
  EXPECT_DOUBLE_EQ(j["metrics"]["rmse_m"].get<double>(), std::sqrt(1.5));
  EXPECT_DOUBLE_EQ(j["metrics"]["delta1"].get<double>(), 0.5);
  EXPECT_TRUE(j["inputs"]["mask"].is_null());
  EXPECT_TRUE(j["options"]["max_depth_m"].is_null());
  EXPECT_EQ(j["options"]["median_scaling"], false);
}

TEST(CliEval, CsvAppendsOneRowPerRunUnderOneHeader) {
  TempDir dir;
  writeDepthPair(dir);
  const std::string base = "eval depth --pred " + quoted(dir / "pred.pfm") + " --gt " + quoted(dir / "gt.pfm") +
                           " --csv " + quoted(dir / "sweep.csv");
  ASSERT_EQ(runSolo(base).exit_code, 0);
  const auto second = runSolo(base + " --median-scale --max-depth 8");
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_NE(second.output.find("AbsRel"), std::string::npos) << "the table still goes to the terminal";
  const std::vector<std::string> text = lines(readText(dir / "sweep.csv"));
  ASSERT_EQ(text.size(), 3u) << "one header, two rows";
  EXPECT_EQ(text[0].rfind("prediction,ground_truth,mask,min_depth_m,max_depth_m,median_scaling,", 0), 0u) << text[0];
  const auto rows = readCsv(dir / "sweep.csv");
  ASSERT_EQ(rows.size(), 2u);
  // First row: no mask, no range, no scaling: empty cells for what was not given.
  EXPECT_EQ(rows[0].at("mask"), "");
  EXPECT_EQ(rows[0].at("max_depth_m"), "");
  EXPECT_EQ(rows[0].at("median_scaling"), "false");
  EXPECT_EQ(rows[0].at("valid_pixels"), "4");
  EXPECT_DOUBLE_EQ(std::stod(rows[0].at("abs_rel")), 0.225);
  EXPECT_DOUBLE_EQ(std::stod(rows[0].at("sq_rel_m")), 0.275);
  // Second row: gt < 8 leaves gt 2, 4, 5 against pred 1, 4, 4; median scale = 4 / 4 = 1;
  // AbsRel = (0.5 + 0 + 0.2) / 3.
  EXPECT_EQ(rows[1].at("max_depth_m"), "8");
  EXPECT_EQ(rows[1].at("median_scaling"), "true");
  EXPECT_EQ(rows[1].at("outside_range"), "1");
  EXPECT_EQ(rows[1].at("valid_pixels"), "3");
  EXPECT_EQ(rows[1].at("scale"), "1");
  EXPECT_DOUBLE_EQ(std::stod(rows[1].at("abs_rel")), 0.7 / 3);
}

TEST(CliEval, CsvWithOtherColumnsIsRefused) {
  TempDir dir;
  writeDepthPair(dir);
  solo::test::writeText(dir / "other.csv", "a,b\n1,2\n");
  const auto r = runSolo("eval depth --pred " + quoted(dir / "pred.pfm") + " --gt " + quoted(dir / "gt.pfm") +
                         " --csv " + quoted(dir / "other.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("other.csv: its columns are not those of `solo eval depth`"), std::string::npos) << r.output;
  EXPECT_EQ(readText(dir / "other.csv"), "a,b\n1,2\n");
}

namespace {

void writeRow(const std::filesystem::path& file, const std::vector<float>& values) {
  solo::writeImage(file, cv::Mat(values, true).reshape(1, 1));
}

/// pred/ and gt/: a (gt 1, pred 3) and b (eight exact pixels). Mean per image: AbsRel 1,
/// RMSE 1; pooled over the 9 pixels: AbsRel 2/9, RMSE 2/3.
void writeDepthFolders(const TempDir& dir) {
  std::filesystem::create_directories(dir / "pred");
  std::filesystem::create_directories(dir / "gt");
  writeRow(dir / "gt" / "a.pfm", {1});
  writeRow(dir / "pred" / "a.pfm", {3});
  writeRow(dir / "gt" / "b.pfm", {1, 2, 3, 4, 5, 6, 7, 8});
  writeRow(dir / "pred" / "b.pfm", {1, 2, 3, 4, 5, 6, 7, 8});
}

}  // namespace

TEST(CliEval, DepthDatasetFromFoldersJsonAndCsvRows) {
  TempDir dir;
  writeDepthFolders(dir);
  const auto r = runSolo("eval depth --pred " + quoted(dir / "pred") + " --gt " + quoted(dir / "gt") +
                         " --json --csv " + quoted(dir / "images.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["command"], "eval depth dataset");
  EXPECT_EQ(j["metrics"]["evaluated"], 2);
  EXPECT_EQ(j["metrics"]["failed"], 0);
  EXPECT_DOUBLE_EQ(j["metrics"]["mean_abs_rel"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(j["metrics"]["mean_rmse_m"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(j["metrics"]["pooled_abs_rel"].get<double>(), 2.0 / 9.0);
  EXPECT_DOUBLE_EQ(j["metrics"]["pooled_rmse_m"].get<double>(), 2.0 / 3.0);
  ASSERT_EQ(j["images"].size(), 2u);
  EXPECT_EQ(j["images"][0]["inputs"]["image"], "a");
  EXPECT_DOUBLE_EQ(j["images"][0]["metrics"]["abs_rel"].get<double>(), 2.0);
  EXPECT_TRUE(j["images"][1]["metrics"]["error"].is_null());
  EXPECT_TRUE(j["failures"].empty());
  const auto rows = readCsv(dir / "images.csv");
  ASSERT_EQ(rows.size(), 2u) << "a row per image";
  EXPECT_EQ(rows[0].at("image"), "a");
  EXPECT_EQ(rows[1].at("image"), "b");
  EXPECT_EQ(rows[1].at("abs_rel"), "0");
  EXPECT_EQ(rows[1].at("error"), "");
}

TEST(CliEval, DepthDatasetNamesEachBadPairGoesOnAndExitsNonZero) {
  TempDir dir;
  writeDepthFolders(dir);
  writeRow(dir / "gt" / "c.pfm", {1});  // no prediction
  solo::test::writeText(dir / "list.txt", "pred/a.pfm gt/a.pfm\npred/b.pfm gt/b.pfm\npred/c.pfm gt/c.pfm\n");
  const auto r = runSolo("eval depth --list " + quoted(dir / "list.txt") + " --csv " + quoted(dir / "images.csv"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("solo: error: " + (dir / "pred" / "c.pfm").string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("solo: error: 1 of 3 images failed"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("pooled over pixels: AbsRel"), std::string::npos) << "the summary still printed";
  const auto rows = readCsv(dir / "images.csv");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].at("error"), "");
  EXPECT_NE(rows[2].at("error").find("c.pfm"), std::string::npos);
  EXPECT_EQ(rows[2].at("abs_rel"), "");
  // Neither --pred/--gt nor --list: named.
  const auto none = runSolo("eval depth");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.output.find("--pred: required (or --list)"), std::string::npos) << none.output;
}

TEST(CliEval, DepthErrorsNameTheFilesAndNeverPrintNaN) {
  TempDir dir;
  writeDepthPair(dir);
  solo::writeImage(dir / "small.pfm", cv::Mat(1, 3, CV_32F, cv::Scalar(1)));
  auto r = runSolo("eval depth --pred " + quoted(dir / "small.pfm") + " --gt " + quoted(dir / "gt.pfm"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("solo: error: " + (dir / "small.pfm").string() + ": prediction is 3x1 but ground truth " +
                          (dir / "gt.pfm").string() + " is 5x1"),
            std::string::npos)
      << r.output;

  r = runSolo("eval depth --pred " + quoted(dir / "pred.pfm") + " --gt " + quoted(dir / "gt.pfm") + " --min-depth 20");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("gt.pfm: no valid pixel to evaluate"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("nan"), std::string::npos) << r.output;

  solo::writeImage(dir / "codes.png", cv::Mat(1, 5, CV_16U, cv::Scalar(512)));
  r = runSolo("eval depth --pred " + quoted(dir / "pred.pfm") + " --gt " + quoted(dir / "codes.png"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("codes.png: uint16 depth needs a scale"), std::string::npos) << r.output;
  // With --gt-scale 1/256 the codes are 2 m everywhere: pred 1, 4, 4, 12, 3 against 2.
  r = runSolo("eval depth --pred " + quoted(dir / "pred.pfm") + " --gt " + quoted(dir / "codes.png") +
              " --gt-scale 0.00390625 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // |2-1|/2 + 1 + 1 + 5 + 0.5 = 8, over 5 pixels.
  EXPECT_DOUBLE_EQ(nlohmann::json::parse(r.output)["metrics"]["abs_rel"].get<double>(), 8.0 / 5.0);
}

TEST(CliEval, DepthMaskFromAPng) {
  TempDir dir;
  writeDepthPair(dir);
  // Mask out the first pixel (the only one with |g-p|/g = 0.5): AbsRel = 0.4 / 3.
  cv::Mat mask(1, 5, CV_8U, cv::Scalar(255));
  mask.at<unsigned char>(0, 0) = 0;
  solo::writeImage(dir / "mask.png", mask);
  const auto r = runSolo("eval depth --pred " + quoted(dir / "pred.pfm") + " --gt " + quoted(dir / "gt.pfm") +
                         " --mask " + quoted(dir / "mask.png") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["metrics"]["masked_out"], 1);
  EXPECT_EQ(j["metrics"]["valid_pixels"], 3);
  EXPECT_DOUBLE_EQ(j["metrics"]["abs_rel"].get<double>(), 0.4 / 3);
}

TEST(CliEval, NormalsJsonAndTable) {
  TempDir dir;
  // gt (0,0,-1) twice; pred equal, then (1,0,0): angles 0 and 90 degrees.
  cv::Mat gt(1, 2, CV_32FC3, cv::Scalar(0, 0, -1)), pred = gt.clone();
  pred.at<cv::Vec3f>(0, 1) = cv::Vec3f(1, 0, 0);
  solo::writeNormals(dir / "gt.exr", gt);
  solo::writeNormals(dir / "pred.exr", pred);
  const std::string args = "eval normals --pred " + quoted(dir / "pred.exr") + " --gt " + quoted(dir / "gt.exr");
  auto r = runSolo(args + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_NEAR(j["metrics"]["mean_deg"].get<double>(), 45.0, 1e-9);
  EXPECT_NEAR(j["metrics"]["median_deg"].get<double>(), 45.0, 1e-9);
  EXPECT_NEAR(j["metrics"]["rmse_deg"].get<double>(), std::sqrt(8100.0 / 2), 1e-9);
  EXPECT_DOUBLE_EQ(j["metrics"]["under_11_25_deg"].get<double>(), 0.5);
  r = runSolo(args);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("mean angle"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("45 deg"), std::string::npos) << r.output;
}

TEST(CliEval, MeshJsonWithReferenceAndCsv) {
  TempDir dir;
  solo::test::writeSquareAndLiftedSquare(dir.path());
  const std::string csv = " --csv " + quoted(dir / "mesh.csv");
  auto r = runSolo("eval mesh " + quoted(dir / "square.off") + " --ref " + quoted(dir / "lifted.ply") +
                   " --samples 500 --seed 9 --json" + csv);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["metrics"]["boundary_loops"], 1);
  EXPECT_EQ(j["metrics"]["boundary_edges"], 4);
  EXPECT_EQ(j["metrics"]["closed"], false);
  EXPECT_EQ(j["options"]["samples"], 500);
  // Parallel squares 0.25 apart: every distance is 0.25.
  EXPECT_NEAR(j["metrics"]["hausdorff"].get<double>(), 0.25, 1e-12);
  EXPECT_NEAR(j["metrics"]["chamfer"].get<double>(), 0.25, 1e-12);
  // Default tau, 1 % of the diagonal sqrt 2, is below the offset 0.25: F-score 0.
  EXPECT_NEAR(j["metrics"]["fscore_tau"].get<double>(), 0.01 * std::sqrt(2.0), 1e-15);
  EXPECT_EQ(j["metrics"]["fscore"].get<double>(), 0.0);
  EXPECT_TRUE(j["options"]["tau_m"].is_null());
  // Without a reference the distance columns stay (empty) so rows line up.
  r = runSolo("eval mesh " + quoted(dir / "square.off") + csv);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("boundary loops"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("Hausdorff"), std::string::npos) << "no distance rows without --ref:\n" << r.output;
  const auto rows = readCsv(dir / "mesh.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].at("boundary_loops"), "1");
  EXPECT_NEAR(std::stod(rows[0].at("hausdorff")), 0.25, 1e-12);
  EXPECT_EQ(rows[1].at("reference"), "");
  EXPECT_EQ(rows[1].at("hausdorff"), "");
  EXPECT_EQ(rows[1].at("chamfer"), "");
  EXPECT_EQ(rows[1].at("boundary_edges"), "4");
}

// The unit square against itself lifted by 0.25: every distance is 0.25, so tau = 0.3 takes
// all samples (P = R = F = 1) and tau = 0.2 none; the table shows the F-score rows.
TEST(CliEval, MeshFScoreAtAGivenTau) {
  TempDir dir;
  solo::test::writeSquareAndLiftedSquare(dir.path());
  const std::string base =
      "eval mesh " + quoted(dir / "square.off") + " --ref " + quoted(dir / "lifted.ply") + " --samples 1000 --seed 2";
  auto r = runSolo(base + " --tau 0.3 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["options"]["tau_m"].get<double>(), 0.3);
  EXPECT_EQ(j["options"]["seed"], 2);
  EXPECT_EQ(j["metrics"]["precision"].get<double>(), 1.0);
  EXPECT_EQ(j["metrics"]["recall"].get<double>(), 1.0);
  EXPECT_EQ(j["metrics"]["fscore"].get<double>(), 1.0);
  r = runSolo(base + " --tau 0.2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("F-score threshold tau"), std::string::npos) << r.output;
  const std::vector<std::string> table = lines(r.output);
  EXPECT_NE(std::find_if(table.begin(), table.end(),
                         [](const std::string& line) {
                           return line.rfind("  F-score ", 0) == 0 && line.size() > 2 &&
                                  line.compare(line.size() - 2, 2, " 0") == 0;
                         }),
            table.end())
      << r.output;
  r = runSolo(base + " --tau -1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--tau"), std::string::npos) << r.output;
}

TEST(CliEval, MeshErrors) {
  TempDir dir;
  auto r = runSolo("eval mesh " + quoted(dir / "none.off"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("none.off: file not found"), std::string::npos) << r.output;
  solo::test::writeText(dir / "line.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n");
  solo::test::writeText(dir / "tri.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  r = runSolo("eval mesh " + quoted(dir / "tri.off") + " --ref " + quoted(dir / "line.off"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("line.off: mesh has no face with non-zero area"), std::string::npos) << r.output;
  r = runSolo("eval mesh " + quoted(dir / "tri.off") + " --ref " + quoted(dir / "tri.off") + " --samples 0");
  EXPECT_NE(r.exit_code, 0);
}

// ---- solo eval scene ------------------------------------------------------------------

namespace {

/// A small synthetic scene (estimated maps at half resolution, exact ground truth beside them).
std::filesystem::path synthScene(const TempDir& dir, const std::string& name = "scene") {
  const std::filesystem::path scene = dir / name;
  const auto r = runSolo("synth --size 160x90 --seed 3 -o " + quoted(scene));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return scene;
}

nlohmann::json evalSceneJson(const std::string& arguments) {
  const auto r = runSolo("eval scene " + arguments + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return r.exit_code == 0 ? nlohmann::json::parse(r.output) : nlohmann::json::object();
}

}  // namespace

TEST(CliEvalScene, GroundTruthAgainstItselfIsExact) {
  TempDir dir;
  const std::filesystem::path scene = synthScene(dir);
  // A folder whose "estimated" maps are the ground truth itself, at full resolution.
  nlohmann::json manifest = nlohmann::json::parse(readText(scene / "gt/scene.json"));
  for (const char* key : {"image", "depth", "normals", "albedo", "roughness", "instances", "labels", "lights",
                          "light_groups"})
    manifest[key] = (scene / "gt" / manifest[key].get<std::string>()).lexically_normal().string();
  manifest["ground_truth"] = (scene / "gt/scene.json").string();
  std::filesystem::create_directories(dir / "self");
  solo::test::writeText(dir / "self/scene.json", manifest.dump(2));

  const auto j = evalSceneJson(quoted(dir / "self"));
  ASSERT_TRUE(j.contains("metrics"));
  const auto& m = j["metrics"];
  EXPECT_EQ(j["command"], "eval scene");
  EXPECT_EQ(m["width"], 160);
  EXPECT_EQ(m["height"], 90);
  EXPECT_EQ(m["est_depth_prediction_invalid"], 0);
  EXPECT_GT(m["est_depth_valid_pixels"].get<std::int64_t>(), 160 * 90 / 2);
  EXPECT_EQ(m["est_depth_abs_rel"].get<double>(), 0.0);
  EXPECT_EQ(m["est_depth_rmse_m"].get<double>(), 0.0);
  EXPECT_EQ(m["est_depth_delta1"].get<double>(), 1.0);
  EXPECT_EQ(m["est_depth_median_scaled_scale"].get<double>(), 1.0);
  EXPECT_EQ(m["est_normals_mean_deg"].get<double>(), 0.0);
  EXPECT_EQ(m["est_normals_under_5_deg"].get<double>(), 1.0);
  EXPECT_TRUE(m["est_normals_skipped"].is_null());
  // Exact depth: the removal is scored; the synthetic street has occlusions to find.
  EXPECT_EQ(m["spurious_depth"], "estimated (upsampled)");
  EXPECT_GT(m["spurious_truth_faces"].get<std::int64_t>(), 0);
  for (const char* key : {"spurious_precision", "spurious_recall"}) {
    EXPECT_GE(m[key].get<double>(), 0.5) << key;
    EXPECT_LE(m[key].get<double>(), 1.0) << key;
  }

  // The same with the true depth 5 % too far: AbsRel 0.05 exactly; median scaling undoes it.
  cv::Mat far = solo::readDepth(scene / "gt/depth.exr", 0) * 1.05;
  solo::writeDepth(dir / "self/far.exr", far);
  manifest["depth"] = (dir / "self/far.exr").string();
  solo::test::writeText(dir / "self/scene.json", manifest.dump(2));
  const auto scaled = evalSceneJson(quoted(dir / "self"));
  ASSERT_TRUE(scaled.contains("metrics"));
  const auto& s = scaled["metrics"];
  EXPECT_NEAR(s["est_depth_abs_rel"].get<double>(), 0.05, 1e-6);
  EXPECT_EQ(s["est_depth_delta1"].get<double>(), 1.0);
  EXPECT_NEAR(s["est_depth_median_scaled_scale"].get<double>(), 1 / 1.05, 1e-6);
  EXPECT_LT(s["est_depth_median_scaled_abs_rel"].get<double>(), 1e-6);
  EXPECT_EQ(s["est_normals_mean_deg"].get<double>(), 0.0);
}

TEST(CliEvalScene, EstimatedMapsAndSkippedOutputs) {
  TempDir dir;
  const std::filesystem::path scene = synthScene(dir);
  const double bias =
      nlohmann::json::parse(readText(scene / "synth.json"))["perturbations"]["depth_scale_bias_drawn"].get<double>();
  ASSERT_GT(std::abs(bias - 1), 0.01) << "seed 3 is expected to draw a visible scale bias";
  ASSERT_LE(std::abs(bias - 1), 0.06);

  const auto j = evalSceneJson(quoted(scene));
  ASSERT_TRUE(j.contains("metrics"));
  const auto& m = j["metrics"];
  EXPECT_EQ(j["inputs"]["ground_truth"], (scene / "gt/scene.json").string());
  // Half-resolution depth with a global scale bias, noise and bleeding across depth edges. At
  // 160x90 the bleeding (2 low-res px each side of every edge) dominates: AbsRel is well above
  // the bias, and median scaling does not remove it (measured: 0.0625 unscaled, 0.0720 scaled,
  // scale 1.033 for a bias of 0.984; docs/evaluation.md).
  const double abs_rel = m["est_depth_abs_rel"].get<double>();
  const double scaled_abs_rel = m["est_depth_median_scaled_abs_rel"].get<double>();
  EXPECT_GT(abs_rel, std::abs(bias - 1));
  EXPECT_LT(abs_rel, 0.15);
  EXPECT_GT(scaled_abs_rel, 0.02);
  EXPECT_LT(scaled_abs_rel, 0.15);
  EXPECT_NEAR(m["est_depth_median_scaled_scale"].get<double>() * bias, 1.0, 0.05);
  EXPECT_GT(m["est_depth_delta1"].get<double>(), 0.9);
  EXPECT_EQ(m["est_depth_pixels"], 160 * 90);
  EXPECT_GT(m["est_depth_ground_truth_invalid"].get<std::int64_t>(), 0) << "sky has no ground-truth depth";
  // Blurred normals with 3 degrees of noise per pixel.
  EXPECT_GT(m["est_normals_mean_deg"].get<double>(), 1.0);
  EXPECT_LT(m["est_normals_mean_deg"].get<double>(), 30.0);
  // No refined depth: the mesh is made of the upsampled estimate; both scores are fractions.
  EXPECT_EQ(m["spurious_depth"], "estimated (upsampled)");
  for (const char* key : {"spurious_precision", "spurious_recall", "removal_precision_with_instance_cut",
                          "removal_recall_with_instance_cut"}) {
    ASSERT_TRUE(m[key].is_number()) << key;
    EXPECT_GE(m[key].get<double>(), 0.0) << key;
    EXPECT_LE(m[key].get<double>(), 1.0) << key;
  }
  // Outputs not written are skipped with the reason; their metrics are null.
  EXPECT_NE(m["refined_skipped"].get<std::string>().find("refined.exr not found"), std::string::npos);
  EXPECT_NE(m["mesh_skipped"].get<std::string>().find("mesh.ply not found"), std::string::npos);
  EXPECT_TRUE(m["refined_depth_abs_rel"].is_null());
  EXPECT_TRUE(m["refined_normals_mean_deg"].is_null());
  EXPECT_TRUE(m["mesh_faces"].is_null());
  EXPECT_TRUE(m["mesh_chamfer"].is_null());
  EXPECT_TRUE(j["inputs"]["refined"].is_null());

  const auto table = runSolo("eval scene " + quoted(scene));
  ASSERT_EQ(table.exit_code, 0) << table.output;
  EXPECT_NE(table.output.find("refined depth skipped"), std::string::npos) << table.output;
  EXPECT_NE(table.output.find("spurious-face precision"), std::string::npos) << table.output;
  EXPECT_EQ(table.output.find("refined depth AbsRel"), std::string::npos) << table.output;
  // The time row keeps its unit however wide the labels are (the spurious-face labels are long).
  const std::size_t time_row = table.output.rfind("\n  time ");
  ASSERT_NE(time_row, std::string::npos) << table.output;
  const std::string row = table.output.substr(time_row + 1, table.output.find('\n', time_row + 1) - time_row - 1);
  EXPECT_EQ(row.substr(row.size() - 2), " s") << row;
}

TEST(CliEvalScene, RefinedDepthAndMeshOneCsvRowPerRun) {
  TempDir dir;
  const std::filesystem::path scene = synthScene(dir);
  const std::string csv = " --csv " + quoted(dir / "scene.csv");
  auto r = runSolo("eval scene " + quoted(scene) + csv);
  ASSERT_EQ(r.exit_code, 0) << r.output;

  r = runSolo("depth " + quoted(scene / "scene.json") + " -o " + quoted(scene / "refined.exr"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = runSolo("mesh from-depth " + quoted(scene / "scene.json") + " -o " + quoted(scene / "mesh.ply") +
              " --uncertain " + quoted(scene / "refined.uncertain.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = evalSceneJson(quoted(scene) + " --samples 2000" + csv);
  ASSERT_TRUE(j.contains("metrics"));
  const auto& m = j["metrics"];
  EXPECT_EQ(j["inputs"]["refined"], (scene / "refined.exr").string());
  EXPECT_EQ(j["inputs"]["refined_normals"], (scene / "refined.normals.exr").string());
  EXPECT_EQ(j["inputs"]["uncertain"], (scene / "refined.uncertain.png").string());
  EXPECT_TRUE(m["refined_skipped"].is_null());
  EXPECT_GT(m["refined_depth_valid_pixels"].get<std::int64_t>(), 0);
  EXPECT_LT(m["refined_depth_median_scaled_abs_rel"].get<double>(), 0.1);
  EXPECT_LT(m["refined_normals_mean_deg"].get<double>(), 45.0);
  EXPECT_EQ(m["spurious_depth"], "refined");
  EXPECT_GE(m["spurious_precision"].get<double>(), 0.0);
  EXPECT_LE(m["spurious_recall"].get<double>(), 1.0);
  EXPECT_GT(m["mesh_faces"].get<std::int64_t>(), 1000);
  EXPECT_TRUE(m["mesh_skipped"].is_null());
  EXPECT_TRUE(m["mesh_distances_skipped"].is_null());
  // Distances to the exact box mesh: metres at this size (measured 9.9 m), far below the scene's
  // extent. The depth-band split says why: the faces beyond 80 m (90 % of the mesh's area: a
  // pixel's area grows as depth squared) carry nearly all of the mean (measured 9.8 m), each a few
  // percent of its depth off (docs/accuracy.md).
  EXPECT_GT(m["mesh_mean_to_ref"].get<double>(), 0.0);
  EXPECT_LE(m["mesh_mean_to_ref"].get<double>(), m["mesh_hausdorff_to_ref"].get<double>());
  EXPECT_LT(m["mesh_mean_to_ref"].get<double>(), 0.1 * m["mesh_ref_bbox_diagonal"].get<double>());
  double area_share = 0;
  for (const char* band : {"0_10", "10_20", "20_40", "40_80", "80_160", "160_up"})
    area_share += m[std::string("mesh_z_") + band + "_area_share"].get<double>();
  EXPECT_NEAR(area_share, 1.0, 1e-9);
  const double far_m = m["mesh_z_80_160_contribution_to_mean"].get<double>() +
                       m["mesh_z_160_up_contribution_to_mean"].get<double>();
  EXPECT_GT(far_m, 0.5 * m["mesh_mean_to_ref"].get<double>());
  EXPECT_LT(m["mesh_mean_relative_to_ref"].get<double>(), 0.2);  // measured 0.05
  EXPECT_GT(m["mesh_truth_covered"].get<double>(), 0.5);         // measured 0.86
  EXPECT_LE(m["mesh_truth_covered"].get<double>(), 1.0);

  const auto rows = readCsv(dir / "scene.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].at("refined"), "");
  EXPECT_EQ(rows[0].at("refined_depth_abs_rel"), "");
  EXPECT_EQ(rows[0].at("mesh_chamfer"), "");
  EXPECT_EQ(rows[0].at("spurious_depth"), "estimated (upsampled)");
  EXPECT_EQ(std::stod(rows[0].at("est_depth_abs_rel")), m["est_depth_abs_rel"].get<double>());
  EXPECT_EQ(rows[1].at("spurious_depth"), "refined");
  EXPECT_EQ(std::stod(rows[1].at("mesh_chamfer")), m["mesh_chamfer"].get<double>());
}

TEST(CliEvalScene, ErrorsNameTheFile) {
  TempDir dir;
  auto r = runSolo("eval scene " + quoted(dir.path()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find((dir / "scene.json").string() + ": file not found"), std::string::npos) << r.output;

  const std::filesystem::path scene = synthScene(dir);
  r = runSolo("eval scene " + quoted(scene / "gt"));  // a manifest, but not of estimated maps
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find((scene / "gt/scene.json").string() + ": has no \"ground_truth\""), std::string::npos)
      << r.output;

  r = runSolo("eval scene " + quoted(scene) + " --refined " + quoted(dir / "none.exr"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("none.exr"), std::string::npos) << r.output;
}

namespace {

/// A flat 960x540 8-bit RGB image of one grey level: luma = level, noise 0, no clipping.
void writeGrey(const std::filesystem::path& file, int level) {
  solo::writeImage(file, cv::Mat(540, 960, CV_8UC3, cv::Scalar::all(level)));
}

std::vector<std::string> strings(const nlohmann::json& array) { return array.get<std::vector<std::string>>(); }

}  // namespace

TEST(CliEvalNight, ReferenceRangeFlagsTheOutlierOnly) {
  TempDir dir;
  std::filesystem::create_directories(dir / "ref");
  for (const int level : {30, 40, 50}) writeGrey(dir / "ref" / ("grey" + std::to_string(level) + ".png"), level);
  writeGrey(dir / "bright.png", 120);
  writeGrey(dir / "typical.png", 40);
  const auto r = runSolo("eval night " + quoted(dir / "bright.png") + " " + quoted(dir / "typical.png") +
                         " --reference " + quoted(dir / "ref") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["command"], "eval night");
  EXPECT_EQ(j["reference"]["images"].size(), 3u);
  EXPECT_NEAR(j["reference"]["median"]["mean"].get<double>(), 40.0, 1e-9);
  EXPECT_NEAR(j["reference"]["min"]["mean"].get<double>(), 30.0, 1e-9);
  EXPECT_NEAR(j["reference"]["max"]["p99"].get<double>(), 50.0, 1e-9);
  EXPECT_TRUE(j["reference"]["median"]["halo_radius_px"].is_null()) << "no clipped blob in the reference";
  const auto& bright = j["images"][0];
  EXPECT_NEAR(bright["statistics"]["mean"].get<double>(), 120.0, 1e-9);
  EXPECT_EQ(bright["statistics"]["noise"].get<double>(), 0.0);
  EXPECT_TRUE(bright["statistics"]["cast_cb"].is_null()) << "no pixel with 20 < Y < 80";
  EXPECT_EQ(strings(bright["outside_reference"]), (std::vector<std::string>{"mean", "p50", "p90", "p99"}));
  EXPECT_TRUE(j["images"][1]["outside_reference"].empty());

  // The same reference as a list file (paths relative to it), the table and a CSV row per image.
  solo::test::writeText(dir / "ref.txt", "# reference\nref/grey30.png\n\nref/grey40.png\nref/grey50.png\n");
  const auto table = runSolo("eval night " + quoted(dir / "bright.png") + " " + quoted(dir / "typical.png") +
                             " --reference " + quoted(dir / "ref.txt") + " --csv " + quoted(dir / "night.csv"));
  ASSERT_EQ(table.exit_code, 0) << table.output;
  EXPECT_NE(table.output.find("outside reference range"), std::string::npos) << table.output;
  EXPECT_NE(table.output.find("mean, p50, p90, p99"), std::string::npos) << table.output;
  EXPECT_NE(table.output.find("(3 images)"), std::string::npos) << table.output;
  const auto rows = readCsv(dir / "night.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].at("outside_reference"), "mean;p50;p90;p99");
  EXPECT_EQ(rows[1].at("outside_reference"), "");
  EXPECT_EQ(rows[0].at("width_px"), "960");
  EXPECT_DOUBLE_EQ(std::stod(rows[1].at("mean")), j["images"][1]["statistics"]["mean"].get<double>());
  EXPECT_EQ(rows[0].at("cast_cb"), "");
}

TEST(CliEvalNight, BadImagesAndReferencesAreNamed) {
  TempDir dir;
  writeGrey(dir / "good.png", 40);
  solo::test::writeText(dir / "bad.png", "not a picture");
  auto r = runSolo("eval night " + quoted(dir / "good.png") + " " + quoted(dir / "bad.png"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find((dir / "bad.png").string()), std::string::npos) << r.output;

  std::filesystem::create_directories(dir / "empty");
  r = runSolo("eval night " + quoted(dir / "good.png") + " --reference " + quoted(dir / "empty"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find((dir / "empty").string() + ": no image"), std::string::npos) << r.output;

  r = runSolo("eval night " + quoted(dir / "good.png") + " --reference " + quoted(dir / "missing.txt"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("missing.txt: reference not found"), std::string::npos) << r.output;
}

TEST(CliEvalNight, NightReportsTheStatisticsOfTheImageItWrote) {
  TempDir dir;
  const std::filesystem::path scene = synthScene(dir);
  const auto night = runSolo("night " + quoted(scene / "scene.json") + " -o " + quoted(dir / "n.png") +
                             " --preset draft");
  ASSERT_EQ(night.exit_code, 0) << night.output;
  EXPECT_NE(night.output.find("realism"), std::string::npos) << "a summary line on the terminal";
  const auto report = nlohmann::json::parse(readText(dir / "n.report.json"));
  nlohmann::json realism;
  for (const auto& s : report["stages"])
    if (s["name"] == "realism") realism = s;
  ASSERT_FALSE(realism.is_null()) << report.dump(2);
  const auto r = runSolo("eval night " + quoted(dir / "n.png") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto statistics = nlohmann::json::parse(r.output)["images"][0]["statistics"];
  for (const char* key : {"mean", "p50", "p99", "clipped", "bright"})
    EXPECT_DOUBLE_EQ(realism["metrics"][key].get<double>(), statistics[key].get<double>()) << key;
  EXPECT_EQ(realism["metrics"]["halo_blobs"].get<double>(), statistics["halo_blobs"].get<double>());
}
