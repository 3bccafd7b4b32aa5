// `solo mesh clean` (cleanMesh) over generated hard meshes and the shared test meshes: every
// output is closed, 2-manifold and free of self-intersections, or the call is a clear error.
// The check is independent of solo's own evaluation (evaluateMesh): edge and vertex
// manifoldness and orientation counted here from the face list, self-intersections by CGAL's
// does_self_intersect on a Surface_mesh built here, degenerate faces by CGAL::collinear.

#include "solo/core/error.h"
#include "solo/core/report.h"
#include "solo/geometry/mesh_cleanup.h"
#include "solo/geometry/mesh_metrics.h"
#include "solo/geometry/triangle_mesh.h"

#include "test_support.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <variant>
#include <vector>

namespace {

using solo::TriangleMesh;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

constexpr double kPi = 3.14159265358979323846;
// Every generated case runs well within this (seconds); the shared meshes get twice as long.
#if defined(__SANITIZE_ADDRESS__)
constexpr double kCaseTimeLimit_s = 20 * 8;  // AddressSanitizer slows CGAL's repair about 5x
#else
constexpr double kCaseTimeLimit_s = 20;
#endif

// ---- generators --------------------------------------------------------------------------

std::uint32_t add(TriangleMesh& m, double x, double y, double z) {
  m.vertices.emplace_back(x, y, z);
  return static_cast<std::uint32_t>(m.vertices.size() - 1);
}

/// A closed UV sphere: one vertex per pole, `rings` latitude bands, `segments` longitudes.
TriangleMesh sphere(const Eigen::Vector3d& centre, double radius, int rings = 16, int segments = 32) {
  TriangleMesh m;
  const std::uint32_t north = add(m, centre.x(), centre.y(), centre.z() + radius);
  for (int r = 1; r < rings; ++r) {
    const double theta = kPi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2 * kPi * s / segments;
      add(m, centre.x() + radius * std::sin(theta) * std::cos(phi), centre.y() + radius * std::sin(theta) * std::sin(phi),
          centre.z() + radius * std::cos(theta));
    }
  }
  const std::uint32_t south = add(m, centre.x(), centre.y(), centre.z() - radius);
  const auto at = [&](int r, int s) { return static_cast<std::uint32_t>(1 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) m.faces.push_back({north, at(1, s), at(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      m.faces.push_back({at(r, s), at(r + 1, s), at(r + 1, s + 1)});
      m.faces.push_back({at(r, s), at(r + 1, s + 1), at(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s) m.faces.push_back({south, at(rings - 1, s + 1), at(rings - 1, s)});
  return m;
}

/// An axis-aligned closed box, outward faces.
TriangleMesh box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    add(m, (i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(), (i & 4) ? hi.z() : lo.z());
  m.faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

/// `b` appended to `a`, its vertices renumbered (no vertex shared).
TriangleMesh joined(TriangleMesh a, const TriangleMesh& b) {
  const auto offset = static_cast<std::uint32_t>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (const auto& f : b.faces) a.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
  return a;
}

/// The upper half of a UV sphere, open at the equator, whose pole is repeated once per
/// longitude: a fan of 24 proper triangles and 24 degenerate ones (two copies of the pole).
TriangleMesh hemisphereWithRepeatedPole(int segments = 24, int rings = 8) {
  TriangleMesh m;
  for (int r = 0; r <= rings; ++r) {
    const double theta = 0.5 * kPi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2 * kPi * s / segments;
      add(m, std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    }
  }
  const auto at = [&](int r, int s) { return static_cast<std::uint32_t>(r * segments + (s % segments)); };
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      m.faces.push_back({at(r, s), at(r + 1, s), at(r + 1, s + 1)});
      m.faces.push_back({at(r, s), at(r + 1, s + 1), at(r, s + 1)});
    }
  return m;
}

/// An open bowl whose rim is one hole of `rim` boundary vertices.
TriangleMesh bowl(int rim, int rings = 3) {
  TriangleMesh m;
  const std::uint32_t bottom = add(m, 0, 0, -1);
  for (int r = 1; r <= rings; ++r) {
    const double theta = 0.5 * kPi * r / rings;
    for (int s = 0; s < rim; ++s) {
      const double phi = 2 * kPi * s / rim;
      add(m, std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), -std::cos(theta));
    }
  }
  const auto at = [&](int r, int s) { return static_cast<std::uint32_t>(1 + (r - 1) * rim + (s % rim)); };
  for (int s = 0; s < rim; ++s) m.faces.push_back({bottom, at(1, s + 1), at(1, s)});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < rim; ++s) {
      m.faces.push_back({at(r, s), at(r, s + 1), at(r + 1, s + 1)});
      m.faces.push_back({at(r, s), at(r + 1, s + 1), at(r + 1, s)});
    }
  return m;
}

// ---- the independent check ---------------------------------------------------------------

/// What keeps `m` from being closed, 2-manifold, consistently oriented and free of
/// self-intersections and degenerate faces; empty when nothing does.
std::string independentDefects(const TriangleMesh& m) {
  if (m.faces.empty()) return "no face";
  std::vector<Point> points;
  for (const auto& v : m.vertices) points.emplace_back(v.x(), v.y(), v.z());
  std::int64_t degenerate = 0;
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const auto& f : m.faces) {
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2] || CGAL::collinear(points[f[0]], points[f[1]], points[f[2]]))
      ++degenerate;
    for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
  }
  // Closed, edge-manifold and oriented: each directed edge once, and its reverse once.
  std::int64_t bad_edges = 0;
  for (const auto& [edge, count] : directed) {
    const auto reverse = directed.find({edge.second, edge.first});
    if (count != 1 || reverse == directed.end() || reverse->second != 1) ++bad_edges;
  }
  // Vertex-manifold: the faces around each vertex form one cycle (their link is connected).
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> link(m.vertices.size());
  for (const auto& f : m.faces)
    for (int k = 0; k < 3; ++k) link[f[k]].push_back({f[(k + 1) % 3], f[(k + 2) % 3]});
  std::int64_t bad_vertices = 0;
  for (const auto& edges : link) {
    if (edges.empty()) continue;
    std::map<std::uint32_t, std::uint32_t> next;
    for (const auto& [a, b] : edges) next[a] = b;
    std::uint32_t v = edges.front().first;
    std::size_t steps = 0;
    do {
      const auto it = next.find(v);
      if (it == next.end()) break;
      v = it->second;
      ++steps;
    } while (v != edges.front().first && steps <= edges.size());
    if (steps != edges.size()) ++bad_vertices;
  }
  std::string out;
  const auto note = [&out](std::int64_t n, const char* what) {
    if (n > 0) out += (out.empty() ? "" : ", ") + std::to_string(n) + " " + what;
  };
  note(degenerate, "degenerate faces");
  note(bad_edges, "open, non-manifold or misoriented edges");
  note(bad_vertices, "non-manifold vertices");
  if (!out.empty()) return out;
  std::vector<std::vector<std::size_t>> polygons;
  for (const auto& f : m.faces) polygons.push_back({f[0], f[1], f[2]});
  CGAL::Surface_mesh<Point> mesh;
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, polygons, mesh);
  if (CGAL::Polygon_mesh_processing::does_self_intersect(mesh)) return "self-intersections";
  return {};
}

