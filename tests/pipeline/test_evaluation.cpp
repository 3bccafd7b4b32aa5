// The evaluations of `solo eval` through the pipeline library, without the CLI: the records'
// values on hand-computed cases, their CSV form and append rule, a scene folder's parts that
// run and those that are skipped, and the night statistics against a reference set.

#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/geometry/triangle_mesh.h>
#include <solo/pipeline/evaluation.h>
#include <solo/pipeline/night_evaluation.h>
#include <solo/synth/scene_folder.h>

#include "test_support.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace {

using solo::EvaluationRecord;
using solo::EvaluationValue;
using solo::test::readText;
using solo::test::TempDir;

/// The field `key` of the record (inputs, options, then metrics); fails the test when missing.
EvaluationValue valueOf(const EvaluationRecord& r, const std::string& key) {
  for (const std::vector<solo::EvaluationField>* fields : {&r.inputs, &r.options, &r.metrics})
    for (const solo::EvaluationField& f : *fields)
      if (f.key == key) return f.value;
  ADD_FAILURE() << "no field " << key << " in `" << r.command << "`";
  return std::monostate{};
}

double number(const EvaluationRecord& r, const std::string& key) {
  const EvaluationValue v = valueOf(r, key);
  return std::holds_alternative<double>(v) ? std::get<double>(v) : std::nan("");
}

std::int64_t integer(const EvaluationRecord& r, const std::string& key) {
  const EvaluationValue v = valueOf(r, key);
  return std::holds_alternative<std::int64_t>(v) ? std::get<std::int64_t>(v) : -1;
}

bool isNone(const EvaluationRecord& r, const std::string& key) {
  return std::holds_alternative<std::monostate>(valueOf(r, key));
}

std::string text(const EvaluationRecord& r, const std::string& key) {
  const EvaluationValue v = valueOf(r, key);
  return std::holds_alternative<std::string>(v) ? std::get<std::string>(v) : "<not text>";
}

/// gt 2, 4, 5, 10 and pred 1, 4, 4, 12 (a 5th pixel without ground truth):
/// AbsRel (0.5 + 0 + 0.2 + 0.2) / 4 = 0.225, SqRel (0.5 + 0 + 0.2 + 0.4) / 4 = 0.275,
/// RMSE sqrt((1 + 0 + 1 + 4) / 4) = sqrt(1.5), delta1: 4/4 and 10/12 pass, 2/1 and 5/4 = 1.25 do not.
void writeDepthPair(const TempDir& dir) {
  solo::writeImage(dir / "gt.pfm", cv::Mat(std::vector<float>{2, 4, 5, 10, 0}, true).reshape(1, 1));
  solo::writeImage(dir / "pred.pfm", cv::Mat(std::vector<float>{1, 4, 4, 12, 3}, true).reshape(1, 1));
}

}  // namespace

TEST(Evaluation, DepthFilesHaveTheHandComputedMetrics) {
  TempDir dir;
  writeDepthPair(dir);
  solo::DepthFilesEvaluationOptions o;
  o.prediction = dir / "pred.pfm";
  o.ground_truth = dir / "gt.pfm";
  const EvaluationRecord r = solo::evaluateDepthFiles(o);
  EXPECT_EQ(r.command, "eval depth");
  EXPECT_EQ(text(r, "prediction"), (dir / "pred.pfm").string());
  EXPECT_TRUE(isNone(r, "mask"));
  EXPECT_TRUE(isNone(r, "max_depth_m"));
  EXPECT_TRUE(isNone(r, "prediction_scale_m_per_unit")) << "0 = the file's own unit: none";
  EXPECT_EQ(integer(r, "pixels"), 5);
  EXPECT_EQ(integer(r, "ground_truth_invalid"), 1);
  EXPECT_EQ(integer(r, "valid_pixels"), 4);
  EXPECT_DOUBLE_EQ(number(r, "abs_rel"), 0.225);
  EXPECT_DOUBLE_EQ(number(r, "sq_rel_m"), 0.275);
  EXPECT_DOUBLE_EQ(number(r, "rmse_m"), std::sqrt(1.5));
  EXPECT_DOUBLE_EQ(number(r, "delta1"), 0.5);
  EXPECT_GE(r.seconds, 0.0);

  // gt < 8 leaves gt 2, 4, 5 against pred 1, 4, 4; median scale 4 / 4 = 1; AbsRel 0.7 / 3.
  o.max_depth_m = 8;
  o.median_scaling = true;
  const EvaluationRecord scaled = solo::evaluateDepthFiles(o);
  EXPECT_DOUBLE_EQ(number(scaled, "max_depth_m"), 8.0);
  EXPECT_EQ(std::get<bool>(valueOf(scaled, "median_scaling")), true);
  EXPECT_EQ(integer(scaled, "outside_range"), 1);
  EXPECT_DOUBLE_EQ(number(scaled, "scale"), 1.0);
  EXPECT_DOUBLE_EQ(number(scaled, "abs_rel"), 0.7 / 3);
}

