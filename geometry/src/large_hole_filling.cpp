// Large holes of general meshes: projected constrained Delaunay triangulation with a bi-harmonic
// fit of the interior, chord splits when no projection is simple (see large_hole_filling.h).

#include "solo/geometry/large_hole_filling.h"

#include "solo/core/report.h"

#include "polygon_cdt.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_2_algorithms.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/Sparse>

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <map>
#include <set>
#include <unordered_set>
#include <utility>

namespace solo {
namespace {

using polygon_cdt::Cdt;
using polygon_cdt::Kernel;
using polygon_cdt::markNesting;
using polygon_cdt::Point2;
using Point3 = Kernel::Point_3;
using Face = std::array<int, 3>;

struct TimeExceeded {};

double segmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-300), 0.0, 1.0);
  return (a + t * ab - p).norm();
}

/// Directions to project a loop along: its vector-area normal (the mean normal of any surface
/// spanning it), then the normal of its least-squares plane.
std::vector<Eigen::Vector3d> projectionDirections(const std::vector<Eigen::Vector3d>& loop) {
  const int n = static_cast<int>(loop.size());
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& p : loop) centre += p;
  centre /= n;
  Eigen::Vector3d area = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    area += (loop[i] - centre).cross(loop[(i + 1) % n] - centre);
    covariance += (loop[i] - centre) * (loop[i] - centre).transpose();
  }
  std::vector<Eigen::Vector3d> directions;
  if (area.norm() > 0) directions.push_back(area.normalized());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  if (solver.info() == Eigen::Success) {
    const Eigen::Vector3d normal = solver.eigenvectors().col(0);
    if (directions.empty() || std::abs(normal.dot(directions[0])) < 0.999) directions.push_back(normal);
  }
  return directions;
}

/// Vertices where a patch over the loop's first n points must bend, added to `cdt` after
/// `last` and appended to `grid` (at most `max_interior` in all). A triangle over three boundary
/// vertices cannot bend: where the boundary folds in 3D (a rim rising around an arch) it cuts the
/// surface. Each gets a vertex at its centroid, which the fit then places (rounds: the insertions
/// flip edges). Likewise an edge between two boundary vertices that are not neighbours on the
/// loop (across a notch of the boundary) gets a vertex at its middle.
void addBendVertices(Cdt& cdt, int n, int max_interior, std::vector<Eigen::Vector2d>& grid, Cdt::Vertex_handle last) {
  for (int round = 0; round < 3; ++round) {
    std::vector<Eigen::Vector2d> centroids;
    // Faces already visited: looked up, never iterated (their addresses depend on the heap).
    std::unordered_set<const void*> visited;
    for (const auto f : cdt.finite_face_handles()) {
      visited.insert(&*f);
      if (f->info() % 2 != 1) continue;
      for (int e = 0; e < 3; ++e) {
        const int a = f->vertex((e + 1) % 3)->info(), b = f->vertex((e + 2) % 3)->info();
        const Cdt::Face_handle g = f->neighbor(e);
        // Each inner edge once (from the second of its faces in the triangulation's order),
        // never a loop edge.
        if (a >= n || b >= n || cdt.is_constrained(Cdt::Edge(f, e)) || cdt.is_infinite(g) || g->info() % 2 != 1 ||
            visited.count(&*g) == 0)
          continue;
        const auto c = CGAL::midpoint(f->vertex((e + 1) % 3)->point(), f->vertex((e + 2) % 3)->point());
        centroids.emplace_back(c.x(), c.y());
      }
      if (f->vertex(0)->info() >= n || f->vertex(1)->info() >= n || f->vertex(2)->info() >= n) continue;
      const auto c = CGAL::centroid(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point());
      centroids.emplace_back(c.x(), c.y());
    }
    if (centroids.empty() || static_cast<int>(grid.size() + centroids.size()) > max_interior) break;
    for (const auto& c : centroids) {
      last = cdt.insert(Point2(c.x(), c.y()), last->face());
      last->info() = n + static_cast<int>(grid.size());
      grid.push_back(c);
    }
    markNesting(cdt);
  }
}

