// Hole filling and generic mesh cleanup (solo mesh clean): every hard case (holes sharing a vertex,
// strongly non-planar and sliver-only boundaries, fillings that would self-intersect,
// non-manifold parts, NaN coordinates) on small hand-built meshes, and the real meshes with holes
// from ../shared/data/meshes.

#include <solo/geometry/boundary_loops.h>
#include <solo/geometry/hole_filling.h>
#include <solo/core/error.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/geometry/mesh_holes.h>
#include <solo/geometry/mesh_metrics.h>
#include <solo/geometry/surface_mesh.h>

#include "test_support.h"

#include <cmath>
#include <random>
#include <limits>
#include <future>
#include <optional>
#include <set>
#include <thread>

namespace {

using solo::TriangleMesh;

using solo::test::metricInt;

/// Unit cube, 12 outward triangles.
TriangleMesh cube() {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) m.vertices.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  m.faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

/// An n x n grid of unit squares in the plane z = height(x, y), two triangles per square,
/// squares listed in `skip` (as x + n * y) left out.
TriangleMesh grid(int n, const std::set<int>& skip, double (*height)(double, double)) {
  TriangleMesh m;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) m.vertices.emplace_back(x, y, height(x, y));
  const auto id = [n](int x, int y) { return static_cast<std::uint32_t>(x + (n + 1) * y); };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      if (skip.count(x + n * y)) continue;
      m.faces.push_back({id(x, y), id(x + 1, y), id(x + 1, y + 1)});
      m.faces.push_back({id(x, y), id(x + 1, y + 1), id(x, y + 1)});
    }
  return m;
}

double flat(double, double) { return 0.0; }
double saddle(double x, double y) { return 0.35 * (x - 3) * (y - 3); }

TEST(HoleFilling, OneTriangleHoleIsClosedWithOneTriangle) {
  TriangleMesh m = cube();
  m.faces.pop_back();
  solo::StageReport report;
  const TriangleMesh out = solo::cleanMesh(m, {}, report);
  EXPECT_EQ(metricInt(report, "holes_found"), 1);
  EXPECT_EQ(metricInt(report, "holes_filled"), 1);
  EXPECT_EQ(metricInt(report, "hole_faces_added"), 1);
  EXPECT_EQ(out.faces.size(), 12u);
  const solo::MeshMetrics after = solo::evaluateMesh(out);
  EXPECT_TRUE(after.closed);
  EXPECT_EQ(after.self_intersecting_pairs, 0);
}

TEST(HoleFilling, ClosedMeshIsLeftUnchanged) {
  const TriangleMesh m = cube();
  solo::StageReport report;
  const TriangleMesh out = solo::cleanMesh(m, {}, report);
  EXPECT_EQ(metricInt(report, "holes_found"), 0);
  ASSERT_EQ(out.vertices.size(), m.vertices.size());
  for (std::size_t i = 0; i < m.vertices.size(); ++i) EXPECT_EQ(out.vertices[i], m.vertices[i]);
  // Same triangles (a face may start at another corner, never reversed).
  const auto canonical = [](std::array<std::uint32_t, 3> f) {
    while (f[0] != std::min({f[0], f[1], f[2]})) f = {f[1], f[2], f[0]};
    return f;
  };
  std::set<std::array<std::uint32_t, 3>> in_faces, out_faces;
  for (const auto& f : m.faces) in_faces.insert(canonical(f));
  for (const auto& f : out.faces) out_faces.insert(canonical(f));
  EXPECT_EQ(in_faces, out_faces);
}

TEST(HoleFilling, EmptyMeshIsSkippedWithReason) {
  solo::StageReport report;
  const TriangleMesh out = solo::cleanMesh(TriangleMesh{}, {}, report);
  EXPECT_TRUE(report.skipped);
  EXPECT_NE(report.skip_reason.find("no face"), std::string::npos);
  EXPECT_TRUE(out.faces.empty());
}

