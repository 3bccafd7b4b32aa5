#pragma once
// Private to the geometry library (CGAL stays out of the public headers): the constrained
// Delaunay triangulation of a polygon with holes used by the two polygon fillers,
// hole_filling.cpp (holes of depth meshes, in pixel coordinates) and large_hole_filling.cpp
// (large holes of general meshes, projected onto a plane).

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <utility>
#include <vector>

namespace solo::polygon_cdt {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point2 = Kernel::Point_2;
// Vertex info: index into the caller's points (boundary first); face info: how many
// constraints separate the face from the infinite face (odd: inside the polygon).
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;
using FaceBase = CGAL::Constrained_triangulation_face_base_2<Kernel, CGAL::Triangulation_face_base_with_info_2<int, Kernel>>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>,
                                                       CGAL::No_constraint_intersection_tag>;

/// Sets every face's info to the number of constraints crossed from the infinite face (flood
/// fill, one level at a time): odd inside the polygon, even outside or in its holes.
inline void markNesting(Cdt& cdt) {
  for (const auto f : cdt.all_face_handles()) f->info() = -1;
  std::vector<Cdt::Face_handle> current{cdt.infinite_face()}, next;
  for (int level = 0; !current.empty(); ++level) {
    while (!current.empty()) {
      const Cdt::Face_handle f = current.back();
      current.pop_back();
      if (f->info() != -1) continue;
      f->info() = level;
      for (int i = 0; i < 3; ++i) {
        const Cdt::Face_handle g = f->neighbor(i);
        if (g->info() != -1) continue;
        (cdt.is_constrained(Cdt::Edge(f, i)) ? next : current).push_back(g);
      }
    }
    std::swap(current, next);
  }
}

}  // namespace solo::polygon_cdt