/// Constrained Delaunay triangulation of the loop projected along one of projectionDirections,
/// with interior vertices on a hexagonal grid. Faces index the loop (0..n-1), then `interior`
/// (n + k), whose points lie in the projection plane (the fit places them). False with the reason
/// when no projection is simple.
bool triangulateProjected(const std::vector<Eigen::Vector3d>& loop, int max_interior, std::vector<Face>& faces, std::vector<Eigen::Vector3d>& interior,
                          std::string& failure) {
  const int n = static_cast<int>(loop.size());
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& p : loop) centre += p;
  centre /= n;
  for (const Eigen::Vector3d& direction : projectionDirections(loop)) {
    const Eigen::Vector3d e1 = direction.unitOrthogonal(), e2 = direction.cross(e1);
    std::vector<Point2> uv;
    std::vector<Eigen::Vector2d> q;
    for (const auto& p : loop) {
      q.emplace_back((p - centre).dot(e1), (p - centre).dot(e2));
      uv.emplace_back(q.back().x(), q.back().y());
    }
    if (!CGAL::is_simple_2(uv.begin(), uv.end(), Kernel())) continue;
    double twice_area = 0, perimeter = 0;
    for (int i = 0; i < n; ++i) {
      twice_area += q[i].x() * q[(i + 1) % n].y() - q[(i + 1) % n].x() * q[i].y();
      perimeter += (q[(i + 1) % n] - q[i]).norm();
    }
    if (!(std::abs(twice_area) > 0)) continue;
    Cdt cdt;
    std::vector<Cdt::Vertex_handle> handles(n);
    for (int i = 0; i < n; ++i) {
      handles[i] = cdt.insert(uv[i], i == 0 ? Cdt::Face_handle() : handles[i - 1]->face());
      handles[i]->info() = i;
    }
    for (int i = 0; i < n; ++i) cdt.insert_constraint(handles[i], handles[(i + 1) % n]);
    markNesting(cdt);
    // Hexagonal grid at the boundary's mean (projected) edge length, coarsened to fit the budget;
    // points closer than half a spacing to the boundary are left out (no slivers along it).
    double spacing = perimeter / n;
    const double cell = 0.5 * std::sqrt(3.0);
    const double estimate = 0.5 * std::abs(twice_area) / (cell * spacing * spacing);
    // A fifth of the budget is kept for the vertices added along the boundary below.
    const double grid_budget = 0.8 * max_interior;
    if (estimate > grid_budget) spacing *= std::sqrt(estimate / std::max(grid_budget, 1.0));
    Eigen::Vector2d low = q[0], high = q[0];
    for (const auto& p : q) low = low.cwiseMin(p), high = high.cwiseMax(p);
    std::vector<Eigen::Vector2d> grid;
    Cdt::Face_handle hint;
    for (int row = 0; low.y() + row * cell * spacing <= high.y(); ++row) {
      const double y = low.y() + row * cell * spacing;
      for (double x = low.x() + (row % 2 ? 0.5 * spacing : 0.0); x <= high.x(); x += spacing) {
        Cdt::Locate_type type;
        int li = 0;
        hint = cdt.locate(Point2(x, y), type, li, hint);
        if (type != Cdt::FACE || cdt.is_infinite(hint) || hint->info() % 2 != 1) continue;
        const Eigen::Vector2d p(x, y);
        bool clear = true;
        for (int i = 0; i < n && clear; ++i) clear = segmentDistance(p, q[i], q[(i + 1) % n]) >= 0.5 * spacing;
        if (clear) grid.push_back(p);
      }
    }
    if (static_cast<int>(grid.size()) > max_interior) grid.resize(static_cast<std::size_t>(max_interior));
    Cdt::Vertex_handle last = handles[n - 1];
    for (std::size_t k = 0; k < grid.size(); ++k) {
      last = cdt.insert(Point2(grid[k].x(), grid[k].y()), last->face());
      last->info() = n + static_cast<int>(k);
    }
    if (!grid.empty()) markNesting(cdt);
    addBendVertices(cdt, n, max_interior, grid, last);
    const int m = static_cast<int>(grid.size());
    faces.clear();
    for (const auto f : cdt.finite_face_handles()) {
      if (f->info() % 2 != 1) continue;
      Face t{f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()};
      if (twice_area < 0) std::swap(t[1], t[2]);  // CGAL's faces turn left; keep the loop's direction
      faces.push_back(t);
    }
    if (static_cast<int>(cdt.number_of_vertices()) != n + m || static_cast<int>(faces.size()) != n - 2 + 2 * m) {
      failure = "projected triangulation is incomplete";
      continue;
    }
    interior.clear();
    for (const auto& p : grid) interior.push_back(centre + p.x() * e1 + p.y() * e2);
    return true;
  }
  failure = "no projection of the boundary is a simple polygon";
  return false;
}

