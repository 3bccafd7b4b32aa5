// Self-intersection removal and alpha wrapping (CGAL 5.5). Every CGAL call of both steps is in
// this one translation unit: each CGAL translation unit costs about 30 s and 1.6 GB to compile.

#include "solo/geometry/mesh_intersection_repair.h"

#include "solo/core/report.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/bbox.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/manifoldness.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_self_intersections.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/shape_predicates.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>
#include <CGAL/boost/graph/helpers.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <iterator>
#include <stdexcept>
#include <vector>

namespace solo {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using FaceIndices = std::vector<std::array<std::size_t, 3>>;
namespace PMP = CGAL::Polygon_mesh_processing;

/// Thrown by the visitors below when a step's deadline passes; caught in this file only.
struct DeadlinePassed {};

/// Remove_self_intersections' visitor: stops between steps and aborts inside one once the
/// deadline has passed (the interrupted copy is thrown away).
struct RepairDeadline {
  const Stopwatch* clock = nullptr;
  double limit_s = 0;
  bool passed() const { return clock->seconds() > limit_s; }
  bool stop() const { return passed(); }
  template <class FaceContainer>
  void status_update(const FaceContainer&) { check(); }
  void start_main_loop() {}
  void end_main_loop() {}
  void start_iteration() { check(); }
  void end_iteration() {}
  void start_component_handling() { check(); }
  void end_component_handling() {}
  void parameters_used(bool, bool, int, double, double, double) {}
  void check() const {
    if (passed()) throw DeadlinePassed{};
  }
};

/// Alpha_wrap_3's visitor: aborts the flood fill once the deadline has passed.
struct WrapDeadline {
  const Stopwatch* clock = nullptr;
  double limit_s = 0;
  std::int64_t facets = 0;
  template <typename Wrapper>
  void on_alpha_wrapping_begin(const Wrapper&) {}
  template <typename Wrapper>
  void on_flood_fill_begin(const Wrapper&) {}
  template <typename Wrapper, typename Gate>
  void before_facet_treatment(const Wrapper&, const Gate&) {
    // The clock is read every 256 facets: a facet costs microseconds.
    if ((++facets & 255) == 0 && clock->seconds() > limit_s) throw DeadlinePassed{};
  }
  template <typename Wrapper, typename P>
  void before_Steiner_point_insertion(const Wrapper&, const P&) {}
  template <typename Wrapper, typename VertexHandle>
  void after_Steiner_point_insertion(const Wrapper&, VertexHandle) {}
  template <typename Wrapper>
  void on_flood_fill_end(const Wrapper&) {}
  template <typename Wrapper>
  void on_alpha_wrapping_end(const Wrapper&) {}
};

std::vector<Point> pointsOf(const TriangleMesh& mesh) {
  std::vector<Point> points;
  points.reserve(mesh.vertices.size());
  for (const auto& v : mesh.vertices) points.emplace_back(v.x(), v.y(), v.z());
  return points;
}

TriangleMesh triangleMeshOf(const Mesh& mesh) {
  TriangleMesh out;
  std::vector<std::uint32_t> index(mesh.number_of_vertices() + mesh.number_of_removed_vertices(), 0);
  for (const auto v : mesh.vertices()) {
    index[v.idx()] = static_cast<std::uint32_t>(out.vertices.size());
    const Point& p = mesh.point(v);
    out.vertices.emplace_back(p.x(), p.y(), p.z());
  }
  for (const auto f : mesh.faces()) {
    std::array<std::uint32_t, 3> corners{};
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh))
      if (k < 3) corners[k++] = index[v.idx()];
    if (k == 3) out.faces.push_back(corners);
  }
  return out;
}

std::int64_t intersectingPairs(const Mesh& mesh) {
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  PMP::self_intersections(mesh, std::back_inserter(pairs));
  return static_cast<std::int64_t>(pairs.size());
}

