#pragma once
// The last two steps of `solo mesh clean` (docs/mesh.md): removal of self-intersections
// (CGAL 5.5 Polygon_mesh_processing::experimental::remove_self_intersections, each round
// verified) and the alpha wrap (CGAL::alpha_wrap_3), closed, 2-manifold and free of
// self-intersections by construction. Both are bounded in wall-clock time.

#include "solo/geometry/triangle_mesh.h"

#include <cstdint>
#include <string>

namespace solo {

struct IntersectionRepairOptions {
  double time_limit_s = 30;  ///< bound of the whole repair (checked between and inside CGAL's steps)
  int max_rounds = 6;        ///< calls of remove_self_intersections, each verified before it is kept
  /// Every patch of the repair stays within this distance (fraction of the bounding-box diagonal)
  /// of the mesh it repairs (CGAL's polyhedral envelope): half the 0.1 % the surface may move.
  double envelope_fraction = 5e-4;
};

struct IntersectionRepair {
  std::int64_t pairs_before = 0;  ///< self-intersecting face pairs before the repair
  std::int64_t pairs_after = 0;   ///< and after it (the last verified round)
  std::int64_t faces_before = 0, faces_after = 0;
  std::int64_t vertices_moved = 0;  ///< single vertices moved across a face they pierced (at most the envelope)
  int rounds_kept = 0;      ///< rounds that passed verification (the vertex moves count as one)
  int rounds_refused = 0;   ///< rounds undone (invalid mesh, more boundary edges, non-manifold or degenerate faces, no progress)
  bool time_limit_hit = false;
  bool repaired = false;    ///< no self-intersecting pair left
  std::string failure;      ///< why not, when not repaired
};

/// Removes the self-intersections of `mesh` in place: first by moving single vertices that lie
/// just on the wrong side of a face they intersect (by at most the envelope), then by rounds of
/// CGAL's repair. Every round is verified on a copy (a valid
/// polygon mesh, no more boundary edges, non-manifold vertices or degenerate faces than before,
/// fewer intersecting pairs) and undone otherwise; the mesh keeps the last verified round. A
/// soup that is not a polygon mesh is left as it is (failure says so).
IntersectionRepair repairSelfIntersections(TriangleMesh& mesh, const IntersectionRepairOptions& options = {});

struct WrapOptions {
  /// alpha (the largest ball that does not pass between two parts of the wrap) as a fraction of the
  /// bounding-box diagonal: 1/100 keeps features of a percent of the object's size.
  double alpha_fraction = 1.0 / 100;
  /// offset (the wrap's distance outside the input) as a fraction of the diagonal: alpha / 30,
  /// CGAL's own default ratio (a smaller offset gives more and worse-shaped wrap triangles).
  double offset_fraction = 1.0 / 3000;
  double time_limit_s = 120;  ///< bound of the wrap (checked at every facet of CGAL's flood fill)
};

struct Wrap {
  TriangleMesh mesh;           ///< empty when the time limit was hit
  double bbox_diagonal = 0;    ///< of the input, in mesh units
  double alpha = 0, offset = 0;  ///< in mesh units
  std::int64_t faces_used = 0;   ///< input faces wrapped (the non-degenerate ones)
  bool time_limit_hit = false;
  double seconds = 0;
};

/// The alpha wrap of the non-degenerate faces of `input` (any soup). Throws std::invalid_argument
/// when no face has an area or a fraction is not positive.
Wrap wrapMesh(const TriangleMesh& input, const WrapOptions& options = {});

}  // namespace solo
