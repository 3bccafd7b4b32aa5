// Mesh metrics on small meshes whose answers can be counted by hand, the distance between a
// cube and its shifted copy computed analytically, and the shared real meshes.

#include <solo/core/error.h>
#include <solo/geometry/mesh_metrics.h>

#include "test_support.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace {

solo::TriangleMesh makeMesh(std::vector<Eigen::Vector3d> vertices, std::vector<std::array<std::uint32_t, 3>> faces) {
  solo::TriangleMesh m;
  m.vertices = std::move(vertices);
  m.faces = std::move(faces);
  return m;
}

/// Corner of the unit cube at the origin, right-angled: three right isosceles faces (angles
/// 90, 45, 45) and one equilateral face of side sqrt 2. Outward orientation.
solo::TriangleMesh tetrahedron() {
  return makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

/// Unit cube [0,1]^3 shifted by `dz` along z, 12 outward triangles.
solo::TriangleMesh cube(double dz = 0) {
  std::vector<Eigen::Vector3d> v;
  v.reserve(8);
  for (int i = 0; i < 8; ++i) v.emplace_back(i & 1, (i >> 1) & 1, ((i >> 2) & 1) + dz);
  return makeMesh(v, {{0, 2, 1},
                      {1, 2, 3},
                      {4, 5, 6},
                      {5, 7, 6},
                      {0, 1, 4},
                      {1, 5, 4},
                      {2, 6, 3},
                      {3, 6, 7},
                      {0, 4, 2},
                      {2, 4, 6},
                      {1, 3, 5},
                      {3, 7, 5}});
}

/// Appends `extra` to `mesh` (vertex indices of `extra` shifted).
solo::TriangleMesh merged(solo::TriangleMesh mesh, const solo::TriangleMesh& extra) {
  const auto offset = static_cast<std::uint32_t>(mesh.vertices.size());
  mesh.vertices.insert(mesh.vertices.end(), extra.vertices.begin(), extra.vertices.end());
  for (auto f : extra.faces) mesh.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
  return mesh;
}

/// Two triangles sharing only vertex 0 (a non-manifold vertex), far from everything else.
solo::TriangleMesh farBowTie() {
  return makeMesh({{100, 100, 100}, {101, 100, 100}, {100, 101, 100}, {99, 100, 100}, {100, 99, 100}},
                  {{0, 1, 2}, {0, 3, 4}});
}

}  // namespace

// V = 4, E = 6, F = 4: Euler characteristic 2, every edge has two faces.
// Aspect ratio sqrt(3) * l_max^2 / (4 A): right isosceles (legs 1): sqrt(3) * 2 / 2 = sqrt 3;
// equilateral: 1. Sorted {1, sqrt3, sqrt3, sqrt3}: median at position 1.5 and p95 at 2.85
// are sqrt 3. Minimum angle 45 degrees.
TEST(MeshMetrics, ClosedTetrahedron) {
  const solo::MeshMetrics m = solo::evaluateMesh(tetrahedron());
  EXPECT_EQ(m.vertices, 4);
  EXPECT_EQ(m.faces, 4);
  EXPECT_EQ(m.edges, 6);
  EXPECT_EQ(m.euler_characteristic, 2);
  EXPECT_EQ(m.components, 1);
  EXPECT_TRUE(m.closed);
  EXPECT_EQ(m.boundary_loops, 0);
  EXPECT_EQ(m.boundary_edges, 0);
  EXPECT_EQ(m.non_manifold_edges, 0);
  EXPECT_EQ(m.non_manifold_vertices, 0);
  EXPECT_EQ(m.self_intersecting_pairs, 0);
  EXPECT_EQ(m.degenerate_faces, 0);
  EXPECT_EQ(m.unreferenced_vertices, 0);
  EXPECT_EQ(m.self_intersection_check, solo::SelfIntersectionCheck::PolygonMesh);
  ASSERT_TRUE(m.quality.has_value());
  EXPECT_NEAR(m.quality->min_angle_deg, 45.0, 1e-12);
  EXPECT_NEAR(m.quality->aspect_ratio_min, 1.0, 1e-12);
  EXPECT_NEAR(m.quality->aspect_ratio_median, std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(m.quality->aspect_ratio_p95, std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(m.quality->aspect_ratio_max, std::sqrt(3.0), 1e-12);
}

// Unit square as 2 triangles: V 4, E 5 (4 sides + diagonal), F 2, Euler characteristic 1;
// the 4 sides are boundary edges forming one loop.
TEST(MeshMetrics, OpenSquareHasOneBoundaryLoopOfFourEdges) {
  const solo::MeshMetrics m =
      solo::evaluateMesh(makeMesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}}));
  EXPECT_FALSE(m.closed);
  EXPECT_EQ(m.boundary_loops, 1);
  EXPECT_EQ(m.boundary_edges, 4);
  EXPECT_EQ(m.edges, 5);
  EXPECT_EQ(m.euler_characteristic, 1);
  EXPECT_EQ(m.components, 1);
  EXPECT_EQ(m.non_manifold_vertices, 0);
  ASSERT_TRUE(m.quality.has_value());
  EXPECT_NEAR(m.quality->min_angle_deg, 45.0, 1e-12);
}