TEST(HoleFilling, NanCoordinateIsAClearError) {
  TriangleMesh m = cube();
  m.vertices[3].y() = std::numeric_limits<double>::quiet_NaN();
  solo::StageReport report;
  try {
    solo::cleanMesh(m, {}, report, "broken.off");
    FAIL() << "expected InputError";
  } catch (const solo::InputError& e) {
    EXPECT_EQ(e.file(), "broken.off");
    EXPECT_NE(e.problem().find("non-finite"), std::string::npos);
  }
}

TEST(HoleFilling, TwoHolesSharingAVertexAreBothFilled) {
  // Squares (1,1) and (2,2) of a 4x4 grid touch at the vertex (2,2): two holes, one pinch.
  const TriangleMesh m = grid(4, {1 + 4 * 1, 2 + 4 * 2}, flat);
  const solo::MeshMetrics before = solo::evaluateMesh(m);
  EXPECT_EQ(before.non_manifold_vertices, 1);
  solo::SurfaceMesh mesh = solo::toSurfaceMesh(m);
  std::vector<solo::VertexLoop> holes;
  for (const auto& loop : solo::findBoundaryLoops(mesh))
    if (loop.size() == 4) holes.push_back(loop);
  ASSERT_EQ(holes.size(), 2u);
  const solo::HoleClosing closing = solo::closeHoles(mesh, holes, {});
  EXPECT_EQ(closing.filled, 2);
  EXPECT_EQ(closing.left_open, 0);
  mesh.garbage_collection();
  const solo::MeshMetrics after = solo::evaluateMesh(solo::toTriangleMesh(mesh));
  EXPECT_EQ(after.non_manifold_vertices, 0);
  EXPECT_EQ(after.boundary_loops, 1);  // only the grid's outer border
  EXPECT_EQ(after.self_intersecting_pairs, 0);
}

TEST(HoleFilling, SmallHoleGetsTheTriangulationOnly) {
  // One missing square of a flat grid: a 4-vertex hole is closed by two triangles, no new vertex
  // (refinement and fairing are kept for holes over max_triangulation_only_vertices).
  const TriangleMesh m = grid(4, {1 + 4 * 2}, flat);
  solo::SurfaceMesh mesh = solo::toSurfaceMesh(m);
  std::vector<solo::VertexLoop> holes;
  for (const auto& loop : solo::findBoundaryLoops(mesh))
    if (loop.size() == 4) holes.push_back(loop);
  ASSERT_EQ(holes.size(), 1u);
  const solo::HoleClosing closing = solo::closeHoles(mesh, holes, {});
  EXPECT_EQ(closing.filled, 1);
  EXPECT_EQ(closing.by_triangulation, 1);
  EXPECT_EQ(closing.by_refine_fair, 0);
  EXPECT_EQ(closing.faces_added, 2);
  EXPECT_EQ(closing.vertices_added, 0);
  mesh.garbage_collection();
  const solo::MeshMetrics after = solo::evaluateMesh(solo::toTriangleMesh(mesh));
  EXPECT_EQ(after.boundary_loops, 1);
  EXPECT_EQ(after.self_intersecting_pairs, 0);
}

TEST(HoleFilling, StronglyNonPlanarBoundaryIsFilledSmoothly) {
  // A saddle z = 0.35 (x-3)(y-3) with a 2x2 hole at its centre: the boundary's corners rise and
  // fall by 0.35 while its edges stay flat.
  const TriangleMesh m = grid(6, {2 + 6 * 2, 3 + 6 * 2, 2 + 6 * 3, 3 + 6 * 3}, saddle);
  solo::SurfaceMesh mesh = solo::toSurfaceMesh(m);
  std::vector<solo::VertexLoop> holes;
  for (const auto& loop : solo::findBoundaryLoops(mesh))
    if (loop.size() == 8) holes.push_back(loop);
  ASSERT_EQ(holes.size(), 1u);
  const solo::HoleClosing closing = solo::closeHoles(mesh, holes, {});
  // Refinement at the boundary's unit edge length adds no vertex to a 2x2 hole: the patch is its
  // triangulation, and is counted as one.
  EXPECT_EQ(closing.filled, 1);
  EXPECT_EQ(closing.by_triangulation, 1);
  EXPECT_EQ(closing.vertices_added, 0);
  mesh.garbage_collection();
  const TriangleMesh out = solo::toTriangleMesh(mesh);
  const solo::MeshMetrics after = solo::evaluateMesh(out);
  EXPECT_EQ(after.boundary_loops, 1);
  EXPECT_EQ(after.self_intersecting_pairs, 0);
  EXPECT_EQ(after.degenerate_faces, 0);
  // The patch stays within the boundary's height range (+-0.35) and over the hole.
  EXPECT_EQ(out.vertices.size(), 49u - 1u + static_cast<std::size_t>(closing.vertices_added));
  for (std::size_t i = 48; i < out.vertices.size(); ++i) {
    EXPECT_LE(std::abs(out.vertices[i].z()), 0.35 + 1e-9);
    EXPECT_GE(out.vertices[i].x(), 2.0);
    EXPECT_LE(out.vertices[i].x(), 4.0);
  }
}

