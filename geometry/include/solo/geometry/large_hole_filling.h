#pragma once
// Filling a large hole of a general mesh (solo mesh clean), where CGAL's triangulation over the
// 3D Delaunay search space fails (the exhaustive search is only affordable up to a few hundred
// boundary vertices) or gives a patch that cuts the mesh.
//  - membrane: the boundary is projected along its vector-area normal (else its least-squares
//    plane normal); when the projected polygon is simple it is triangulated by a constrained
//    Delaunay triangulation with interior vertices on a hexagonal grid of the boundary's mean
//    edge length, and the interior is placed in 3D by a bi-harmonic fit: the umbrella Laplacian
//    of every interior vertex and (with `ring`) of every boundary vertex, over its neighbours in
//    the patch and in the mesh, is minimised in least squares (sparse LDLT), boundary fixed. With
//    the mesh's neighbours the patch continues the surface's slope across the boundary.
//  - chord_split: when no projection is simple, the loop is cut by the chord between two
//    boundary vertices that are closest in 3D relative to their distance along the loop (each
//    side at least a sixth of the loop; chords through the mesh refused), and each side is
//    filled alone (membrane, else split again, else CGAL's triangulation up to
//    options.max_cubic_boundary_vertices); the pieces share the chord and the bi-harmonic fit
//    runs over the whole patch.
// Bounded work: at most `max_interior_vertices` new vertices, `max_pieces` pieces, the time limit
// of HoleFillOptions checked between steps. The caller verifies the patch (no intersection).
// Units: those of the points.

#include "solo/geometry/hole_filling.h"

#include <Eigen/Core>

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace solo {

struct LargeHoleOptions {
  bool enabled = true;               ///< closeHoles: try this before the centroid fan (general meshes)
  int max_interior_vertices = 10000;  ///< the grid is coarsened to stay under this
  int max_pieces = 64;               ///< chord splits stop here
  int chord_candidates = 3;          ///< chords tried at the top level, best first
  /// The fit includes the boundary vertices' Laplacians over their mesh neighbours (the patch
  /// continues the surface's slope); false: a membrane over the boundary alone.
  bool tangent_continuous = true;
  /// closeHoles: passes over the loops left inside a split hole whose piece could not be attached.
  int refill_passes = 1;
  /// closeHoles: the fallbacks for holes of any size (else only beyond the exhaustive search).
  bool any_size = false;
};

struct LargeHolePatch {
  HolePatch patch;
  std::string method;  ///< "membrane" or "chord_split" when filled
  int pieces = 0;      ///< sub-holes after chord splits (1: none)
};

/// Whether the segment between two boundary points (a candidate chord) passes through the mesh.
using ChordTest = std::function<bool(const Eigen::Vector3d&, const Eigen::Vector3d&)>;

/// Up to `count` chords (a < b, positions in `loop`) between points close in 3D but far along the
/// loop, best first (the 3D distance over the shorter arc; each side keeps at least a sixth of
/// the loop and 3 vertices); chords `blocked` refuses are skipped (at most 256 looked at).
std::vector<std::pair<int, int>> chooseChords(const std::vector<Eigen::Vector3d>& loop, int count,
                                              const ChordTest& blocked = {});

/// Fills the closed polyline `boundary` (first point not repeated, in the direction of the mesh's
/// border half-edges: the patch keeps edge i -> i+1). `ring[i]` (optional, empty or one list per
/// boundary point): the positions of boundary point i's neighbours in the mesh that are not on
/// the loop. `chord_blocked` (optional): chords it refuses are not used. Never throws for
/// geometric reasons: a failure leaves patch.filled false with the reason.
LargeHolePatch fillLargeHole(const std::vector<Eigen::Vector3d>& boundary,
                             const std::vector<std::vector<Eigen::Vector3d>>& ring, const HoleFillOptions& options = {},
                             const LargeHoleOptions& large = {}, const ChordTest& chord_blocked = {});

}  // namespace solo