// Three triangles on edge (0, 1), fins in three directions: that edge has 3 faces; each fin
// adds 2 boundary edges (6); vertices 0 and 1 each have one fan (the faces are joined through
// the shared edge), so no vertex is non-manifold. Not a polygon mesh: checked as a soup.
TEST(MeshMetrics, EdgeSharedByThreeFacesIsNonManifold) {
  const solo::MeshMetrics m = solo::evaluateMesh(
      makeMesh({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 0, 1}, {0.5, -1, 0.5}}, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}}));
  EXPECT_EQ(m.non_manifold_edges, 1);
  EXPECT_EQ(m.non_manifold_vertices, 0);
  EXPECT_EQ(m.boundary_edges, 6);
  EXPECT_EQ(m.boundary_loops, 1);
  EXPECT_EQ(m.components, 1);
  EXPECT_EQ(m.edges, 7);
  EXPECT_EQ(m.self_intersecting_pairs, 0);
  EXPECT_EQ(m.self_intersection_check, solo::SelfIntersectionCheck::TriangleSoup);
}

// Bow-tie: two triangles sharing vertex 0 only. Vertex 0 has two fans: non-manifold. Each
// triangle is its own edge-connected component with its own boundary loop of 3 edges.
TEST(MeshMetrics, BowTieHasOneNonManifoldVertex) {
  const solo::MeshMetrics m = solo::evaluateMesh(farBowTie());
  EXPECT_EQ(m.non_manifold_vertices, 1);
  EXPECT_EQ(m.non_manifold_edges, 0);
  EXPECT_EQ(m.components, 2);
  EXPECT_EQ(m.boundary_loops, 2);
  EXPECT_EQ(m.boundary_edges, 6);
  EXPECT_EQ(m.euler_characteristic, 5 - 6 + 2);
  EXPECT_EQ(m.self_intersecting_pairs, 0);
  EXPECT_EQ(m.self_intersection_check, solo::SelfIntersectionCheck::TriangleSoup);
}

// Each case is checked twice: alone (a valid polygon mesh: CGAL PMP on a Surface_mesh) and with
// a far-away bow-tie added (no longer a polygon mesh: the soup check). Both must agree.
TEST(MeshMetrics, SelfIntersectionsAgreeBetweenPolygonMeshAndSoupChecks) {
  struct Case {
    const char* name;
    solo::TriangleMesh mesh;
    std::int64_t pairs;
  };
  const Case cases[] = {
      {"two triangles crossing, no shared vertex",
       makeMesh({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.3, 0.3, -1}, {0.3, 0.3, 1}, {0.6, 0.3, 0}},
                {{0, 1, 2}, {3, 4, 5}}),
       1},
      {"disjoint triangles",
       makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}}, {{0, 1, 2}, {3, 4, 5}}), 0},
      // Faces 0 and 2 share only vertex 0; face 1 joins them through edges 0-2 and 0-3 so that
      // vertex 0 is manifold. Face 2's edge opposite vertex 0, (1,0.5,-1)-(0.5,1,1), crosses z = 0
      // at (0.75, 0.75, 0), inside face 0. Edge-adjacent faces are not coplanar: no other pair.
      {"shared vertex, piercing",
       makeMesh({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {1, 0.5, -1}, {0.5, 1, 1}}, {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}}), 1},
      // Face 2 lies in the plane x + y + z = 0, which face 0's far edge (x + y = 2, z = 0) misses.
      {"shared vertex, touching only",
       makeMesh({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {-1, 0, 1}, {0, -1, 1}}, {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}}), 0},
      {"shared edge, folded flat onto each other",
       makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.3, 0.3, 0}}, {{0, 1, 2}, {1, 0, 3}}), 1},
      {"shared edge, hinge", makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, -1, 0.5}}, {{0, 1, 2}, {1, 0, 3}}), 0},
      {"same triangle twice, opposite orientations",
       makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 1}}), 1},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const solo::MeshMetrics alone = solo::evaluateMesh(c.mesh);
    EXPECT_EQ(alone.self_intersection_check, solo::SelfIntersectionCheck::PolygonMesh);
    EXPECT_EQ(alone.self_intersecting_pairs, c.pairs);
    EXPECT_EQ(alone.self_intersecting_faces, 2 * c.pairs);
    const solo::MeshMetrics soup = solo::evaluateMesh(merged(c.mesh, farBowTie()));
    EXPECT_EQ(soup.self_intersection_check, solo::SelfIntersectionCheck::TriangleSoup);
    EXPECT_EQ(soup.self_intersecting_pairs, c.pairs);
  }
  // The same triangle twice in the same orientation is no polygon mesh: a duplicated face.
  const solo::MeshMetrics duplicate =
      solo::evaluateMesh(makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 1, 2}}));
  EXPECT_EQ(duplicate.self_intersection_check, solo::SelfIntersectionCheck::TriangleSoup);
  EXPECT_EQ(duplicate.self_intersecting_pairs, 1);
  EXPECT_EQ(duplicate.non_manifold_edges, 0);
}