TEST(HoleFilling, SliverOnlyBoundaryIsLeftOpenWithAWarning) {
  // Three collinear boundary points: every triangle over them is degenerate.
  const std::vector<Eigen::Vector3d> boundary = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  for (const auto method : {solo::HoleFillMethod::TriangulateRefineFair, solo::HoleFillMethod::CentroidFan}) {
    const solo::HolePatch patch = solo::fillHolePolyline(boundary, method);
    EXPECT_FALSE(patch.filled);
    EXPECT_NE(patch.failure.find("collinear"), std::string::npos);
  }
  // In a mesh: a crack A-B-C closed below by one face A-Q-C.
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {1, 1, 0}, {1, -1, 0}};
  m.faces = {{0, 1, 3}, {1, 2, 3}, {0, 4, 2}};
  solo::SurfaceMesh mesh = solo::toSurfaceMesh(m);
  std::vector<solo::VertexLoop> holes;
  for (const auto& loop : solo::findBoundaryLoops(mesh))
    if (loop.size() == 3) holes.push_back(loop);
  ASSERT_EQ(holes.size(), 1u);
  const solo::HoleClosing closing = solo::closeHoles(mesh, holes, {});
  EXPECT_EQ(closing.left_open, 1);
  EXPECT_EQ(closing.faces_added, 0);
  ASSERT_EQ(closing.warnings.size(), 1u);
  EXPECT_NE(closing.warnings[0].find("collinear"), std::string::npos);
}

TEST(HoleFilling, FillingThatWouldSelfIntersectIsRejected) {
  // A flat 4x4 grid with a 2x2 hole, and a separate vertical triangle standing through the
  // hole's centre: every filling in the plane would cut it.
  TriangleMesh m = grid(4, {1 + 4 * 1, 2 + 4 * 1, 1 + 4 * 2, 2 + 4 * 2}, flat);
  const auto base = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.emplace_back(1.6, 2.0, -0.5);
  m.vertices.emplace_back(2.4, 2.0, -0.5);
  m.vertices.emplace_back(2.0, 2.0, 0.5);
  m.faces.push_back({base, base + 1, base + 2});
  solo::SurfaceMesh mesh = solo::toSurfaceMesh(m);
  std::vector<solo::VertexLoop> holes;
  for (const auto& loop : solo::findBoundaryLoops(mesh))
    if (loop.size() == 8) holes.push_back(loop);
  ASSERT_EQ(holes.size(), 1u);
  const solo::HoleClosing closing = solo::closeHoles(mesh, holes, {});
  EXPECT_EQ(closing.filled, 0);
  EXPECT_EQ(closing.left_open, 1);
  EXPECT_EQ(closing.patches_rejected_for_intersection, 3);  // each method tried and refused
  ASSERT_EQ(closing.warnings.size(), 1u);
  EXPECT_NE(closing.warnings[0].find("intersects"), std::string::npos);
  EXPECT_EQ(solo::evaluateMesh(solo::toTriangleMesh(mesh)).self_intersecting_pairs, 0);
}