/// Places the interior vertices (indices n..): least squares of the umbrella Laplacian at every
/// interior vertex and at every boundary vertex with a ring (its mesh neighbours), boundary and
/// ring fixed: the discrete bi-harmonic surface, tangent to the mesh where the ring is given.
bool fitBiharmonic(const std::vector<Eigen::Vector3d>& boundary, const std::vector<std::vector<Eigen::Vector3d>>& ring,
                   const std::vector<Face>& faces, std::vector<Eigen::Vector3d>& interior) {
  const int n = static_cast<int>(boundary.size()), m = static_cast<int>(interior.size());
  if (m == 0) return true;
  std::vector<std::set<int>> neighbours(n + m);
  for (const Face& f : faces)
    for (int k = 0; k < 3; ++k) {
      neighbours[f[k]].insert(f[(k + 1) % 3]);
      neighbours[f[(k + 1) % 3]].insert(f[k]);
    }
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<Eigen::Vector3d> constants;
  int row = 0;
  for (int v = 0; v < n + m; ++v) {
    const bool has_ring = v < n && v < static_cast<int>(ring.size()) && !ring[v].empty();
    if (v < n && !has_ring) continue;
    const std::size_t degree = neighbours[v].size() + (has_ring ? ring[v].size() : 0);
    if (degree == 0) continue;
    const double w = 1.0 / static_cast<double>(degree);
    Eigen::Vector3d constant = Eigen::Vector3d::Zero();
    for (const int u : neighbours[v]) {
      if (u < n) constant += w * boundary[u];
      else entries.emplace_back(row, u - n, w);
    }
    if (has_ring)
      for (const auto& p : ring[v]) constant += w * p;
    if (v < n) constant -= boundary[v];
    else entries.emplace_back(row, v - n, -1.0);
    constants.push_back(constant);
    ++row;
  }
  Eigen::SparseMatrix<double> a(row, m);
  a.setFromTriplets(entries.begin(), entries.end());
  Eigen::MatrixXd b(row, 3);
  for (int r = 0; r < row; ++r) b.row(r) = -constants[r].transpose();
  const Eigen::SparseMatrix<double> normal = Eigen::SparseMatrix<double>(a.transpose()) * a;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  if (solver.info() != Eigen::Success) return false;
  const Eigen::MatrixXd x = solver.solve(Eigen::MatrixXd(a.transpose() * b));
  if (solver.info() != Eigen::Success || !x.allFinite()) return false;
  for (int k = 0; k < m; ++k) interior[k] = x.row(k).transpose();
  return true;
}

/// For each interior vertex (n + k), the number of edges to the nearest boundary vertex.
std::vector<int> hopsFromBoundary(int n, const std::vector<Face>& faces, int m) {
  std::vector<std::vector<int>> neighbours(n + m);
  for (const Face& f : faces)
    for (int k = 0; k < 3; ++k) neighbours[f[k]].push_back(f[(k + 1) % 3]), neighbours[f[(k + 1) % 3]].push_back(f[k]);
  std::vector<int> hops(n + m, -1), queue;
  for (int i = 0; i < n; ++i) hops[i] = 0, queue.push_back(i);
  for (std::size_t head = 0; head < queue.size(); ++head)
    for (const int u : neighbours[queue[head]])
      if (hops[u] < 0) hops[u] = hops[queue[head]] + 1, queue.push_back(u);
  std::vector<int> out(m);
  for (int k = 0; k < m; ++k) out[k] = hops[n + k] < 0 ? 1 << 20 : hops[n + k];
  return out;
}

struct Splitter {
  const std::vector<Eigen::Vector3d>& boundary;
  const HoleFillOptions& options;
  const LargeHoleOptions& large;
  const Stopwatch& clock;
  const ChordTest& chord_blocked;
  std::vector<Face> faces;               ///< over boundary (0..n-1) and interior (n + k)
  std::vector<Eigen::Vector3d> interior;
  int pieces = 0;
  std::string failure;

  void checkTime() const {
    if (clock.seconds() > options.time_limit_s) throw TimeExceeded{};
  }