// A collinear triangle and a triangle with a repeated index are degenerate; they are left out
// of the quality figures and the self-intersection test. Vertex 6 is used by no face.
TEST(MeshMetrics, DegenerateFacesAndUnreferencedVertices) {
  const solo::MeshMetrics m =
      solo::evaluateMesh(makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 0, 0}, {6, 0, 0}, {7, 0, 0}, {9, 9, 9}},
                                  {{0, 1, 2}, {3, 4, 5}, {3, 3, 4}}));
  EXPECT_EQ(m.degenerate_faces, 2);
  EXPECT_EQ(m.unreferenced_vertices, 1);
  EXPECT_EQ(m.self_intersecting_pairs, 0);
  ASSERT_TRUE(m.quality.has_value());
  EXPECT_NEAR(m.quality->min_angle_deg, 45.0, 1e-12);
  EXPECT_NEAR(m.quality->aspect_ratio_max, std::sqrt(3.0), 1e-12);
  const solo::MeshMetrics only_degenerate =
      solo::evaluateMesh(makeMesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {{0, 1, 2}}));
  EXPECT_EQ(only_degenerate.degenerate_faces, 1);
  EXPECT_FALSE(only_degenerate.quality.has_value());
}

TEST(MeshMetrics, FaceWithAMissingVertexIsRejected) {
  EXPECT_THROW(solo::evaluateMesh(makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 3}})), std::invalid_argument);
}

// Cube A = [0,1]^3 and B = A + (0, 0, 0.1). Every point of A's bottom is 0.1 from B (straight up
// to B's bottom) and no point of A is farther: Hausdorff 0.1 both ways (symmetric by the
// reflection z -> 1.1 - z), attained at A's bottom vertices, so exact.
// Mean distance A -> B, integrated over A's 6 unit faces: bottom 0.1; top min(0.1, distance to
// the nearest side) = integral_0^0.1 (1 - 2t)^2 dt = (1 - 0.8^3) / 6 = 0.0813333; each side
// integral_0^0.1 (0.1 - z) dz = 0.005. Mean = (0.1 + 0.0813333 + 0.02) / 6 = 0.0335556, and
// the same B -> A, so Chamfer = 0.0335556. Monte Carlo with 20000 samples per direction: the
// per-point distance has a standard deviation of 0.045, so the Chamfer's is 0.045 / 200 = 2.2e-4.
TEST(MeshDistances, CubeAgainstShiftedCube) {
  solo::MeshDistanceOptions options;
  options.samples = 20000;
  options.seed = 3;
  const solo::MeshDistances d = solo::measureMeshDistances(cube(), cube(0.1), options);
  EXPECT_NEAR(d.hausdorff_to_reference, 0.1, 1e-12);
  EXPECT_NEAR(d.hausdorff_from_reference, 0.1, 1e-12);
  EXPECT_NEAR(d.hausdorff, 0.1, 1e-12);
  const double expected_mean = (0.1 + (1 - 0.512) / 6 + 0.02) / 6;
  EXPECT_NEAR(d.mean_to_reference, expected_mean, 1.5e-3);
  EXPECT_NEAR(d.mean_from_reference, expected_mean, 1.5e-3);
  EXPECT_NEAR(d.chamfer, expected_mean, 1.2e-3);
  EXPECT_DOUBLE_EQ(d.chamfer, (d.mean_to_reference + d.mean_from_reference) / 2);
  EXPECT_EQ(d.samples_per_direction, 20000);
  EXPECT_EQ(d.mesh_vertices_checked, 8);
  EXPECT_NEAR(d.reference_bbox_diagonal, std::sqrt(3.0), 1e-12);

  // Seeded: the same seed gives the same numbers, another seed different ones.
  const solo::MeshDistances again = solo::measureMeshDistances(cube(), cube(0.1), options);
  EXPECT_EQ(again.chamfer, d.chamfer);
  options.seed = 4;
  EXPECT_NE(solo::measureMeshDistances(cube(), cube(0.1), options).chamfer, d.chamfer);
}