double metricValue(const solo::StageReport& report, const std::string& name) {
  const solo::MetricValue* v = report.find(name);
  if (!v) return std::nan("");
  if (const auto* d = std::get_if<double>(v)) return *d;
  if (const auto* i = std::get_if<std::int64_t>(v)) return static_cast<double>(*i);
  if (const auto* b = std::get_if<bool>(v)) return *b ? 1 : 0;
  return std::nan("");
}

/// Whether the input's surface can be kept within 0.1 % of the diagonal: not where parts of it
/// must go (the inner halves of overlapping spheres, a fin on an edge).
enum class Surface { Kept, MayDepart };

/// Cleans `input` and checks the output: watertight by the independent check and by the
/// report. Without a wrap, every input point is within 0.1 % of the diagonal of the output
/// (measured again here with another seed), or, where the case allows it, a warning says how
/// far it departs; with a wrap, the wrap is within alpha of the input and the distances are
/// reported. Returns the report.
solo::StageReport cleanAndCheck(const TriangleMesh& input, const std::string& name, Surface surface = Surface::Kept,
                                double time_limit_s = kCaseTimeLimit_s, solo::MeshCleanupOptions options = {}) {
  solo::StageReport report;
  const solo::Stopwatch clock;
  const TriangleMesh out = solo::cleanMesh(input, options, report, name);
  const double seconds = clock.seconds();
  EXPECT_LT(seconds, time_limit_s) << name;
  EXPECT_EQ(independentDefects(out), "") << name;
  EXPECT_EQ(metricValue(report, "after_closed"), 1) << name;
  const double in_to_out = metricValue(report, "hausdorff_input_to_output_fraction");
  const double out_to_in = metricValue(report, "hausdorff_output_to_input_fraction");
  EXPECT_TRUE(std::isfinite(in_to_out) && std::isfinite(out_to_in)) << name;
  EXPECT_TRUE(std::isfinite(metricValue(report, "hausdorff_symmetric_fraction"))) << name;
  bool departure_warned = false;
  for (const auto& w : report.warnings) departure_warned = departure_warned || w.find("departs from the input") != std::string::npos;
  if (metricValue(report, "wrapped") == 1) {
    EXPECT_LE(out_to_in, options.wrapping.alpha_fraction) << name;
  } else if (surface == Surface::Kept) {
    solo::MeshDistanceOptions sampling;
    sampling.samples = 5000;
    sampling.seed = 7;
    const solo::MeshDistances d = solo::measureMeshDistances(out, input, sampling);
    EXPECT_LE(d.hausdorff_from_reference, 1e-3 * d.reference_bbox_diagonal) << name;
    EXPECT_LE(in_to_out, 1e-3) << name;
    EXPECT_FALSE(departure_warned) << name;
  } else {
    EXPECT_EQ(departure_warned, in_to_out > 1e-3) << name << ": " << in_to_out;
  }
  return report;
}