  /// Fills the sub-loop `loop` (indices into boundary, in the loop's direction).
  bool fill(const std::vector<int>& loop, bool top) {
    checkTime();
    const int k = static_cast<int>(loop.size());
    std::vector<Eigen::Vector3d> points;
    for (const int i : loop) points.push_back(boundary[i]);
    const int budget = std::max(0, large.max_interior_vertices - static_cast<int>(interior.size()));
    std::vector<Face> local;
    std::vector<Eigen::Vector3d> inner;
    std::string why;
    if (k == 3 || triangulateProjected(points, budget, local, inner, why)) {
      if (k == 3) local = {Face{0, 1, 2}};
      add(loop, local, inner);
      ++pieces;
      return true;
    }
    // Split further while pieces remain (pieces with interior vertices bend with the fit);
    // CGAL's triangulation is the last resort for a piece (the whole hole already failed it).
    const std::vector<std::pair<int, int>> chords =
        pieces + 2 <= large.max_pieces ? chooseChords(points, top ? large.chord_candidates : 1, chord_blocked)
                                       : std::vector<std::pair<int, int>>{};
    if (chords.empty() && !top && k <= options.max_cubic_boundary_vertices) {
      HolePatch patch = fillHolePolyline(points, HoleFillMethod::Triangulate, options);
      if (patch.filled) {
        add(loop, patch.faces, {});
        ++pieces;
        return true;
      }
    }
    if (chords.empty()) {
      failure = why + (pieces + 2 <= large.max_pieces ? ", and no chord splits it" : ", and the pieces are at their limit");
      return false;
    }
    for (const auto& [a, b] : chords) {
      const std::size_t face_count = faces.size(), point_count = interior.size();
      const int piece_count = pieces;
      std::vector<int> first(loop.begin() + a, loop.begin() + b + 1), second(loop.begin() + b, loop.end());
      second.insert(second.end(), loop.begin(), loop.begin() + a + 1);
      if (fill(first, false) && fill(second, false)) return true;
      faces.resize(face_count);  // undo this chord's pieces before the next one
      interior.resize(point_count);
      pieces = piece_count;
    }
    return false;
  }

  void add(const std::vector<int>& loop, const std::vector<Face>& local, const std::vector<Eigen::Vector3d>& inner) {
    const int k = static_cast<int>(loop.size());
    const int n = static_cast<int>(boundary.size());
    const int base = n + static_cast<int>(interior.size());
    for (const Face& f : local) {
      Face g{};
      for (int c = 0; c < 3; ++c) g[c] = f[c] < k ? loop[f[c]] : base + (f[c] - k);
      faces.push_back(g);
    }
    interior.insert(interior.end(), inner.begin(), inner.end());
  }

};

bool anyDegenerate(const std::vector<Eigen::Vector3d>& boundary, const std::vector<Eigen::Vector3d>& interior,
                   const std::vector<Face>& faces) {
  const int n = static_cast<int>(boundary.size());
  const auto at = [&](int i) {
    const Eigen::Vector3d& p = i < n ? boundary[i] : interior[i - n];
    return Point3(p.x(), p.y(), p.z());
  };
  for (const Face& f : faces)
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2] || CGAL::collinear(at(f[0]), at(f[1]), at(f[2]))) return true;
  return false;
}

}  // namespace

/// Chords (a < b, positions in the loop) between points close in 3D but far along the loop
/// (each side at least a sixth of it), best first: the 3D distance over the shorter arc.
std::vector<std::pair<int, int>> chooseChords(const std::vector<Eigen::Vector3d>& points, int count, const ChordTest& blocked) {
  const int k = static_cast<int>(points.size());
  const int min_side = std::max(3, k / 6);
  std::vector<double> arc(k + 1, 0.0);
  for (int i = 0; i < k; ++i) arc[i + 1] = arc[i] + (points[(i + 1) % k] - points[i]).norm();
  // Very long loops: every `stride`-th vertex is a candidate end (bounded work).
  const int stride = std::max(1, k / 2000);
  std::vector<std::pair<double, std::pair<int, int>>> scored;
  for (int a = 0; a < k; a += stride)
    for (int b = a + min_side; b <= a + k - min_side && b < k; b += stride) {
      const double along = std::min(arc[b] - arc[a], arc[k] - (arc[b] - arc[a]));
      const double across = (points[b] - points[a]).norm();
      if (!(across > 0) || !(along > 0)) continue;
      scored.push_back({across / along, {a, b}});
    }
  // A chord through the mesh leaves the hole: the best few that do not (at most 256 looked at).
  const std::size_t looked = std::min<std::size_t>(scored.size(), 256);
  std::partial_sort(scored.begin(), scored.begin() + static_cast<std::ptrdiff_t>(looked), scored.end());
  std::vector<std::pair<int, int>> out;
  for (std::size_t i = 0; i < looked && static_cast<int>(out.size()) < count; ++i) {
    const auto [a, b] = scored[i].second;
    if (!blocked || !blocked(points[a], points[b])) out.push_back(scored[i].second);
  }
  return out;
}