/// What a repair round must not make worse.
struct MeshState {
  bool valid = false;
  std::int64_t boundary_edges = 0, non_manifold_vertices = 0, degenerate_faces = 0, pairs = 0;
  std::int64_t components = 0;
};

MeshState stateOf(Mesh& mesh) {
  MeshState s;
  s.valid = CGAL::is_valid_polygon_mesh(mesh) && CGAL::is_triangle_mesh(mesh);
  if (!s.valid) return s;
  for (const auto e : mesh.edges()) s.boundary_edges += mesh.is_border(e);
  std::vector<Mesh::Halfedge_index> pinched;
  PMP::non_manifold_vertices(mesh, std::back_inserter(pinched));
  s.non_manifold_vertices = static_cast<std::int64_t>(pinched.size());
  std::vector<Mesh::Face_index> degenerate;
  PMP::degenerate_faces(mesh, std::back_inserter(degenerate));
  s.degenerate_faces = static_cast<std::int64_t>(degenerate.size());
  s.pairs = intersectingPairs(mesh);
  auto component = mesh.add_property_map<Mesh::Face_index, std::size_t>("f:solo_component", 0).first;
  s.components = static_cast<std::int64_t>(PMP::connected_components(mesh, component));
  mesh.remove_property_map(component);
  return s;
}

/// Why a round's result is refused (empty: kept).
std::string refusal(const MeshState& before, const MeshState& after) {
  if (!after.valid) return "the round left an invalid polygon mesh";
  if (after.boundary_edges > before.boundary_edges) return "the round opened the mesh";
  if (after.non_manifold_vertices > before.non_manifold_vertices) return "the round made a vertex non-manifold";
  if (after.degenerate_faces > before.degenerate_faces) return "the round made degenerate faces";
  if (after.components < before.components) return "the round removed a component";
  if (after.pairs >= before.pairs) return "the round removed no intersecting pair";
  return {};
}

/// A vertex of one face of an intersecting pair, moved along the other face's normal to just
/// past that face's plane.
struct Nudge {
  double distance = 0;  ///< how far the vertex moves
  Mesh::Vertex_index vertex;
  Point target;
};

/// The moves that take a vertex of `a` not shared with `b` across `b`'s plane, at most max_move.
void addNudges(const Mesh& mesh, Mesh::Face_index a, Mesh::Face_index b, double max_move, double margin,
               std::vector<Nudge>& out) {
  std::vector<Mesh::Vertex_index> corners_b;
  for (const auto v : CGAL::vertices_around_face(mesh.halfedge(b), mesh)) corners_b.push_back(v);
  const Point &p0 = mesh.point(corners_b[0]), &p1 = mesh.point(corners_b[1]), &p2 = mesh.point(corners_b[2]);
  Kernel::Vector_3 normal = CGAL::cross_product(p1 - p0, p2 - p0);
  const double length = std::sqrt(CGAL::to_double(normal.squared_length()));
  if (!(length > 0)) return;
  normal = normal / length;
  for (const auto v : CGAL::vertices_around_face(mesh.halfedge(a), mesh)) {
    if (std::find(corners_b.begin(), corners_b.end(), v) != corners_b.end()) continue;
    const double d = (mesh.point(v) - p0) * normal;
    const double move = std::abs(d) + margin;
    if (move > max_move) continue;
    out.push_back({move, v, mesh.point(v) - (d + (d >= 0 ? margin : -margin)) * normal});
  }
}

/// The faces whose boxes meet the box of the faces around `v` (grown by `margin`).
std::vector<Mesh::Face_index> facesNear(const Mesh& mesh, Mesh::Vertex_index v, double margin) {
  CGAL::Bbox_3 box = mesh.point(v).bbox();
  for (const auto f : CGAL::faces_around_target(mesh.halfedge(v), mesh))
    if (f != Mesh::null_face()) box += PMP::face_bbox(f, mesh);
  box = CGAL::Bbox_3(box.xmin() - margin, box.ymin() - margin, box.zmin() - margin, box.xmax() + margin,
                     box.ymax() + margin, box.zmax() + margin);
  std::vector<Mesh::Face_index> near;
  for (const auto f : mesh.faces())
    if (CGAL::do_overlap(box, PMP::face_bbox(f, mesh))) near.push_back(f);
  return near;
}

