#pragma once
// Mesh evaluation: topology (components, boundary loops, manifoldness), defects
// (self-intersections, degenerate faces, unreferenced vertices), triangle quality, and the
// distance to a reference mesh (Hausdorff both ways, Chamfer, and precision, recall and F-score
// at a distance threshold as Tanks and Temples defines them). Works on any soup,
// non-manifold ones included. Definitions: docs/evaluation.md. Lengths are in the mesh's
// units (metres for solo's meshes).

#include "solo/geometry/triangle_mesh.h"

#include <cstdint>
#include <filesystem>
#include <optional>

namespace solo {

/// Triangle shape over the non-degenerate faces.
struct TriangleQuality {
  double min_angle_deg = 0;  ///< smallest interior angle of any face, degrees
  /// Aspect ratio sqrt(3) * longest_edge^2 / (4 * area): 1 for an equilateral triangle,
  /// sqrt(3) for a right isosceles one, growing without bound for slivers. Median and p95
  /// are NumPy's linear-interpolation quantiles.
  double aspect_ratio_min = 0, aspect_ratio_median = 0, aspect_ratio_p95 = 0, aspect_ratio_max = 0;
};

/// How self-intersections were found.
enum class SelfIntersectionCheck {
  PolygonMesh,   ///< the soup is a valid polygon mesh: CGAL PMP self_intersections on a Surface_mesh
  TriangleSoup,  ///< it is not: the same rules on the soup (CGAL 5.5 has no soup version)
};
const char* selfIntersectionCheckName(SelfIntersectionCheck check);

struct MeshMetrics {
  std::int64_t vertices = 0, faces = 0;    ///< as stored
  std::int64_t unreferenced_vertices = 0;  ///< vertices no face uses
  /// Faces with a repeated vertex index or three collinear corners (exact predicate).
  std::int64_t degenerate_faces = 0;
  // Topology, over the faces with three distinct vertex indices:
  std::int64_t edges = 0;                  ///< distinct undirected edges
  std::int64_t euler_characteristic = 0;   ///< V - E + F (V: vertices those faces use)
  std::int64_t components = 0;             ///< sets of faces connected through shared edges
  std::int64_t boundary_edges = 0;         ///< edges with exactly one face
  std::int64_t boundary_loops = 0;         ///< connected chains of boundary edges, non-manifold vertices split per fan
  bool closed = false;                     ///< at least one face and no boundary edge
  std::int64_t non_manifold_edges = 0;     ///< edges with more than two faces
  std::int64_t non_manifold_vertices = 0;  ///< vertices whose faces form more than one edge-connected fan
  // Self-intersections, between non-degenerate faces:
  std::int64_t self_intersecting_pairs = 0;  ///< face pairs that meet other than in a shared edge or vertex
  std::int64_t self_intersecting_faces = 0;  ///< faces in at least one such pair
  SelfIntersectionCheck self_intersection_check = SelfIntersectionCheck::PolygonMesh;
  std::optional<TriangleQuality> quality;  ///< none when no face is non-degenerate
};

/// Topology, defects and triangle quality of a triangle soup. Throws std::invalid_argument
/// when a face refers to a vertex that does not exist.
MeshMetrics evaluateMesh(const TriangleMesh& mesh);

/// The F-score threshold when none is given, as a fraction of the reference's bounding-box
/// diagonal (the "F-score at 1 %" of shape reconstruction; docs/evaluation.md says why).
inline constexpr double kDefaultFScoreTauFraction = 0.01;

struct MeshDistanceOptions {
  std::int64_t samples = 100000;  ///< random surface points per direction (area-uniform), > 0
  std::uint64_t seed = 0;         ///< seeds the sampling (std::mt19937_64)
  /// Distance threshold of precision, recall and F-score, mesh units, finite and > 0; unset:
  /// kDefaultFScoreTauFraction times the reference's bounding-box diagonal.
  std::optional<double> tau;
};

/// Distances between two surfaces (their non-degenerate faces), in mesh units. d(x, S) is the
/// exact distance from point x to the nearest point of surface S (CGAL AABB tree).
struct MeshDistances {
  double hausdorff_to_reference = 0;            ///< max d(x, reference) over x on the mesh
  double hausdorff_from_reference = 0;          ///< max d(y, mesh) over y on the reference
  double hausdorff = 0;                         ///< the larger of the two (symmetric Hausdorff)
  double mean_to_reference = 0;                 ///< mean d(x, reference) over the mesh's random samples
  double mean_from_reference = 0;               ///< mean d(y, mesh) over the reference's random samples
  double chamfer = 0;                           ///< (mean_to_reference + mean_from_reference) / 2
  std::int64_t samples_per_direction = 0;       ///< random points drawn on each surface
  std::int64_t mesh_vertices_checked = 0;       ///< mesh vertices added to the maximum's points
  std::int64_t reference_vertices_checked = 0;  ///< reference vertices added likewise
  double reference_bbox_diagonal = 0;           ///< for relative figures (distance / diagonal)
  // Tanks and Temples (Knapitsch et al. 2017), over the random samples only:
  double tau = 0;          ///< the distance threshold used, mesh units
  bool tau_given = false;  ///< false: the default fraction of reference_bbox_diagonal
  double precision = 0;    ///< share of the mesh's samples x with d(x, reference) < tau
  double recall = 0;       ///< share of the reference's samples y with d(y, mesh) < tau
  double f_score = 0;      ///< 2 P R / (P + R), 0 when both are 0
};

/// Samples each surface (area-uniform random points, seeded) and measures their distance to
/// the other. The maxima also include every vertex of a non-degenerate face, so a Hausdorff
/// distance attained at a vertex is exact; the means use the random samples only (an unbiased
/// estimate of the area-weighted mean), and so do precision, recall and F-score. Throws
/// InputError naming the file when either mesh has no non-degenerate face,
/// std::invalid_argument when options.samples < 1 or options.tau is not finite and > 0.
MeshDistances measureMeshDistances(const TriangleMesh& mesh, const TriangleMesh& reference,
                                   const MeshDistanceOptions& options = {},
                                   const std::filesystem::path& mesh_file = "mesh",
                                   const std::filesystem::path& reference_file = "reference");

}  // namespace solo