// Patches as image-space hole filling makes them: a grid of pixel positions lifted along the
// camera's rays (focal 100 px, centre 0) to a depth tilted across the patch, so that its faces
// lie over disjoint triangles of the image and never meet one another. Appends to points and
// faces.
void addImagePatch(std::vector<Eigen::Vector3d>& points, std::vector<std::array<int, 3>>& faces, int u0, int v0,
                   int size, double depth_m, double tilt_m_per_px) {
  const int base = static_cast<int>(points.size());
  for (int y = 0; y <= size; ++y)
    for (int x = 0; x <= size; ++x) {
      const double u = u0 + x, v = v0 + y, z = depth_m + tilt_m_per_px * (x - y);
      points.emplace_back(u / 100.0 * z, v / 100.0 * z, z);
    }
  const auto id = [&](int x, int y) { return base + x + (size + 1) * y; };
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      faces.push_back({id(x, y), id(x + 1, y), id(x + 1, y + 1)});
      faces.push_back({id(x, y), id(x + 1, y + 1), id(x, y + 1)});
    }
}

// Faces grouped by patch are tested only against the other patches, the ungrouped faces and
// the mesh: on patches that do not meet themselves the answer is the ungrouped test's, face for
// face, over 20 seeded sets of overlapping patches at crossing depths and loose triangles.
TEST(HoleFilling, GroupedPatchesFindTheSameIntersectionsAsAllPairs) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> corner(-20, 10), size(4, 12);
  std::uniform_real_distribution<double> depth(4.0, 6.0), tilt(-0.1, 0.1), jitter(-0.5, 0.5);
  std::int64_t hits = 0, grouped_faces = 0;
  for (int set = 0; set < 20; ++set) {
    std::vector<Eigen::Vector3d> points;
    std::vector<std::array<int, 3>> candidates, others;
    std::vector<int> group;
    for (int patch = 0; patch < 4; ++patch) {
      addImagePatch(points, candidates, corner(rng), corner(rng), size(rng), depth(rng), tilt(rng));
      group.resize(candidates.size(), patch);
    }
    grouped_faces += static_cast<std::int64_t>(candidates.size());
    for (int loose = 0; loose < 6; ++loose) {  // ungrouped faces: any triangle
      for (int k = 0; k < 3; ++k) points.emplace_back(jitter(rng) * 2, jitter(rng) * 2, 5.0 + jitter(rng) * 2);
      const int n = static_cast<int>(points.size());
      candidates.push_back({n - 3, n - 2, n - 1});
      group.push_back(-1);
    }
    addImagePatch(points, others, -5, -5, 10, 5.0, 0.05);  // the mesh
    const auto all_pairs = solo::findIntersectingFaces(points, candidates, others);
    const auto by_group = solo::findIntersectingFaces(points, candidates, others, true, group);
    ASSERT_EQ(all_pairs.size(), by_group.size());
    for (std::size_t i = 0; i < all_pairs.size(); ++i) {
      EXPECT_EQ(all_pairs[i], by_group[i]) << "set " << set << ", face " << i << " of group " << group[i];
      hits += all_pairs[i];
    }
  }
  // Not a vacuous comparison: hundreds of faces cross another patch or the mesh.
  EXPECT_GT(hits, grouped_faces / 50);
  EXPECT_LT(hits, grouped_faces);
}

// The grouping is a promise: two crossing faces given one group are not tested against each
// other; in two groups, or ungrouped, they are found.
TEST(HoleFilling, FacesOfOneGroupAreNotTestedAgainstEachOther) {
  const std::vector<Eigen::Vector3d> points = {{0, 0, 0}, {2, 0, 0}, {1, 2, 0}, {1, 1, -1}, {1, 1, 1}, {1, -1, 0.5}};
  const std::vector<std::array<int, 3>> crossing = {{0, 1, 2}, {3, 4, 5}};
  const auto ungrouped = solo::findIntersectingFaces(points, crossing, {});
  EXPECT_EQ(ungrouped, (std::vector<std::uint8_t>{1, 1}));
  EXPECT_EQ(solo::findIntersectingFaces(points, crossing, {}, true, {0, 1}), ungrouped);
  EXPECT_EQ(solo::findIntersectingFaces(points, crossing, {}, true, {-1, 0}), ungrouped);
  EXPECT_EQ(solo::findIntersectingFaces(points, crossing, {}, true, {3, 3}), (std::vector<std::uint8_t>{0, 0}));
  EXPECT_EQ(solo::findIntersectingFaces(points, crossing, {}, false), (std::vector<std::uint8_t>{0, 0}));
}

