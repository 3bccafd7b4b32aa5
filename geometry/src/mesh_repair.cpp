#include "solo/geometry/mesh_repair.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <vector>

namespace solo {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
namespace PMP = CGAL::Polygon_mesh_processing;

Point pointOf(const SurfaceMesh& mesh, OpenMesh::VertexHandle v) {
  const auto& p = mesh.point(v);
  return Point(p[0], p[1], p[2]);
}

bool isCollinear(const SurfaceMesh& mesh, OpenMesh::FaceHandle f) {
  OpenMesh::VertexHandle v[3];
  int k = 0;
  for (const auto vh : mesh.fv_range(f)) v[k++] = vh;
  return CGAL::collinear(pointOf(mesh, v[0]), pointOf(mesh, v[1]), pointOf(mesh, v[2]));
}

using Polygons = std::vector<std::vector<std::size_t>>;

/// Groups of two or more boundary vertices (on an edge of a single face) at exactly one position
/// whose members share no face: the pinch points of a boundary that passes twice through one
/// place, or the two sides of a slit.
std::vector<std::vector<std::size_t>> coincidentBoundaryVertices(const std::vector<Point>& points, const Polygons& polygons) {
  std::map<std::pair<std::size_t, std::size_t>, int> edge_faces;
  for (const auto& f : polygons)
    for (std::size_t k = 0; k < f.size(); ++k) {
      const std::size_t a = f[k], b = f[(k + 1) % f.size()];
      ++edge_faces[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<std::uint8_t> on_boundary(points.size(), 0);
  for (const auto& [edge, count] : edge_faces)
    if (count == 1) on_boundary[edge.first] = on_boundary[edge.second] = 1;
  std::map<std::array<double, 3>, std::vector<std::size_t>> at;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (on_boundary[i]) at[{points[i].x(), points[i].y(), points[i].z()}].push_back(i);
  std::vector<std::size_t> group_of(points.size(), SIZE_MAX);
  std::vector<std::vector<std::size_t>> groups;
  for (auto& [position, members] : at) {
    if (members.size() < 2) continue;
    for (const std::size_t v : members) group_of[v] = groups.size();
    groups.push_back(members);
  }
  // A face with two corners of one group would become degenerate: such a group stays apart.
  std::vector<std::uint8_t> refused(groups.size(), 0);
  for (const auto& f : polygons)
    for (std::size_t a = 0; a < f.size(); ++a)
      for (std::size_t b = a + 1; b < f.size(); ++b)
        if (group_of[f[a]] != SIZE_MAX && group_of[f[a]] == group_of[f[b]]) refused[group_of[f[a]]] = 1;
  std::vector<std::vector<std::size_t>> kept;
  for (std::size_t g = 0; g < groups.size(); ++g)
    if (!refused[g]) kept.push_back(std::move(groups[g]));
  return kept;
}

Polygons mergedInto(const Polygons& polygons, const std::vector<std::vector<std::size_t>>& groups, std::size_t vertices) {
  std::vector<std::size_t> target(vertices);
  for (std::size_t i = 0; i < vertices; ++i) target[i] = i;
  for (const auto& g : groups)
    for (const std::size_t v : g) target[v] = g.front();
  Polygons out = polygons;
  for (auto& f : out)
    for (auto& v : f) v = target[v];
  return out;
}

/// Unites corners of one face that lie at exactly one position (zero-length edges: the copies of
/// a pole in a fan of degenerate faces, a collapsed quad's two ends) and renames them in every
/// face; returns the number of vertices merged away. Such corners never are seams: no proper
/// triangle has two of them.
std::int64_t mergeCoincidentCorners(const std::vector<Point>& points, Polygons& polygons) {
  std::vector<std::size_t> parent(points.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = i;
  const auto root = [&](std::size_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  std::int64_t merged = 0;
  for (const auto& f : polygons)
    for (std::size_t a = 0; a < f.size(); ++a)
      for (std::size_t b = a + 1; b < f.size(); ++b) {
        if (f[a] == f[b] || points[f[a]] != points[f[b]]) continue;
        const std::size_t ra = root(f[a]), rb = root(f[b]);
        if (ra == rb) continue;
        parent[std::max(ra, rb)] = std::min(ra, rb);
        ++merged;
      }
  if (merged == 0) return 0;
  for (auto& f : polygons)
    for (auto& v : f) v = root(v);
  return merged;
}

/// Orients a soup that is not a polygon mesh consistently (CGAL orient_polygon_soup: faces
/// reversed, points of non-manifold vertices and edges duplicated so that every piece can be
/// oriented); returns the number of faces reversed.
std::int64_t orientSoup(std::vector<Point>& points, Polygons& polygons, std::int64_t& points_duplicated) {
  const Polygons before = polygons;
  const std::size_t point_count = points.size();
  PMP::orient_polygon_soup(points, polygons);
  points_duplicated = static_cast<std::int64_t>(points.size() - point_count);
  std::int64_t reversed = 0;
  for (std::size_t i = 0; i < polygons.size() && i < before.size(); ++i) {
    const auto& a = before[i];
    const auto& b = polygons[i];
    // Reversed: b is a read backwards (whatever corner it starts at), up to duplicated points.
    const auto same = [&](std::size_t p, std::size_t q) { return p == q || points[p] == points[q]; };
    for (std::size_t k = 0; k < 3; ++k)
      if (same(a[0], b[k]) && same(a[1], b[(k + 2) % 3]) && same(a[2], b[(k + 1) % 3]) && !same(a[1], a[2])) {
        ++reversed;
        break;
      }
  }
  return reversed;
}

std::int64_t facesRefused(const std::vector<Point>& points, const Polygons& polygons) {
  TriangleMesh soup;
  soup.vertices.resize(points.size(), Eigen::Vector3d::Zero());
  for (const auto& f : polygons)
    soup.faces.push_back({static_cast<std::uint32_t>(f[0]), static_cast<std::uint32_t>(f[1]), static_cast<std::uint32_t>(f[2])});
  std::int64_t refused = 0;
  toSurfaceMesh(soup, &refused);
  return refused;
}

}  // namespace

SurfaceMesh repairSoup(const TriangleMesh& soup, SoupRepair* stats) {
  SoupRepair s;
  std::vector<Point> points;
  points.reserve(soup.vertices.size());
  for (const auto& p : soup.vertices) points.emplace_back(p.x(), p.y(), p.z());
  std::vector<std::vector<std::size_t>> polygons;
  polygons.reserve(soup.faces.size());
  for (const auto& f : soup.faces) polygons.push_back({f[0], f[1], f[2]});

  // A soup that already is a valid polygon mesh keeps coincident vertices apart (seams made on
  // purpose; merging them would pinch the surface). Other soups (STL-like) get them merged.
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons))
    s.duplicate_points_merged = static_cast<std::int64_t>(PMP::merge_duplicate_points_in_polygon_soup(points, polygons));
  s.coincident_corners_merged = mergeCoincidentCorners(points, polygons);
  const std::size_t before = polygons.size();
  polygons.erase(std::remove_if(polygons.begin(), polygons.end(),
                                [](const std::vector<std::size_t>& f) { return f[0] == f[1] || f[1] == f[2] || f[0] == f[2]; }),
                 polygons.end());
  s.faces_with_repeated_corner_removed = static_cast<std::int64_t>(before - polygons.size());
  s.duplicate_faces_removed = static_cast<std::int64_t>(PMP::merge_duplicate_polygons_in_polygon_soup(points, polygons));
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons))
    s.faces_reoriented = orientSoup(points, polygons, s.non_manifold_points_duplicated);
  // Boundary vertices at one position (kept apart above when the soup was a valid mesh): a hole
  // through such a pinch touches itself there, so no patch over it passes verification, and the
  // faces around the two copies count as intersecting. Merged, the loop splits at the pinch into
  // holes that close (closing both sides makes the vertex manifold). Kept only when the merged
  // soup loses no more faces to non-manifold edges than before.
  if (const auto groups = coincidentBoundaryVertices(points, polygons); !groups.empty()) {
    Polygons merged = mergedInto(polygons, groups, points.size());
    if (facesRefused(points, merged) <= facesRefused(points, polygons)) {
      polygons = std::move(merged);
      for (const auto& g : groups) s.coincident_boundary_vertices_merged += static_cast<std::int64_t>(g.size() - 1);
    }
  }
  s.unreferenced_vertices_removed = static_cast<std::int64_t>(PMP::remove_isolated_points_in_polygon_soup(points, polygons));

