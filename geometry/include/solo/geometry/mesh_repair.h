#pragma once
// Repair of an arbitrary triangle soup into a SurfaceMesh, before hole filling:
//  - duplicate points merged (exactly equal coordinates), only in soups that are not already a
//    valid polygon mesh (there coincident vertices are seams kept apart on purpose);
//  - corners of one face at exactly one position merged (zero-length edges, such as a pole
//    repeated once per face of its fan), in every soup;
//  - faces with a repeated corner, duplicate faces and unreferenced vertices removed (CGAL
//    polygon-soup repair);
//  - a soup that still is not a polygon mesh oriented consistently (CGAL orient_polygon_soup:
//    faces reversed, points of non-manifold vertices or edges duplicated);
//  - boundary vertices at exactly one position merged (a hole that passes twice through one
//    place, the sides of a slit) when no face has two of them and no face is lost by it;
//  - faces that would make an edge non-manifold left out (OpenMesh refuses them; their place
//    becomes a hole that is filled);
//  - degenerate faces (three distinct collinear corners, exact predicate) removed by flipping
//    their longest edge when that gives two proper triangles, else deleted.

#include "solo/geometry/surface_mesh.h"
#include "solo/geometry/triangle_mesh.h"

#include <cstdint>

namespace solo {

struct SoupRepair {
  std::int64_t duplicate_points_merged = 0;
  std::int64_t coincident_corners_merged = 0;
  std::int64_t faces_with_repeated_corner_removed = 0;
  std::int64_t duplicate_faces_removed = 0;
  std::int64_t unreferenced_vertices_removed = 0;
  std::int64_t faces_reoriented = 0;
  std::int64_t non_manifold_points_duplicated = 0;
  std::int64_t coincident_boundary_vertices_merged = 0;
  std::int64_t non_manifold_faces_removed = 0;
  std::int64_t degenerate_faces_flipped = 0;
  std::int64_t degenerate_faces_removed = 0;
};

/// The repaired mesh; `stats` receives what was done.
SurfaceMesh repairSoup(const TriangleMesh& soup, SoupRepair* stats = nullptr);

}  // namespace solo