// ---- generated cases ---------------------------------------------------------------------

TEST(MeshRepairCorpus, TwoOverlappingSpheres) {
  const TriangleMesh m = joined(sphere({0, 0, 0}, 1), sphere({1.2, 0, 0}, 1));
  const solo::StageReport r = cleanAndCheck(m, "two overlapping spheres", Surface::MayDepart);
  EXPECT_GT(metricValue(r, "before_self_intersecting_pairs"), 0);
}

TEST(MeshRepairCorpus, FlippedFaces) {
  TriangleMesh m = sphere({0, 0, 0}, 1);
  for (std::size_t i = 0; i < m.faces.size(); i += 7) std::swap(m.faces[i][1], m.faces[i][2]);
  cleanAndCheck(m, "flipped faces");
}

TEST(MeshRepairCorpus, NonManifoldEdge) {
  // A fin of two faces on an edge of a closed box: that edge has four faces.
  TriangleMesh m = box({0, 0, 0}, {1, 1, 1});
  const std::uint32_t tip = add(m, 0.5, -0.8, -0.8);
  m.faces.push_back({0, 1, tip});
  m.faces.push_back({1, 0, tip});
  cleanAndCheck(m, "non-manifold edge", Surface::MayDepart);
}

TEST(MeshRepairCorpus, NonManifoldVertex) {
  // Two boxes sharing one corner vertex by index.
  TriangleMesh m = box({0, 0, 0}, {1, 1, 1});
  TriangleMesh other = box({1, 1, 1}, {2, 2, 2});
  const auto offset = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), other.vertices.begin(), other.vertices.end());
  for (auto f : other.faces) {
    for (auto& v : f) v = v == 0 ? 7 : v + offset;  // its corner 0 is the first box's corner 7
    m.faces.push_back(f);
  }
  cleanAndCheck(m, "non-manifold vertex");
}

TEST(MeshRepairCorpus, DuplicatedAndDegenerateFaces) {
  TriangleMesh m = sphere({0, 0, 0}, 1);
  const std::size_t n = m.faces.size();
  for (std::size_t i = 0; i < n; i += 5) m.faces.push_back(m.faces[i]);
  for (std::size_t i = 0; i < n; i += 11) m.faces.push_back({m.faces[i][0], m.faces[i][0], m.faces[i][1]});
  // A collinear face: a new vertex in the middle of an edge.
  const auto& f = m.faces[3];
  const Eigen::Vector3d mid = 0.5 * (m.vertices[f[0]] + m.vertices[f[1]]);
  const std::uint32_t v = add(m, mid.x(), mid.y(), mid.z());
  m.faces.push_back({f[0], v, f[1]});
  cleanAndCheck(m, "duplicated and degenerate faces");
}

TEST(MeshRepairCorpus, TriangleSoup) {
  const TriangleMesh s = sphere({0, 0, 0}, 1);
  TriangleMesh m;
  for (const auto& f : s.faces) {
    std::array<std::uint32_t, 3> g{};
    for (int k = 0; k < 3; ++k) g[k] = add(m, s.vertices[f[k]].x(), s.vertices[f[k]].y(), s.vertices[f[k]].z());
    m.faces.push_back(g);
  }
  cleanAndCheck(m, "triangle soup");
}

TEST(MeshRepairCorpus, LargeAndSmallCoordinates) {
  for (const double scale : {1e6, 1e-6}) {
    TriangleMesh m = sphere({0, 0, 0}, scale);
    m.faces.erase(m.faces.begin() + 40, m.faces.begin() + 44);  // a hole to fill
    cleanAndCheck(m, "sphere of radius " + std::to_string(scale));
  }
  // A metre-sized sphere 1000 km from the origin.
  TriangleMesh far = sphere({1e6, 1e6, 1e6}, 1);
  far.faces.erase(far.faces.begin() + 40, far.faces.begin() + 44);
  cleanAndCheck(far, "sphere far from the origin");
}

