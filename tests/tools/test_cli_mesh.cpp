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

/// Two unit cubes as OFF, each with its own vertices, the second moved by (dx, dy, 0).
std::string twoCubesOff(double dx, double dy) {
  std::string off = "OFF\n16 24 0\n";
  for (int c = 0; c < 2; ++c)
    for (int i = 0; i < 8; ++i)
      off += std::to_string((i & 1) + c * dx) + " " + std::to_string(((i >> 1) & 1) + c * dy) + " " +
             std::to_string((i >> 2) & 1) + "\n";
  const int faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                            {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (int c = 0; c < 2; ++c)
    for (const auto& f : faces)
      off += "3 " + std::to_string(f[0] + 8 * c) + " " + std::to_string(f[1] + 8 * c) + " " + std::to_string(f[2] + 8 * c) + "\n";
  return off;
}

bool watertight(const solo::MeshMetrics& m) {
  return m.closed && m.non_manifold_edges == 0 && m.non_manifold_vertices == 0 && m.self_intersecting_pairs == 0 &&
         m.degenerate_faces == 0;
}

TEST(CliMesh, CubesTouchingAtAnEdgeComeOutClosedOrSaySo) {
  TempDir dir;
  writeText(dir / "cubes.off", twoCubesOff(1, 1));
  const auto r = runSolo("mesh clean " + quoted(dir / "cubes.off") + " -o " + quoted(dir / "out.ply") + " --report " +
                         quoted(dir / "r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const solo::MeshMetrics m = solo::evaluateMesh(solo::readMesh(dir / "out.ply"));
  EXPECT_TRUE(watertight(m)) << r.output;
  EXPECT_NE(r.output.find("result: closed"), std::string::npos) << r.output;
  const nlohmann::json report = nlohmann::json::parse(readText(dir / "r.json"));
  EXPECT_GT(metric(report, "before_self_intersecting_pairs")->get<int>(), 0);
  EXPECT_EQ(*metric(report, "after_self_intersecting_pairs"), 0);
  ASSERT_NE(metric(report, "hausdorff_symmetric_fraction"), nullptr);
}

TEST(CliMesh, WithoutRepairOrWrapTheIntersectionsAreNamedAndClosedIsNotPrinted) {
  TempDir dir;
  // Overlapping cubes: each closed, the pair intersecting.
  writeText(dir / "cubes.off", twoCubesOff(0.5, 0.5));
  const auto r = runSolo("mesh clean " + quoted(dir / "cubes.off") + " -o " + quoted(dir / "out.ply") +
                         " --no-repair-intersections --no-wrap-fallback --report " + quoted(dir / "r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("result: closed"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("solo: warning: the result is NOT closed:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("self-intersecting face pairs"), std::string::npos) << r.output;
  const nlohmann::json report = nlohmann::json::parse(readText(dir / "r.json"));
  EXPECT_EQ(*metric(report, "after_closed"), false);
}

TEST(CliMesh, WrapWritesAClosedMeshAndItsDistances) {
  TempDir dir;
  writeText(dir / "cubes.off", twoCubesOff(0.5, 0.5));
  const auto r = runSolo("mesh clean " + quoted(dir / "cubes.off") + " -o " + quoted(dir / "out.ply") +
                         " --wrap --wrap-alpha 0.02 --report " + quoted(dir / "r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(watertight(solo::evaluateMesh(solo::readMesh(dir / "out.ply")))) << r.output;
  const nlohmann::json report = nlohmann::json::parse(readText(dir / "r.json"));
  EXPECT_EQ(*metric(report, "wrapped"), true);
  EXPECT_DOUBLE_EQ(metric(report, "wrap_alpha_fraction")->get<double>(), 0.02);
  for (const char* name : {"hausdorff_input_to_output_fraction", "hausdorff_output_to_input_fraction",
                           "hausdorff_symmetric_fraction"}) {
    ASSERT_NE(metric(report, name), nullptr) << name;
    EXPECT_GT(metric(report, name)->get<double>(), 0) << name;
  }
  // The wrap lies about the offset outside the input; the cubes' inner parts are far from it.
  EXPECT_LT(metric(report, "hausdorff_output_to_input_fraction")->get<double>(), 0.02);
  EXPECT_GT(metric(report, "hausdorff_input_to_output_fraction")->get<double>(), 0.1);
  EXPECT_NE(r.output.find("departs from the input surface"), std::string::npos) << r.output;
}

TEST(CliMesh, HemisphereWithARepeatedPoleBecomesOneClosedComponent) {
  TempDir dir;
  const int segments = 24, rings = 6;
  solo::TriangleMesh m;
  for (int r = 0; r <= rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double theta = 0.5 * 3.14159265358979 * r / rings, phi = 2 * 3.14159265358979 * s / segments;
      m.vertices.emplace_back(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    }
  const auto at = [&](int r, int s) { return static_cast<std::uint32_t>(r * segments + s % segments); };
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      m.faces.push_back({at(r, s), at(r + 1, s), at(r + 1, s + 1)});
      m.faces.push_back({at(r, s), at(r + 1, s + 1), at(r, s + 1)});
    }
  solo::writeMesh(dir / "dome.ply", m);
  const auto r = runSolo("mesh clean " + quoted(dir / "dome.ply") + " -o " + quoted(dir / "out.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const solo::MeshMetrics out = solo::evaluateMesh(solo::readMesh(dir / "out.ply"));
  EXPECT_TRUE(watertight(out)) << r.output;
  EXPECT_EQ(out.components, 1);
  EXPECT_NE(r.output.find("result: closed"), std::string::npos) << r.output;
}

TEST(CliMesh, WrapOptionsMustBeFiniteAndPositive) {
  TempDir dir;
  writeText(dir / "cube.off", cubeOff());
  for (const char* option : {"--wrap-alpha nan", "--wrap-offset 0", "--repair-time-limit -1", "--wrap-time-limit inf"}) {
    const auto r = runSolo("mesh clean " + quoted(dir / "cube.off") + " -o " + quoted(dir / "out.ply") + " " + option);
    EXPECT_EQ(r.exit_code, 2) << option << "\n" << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "out.ply")) << option;
  }
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