namespace {

void writeRow(const std::filesystem::path& file, const std::vector<float>& values) {
  solo::writeImage(file, cv::Mat(values, true).reshape(1, 1));
}

/// pred/ and gt/ of four images and one extra prediction: a (gt 1, pred 3) and b (eight exact
/// pixels) evaluate; c has no prediction; d's prediction is not a depth file.
void writeDepthDataset(const TempDir& dir) {
  std::filesystem::create_directories(dir / "pred");
  std::filesystem::create_directories(dir / "gt");
  writeRow(dir / "gt" / "a.pfm", {1});
  writeRow(dir / "pred" / "a.pfm", {3});
  writeRow(dir / "gt" / "b.pfm", {1, 2, 3, 4, 5, 6, 7, 8});
  writeRow(dir / "pred" / "b.exr", {1, 2, 3, 4, 5, 6, 7, 8});
  writeRow(dir / "gt" / "c.pfm", {1});
  writeRow(dir / "gt" / "d.pfm", {1});
  solo::test::writeText(dir / "pred" / "d.pfm", "not a depth map");
  writeRow(dir / "pred" / "extra.pfm", {1});
  solo::test::writeText(dir / "gt" / "README.txt", "not a depth file: ignored");
}

}  // namespace

// Mean per image: AbsRel (2 + 0) / 2 = 1, RMSE (2 + 0) / 2 = 1; pooled over the 9 pixels:
// AbsRel 2/9, RMSE sqrt(4/9) = 2/3 (test_depth_metrics' hand case).
TEST(Evaluation, DepthDatasetFromFoldersKeepsGoingPastBadPairs) {
  TempDir dir;
  writeDepthDataset(dir);
  solo::DepthFilesEvaluationOptions o;
  o.prediction = dir / "pred";
  o.ground_truth = dir / "gt";
  ASSERT_TRUE(solo::isDepthDataset(o));
  const solo::DepthDatasetEvaluation d = solo::evaluateDepthDataset(o);
  const EvaluationRecord& s = d.summary;
  EXPECT_EQ(s.command, "eval depth dataset");
  EXPECT_EQ(integer(s, "images"), 4);
  EXPECT_EQ(integer(s, "evaluated"), 2);
  EXPECT_EQ(integer(s, "failed"), 2);
  EXPECT_EQ(integer(s, "unpaired_predictions"), 1);
  EXPECT_EQ(integer(s, "valid_pixels"), 9);
  EXPECT_DOUBLE_EQ(number(s, "mean_abs_rel"), 1.0);
  EXPECT_DOUBLE_EQ(number(s, "mean_rmse_m"), 1.0);
  EXPECT_DOUBLE_EQ(number(s, "pooled_abs_rel"), 2.0 / 9.0);
  EXPECT_DOUBLE_EQ(number(s, "pooled_rmse_m"), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(number(s, "pooled_delta1"), 8.0 / 9.0);

  ASSERT_EQ(d.images.size(), 4u);
  EXPECT_EQ(text(d.images[0], "image"), "a");
  EXPECT_TRUE(isNone(d.images[0], "error"));
  EXPECT_DOUBLE_EQ(number(d.images[0], "abs_rel"), 2.0);
  EXPECT_EQ(text(d.images[1], "prediction"), (dir / "pred" / "b.exr").string());
  EXPECT_DOUBLE_EQ(number(d.images[1], "abs_rel"), 0.0);
  EXPECT_NE(text(d.images[2], "error").find((dir / "gt" / "c.pfm").string() + ": no prediction named c.*"),
            std::string::npos)
      << text(d.images[2], "error");
  EXPECT_TRUE(isNone(d.images[2], "abs_rel"));
  EXPECT_NE(text(d.images[3], "error").find((dir / "pred" / "d.pfm").string()), std::string::npos)
      << text(d.images[3], "error");
  ASSERT_EQ(d.failures.size(), 2u);
  EXPECT_EQ(d.failures[0], text(d.images[2], "error"));
  for (const EvaluationRecord& image : d.images)
    EXPECT_EQ(solo::evaluationCsvHeader(image), solo::evaluationCsvHeader(d.images[0])) << "one CSV header";
}

TEST(Evaluation, DepthDatasetFromAListAndItsErrors) {
  TempDir dir;
  writeDepthDataset(dir);
  solo::test::writeText(dir / "pairs.txt", "# prediction ground truth\n\npred/a.pfm gt/a.pfm\n" +
                                               (dir / "pred" / "b.exr").string() + "\tgt/b.pfm\n");
  solo::DepthFilesEvaluationOptions o;
  o.list = dir / "pairs.txt";
  ASSERT_TRUE(solo::isDepthDataset(o));
  const solo::DepthDatasetEvaluation d = solo::evaluateDepthDataset(o);
  EXPECT_EQ(integer(d.summary, "evaluated"), 2);
  EXPECT_TRUE(d.failures.empty());
  EXPECT_DOUBLE_EQ(number(d.summary, "pooled_abs_rel"), 2.0 / 9.0);
  EXPECT_EQ(text(d.images[0], "image"), (dir / "pairs.txt").string() + ":3");

  solo::test::writeText(dir / "bad.txt", "pred/a.pfm\n");
  o.list = dir / "bad.txt";
  try {
    solo::evaluateDepthDataset(o);
    ADD_FAILURE() << "no error";
  } catch (const solo::InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              (dir / "bad.txt").string() + ": line 1 has 1 fields, expected PREDICTION GROUND_TRUTH [MASK]");
  }
  o.prediction = dir / "pred";
  EXPECT_THROW(solo::evaluateDepthDataset(o), solo::InputError) << "--list with --pred";
}