TEST(HoleFilling, NonManifoldAndDuplicatePartsAreRepaired) {
  TriangleMesh m = cube();
  m.faces.push_back({0, 2, 1});          // the first face again
  m.vertices.emplace_back(5, 5, 5);      // vertex 8: used by no face
  m.vertices.push_back(m.vertices[7]);   // vertex 9: a copy of vertex 7...
  m.faces.push_back({3, 6, 9});          // ...making a copy of face {3, 6, 7} once merged
  solo::StageReport report;
  const TriangleMesh out = solo::cleanMesh(m, {}, report);
  EXPECT_EQ(metricInt(report, "duplicate_points_merged"), 1);
  EXPECT_EQ(metricInt(report, "duplicate_faces_removed"), 2);
  EXPECT_EQ(metricInt(report, "unreferenced_vertices_removed"), 1);
  const solo::MeshMetrics after = solo::evaluateMesh(out);
  EXPECT_TRUE(after.closed);
  EXPECT_EQ(after.non_manifold_edges, 0);
  EXPECT_EQ(after.unreferenced_vertices, 0);
}

struct SharedMesh {
  const char* file;
  std::int64_t holes, filled;
};

class SharedMeshes : public ::testing::TestWithParam<SharedMesh> {};

TEST_P(SharedMeshes, AllHolesClosedWithoutNewSelfIntersections) {
  const SharedMesh& c = GetParam();
  const std::filesystem::path file = solo::test::sharedData(std::string("meshes/") + c.file);
  if (file.empty()) GTEST_SKIP_("shared data meshes/ is absent (developer machines and CI only)");
  solo::StageReport report;
  const TriangleMesh in = solo::readMesh(file);
  const TriangleMesh out = solo::cleanMesh(in, {}, report, file);
  EXPECT_EQ(metricInt(report, "holes_found"), c.holes);
  EXPECT_EQ(metricInt(report, "holes_filled"), c.filled);
  EXPECT_EQ(metricInt(report, "after_boundary_loops_total"), c.holes - c.filled);
  EXPECT_EQ(metricInt(report, "after_non_manifold_edges"), 0);
  EXPECT_EQ(metricInt(report, "after_non_manifold_vertices"), 0);
  EXPECT_EQ(metricInt(report, "after_degenerate_faces"), 0);
  // Some inputs already self-intersect (pig 3 pairs, beetle 5, camelhead 5): none is added (the
  // beetle's 5 are faces at two pinch points of its largest hole, merged by the repair: 0 after).
  EXPECT_LE(metricInt(report, "after_self_intersecting_pairs"), metricInt(report, "before_self_intersecting_pairs"));
  EXPECT_EQ(solo::evaluateMesh(out).closed, c.holes == c.filled);
}

INSTANTIATE_TEST_SUITE_P(Meshes, SharedMeshes,
                         // The beetle's largest hole (512 boundary vertices) passes twice through two
                         // positions: merged, it is a 464-vertex hole and two of 24, all closed
                         // (the 464-vertex one in pieces: test_large_holes.cpp).
                         ::testing::Values(SharedMesh{"mech-holes-shark.off", 4, 4}, SharedMesh{"pig.off", 7, 7},
                                           SharedMesh{"beetle.off", 13, 13}, SharedMesh{"camelhead.off", 1, 1},
                                           SharedMesh{"bun_zipper.ply", 5, 5}, SharedMesh{"elephant.off", 0, 0}),
                         [](const auto& info) {
                           std::string name = info.param.file;
                           return name.substr(0, name.find_first_of(".-"));
                         });

TEST(SharedMeshesBunny, UnreferencedVerticesAreDropped) {
  SOLO_REQUIRE_SHARED_DATA(file, "meshes/bun_zipper.ply");
  solo::StageReport report;
  solo::cleanMesh(solo::readMesh(file), {}, report, file);
  EXPECT_EQ(metricInt(report, "before_unreferenced_vertices"), 1113);
  EXPECT_EQ(metricInt(report, "unreferenced_vertices_removed"), 1113);
  EXPECT_EQ(metricInt(report, "after_unreferenced_vertices"), 0);
}

}  // namespace

