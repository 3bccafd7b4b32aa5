// `solo mesh clean` and `solo mesh from-depth` end to end: outputs, reports, errors.

#include <solo/geometry/mesh_metrics.h>
#include <solo/geometry/triangle_mesh.h>

#include <nlohmann/json.hpp>

#include "test_support.h"

#include <cmath>

using solo::test::readText;
using solo::test::runSolo;
using solo::test::TempDir;
using solo::test::writeText;

namespace {

std::string quoted(const std::filesystem::path& p) { return "\"" + p.string() + "\""; }

/// The unit cube as OFF without its last face (one triangular hole).
std::string cubeOff() {
  return "OFF\n8 11 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
         "3 0 2 1\n3 1 2 3\n3 4 5 6\n3 5 7 6\n3 0 1 4\n3 1 5 4\n3 2 6 3\n3 3 6 7\n3 0 4 2\n3 2 4 6\n3 1 3 5\n";
}

/// A metric of the report's first stage: stored as a bare value, or {"value", "unit"}.
const nlohmann::json* metric(const nlohmann::json& report, const std::string& name) {
  const nlohmann::json& metrics = report["stages"][0]["metrics"];
  if (!metrics.contains(name)) return nullptr;
  const nlohmann::json& m = metrics[name];
  return m.is_object() ? &m["value"] : &m;
}

TEST(CliMesh, CleanClosesTheHoleAndWritesTheReport) {
  TempDir dir;
  writeText(dir / "cube.off", cubeOff());
  const auto r = runSolo("mesh clean " + quoted(dir / "cube.off") + " -o " + quoted(dir / "closed.ply") + " --report " +
                         quoted(dir / "r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("holes_filled"), std::string::npos);
  const solo::MeshMetrics m = solo::evaluateMesh(solo::readMesh(dir / "closed.ply"));
  EXPECT_TRUE(m.closed);
  EXPECT_EQ(m.faces, 12);
  const nlohmann::json report = nlohmann::json::parse(readText(dir / "r.json"));
  EXPECT_EQ(report["command"], "mesh clean");
  ASSERT_NE(metric(report, "holes_filled"), nullptr);
  EXPECT_EQ(*metric(report, "holes_filled"), 1);
  EXPECT_EQ(*metric(report, "after_boundary_loops_total"), 0);
}

TEST(CliMesh, CleanRefusesNanCoordinates) {
  TempDir dir;
  // A binary PLY stores a NaN as it is (text readers stop at "nan" as malformed).
  solo::TriangleMesh bad;
  bad.vertices = {{0, 0, 0}, {1, 0, 0}, {0, std::nan(""), 0}};
  bad.faces = {{0, 1, 2}};
  solo::writeMesh(dir / "bad.ply", bad);
  const auto r = runSolo("mesh clean " + quoted(dir / "bad.ply") + " -o " + quoted(dir / "out.off"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("solo: error: " + (dir / "bad.ply").string() + ": vertex 2 has a non-finite coordinate"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.off"));
}

TEST(CliMesh, FromDepthScoresAgainstGroundTruthAndRefusesAnotherSize) {
  TempDir dir;
  ASSERT_EQ(runSolo("synth -o " + quoted(dir / "s") + " --size 192x108 --seed 3").exit_code, 0);
  const auto gt = dir / "s/gt/scene.json";
  const auto r = runSolo("mesh from-depth " + quoted(gt) + " -o " + quoted(dir / "m.ply") + " --truth " + quoted(gt) +
                         " --report " + quoted(dir / "r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json report = nlohmann::json::parse(readText(dir / "r.json"));
  ASSERT_NE(metric(report, "spurious_precision"), nullptr);
  EXPECT_GT(metric(report, "spurious_precision")->get<double>(), 0.5);
  EXPECT_EQ(*metric(report, "after_non_manifold_edges"), 0);
  EXPECT_EQ(*metric(report, "after_non_manifold_vertices"), 0);
  EXPECT_EQ(*metric(report, "after_degenerate_faces"), 0);
  EXPECT_GT(solo::readMesh(dir / "m.ply").faces.size(), 10000u);
  // The estimated depth is half the ground truth's resolution.
  const auto bad = runSolo("mesh from-depth " + quoted(dir / "s/scene.json") + " -o " + quoted(dir / "e.ply") +
                           " --truth " + quoted(gt));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("ground-truth depth is 192x108, the scene's depth 96x54"), std::string::npos) << bad.output;
}

}  // namespace