TEST(Evaluation, NormalFilesHaveTheHandComputedAngles) {
  TempDir dir;
  // gt (0,0,-1) twice; pred equal, then (1,0,0): angles 0 and 90 degrees.
  cv::Mat gt(1, 2, CV_32FC3, cv::Scalar(0, 0, -1)), pred = gt.clone();
  pred.at<cv::Vec3f>(0, 1) = cv::Vec3f(1, 0, 0);
  solo::writeNormals(dir / "gt.exr", gt);
  solo::writeNormals(dir / "pred.exr", pred);
  solo::NormalFilesEvaluationOptions o;
  o.prediction = dir / "pred.exr";
  o.ground_truth = dir / "gt.exr";
  const EvaluationRecord r = solo::evaluateNormalFiles(o);
  EXPECT_EQ(r.command, "eval normals");
  EXPECT_TRUE(r.options.empty());
  EXPECT_EQ(integer(r, "valid_pixels"), 2);
  EXPECT_NEAR(number(r, "mean_deg"), 45.0, 1e-9);
  EXPECT_NEAR(number(r, "median_deg"), 45.0, 1e-9);
  EXPECT_NEAR(number(r, "rmse_deg"), std::sqrt(8100.0 / 2), 1e-9);
  EXPECT_DOUBLE_EQ(number(r, "under_11_25_deg"), 0.5);
}