// OpenMesh's error stream is silenced while any guard lives, on any thread, and restored (to
// what it was) when the last one ends.
TEST(SurfaceMesh, QuietOpenMeshErrorsNestsAndRestoresTheStreamAcrossThreads) {
  ASSERT_TRUE(omerr().is_enabled());
  std::optional<solo::QuietOpenMeshErrors> outer;
  outer.emplace();
  EXPECT_FALSE(omerr().is_enabled());
  {
    const solo::QuietOpenMeshErrors nested;
    EXPECT_FALSE(omerr().is_enabled());
  }
  EXPECT_FALSE(omerr().is_enabled()) << "the outer guard still lives";
  std::promise<void> inner_made, outer_gone;
  bool quiet_after_outer = false;
  std::thread other([&] {
    const solo::QuietOpenMeshErrors inner;
    inner_made.set_value();
    outer_gone.get_future().wait();
    quiet_after_outer = !omerr().is_enabled();
  });
  inner_made.get_future().wait();
  outer.reset();
  outer_gone.set_value();
  other.join();
  EXPECT_TRUE(quiet_after_outer) << "the other thread's guard outlived the first one";
  EXPECT_TRUE(omerr().is_enabled()) << "restored when the last guard ended";
  omerr().disable();
  { const solo::QuietOpenMeshErrors guard; }
  EXPECT_FALSE(omerr().is_enabled()) << "a stream that was off stays off";
  omerr().enable();
}

TEST(SurfaceMesh, CollectGarbageMatchesOpenMeshsOwnAndKeepsTheImageProperties) {
  // collectGarbage instantiates OpenMesh's compaction in solo (Debian's library runs it with
  // its assertions on): the same mesh as OpenMesh's garbage_collection(), element for element,
  // with the per-vertex image properties moved along with their vertices.
  const TriangleMesh m = grid(5, {}, flat);  // 6 x 6 vertices
  solo::SurfaceMesh ours = solo::toSurfaceMesh(m);
  const solo::ImageVertexProperties props = solo::ImageVertexProperties::getOrAdd(ours);
  for (const auto v : ours.vertices()) {
    ours.property(props.pixel, v) = OpenMesh::Vec2i(v.idx() % 6, v.idx() / 6);
    ours.property(props.instance, v) = 1000 + v.idx();
  }
  // Delete a vertex inside (its fan goes with it) and one face elsewhere.
  ours.delete_vertex(OpenMesh::VertexHandle(2 + 6 * 2), true);
  ours.delete_face(OpenMesh::FaceHandle(0), true);
  solo::SurfaceMesh theirs = ours;
  solo::collectGarbage(ours);
  theirs.garbage_collection();
  ASSERT_EQ(ours.n_vertices(), theirs.n_vertices());
  ASSERT_EQ(ours.n_faces(), theirs.n_faces());
  ASSERT_EQ(ours.n_edges(), theirs.n_edges());
  EXPECT_EQ(ours.n_vertices(), 35u);
  EXPECT_EQ(ours.n_faces(), 2u * 25u - 6u - 1u);  // the vertex's six faces and one more
  for (const auto v : ours.vertices()) {
    EXPECT_EQ(ours.point(v), theirs.point(v));
    const OpenMesh::Vec2i pixel = ours.property(props.pixel, v);
    EXPECT_EQ(ours.property(props.instance, v), 1000 + pixel[0] + 6 * pixel[1]) << v.idx();
    EXPECT_EQ(ours.point(v)[0], m.vertices[static_cast<std::size_t>(pixel[0] + 6 * pixel[1])].x()) << v.idx();
  }
  for (const auto f : ours.faces()) {
    std::vector<int> a, b;
    for (const auto v : ours.fv_range(f)) a.push_back(v.idx());
    for (const auto v : theirs.fv_range(OpenMesh::FaceHandle(f.idx()))) b.push_back(v.idx());
    EXPECT_EQ(a, b) << f.idx();
  }
}