TEST(MeshRepairCorpus, HoleOf5000BoundaryVertices) {
  const solo::StageReport r = cleanAndCheck(bowl(5000), "bowl of 5000 rim vertices");
  EXPECT_EQ(metricValue(r, "largest_hole_vertices"), 5000);
}

TEST(MeshRepairCorpus, TwoCubesTouchingAtAnEdge) {
  const TriangleMesh m = joined(box({0, 0, 0}, {1, 1, 1}), box({1, 1, 0}, {2, 2, 1}));
  const solo::StageReport r = cleanAndCheck(m, "two cubes touching at an edge", Surface::MayDepart);
  EXPECT_GT(metricValue(r, "before_self_intersecting_pairs"), 0);
}

TEST(MeshRepairCorpus, HemisphereWith24CoincidentPoleVertices) {
  const solo::StageReport r = cleanAndCheck(hemisphereWithRepeatedPole(), "hemisphere with 24 pole copies");
  EXPECT_EQ(metricValue(r, "coincident_corners_merged"), 23);
  EXPECT_EQ(metricValue(r, "after_components"), 1);
  EXPECT_EQ(metricValue(r, "wrapped"), 0);
}

TEST(MeshRepairCorpus, NoSurfaceIsAClearError) {
  TriangleMesh m;
  add(m, 0, 0, 0), add(m, 1, 0, 0), add(m, 2, 0, 0);
  m.faces = {{0, 1, 2}, {0, 0, 1}};
  solo::StageReport report;
  try {
    solo::cleanMesh(m, {}, report, "line.off");
    ADD_FAILURE() << "a mesh without area was accepted";
  } catch (const solo::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("has an area"), std::string::npos) << e.what();
  }
}

TEST(MeshRepairCorpus, WrapIsClosedAndReportsItsDistances) {
  solo::MeshCleanupOptions options;
  options.wrap = true;
  const solo::StageReport r =
      cleanAndCheck(joined(sphere({0, 0, 0}, 1), sphere({1.2, 0, 0}, 1)), "wrap", Surface::MayDepart, kCaseTimeLimit_s, options);
  EXPECT_EQ(metricValue(r, "wrapped"), 1);
  EXPECT_GT(metricValue(r, "hausdorff_output_to_input_fraction"), 0);
}

TEST(MeshRepairCorpus, TimeLimitsAreReportedAndTheOutputStaysClosed) {
  const TriangleMesh spheres = joined(sphere({0, 0, 0}, 1), sphere({1.2, 0, 0}, 1));
  solo::MeshCleanupOptions options;
  options.intersection_repair.time_limit_s = 1e-9;  // the repair stops at once: the wrap takes over
  const solo::StageReport r = cleanAndCheck(spheres, "repair time limit", Surface::MayDepart, kCaseTimeLimit_s, options);
  EXPECT_EQ(metricValue(r, "intersection_repair_time_limit_hit"), 1);
  EXPECT_EQ(metricValue(r, "wrapped"), 1);
  bool said = false;
  for (const auto& w : r.warnings) said = said || w.find("stopped at its time limit") != std::string::npos;
  EXPECT_TRUE(said);

  options = {};
  options.wrap = true;
  options.wrapping.time_limit_s = 1e-9;  // the wrap asked for stops at once: the repair takes over
  const solo::StageReport w = cleanAndCheck(sphere({0, 0, 0}, 1), "wrap time limit", Surface::Kept, kCaseTimeLimit_s, options);
  EXPECT_EQ(metricValue(w, "wrap_time_limit_hit"), 1);
  EXPECT_EQ(metricValue(w, "wrapped"), 0);
}

// ---- the shared meshes -------------------------------------------------------------------

class SharedMeshRepair : public ::testing::TestWithParam<const char*> {};

// Without a wrap, every input point stays within 0.1 % of the diagonal (cleanAndCheck). The
// pig's file folds through itself at one quad: one vertex moved 0.015 % clears it.
TEST_P(SharedMeshRepair, ClosedManifoldAndFreeOfSelfIntersections) {
  const std::string relative = std::string("meshes/") + GetParam();
  const std::filesystem::path file = solo::test::sharedData(relative);
  if (file.empty()) GTEST_SKIP_("shared data meshes/ is absent (developer machines and CI only)");
  const solo::StageReport r = cleanAndCheck(solo::readMesh(file), GetParam(), Surface::Kept, 2 * kCaseTimeLimit_s + 20);
  EXPECT_EQ(metricValue(r, "wrapped"), 0) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Meshes, SharedMeshRepair,
                         ::testing::Values("beetle.off", "bun_zipper.ply", "camelhead.off", "elephant.off",
                                           "mech-holes-shark.off", "pig.off"),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                           std::string name = info.param;
                           name = name.substr(0, name.find('.'));
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

}  // namespace