std::int64_t pairsAmong(const std::vector<Mesh::Face_index>& faces, const Mesh& mesh) {
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  PMP::self_intersections(faces, mesh, std::back_inserter(pairs));
  return static_cast<std::int64_t>(pairs.size());
}

/// Tries the smallest moves of single vertices that clear an intersecting pair (a corner just
/// on the wrong side of a face): a move is kept when it leaves fewer intersecting pairs around
/// the vertex and no degenerate face there. Returns the vertices moved; stops at the deadline.
std::int64_t nudgeVertices(Mesh& mesh, double max_move, const Stopwatch& clock, double limit_s) {
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  PMP::self_intersections(mesh, std::back_inserter(pairs));
  const double margin = 0.05 * max_move;
  std::int64_t moved = 0;
  for (const auto& [f, g] : pairs) {
    if (clock.seconds() > limit_s) break;
    std::vector<Nudge> nudges;
    addNudges(mesh, f, g, max_move, margin, nudges);
    addNudges(mesh, g, f, max_move, margin, nudges);
    std::sort(nudges.begin(), nudges.end(), [](const Nudge& a, const Nudge& b) { return a.distance < b.distance; });
    for (const Nudge& n : nudges) {
      const std::vector<Mesh::Face_index> near = facesNear(mesh, n.vertex, max_move);
      const std::int64_t before = pairsAmong(near, mesh);
      const Point old = mesh.point(n.vertex);
      mesh.point(n.vertex) = n.target;
      bool degenerate = false;
      for (const auto h : CGAL::halfedges_around_target(mesh.halfedge(n.vertex), mesh))
        if (!mesh.is_border(h)) degenerate = degenerate || PMP::is_degenerate_triangle_face(mesh.face(h), mesh);
      if (!degenerate && pairsAmong(facesNear(mesh, n.vertex, max_move), mesh) < before) {
        ++moved;
        break;
      }
      mesh.point(n.vertex) = old;
    }
  }
  return moved;
}

/// One call of CGAL's repair on a copy of `mesh`; false when the deadline passed inside it.
bool repairRound(const Mesh& mesh, Mesh& trial, double envelope, const Stopwatch& clock, double limit_s) {
  trial = mesh;
  RepairDeadline deadline{&clock, limit_s};
  try {
    PMP::experimental::remove_self_intersections(
        trial, CGAL::parameters::visitor(deadline).preserve_genus(true).polyhedral_envelope_epsilon(envelope));
  } catch (const DeadlinePassed&) {
    return false;
  }
  return true;
}

bool soupAsMesh(const TriangleMesh& soup, Mesh& mesh) {
  std::vector<Point> points = pointsOf(soup);
  std::vector<std::vector<std::size_t>> polygons;
  polygons.reserve(soup.faces.size());
  for (const auto& f : soup.faces) polygons.push_back({f[0], f[1], f[2]});
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons)) return false;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
  return true;
}

}  // namespace