TEST(MeshDistances, IdenticalMeshesAreZeroApart) {
  solo::MeshDistanceOptions options;
  options.samples = 2000;
  const solo::MeshDistances d = solo::measureMeshDistances(tetrahedron(), tetrahedron(), options);
  EXPECT_NEAR(d.hausdorff, 0.0, 1e-12);
  EXPECT_NEAR(d.chamfer, 0.0, 1e-12);
}

TEST(MeshDistances, MeshWithoutAreaIsAnInputErrorNamingTheFile) {
  const solo::TriangleMesh flat = makeMesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {{0, 1, 2}});
  try {
    solo::measureMeshDistances(cube(), flat, {}, "a.off", "ref.off");
    FAIL() << "no error";
  } catch (const solo::InputError& e) {
    EXPECT_EQ(std::string(e.what()), "ref.off: mesh has no face with non-zero area to measure distances on");
  }
  solo::MeshDistanceOptions no_samples;
  no_samples.samples = 0;
  EXPECT_THROW(solo::measureMeshDistances(cube(), cube(), no_samples), std::invalid_argument);
}

/// The square [0, width] x [0, 1] at height z, two triangles with normal +z.
solo::TriangleMesh square(double width = 1, double z = 0) {
  return makeMesh({{0, 0, z}, {width, 0, z}, {width, 1, z}, {0, 1, z}}, {{0, 1, 2}, {0, 2, 3}});
}

// Every point of a square is exactly d = 0.1 from the copy offset by d along the normal (its
// foot is inside the copy), both ways: P = R = F = 1 for any tau > d and 0 for any tau < d.
TEST(MeshFScore, SquareAgainstItsOffsetCopyIsAllOrNothingAtTheOffset) {
  solo::MeshDistanceOptions options;
  options.samples = 5000;
  options.tau = 0.1001;
  const solo::MeshDistances above = solo::measureMeshDistances(square(), square(1, 0.1), options);
  EXPECT_EQ(above.precision, 1.0);
  EXPECT_EQ(above.recall, 1.0);
  EXPECT_EQ(above.f_score, 1.0);
  EXPECT_EQ(above.tau, 0.1001);
  EXPECT_TRUE(above.tau_given);
  options.tau = 0.0999;
  const solo::MeshDistances below = solo::measureMeshDistances(square(), square(1, 0.1), options);
  EXPECT_EQ(below.precision, 0.0);
  EXPECT_EQ(below.recall, 0.0);
  EXPECT_EQ(below.f_score, 0.0);  // not NaN
}

// The left half of a square against the whole: every point of the half lies on the reference
// (P = 1); a reference point is within tau of the half when x < 0.5 + tau, so R = 0.5 + tau.
// With N = 20000 samples R's standard error is sqrt(0.25 / N) = 0.0035: checked within 4 of it.
TEST(MeshFScore, HalfCoveredReferenceHasRecallOneHalf) {
  solo::MeshDistanceOptions options;
  options.samples = 20000;
  options.seed = 7;
  options.tau = 1e-3;
  const solo::MeshDistances d = solo::measureMeshDistances(square(0.5), square(), options);
  EXPECT_EQ(d.precision, 1.0);
  EXPECT_NEAR(d.recall, 0.501, 0.014);
  EXPECT_DOUBLE_EQ(d.f_score, 2 * d.precision * d.recall / (d.precision + d.recall));
  // Swapping the roles swaps precision and recall.
  const solo::MeshDistances swapped = solo::measureMeshDistances(square(), square(0.5), options);
  EXPECT_NEAR(swapped.precision, 0.501, 0.014);
  EXPECT_EQ(swapped.recall, 1.0);
}