TEST(Evaluation, MeshFileIsClosedOnlyWhenWatertight) {
  // Two unit cubes, each without a boundary edge, the second moved by (1, 1, 0): they touch
  // along the edge x = y = 1, where faces of both meet: closed in the topological sense only.
  TempDir dir;
  solo::TriangleMesh cubes;
  for (const Eigen::Vector3d& offset : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 0)}) {
    const auto first = static_cast<std::uint32_t>(cubes.vertices.size());
    for (int corner = 0; corner < 8; ++corner)
      cubes.vertices.push_back(offset + Eigen::Vector3d(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1));
    const std::array<std::array<std::uint32_t, 3>, 12> faces = {{{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                                                {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                                                {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}}};
    for (const auto& f : faces) cubes.faces.push_back({first + f[0], first + f[1], first + f[2]});
  }
  solo::writeMesh(dir / "cubes.off", cubes);
  solo::MeshFileEvaluationOptions o;
  o.mesh = dir / "cubes.off";
  const EvaluationRecord r = solo::evaluateMeshFile(o);
  EXPECT_EQ(integer(r, "boundary_edges"), 0);
  EXPECT_EQ(std::get<bool>(valueOf(r, "no_boundary")), true);
  EXPECT_GT(integer(r, "self_intersecting_pairs"), 0);
  EXPECT_EQ(std::get<bool>(valueOf(r, "closed")), false);
  EXPECT_EQ(std::get<std::string>(valueOf(r, "open_because")),
            std::to_string(integer(r, "self_intersecting_pairs")) + " self-intersecting face pairs");
  // One cube alone is closed, and nothing keeps it open.
  cubes.vertices.resize(8);
  cubes.faces.resize(12);
  solo::writeMesh(dir / "cube.off", cubes);
  o.mesh = dir / "cube.off";
  const EvaluationRecord one = solo::evaluateMeshFile(o);
  EXPECT_EQ(std::get<bool>(valueOf(one, "closed")), true);
  EXPECT_EQ(std::get<std::string>(valueOf(one, "open_because")), "nothing");
}

TEST(Evaluation, MeshFileWithAndWithoutReference) {
  TempDir dir;
  solo::test::writeSquareAndLiftedSquare(dir.path());
  solo::MeshFileEvaluationOptions o;
  o.mesh = dir / "square.off";
  o.reference = dir / "lifted.ply";
  o.samples = 500;
  o.seed = 9;
  const EvaluationRecord r = solo::evaluateMeshFile(o);
  EXPECT_EQ(r.command, "eval mesh");
  EXPECT_EQ(integer(r, "vertices"), 4);
  EXPECT_EQ(integer(r, "faces"), 2);
  EXPECT_EQ(integer(r, "boundary_loops"), 1);
  EXPECT_EQ(integer(r, "boundary_edges"), 4);
  EXPECT_EQ(std::get<bool>(valueOf(r, "closed")), false);
  EXPECT_EQ(std::get<std::string>(valueOf(r, "open_because")), "1 boundary loops");
  EXPECT_EQ(std::get<bool>(valueOf(r, "no_boundary")), false);
  EXPECT_EQ(integer(r, "samples"), 500);
  EXPECT_EQ(integer(r, "seed"), 9);
  // Parallel squares 0.25 apart: every distance is 0.25.
  EXPECT_NEAR(number(r, "hausdorff"), 0.25, 1e-12);
  EXPECT_NEAR(number(r, "chamfer"), 0.25, 1e-12);
  // Default tau: 1 % of the unit square's diagonal, far below 0.25: nothing within it.
  EXPECT_TRUE(isNone(r, "tau_m"));
  EXPECT_NEAR(number(r, "fscore_tau"), 0.01 * std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(number(r, "fscore_tau_relative"), 0.01, 1e-15);
  EXPECT_EQ(number(r, "precision"), 0.0);
  EXPECT_EQ(number(r, "fscore"), 0.0);
  // tau above the offset: everything within it.
  o.tau_m = 0.3;
  const EvaluationRecord wide = solo::evaluateMeshFile(o);
  EXPECT_EQ(number(wide, "tau_m"), 0.3);
  EXPECT_EQ(number(wide, "fscore_tau"), 0.3);
  EXPECT_EQ(number(wide, "precision"), 1.0);
  EXPECT_EQ(number(wide, "recall"), 1.0);
  EXPECT_EQ(number(wide, "fscore"), 1.0);
  o.tau_m = 0;
  EXPECT_THROW(solo::evaluateMeshFile(o), solo::InputError);
  o.tau_m.reset();

  o.reference.reset();
  const EvaluationRecord alone = solo::evaluateMeshFile(o);
  EXPECT_EQ(solo::evaluationCsvHeader(alone), solo::evaluationCsvHeader(r)) << "the same columns";
  EXPECT_TRUE(isNone(alone, "reference"));
  EXPECT_TRUE(isNone(alone, "hausdorff"));
  EXPECT_TRUE(isNone(alone, "chamfer"));
  EXPECT_EQ(integer(alone, "boundary_edges"), 4);
}

TEST(EvaluationRecord, CsvCellsAndTheAppendRule) {
  EvaluationRecord r;
  r.command = "eval test";
  r.inputs = {{"file", "file", std::string("a,\"b\""), ""}, {"none", "none", std::monostate{}, ""}};
  r.options = {{"flag", "flag", true, ""}, {"count", "count", std::int64_t{-3}, ""}};
  r.metrics = {{"tenth", "tenth", 0.1, "m"}, {"third", "third", 1.0 / 3, ""}};
  EXPECT_EQ(solo::evaluationCsvHeader(r), "file,none,flag,count,tenth,third\n");
  EXPECT_EQ(solo::evaluationCsvRow(r), "\"a,\"\"b\"\"\",,true,-3,0.1,0.3333333333333333\n");

  TempDir dir;
  solo::appendEvaluationCsvRow(dir / "rows.csv", r);
  r.options[0].value = false;
  solo::appendEvaluationCsvRow(dir / "rows.csv", r);
  EXPECT_EQ(readText(dir / "rows.csv"),
            "file,none,flag,count,tenth,third\n"
            "\"a,\"\"b\"\"\",,true,-3,0.1,0.3333333333333333\n"
            "\"a,\"\"b\"\"\",,false,-3,0.1,0.3333333333333333\n");

  solo::test::writeText(dir / "other.csv", "a,b\n1,2\n");
  try {
    solo::appendEvaluationCsvRow(dir / "other.csv", r);
    ADD_FAILURE() << "a file with other columns is refused";
  } catch (const solo::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("its columns are not those of `solo eval test`"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(readText(dir / "other.csv"), "a,b\n1,2\n");
}

TEST(Evaluation, SceneFolderScoresTheGivenRefinedDepthAndSaysWhatItSkipped) {
  TempDir dir;
  solo::SyntheticSceneOptions synth;
  synth.seed = 3;
  synth.width = 160;
  synth.height = 90;
  const std::filesystem::path scene = solo::writeSyntheticScene(dir / "scene", synth).folder;

  solo::SceneFolderEvaluationOptions o;
  o.scene_dir = scene;
  o.refined = scene / "gt/depth.exr";  // the exact depth as the refined one: no error at all
  const EvaluationRecord r = solo::evaluateSceneFolder(o);
  EXPECT_EQ(r.command, "eval scene");
  EXPECT_EQ(text(r, "ground_truth"), (scene / "gt/scene.json").string());
  EXPECT_EQ(integer(r, "width"), 160);
  EXPECT_EQ(integer(r, "height"), 90);
  EXPECT_GT(number(r, "est_depth_abs_rel"), 0.0) << "the estimate is perturbed";
  EXPECT_TRUE(isNone(r, "refined_skipped"));
  EXPECT_EQ(number(r, "refined_depth_abs_rel"), 0.0);
  EXPECT_EQ(number(r, "refined_depth_delta1"), 1.0);
  EXPECT_EQ(number(r, "refined_depth_median_scaled_scale"), 1.0);
  EXPECT_EQ(text(r, "refined_normals_skipped"), (scene / "gt/depth.normals.exr").string() + " not found");
  EXPECT_TRUE(isNone(r, "refined_normals_mean_deg"));
  EXPECT_EQ(text(r, "spurious_depth"), "refined");
  EXPECT_EQ(text(r, "spurious_uncertain_skipped"),
            (scene / "gt/depth.uncertain.png").string() + " not found: uncertain criterion not applied");
  EXPECT_GT(integer(r, "spurious_truth_faces"), 0) << "the street has occlusions to find";
  EXPECT_EQ(text(r, "mesh_skipped"), (scene / "mesh.ply").string() +
                                         " not found (solo mesh from-depth SCENE_DIR/scene.json -o SCENE_DIR/mesh.ply)");
  EXPECT_EQ(text(r, "mesh_distances_skipped"), "no mesh");
  EXPECT_TRUE(isNone(r, "mesh_vertices"));
  EXPECT_TRUE(isNone(r, "mesh_hausdorff"));
  EXPECT_TRUE(isNone(r, "mesh_area_m2"));

  try {
    o.scene_dir = dir / "missing";
    solo::evaluateSceneFolder(o);
    ADD_FAILURE() << "a missing folder is named";
  } catch (const solo::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("folder not found"), std::string::npos) << e.what();
  }
}

TEST(NightEvaluation, ReferenceRangeFlagsTheOutlierOnly) {
  TempDir dir;
  const auto write_grey = [](const std::filesystem::path& file, int level) {
    solo::writeImage(file, cv::Mat(54, 96, CV_8UC3, cv::Scalar::all(level)));
  };
  std::filesystem::create_directories(dir / "ref");
  for (const int level : {50, 30, 40}) write_grey(dir / "ref" / ("grey" + std::to_string(level) + ".png"), level);
  write_grey(dir / "bright.png", 120);
  write_grey(dir / "typical.png", 40);
  solo::test::writeText(dir / "ref.txt", "# reference\n  ref/grey30.png \n\nref/grey40.png\nref/grey50.png\n");
  EXPECT_EQ(solo::nightReferenceImages(dir / "ref"), solo::nightReferenceImages(dir / "ref.txt"))
      << "a folder's images sorted, a list's relative to its folder";

  solo::NightEvaluationOptions o;
  o.images = {dir / "bright.png", dir / "typical.png"};
  o.reference = dir / "ref.txt";
  const solo::NightEvaluation night = solo::evaluateNightImages(o);
  ASSERT_EQ(night.statistics.size(), 2u);
  ASSERT_EQ(night.reference_files.size(), 3u);
  EXPECT_EQ(night.reference_files[0], dir / "ref/grey30.png");
  const std::vector<solo::NamedNightStatistic> keys = solo::namedNightStatistics(solo::NightStatistics{});
  ASSERT_EQ(night.ranges.size(), keys.size());
  ASSERT_EQ(keys[0].key, "mean");
  EXPECT_NEAR(*night.ranges[0].median, 40.0, 1e-9);
  EXPECT_NEAR(*night.ranges[0].min, 30.0, 1e-9);
  EXPECT_NEAR(*night.ranges[0].max, 50.0, 1e-9);
  EXPECT_EQ(solo::nightStatisticsOutsideRange(night.statistics[0], night.ranges),
            (std::vector<std::string>{"mean", "p50", "p90", "p99"}));
  EXPECT_TRUE(solo::nightStatisticsOutsideRange(night.statistics[1], night.ranges).empty());

  const EvaluationRecord bright = solo::nightEvaluationRecord(night, 0);
  EXPECT_EQ(bright.command, "eval night");
  EXPECT_EQ(integer(bright, "width_px"), 96);
  EXPECT_EQ(text(bright, "reference"), (dir / "ref.txt").string());
  EXPECT_NEAR(number(bright, "mean"), 120.0, 1e-9);
  EXPECT_TRUE(isNone(bright, "cast_cb")) << "no pixel with 20 < Y < 80";
  EXPECT_EQ(text(bright, "outside_reference"), "mean;p50;p90;p99");
  EXPECT_EQ(text(solo::nightEvaluationRecord(night, 1), "outside_reference"), "");

  o.reference.reset();
  const solo::NightEvaluation alone = solo::evaluateNightImages(o);
  EXPECT_TRUE(alone.ranges.empty());
  EXPECT_TRUE(isNone(solo::nightEvaluationRecord(alone, 0), "outside_reference"));
}