IntersectionRepair repairSelfIntersections(TriangleMesh& mesh, const IntersectionRepairOptions& options) {
  const Stopwatch clock;
  IntersectionRepair r;
  r.faces_before = r.faces_after = static_cast<std::int64_t>(mesh.faces.size());
  Mesh current;
  if (!soupAsMesh(mesh, current)) {
    r.failure = "the mesh is not a polygon mesh (an edge with more than two faces or faces of opposite orientation)";
    return r;
  }
  r.pairs_before = r.pairs_after = intersectingPairs(current);
  if (r.pairs_before == 0) {
    r.repaired = true;
    return r;
  }
  MeshState state = stateOf(current);
  const CGAL::Bbox_3 box = PMP::bbox(current);
  const double envelope = options.envelope_fraction * std::sqrt(CGAL::square(box.xmax() - box.xmin()) +
                                                                CGAL::square(box.ymax() - box.ymin()) +
                                                                CGAL::square(box.zmax() - box.zmin()));
  // The smallest repair first: single vertices moved across a face they barely pierce.
  Mesh nudged = current;
  r.vertices_moved = nudgeVertices(nudged, envelope, clock, options.time_limit_s);
  if (r.vertices_moved > 0) {
    const MeshState after = stateOf(nudged);
    if (refusal(state, after).empty()) {
      current = std::move(nudged);
      state = after;
      ++r.rounds_kept;
    } else {
      r.vertices_moved = 0;
    }
  }
  for (int round = 0; round < options.max_rounds && state.pairs > 0; ++round) {
    if (clock.seconds() > options.time_limit_s) {
      r.time_limit_hit = true;
      break;
    }
    Mesh trial;
    if (!repairRound(current, trial, envelope, clock, options.time_limit_s)) {
      r.time_limit_hit = true;
      break;
    }
    const MeshState after = stateOf(trial);
    if (const std::string why = refusal(state, after); !why.empty()) {
      ++r.rounds_refused;
      r.failure = why;
      break;
    }
    current = std::move(trial);
    state = after;
    ++r.rounds_kept;
  }
  r.pairs_after = state.pairs;
  r.repaired = state.pairs == 0;
  if (r.repaired) r.failure.clear();
  else if (r.time_limit_hit) r.failure = "the time limit was reached";
  else if (r.failure.empty()) r.failure = "the rounds ran out";
  if (r.rounds_kept > 0) {
    mesh = triangleMeshOf(current);
    r.faces_after = static_cast<std::int64_t>(mesh.faces.size());
  }
  return r;
}

Wrap wrapMesh(const TriangleMesh& input, const WrapOptions& options) {
  if (!(options.alpha_fraction > 0) || !(options.offset_fraction > 0) || !std::isfinite(options.alpha_fraction) ||
      !std::isfinite(options.offset_fraction))
    throw std::invalid_argument("wrapMesh: alpha and offset fractions must be positive and finite");
  const Stopwatch clock;
  Wrap w;
  const std::vector<Point> points = pointsOf(input);
  FaceIndices faces;
  CGAL::Bbox_3 box;
  for (const auto& f : input.faces) {
    const Point &a = points[f[0]], &b = points[f[1]], &c = points[f[2]];
    if (CGAL::collinear(a, b, c)) continue;
    faces.push_back({f[0], f[1], f[2]});
    box += a.bbox() + b.bbox() + c.bbox();
  }
  if (faces.empty()) throw std::invalid_argument("wrapMesh: no face with an area to wrap");
  w.faces_used = static_cast<std::int64_t>(faces.size());
  w.bbox_diagonal = std::sqrt(CGAL::square(box.xmax() - box.xmin()) + CGAL::square(box.ymax() - box.ymin()) +
                              CGAL::square(box.zmax() - box.zmin()));
  w.alpha = options.alpha_fraction * w.bbox_diagonal;
  w.offset = options.offset_fraction * w.bbox_diagonal;
  Mesh wrap;
  WrapDeadline deadline{&clock, options.time_limit_s};
  try {
    CGAL::alpha_wrap_3(points, faces, w.alpha, w.offset, wrap, CGAL::parameters::default_values(),
                       CGAL::parameters::visitor(std::ref(deadline)));
    w.mesh = triangleMeshOf(wrap);
  } catch (const DeadlinePassed&) {
    w.time_limit_hit = true;
  }
  w.seconds = clock.seconds();
  return w;
}

}  // namespace solo