  TriangleMesh cleaned;
  for (const Point& p : points) cleaned.vertices.emplace_back(p.x(), p.y(), p.z());
  for (const auto& f : polygons)
    cleaned.faces.push_back({static_cast<std::uint32_t>(f[0]), static_cast<std::uint32_t>(f[1]), static_cast<std::uint32_t>(f[2])});
  SurfaceMesh mesh = toSurfaceMesh(cleaned, &s.non_manifold_faces_removed);

  std::vector<OpenMesh::FaceHandle> degenerate;
  for (const auto f : mesh.faces())
    if (isCollinear(mesh, f)) degenerate.push_back(f);
  for (const auto f : degenerate) {
    if (mesh.status(f).deleted() || !isCollinear(mesh, f)) continue;
    // The longest edge of a collinear triangle is the one its middle corner lies on.
    OpenMesh::HalfedgeHandle longest;
    double length = -1;
    for (const auto h : mesh.fh_range(f))
      if (mesh.calc_edge_sqr_length(h) > length) {
        length = mesh.calc_edge_sqr_length(h);
        longest = h;
      }
    const auto edge = mesh.edge_handle(longest);
    bool fixed = false;
    if (!mesh.is_boundary(edge) && mesh.is_flip_ok(edge)) {
      mesh.flip(edge);
      const auto f0 = mesh.face_handle(mesh.halfedge_handle(edge, 0));
      const auto f1 = mesh.face_handle(mesh.halfedge_handle(edge, 1));
      if (!isCollinear(mesh, f0) && !isCollinear(mesh, f1)) fixed = true;
      else mesh.flip(edge);
    }
    if (fixed) {
      ++s.degenerate_faces_flipped;
    } else {
      mesh.delete_face(f, true);
      ++s.degenerate_faces_removed;
    }
  }
  if (s.degenerate_faces_removed > 0) collectGarbage(mesh);
  if (stats) *stats = s;
  return mesh;
}

}  // namespace solo