// Default tau: 1 % of the reference's bounding-box diagonal, sqrt(3) / 100 for the unit cube.
// Cube A against B = A shifted by 0.1 along z, tau < 0.1: A's bottom is 0.1 below B (never
// within); a point of A's top lies inside B, min(x, 1-x, y, 1-y) from B's sides (within on
// 1 - (1 - 2 tau)^2 of it); a side point at height z is 0.1 - z from B for z < 0.1, on B above
// (within on 0.9 + tau of it). P = (1 - (1 - 2 tau)^2 + 4 (0.9 + tau)) / 6 = 0.622894, and R
// the same by symmetry; standard error sqrt(0.62 0.38 / 20000) = 0.0034, checked within 0.015.
TEST(MeshFScore, DefaultTauIsOnePercentOfTheReferenceDiagonal) {
  solo::MeshDistanceOptions options;
  options.samples = 20000;
  options.seed = 3;
  const solo::MeshDistances d = solo::measureMeshDistances(cube(), cube(0.1), options);
  const double tau = std::sqrt(3.0) * solo::kDefaultFScoreTauFraction;
  EXPECT_NEAR(d.tau, tau, 1e-15);
  EXPECT_FALSE(d.tau_given);
  const double expected = (1 - std::pow(1 - 2 * tau, 2) + 4 * (0.9 + tau)) / 6;
  EXPECT_NEAR(d.precision, expected, 0.015);
  EXPECT_NEAR(d.recall, expected, 0.015);
  EXPECT_NEAR(d.f_score, expected, 0.015);
}

TEST(MeshFScore, TauMustBePositiveAndFinite) {
  for (const double tau : {0.0, -1.0, std::nan(""), HUGE_VAL}) {
    solo::MeshDistanceOptions options;
    options.tau = tau;
    EXPECT_THROW(solo::measureMeshDistances(square(), square(), options), std::invalid_argument) << tau;
  }
}

// Hole counts from ../shared/data/README.md. The Euler characteristic 2 - 2 genus - holes then
// says the open ones are spheres with holes (genus 0).
TEST(MeshMetricsSharedData, PigHasSevenHoles) {
  SOLO_REQUIRE_SHARED_DATA(file, "meshes/pig.off");
  const solo::MeshMetrics m = solo::evaluateMesh(solo::readMesh(file));
  EXPECT_EQ(m.boundary_loops, 7);
  EXPECT_FALSE(m.closed);
  EXPECT_EQ(m.euler_characteristic, 2 - 7);
  EXPECT_EQ(m.components, 1);
  EXPECT_EQ(m.non_manifold_edges + m.non_manifold_vertices, 0);
  // The soup check finds the same self-intersections as PMP on the Surface_mesh.
  const solo::MeshMetrics soup = solo::evaluateMesh(merged(solo::readMesh(file), farBowTie()));
  EXPECT_EQ(soup.self_intersection_check, solo::SelfIntersectionCheck::TriangleSoup);
  EXPECT_EQ(soup.self_intersecting_pairs, m.self_intersecting_pairs);
  EXPECT_EQ(soup.boundary_loops, 7 + 2);
}

TEST(MeshMetricsSharedData, SharkHasFourHoles) {
  SOLO_REQUIRE_SHARED_DATA(file, "meshes/mech-holes-shark.off");
  const solo::MeshMetrics m = solo::evaluateMesh(solo::readMesh(file));
  EXPECT_EQ(m.boundary_loops, 4);
  EXPECT_EQ(m.euler_characteristic, 2 - 4);
  EXPECT_EQ(m.self_intersecting_pairs, 0);
}

TEST(MeshMetricsSharedData, ElephantIsClosed) {
  SOLO_REQUIRE_SHARED_DATA(file, "meshes/elephant.off");
  const solo::MeshMetrics m = solo::evaluateMesh(solo::readMesh(file));
  EXPECT_TRUE(m.closed);
  EXPECT_EQ(m.boundary_loops, 0);
  EXPECT_EQ(m.boundary_edges, 0);
  EXPECT_EQ(m.edges * 2, m.faces * 3);  // closed and manifold: every edge has two faces
  EXPECT_EQ(m.euler_characteristic, m.vertices - m.edges + m.faces);
  EXPECT_EQ(m.non_manifold_edges + m.non_manifold_vertices, 0);
}

TEST(MeshMetricsSharedData, BunnyScanHasFiveHolesAndUnreferencedVertices) {
  SOLO_REQUIRE_SHARED_DATA(file, "meshes/bun_zipper.ply");
  const solo::MeshMetrics m = solo::evaluateMesh(solo::readMesh(file));
  EXPECT_EQ(m.vertices, 35947);
  EXPECT_EQ(m.unreferenced_vertices, 1113);
  EXPECT_EQ(m.boundary_loops, 5);
  EXPECT_EQ(m.euler_characteristic, 2 - 5);
}