LargeHolePatch fillLargeHole(const std::vector<Eigen::Vector3d>& boundary,
                             const std::vector<std::vector<Eigen::Vector3d>>& ring, const HoleFillOptions& options,
                             const LargeHoleOptions& large, const ChordTest& chord_blocked) {
  LargeHolePatch result;
  HolePatch& patch = result.patch;
  const int n = static_cast<int>(boundary.size());
  if (n < 3) {
    patch.failure = "boundary has fewer than 3 vertices";
    return result;
  }
  for (const auto& p : boundary)
    if (!p.allFinite()) {
      patch.failure = "boundary has a non-finite coordinate";
      return result;
    }
  for (int i = 0; i < n; ++i)
    if (boundary[i] == boundary[(i + 1) % n]) {
      patch.failure = "boundary has an edge of zero length";
      return result;
    }
  const Stopwatch clock;
  Splitter splitter{boundary, options, large, clock, chord_blocked, {}, {}, 0, {}};
  try {
    std::vector<int> loop(n);
    for (int i = 0; i < n; ++i) loop[i] = i;
    if (!splitter.fill(loop, true)) {
      patch.failure = splitter.failure.empty() ? "no piece could be triangulated" : splitter.failure;
      return result;
    }
    splitter.checkTime();
    std::vector<Eigen::Vector3d> membrane = splitter.interior;
    if (!fitBiharmonic(boundary, {}, splitter.faces, membrane)) {
      patch.failure = "the membrane fit could not be solved";
      return result;
    }
    if (large.tangent_continuous) {
      std::vector<Eigen::Vector3d> tangent = splitter.interior;
      if (!fitBiharmonic(boundary, ring, splitter.faces, tangent)) {
        patch.failure = "the bi-harmonic fit could not be solved";
        return result;
      }
      // A patch as close to the true surface as the mesh around it crosses the mesh's ragged
      // rim (a staircase of faces) here and there; the membrane lies on the chord side of it.
      // So the patch is kTangentShare of the tangent fit and the rest membrane (on the wavy torus
      // hole of the tests: 1.0 gives 14 faces meeting the mesh, 0.9 8, 0.75 none; mean distance
      // to the torus 0.053 against 0.141 for the membrane), and the membrane alone next to the
      // boundary, blended over kBlendRings rings (hops from the boundary in the patch).
      constexpr int kBlendRings = 4;
      constexpr double kTangentShare = 0.75;
      const std::vector<int> hops = hopsFromBoundary(n, splitter.faces, static_cast<int>(membrane.size()));
      for (std::size_t k = 0; k < membrane.size(); ++k) {
        const double w = kTangentShare * std::min(1.0, hops[k] / static_cast<double>(kBlendRings));
        membrane[k] = w * tangent[k] + (1 - w) * membrane[k];
      }
    }
    splitter.interior = std::move(membrane);
  } catch (const TimeExceeded&) {
    patch.failure = "exceeded its time limit of " + std::to_string(options.time_limit_s) + " s";
    return result;
  } catch (const std::exception& e) {
    patch.failure = std::string("large-hole filling failed: ") + e.what();
    return result;
  }
  if (anyDegenerate(boundary, splitter.interior, splitter.faces)) {
    patch.failure = "the patch has a degenerate triangle";
    return result;
  }
  patch.faces = std::move(splitter.faces);
  patch.new_points = std::move(splitter.interior);
  patch.filled = true;
  patch.faired = !patch.new_points.empty();
  result.pieces = splitter.pieces;
  result.method = splitter.pieces > 1 ? "chord_split" : "membrane";
  return result;
}

}  // namespace solo
