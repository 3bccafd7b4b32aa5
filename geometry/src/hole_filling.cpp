// Hole filling and patch verification: the CGAL translation unit of the mesh stage.

#include "solo/geometry/hole_filling.h"

#include "solo/core/report.h"

#include "polygon_cdt.h"

#include <CGAL/Box_intersection_d/Box_with_info_d.h>
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_2_algorithms.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/Polygon_mesh_processing/fair.h>
#include <CGAL/Polygon_mesh_processing/refine.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>

#include <Eigen/Sparse>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <exception>
#include <functional>
#include <iterator>
#include <set>
#include <utility>

namespace solo {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using PatchMesh = CGAL::Surface_mesh<Point>;
using Triangle = Kernel::Triangle_3;
using Segment = Kernel::Segment_3;
namespace PMP = CGAL::Polygon_mesh_processing;

// Image-space hole filling: vertex info = index into the patch's points (boundary first), face
// info = how many constraints separate the face from the infinite face (1: inside the polygon).
using polygon_cdt::Cdt;
using polygon_cdt::markNesting;
using polygon_cdt::Point2;

struct DeadlineExceeded {};

// A frame hole's vertex whose pixel shows a surface (obstacle depth) more than this factor
// behind the extended depth sees a farther surface there; more than this fraction of the
// covered vertices doing so means the region is not behind an occluder.
constexpr double kHiddenDepthRatio = 1.1;
constexpr double kMaxHiddenFraction = 0.05;

/// CGAL hole-filling visitor that aborts a call running past its deadline (the quadratic and
/// cubic phases report every step; an exception unwinds CGAL's containers cleanly).
struct DeadlineVisitor : PMP::Hole_filling::Default_visitor {
  const Stopwatch* clock = nullptr;
  double limit_s = 0;
  void check() const {
    if (clock->seconds() > limit_s) throw DeadlineExceeded{};
  }
  void quadratic_step() const { check(); }
  void cubic_step() const { check(); }
  void start_cubic_phase(int) const { check(); }
  void start_quadratic_phase(std::size_t) const { check(); }
};

Point toPoint(const Eigen::Vector3d& p) { return Point(p.x(), p.y(), p.z()); }

/// Triangles over the polyline, oriented along it (edge i -> i+1 appears as i -> i+1).
bool triangulatePolyline(const std::vector<Point>& polyline, const HoleFillOptions& options, const Stopwatch& clock,
                         std::vector<std::array<int, 3>>& faces, std::string& failure) {
  const int n = static_cast<int>(polyline.size());
  DeadlineVisitor visitor;
  visitor.clock = &clock;
  visitor.limit_s = options.time_limit_s;
  std::vector<CGAL::Triple<int, int, int>> triples;
  try {
    PMP::triangulate_hole_polyline(polyline, std::back_inserter(triples),
                                   CGAL::parameters::use_2d_constrained_delaunay_triangulation(true)
                                       .use_delaunay_triangulation(true)
                                       .do_not_use_cubic_algorithm(n > options.max_cubic_boundary_vertices)
                                       .visitor(visitor));
  } catch (const DeadlineExceeded&) {
    failure = "triangulation exceeded its time limit";
    return false;
  } catch (const std::exception& e) {
    failure = std::string("triangulation failed: ") + e.what();
    return false;
  }
  if (static_cast<int>(triples.size()) != n - 2) {
    failure = "no valid triangulation (" + std::to_string(triples.size()) + " of " + std::to_string(n - 2) +
              " triangles" + (n > options.max_cubic_boundary_vertices ? ", exhaustive search skipped for its size)" : ")");
    return false;
  }
  faces.clear();
  for (const auto& t : triples) {
    std::array<int, 3> f{t.first, t.second, t.third};
    std::sort(f.begin(), f.end());  // corners in increasing order run along the polyline
    faces.push_back(f);
  }
  return true;
}

void refineAndFair(const std::vector<Point>& polyline, const HoleFillOptions& options, const Stopwatch& clock,
                   HolePatch& patch) {
  // Refinement makes triangles of about the boundary's edge length: a patch that would get more
  // vertices than can be faired keeps its triangulation (refined without fairing it would only be
  // a denser copy of the same surface, at the cost of the refinement and of its verification).
  const int n = static_cast<int>(polyline.size());
  double edge_sum = 0, area = 0;
  for (int i = 0; i < n; ++i) edge_sum += std::sqrt(CGAL::squared_distance(polyline[i], polyline[(i + 1) % n]));
  for (const auto& f : patch.faces)
    area += std::sqrt(Triangle(polyline[f[0]], polyline[f[1]], polyline[f[2]]).squared_area());
  const double edge = edge_sum / n;
  if (edge > 0 && area / (0.866 * edge * edge) > options.max_fair_vertices) return;
  PatchMesh mesh;
  std::vector<PatchMesh::Vertex_index> vertices;
  for (const Point& p : polyline) vertices.push_back(mesh.add_vertex(p));
  for (const auto& f : patch.faces)
    if (mesh.add_face(vertices[f[0]], vertices[f[1]], vertices[f[2]]) == PatchMesh::null_face())
      throw std::runtime_error("patch is not a valid surface");
  std::vector<PatchMesh::Face_index> new_faces;
  std::vector<PatchMesh::Vertex_index> new_vertices;
  PMP::refine(mesh, faces(mesh), std::back_inserter(new_faces), std::back_inserter(new_vertices),
              CGAL::parameters::density_control_factor(options.density_control_factor));
  if (clock.seconds() > options.time_limit_s) throw DeadlineExceeded{};
  if (!new_vertices.empty() && static_cast<int>(new_vertices.size()) <= options.max_fair_vertices)
    patch.faired = PMP::fair(mesh, new_vertices, CGAL::parameters::fairing_continuity(options.fairing_continuity));
  // Boundary vertices keep indices 0..n-1; the others are numbered in order of addition.
  std::vector<int> index(mesh.number_of_vertices(), -1);
  for (int i = 0; i < n; ++i) index[vertices[i]] = i;
  patch.new_points.clear();
  for (const auto v : mesh.vertices()) {
    if (index[v] >= 0) continue;
    index[v] = n + static_cast<int>(patch.new_points.size());
    const Point& p = mesh.point(v);
    patch.new_points.emplace_back(p.x(), p.y(), p.z());
  }
  patch.faces.clear();
  for (const auto f : mesh.faces()) {
    std::array<int, 3> t{};
    int k = 0;
    for (const auto v : vertices_around_face(mesh.halfedge(f), mesh)) t[k++] = index[v];
    patch.faces.push_back(t);
  }
}

bool faceIsDegenerate(const std::vector<Point>& points, const std::array<int, 3>& f) {
  return f[0] == f[1] || f[1] == f[2] || f[0] == f[2] || CGAL::collinear(points[f[0]], points[f[1]], points[f[2]]);
}

/// The evaluation rules for two non-degenerate faces (docs/evaluation.md).
bool facesIntersect(const std::vector<Point>& points, const std::array<int, 3>& a, const std::array<int, 3>& b) {
  int shared = 0, a_shared[3] = {0, 0, 0}, b_shared[3] = {0, 0, 0};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (a[i] == b[j]) {
        ++shared;
        a_shared[i] = 1;
        b_shared[j] = 1;
      }
  const Triangle ta(points[a[0]], points[a[1]], points[a[2]]), tb(points[b[0]], points[b[1]], points[b[2]]);
  if (shared == 0) return CGAL::do_intersect(ta, tb);
  if (shared == 3) return true;
  if (shared == 1) {
    int ia = 0, ib = 0;
    while (!a_shared[ia]) ++ia;
    while (!b_shared[ib]) ++ib;
    const Segment opposite_a(points[a[(ia + 1) % 3]], points[a[(ia + 2) % 3]]);
    const Segment opposite_b(points[b[(ib + 1) % 3]], points[b[(ib + 2) % 3]]);
    return CGAL::do_intersect(opposite_a, tb) || CGAL::do_intersect(opposite_b, ta);
  }
  int ia = 0, ib = 0;  // shared == 2: the corners not shared
  while (a_shared[ia]) ++ia;
  while (b_shared[ib]) ++ib;
  int s0 = -1, s1 = -1;
  for (int i = 0; i < 3; ++i)
    if (a_shared[i]) (s0 < 0 ? s0 : s1) = a[i];
  const Point &p = points[s0], &q = points[s1], &ra = points[a[ia]], &rb = points[b[ib]];
  return CGAL::coplanar(p, q, ra, rb) && CGAL::coplanar_orientation(p, q, ra, rb) == CGAL::POSITIVE;
}

/// Pixel centres inside the polygon and about 2 pixels or more from its edges (a band of width
/// 2 along the edges is cleared), every `step`-th in both axes (step grows until at most
/// max_points are left). For a backdrop: every centre inside within about 1.5 pixels of an edge
/// between two known points (`known`, per polygon point: where the patch meets the mesh) or
/// where no surface is seen, every hidden_spacing_px-th elsewhere.
std::vector<Point2> interiorPixelCentres(const std::vector<Point2>& uv, const Cdt& cdt, int max_points,
                                         const ImageBackdrop* backdrop, const std::vector<std::uint8_t>& known) {
  double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
  for (const auto& p : uv) u0 = std::min(u0, p.x()), v0 = std::min(v0, p.y()), u1 = std::max(u1, p.x()), v1 = std::max(v1, p.y());
  const int x0 = static_cast<int>(std::floor(u0)), y0 = static_cast<int>(std::floor(v0));
  const int width = static_cast<int>(std::ceil(u1)) - x0 + 1, height = static_cast<int>(std::ceil(v1)) - y0 + 1;
  if (max_points <= 0 || double(width) * height > 64e6) return {};
  cv::Mat mask(height, width, CV_8U, cv::Scalar(0));
  std::vector<std::vector<cv::Point>> polygon(1);
  constexpr int kShift = 8;  // sub-pixel vertices: hole-fill vertices and chords are off the grid
  for (const auto& p : uv)
    polygon[0].emplace_back(static_cast<int>(std::lround((p.x() - x0) * (1 << kShift))),
                            static_cast<int>(std::lround((p.y() - y0) * (1 << kShift))));
  cv::fillPoly(mask, polygon, cv::Scalar(255), cv::LINE_8, kShift);
  // A backdrop keeps the centres along the edges (the raster is widened; the triangulation
  // decides), at full resolution along the runs.
  cv::Mat band;
  if (backdrop) {
    band = cv::Mat::zeros(height, width, CV_8U);
    cv::polylines(band, polygon, true, cv::Scalar(255), 3, cv::LINE_8, kShift);
    mask |= band;
    band.setTo(0);
    const std::size_t count = polygon[0].size();
    for (std::size_t i = 0; i < count; ++i)
      if (i < known.size() && known[i] && known[(i + 1) % count])
        cv::line(band, polygon[0][i], polygon[0][(i + 1) % count], cv::Scalar(255), 3, cv::LINE_8, kShift);
  } else {
    cv::polylines(mask, polygon, true, cv::Scalar(0), 2, cv::LINE_8, kShift);
  }
  const int inside = cv::countNonZero(mask);
  int step = 1;
  while (!backdrop && inside / (double(step) * step) > max_points) ++step;
  const int spacing = backdrop ? std::max(1, backdrop->hidden_spacing_px) : 1;
  std::vector<Point2> points;
  Cdt::Face_handle hint;
  for (int y = 0; y < height; ++y) {
    if ((y + y0) % step != 0) continue;
    const auto* row = mask.ptr<std::uint8_t>(y);
    for (int x = 0; x < width; ++x) {
      if (!row[x] || (x + x0) % step != 0) continue;
      if (backdrop && !band.at<std::uint8_t>(y, x) && ((x + x0) % spacing != 0 || (y + y0) % spacing != 0)) {
        const bool seen = backdrop->surface_seen ? backdrop->surface_seen(x + x0, y + y0)
                                                 : !backdrop->obstacle_within_m ||
                                                       backdrop->obstacle_within_m(x + x0, y + y0, 0) > 0;
        if (seen) continue;  // hidden, off the coarse grid
      }
      const Point2 p(x + x0, y + y0);
      Cdt::Locate_type type;
      int li = 0;
      hint = cdt.locate(p, type, li, hint);
      // The raster is approximate: the triangulation decides what is inside (a centre on an
      // unconstrained edge, e.g. a diagonal through grid points, is inside with its faces).
      const bool on_free_edge = type == Cdt::EDGE && !cdt.is_constrained(Cdt::Edge(hint, li));
      if ((type == Cdt::FACE || on_free_edge) && !cdt.is_infinite(hint) && hint->info() % 2 == 1) points.push_back(p);
    }
  }
  return points;
}

// The polygon's order of the points (index i < n: boundary point i; n + k: closing-path point
// k), each closing-path point after the boundary index `after[k]` (all after the last when
// `after` is empty). False with the reason when `after` does not fit the path.
bool polygonOrder(int n, int f, const std::vector<int>& after, std::vector<int>& order, std::string& failure) {
  order.reserve(n + f);
  if (after.empty()) {
    for (int i = 0; i < n + f; ++i) order.push_back(i);
    return true;
  }
  if (static_cast<int>(after.size()) != f) {
    failure = "closing path positions do not match the closing path";
    return false;
  }
  int k = 0;
  for (int i = 0; i < n; ++i) {
    order.push_back(i);
    for (; k < f && after[k] == i; ++k) order.push_back(n + k);
  }
  if (k != f) {
    failure = "closing path positions are not increasing boundary indices";
    return false;
  }
  return true;
}

// The image positions of the boundary points (projected) and of the closing path's points, in
// that index order. False with the reason for a point behind the camera or not finite.
bool imagePositions(const std::vector<Eigen::Vector3d>& boundary, const PinholeCamera& camera,
                    const std::vector<Eigen::Vector2d>& closing_path_px, std::vector<Point2>& uv, std::string& failure) {
  uv.reserve(boundary.size() + closing_path_px.size());
  for (const auto& p : boundary) {
    if (!p.allFinite() || !(p.z() > 0)) {
      failure = "a boundary point is not in front of the camera";
      return false;
    }
    const Eigen::Vector2d q = camera.project(p);
    uv.emplace_back(q.x(), q.y());
  }
  for (const auto& q : closing_path_px) {
    if (!q.allFinite()) {
      failure = "a closing-path point is not finite";
      return false;
    }
    uv.emplace_back(q.x(), q.y());
  }
  return true;
}

// Every pixel centre inside is a vertex of a backdrop, so the triangulation splits whole pixel
// quads; where the mesh has the other diagonal of a quad, the patch takes it: two halves split
// differently overlap, and a patch face beside a run vertex in front of a farther mesh face
// would cross it.
void takeMeshDiagonals(Cdt& cdt, const ImageBackdrop& backdrop) {
  const auto pixel = [](const Cdt::Vertex_handle& v) {
    return std::pair<long, long>(std::lround(v->point().x()), std::lround(v->point().y()));
  };
  std::vector<std::pair<Cdt::Vertex_handle, Cdt::Vertex_handle>> to_flip;
  for (const auto& e : cdt.finite_edges()) {
    if (cdt.is_constrained(e)) continue;
    const Cdt::Face_handle g = e.first, h = g->neighbor(e.second);
    if (cdt.is_infinite(g) || cdt.is_infinite(h)) continue;
    const auto a = pixel(g->vertex(Cdt::cw(e.second))), b = pixel(g->vertex(Cdt::ccw(e.second)));
    if (std::abs(a.first - b.first) != 1 || std::abs(a.second - b.second) != 1) continue;
    const auto c = pixel(g->vertex(e.second)), d = pixel(h->vertex(h->index(g)));
    const std::pair<long, long> corner1(a.first, b.second), corner2(b.first, a.second);
    if (!((c == corner1 && d == corner2) || (c == corner2 && d == corner1))) continue;
    if (backdrop.mesh_has_edge(int(c.first), int(c.second), int(d.first), int(d.second)) &&
        !backdrop.mesh_has_edge(int(a.first), int(a.second), int(b.first), int(b.second)))
      to_flip.emplace_back(g->vertex(Cdt::cw(e.second)), g->vertex(Cdt::ccw(e.second)));
  }
  for (const auto& [va, vb] : to_flip) {
    Cdt::Face_handle g;
    int i = 0;
    if (cdt.is_edge(va, vb, g, i) && !cdt.is_constrained(Cdt::Edge(g, i))) cdt.flip(g, i);
  }
}

// The polygon `uv` (in `order`) triangulated with the interior pixel centres as vertices
// (returned; vertex info: index into uv, then polygon_size + k for interior[k]), the faces
// inside marked by markNesting.
std::vector<Point2> triangulateImagePolygon(const std::vector<Point2>& uv, const std::vector<int>& order,
                                            const std::vector<Point2>& polygon_uv,
                                            const std::vector<std::uint8_t>& polygon_known,
                                            const HoleFillOptions& options, const ImageBackdrop* backdrop, Cdt& cdt) {
  const int polygon_size = static_cast<int>(uv.size());
  std::vector<Cdt::Vertex_handle> handles(polygon_size);
  for (int i = 0; i < polygon_size; ++i) {
    handles[i] = cdt.insert(uv[i], i == 0 ? Cdt::Face_handle() : handles[i - 1]->face());
    handles[i]->info() = i;
  }
  for (int i = 0; i < polygon_size; ++i)
    cdt.insert_constraint(handles[order[i]], handles[order[(i + 1) % polygon_size]]);
  markNesting(cdt);
  const std::vector<Point2> interior =
      interiorPixelCentres(polygon_uv, cdt, options.max_image_interior_vertices, backdrop, polygon_known);
  Cdt::Vertex_handle last = handles[polygon_size - 1];
  for (int k = 0; k < static_cast<int>(interior.size()); ++k) {
    last = cdt.insert(interior[k], last->face());
    last->info() = polygon_size + k;
  }
  if (backdrop && backdrop->mesh_has_edge) takeMeshDiagonals(cdt, *backdrop);
  return interior;
}

// The faces inside the polygon, as vertex infos, turning the polygon's way (`orientation`).
std::vector<std::array<int, 3>> insideFaces(const Cdt& cdt, CGAL::Orientation orientation) {
  std::vector<std::array<int, 3>> faces;
  for (const auto f : cdt.finite_face_handles()) {
    if (f->info() % 2 != 1) continue;
    std::array<int, 3> t{f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()};
    if (orientation == CGAL::RIGHT_TURN) std::swap(t[1], t[2]);  // CGAL's faces turn left
    faces.push_back(t);
  }
  return faces;
}

// The boundary's least-squares affine inverse depth in the image (inverse depth is affine in
// the image on a plane); zero everywhere for a backdrop.
struct AffineInverseDepth {
  bool zero = false;
  double c = 0, gu = 0, gv = 0, centre_u = 0, centre_v = 0;

  double operator()(const Point2& p) const {
    if (zero) return 0.0;
    return c + gu * (p.x() - centre_u) + gv * (p.y() - centre_v);
  }
};

// Fits the affine inverse depth to the boundary points (positions uv[0..n-1]).
AffineInverseDepth fitAffineInverseDepth(const std::vector<Point2>& uv, const std::vector<Eigen::Vector3d>& boundary) {
  const int n = static_cast<int>(boundary.size());
  AffineInverseDepth affine;
  for (int i = 0; i < n; ++i) affine.centre_u += uv[i].x() / n, affine.centre_v += uv[i].y() / n;
  double suu = 0, suv = 0, svv = 0, sy = 0, suy = 0, svy = 0;
  for (int i = 0; i < n; ++i) {
    const double du = uv[i].x() - affine.centre_u, dv = uv[i].y() - affine.centre_v, y = 1.0 / boundary[i].z();
    suu += du * du, suv += du * dv, svv += dv * dv, sy += y, suy += du * y, svy += dv * y;
  }
  // A tiny ridge keeps the fit defined when the boundary is a straight line in the image
  // (no gradient across it is then extrapolated); it is far below any real spread.
  suu += 1e-6 * n, svv += 1e-6 * n;
  const double det = suu * svv - suv * suv;
  affine.c = sy / n;
  affine.gu = (svv * suy - suv * svy) / det;
  affine.gv = (suu * svy - suv * suy) / det;
  return affine;
}

// Per edge with an unknown end (key: lower index << 32 | higher index), in key order: its
// cotangent weight, its faces' halves summed (sorted by edge, not hashed: a backdrop has
// hundreds of thousands of edges, and a hash map cost a quarter of its fill).
using EdgeWeights = std::vector<std::pair<std::uint64_t, double>>;
EdgeWeights cotangentWeights(const std::vector<std::array<int, 3>>& faces, const std::vector<Point2>& position, int n) {
  EdgeWeights weight;
  weight.reserve(3 * faces.size());
  for (const auto& t : faces)
    for (int k = 0; k < 3; ++k) {
      const int i = t[(k + 1) % 3], j = t[(k + 2) % 3];
      if (i < n && j < n) continue;
      const auto e1 = position[i] - position[t[k]], e2 = position[j] - position[t[k]];
      const double cross = std::abs(e1.x() * e2.y() - e1.y() * e2.x());
      const std::uint64_t key = (std::uint64_t(std::min(i, j)) << 32) | std::uint32_t(std::max(i, j));
      weight.emplace_back(key, 0.5 * (e1 * e2) / std::max(cross, 1e-300));
    }
  std::sort(weight.begin(), weight.end());
  std::size_t edge_count = 0;
  for (std::size_t q = 0; q < weight.size(); ++q)
    if (edge_count > 0 && weight[edge_count - 1].first == weight[q].first) weight[edge_count - 1].second += weight[q].second;
    else weight[edge_count++] = weight[q];
  weight.resize(edge_count);
  return weight;
}

// The depth each unknown stays behind (0: none). A backdrop's vertex: every surface within the
// reach of its faces (its longest edge, plus a pixel for the mesh faces' own extent).
std::vector<double> obstacleDepths(const std::vector<std::array<int, 3>>& faces, const std::vector<Point2>& position,
                                   const std::vector<Point2>& unknown_uv, int n, const ImageBackdrop* backdrop,
                                   const std::function<double(int, int)>& obstacle_depth_m) {
  const int m = static_cast<int>(unknown_uv.size());
  std::vector<double> obstacle(m, 0.0);
  if (backdrop && backdrop->obstacle_within_m) {
    std::vector<double> reach(m, 0.0);
    for (const auto& t : faces)
      for (int k = 0; k < 3; ++k) {
        const int i = t[k], j = t[(k + 1) % 3];
        const double length = std::sqrt(CGAL::squared_distance(position[i], position[j]));
        if (i >= n) reach[i - n] = std::max(reach[i - n], length);
        if (j >= n) reach[j - n] = std::max(reach[j - n], length);
      }
    for (int k = 0; k < m; ++k)
      obstacle[k] = backdrop->obstacle_within_m(static_cast<int>(std::lround(unknown_uv[k].x())),
                                                static_cast<int>(std::lround(unknown_uv[k].y())),
                                                static_cast<int>(std::ceil(reach[k])) + 1);
  } else if (obstacle_depth_m) {
    for (int k = 0; k < m; ++k)
      obstacle[k] = obstacle_depth_m(static_cast<int>(std::lround(unknown_uv[k].x())),
                                     static_cast<int>(std::lround(unknown_uv[k].y())));
  }
  return obstacle;
}

// Inverse depth of the unknown vertices: harmonic in the image (cotangent weights, which are
// non-negative across the unconstrained edges of a constrained Delaunay triangulation). The
// closing path's points are free (a natural boundary: no flux across the frame); so that a
// plane is still reproduced exactly there, the harmonic part extends the residual of the
// boundary's inverse depth from its affine fit (an affine function is harmonic).
struct HarmonicInverseDepth {
  const std::vector<Eigen::Vector3d>& boundary;  // points 0..n-1, known depth
  const std::vector<Point2>& position;           // every vertex's image position
  const std::vector<Point2>& unknown_uv;         // unknown k's position (vertex n + k)
  const EdgeWeights& weight;
  const AffineInverseDepth& affine;
  bool extended;  // a closing path: the unknowns extend the boundary's affine part
  bool backdrop;

  // One solve of the free unknowns (`unknown[k]`: k's index among them, -1 for a pinned one,
  // whose inverse depth is pinned[k]). False with the reason when it has no solution in front
  // of the camera.
  bool solveFree(const std::vector<double>& pinned, const std::vector<int>& unknown, int free_count,
                 Eigen::VectorXd& solved, std::string& failure) const {
    const int n = static_cast<int>(boundary.size());
    const int m = static_cast<int>(unknown_uv.size());
    // The harmonic unknowns are residuals from the affine part (zero without a closing path).
    const auto known = [&](int i) {
      return (i < n ? 1.0 / boundary[i].z() : pinned[i - n]) - (extended ? affine(position[i]) : 0.0);
    };
    std::vector<Eigen::Triplet<double>> entries;
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(free_count);
    for (const auto& [key, w_raw] : weight) {
      const int i = static_cast<int>(key >> 32), j = static_cast<int>(key & 0xffffffffu);
      const double w = std::max(w_raw, 0.0) + 1e-6;  // keeps the system definite on flat fans
      for (const auto& [a, b] : {std::pair(i, j), std::pair(j, i)}) {
        if (a < n || unknown[a - n] < 0) continue;
        entries.emplace_back(unknown[a - n], unknown[a - n], w);
        if (b >= n && unknown[b - n] >= 0) entries.emplace_back(unknown[a - n], unknown[b - n], -w);
        else rhs[unknown[a - n]] += w * known(b);
      }
    }
    if (free_count > 0) {
      Eigen::SparseMatrix<double> laplacian(free_count, free_count);
      laplacian.setFromTriplets(entries.begin(), entries.end());
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(laplacian);
      solved = solver.solve(rhs);
      if (solver.info() != Eigen::Success || !solved.allFinite() ||
          (!extended && solved.size() > 0 && solved.minCoeff() <= 0)) {
        failure = "harmonic inverse depth could not be solved";
        return false;
      }
    }
    if (extended) {
      for (int k = 0; k < m; ++k)
        if (unknown[k] >= 0) solved[unknown[k]] += affine(unknown_uv[k]);
      if (solved.size() > 0 && !(solved.minCoeff() > 0)) {
        failure = "the inverse depth extended to the frame is not positive (the surface would pass behind the camera)";
        return false;
      }
    }
    return true;
  }

  // Where an obstacle (a nearer surface of the mesh, `obstacle[k]` > 0) covers a vertex's pixel
  // and the harmonic surface comes in front of it, that vertex is pinned behind the obstacle
  // and the others are solved again (a few rounds: pinning can push neighbours forward).
  bool solve(const std::vector<double>& obstacle, Eigen::VectorXd& inverse_depth, std::string& failure) const {
    const int m = static_cast<int>(unknown_uv.size());
    std::vector<double> pinned(m, 0.0);  // inverse depth, 0: free
    inverse_depth.resize(m);
    const int rounds = backdrop ? 1 : 4;
    for (int round = 0; round < rounds; ++round) {
      std::vector<int> unknown(m, -1);
      int free_count = 0;
      for (int k = 0; k < m; ++k)
        if (pinned[k] == 0) unknown[k] = free_count++;
      Eigen::VectorXd solved;
      if (!solveFree(pinned, unknown, free_count, solved, failure)) return false;
      bool changed = false;
      std::int64_t covered = 0, hidden = 0;
      for (int k = 0; k < m; ++k) {
        inverse_depth[k] = unknown[k] >= 0 ? solved[unknown[k]] : pinned[k];
        if (unknown[k] < 0) continue;
        const double z = obstacle[k];
        if (z > 0) {
          ++covered;
          hidden += z > kHiddenDepthRatio / inverse_depth[k];
        }
        if (z > 0 && 1.0 / inverse_depth[k] < z) {
          pinned[k] = 1.0 / z;
          changed = true;
        }
      }
      // A frame hole's region reaches the frame: it is the part behind an occluder only when
      // the surfaces seen inside it are nearer than the extension. Surfaces farther away are
      // seen there: the region is not behind the occluder (the run outlines a sheet standing
      // against other surfaces), and a patch pinned behind them would be a wall of nothing.
      if (extended && !backdrop && round == 0 && hidden > kMaxHiddenFraction * covered) {
        failure = "frame hole region shows " + std::to_string(hidden) + " of " + std::to_string(covered) +
                  " covered vertices farther than the extension (not behind an occluder)";
        return false;
      }
      if (!changed) break;
    }
    // A backdrop is clamped behind its obstacles after its last solve (the solves only
    // smooth it around the pins).
    if (backdrop)
      for (int k = 0; k < m; ++k)
        if (obstacle[k] > 0 && 1.0 / inverse_depth[k] < obstacle[k]) inverse_depth[k] = 1.0 / obstacle[k];
    return true;
  }
};

// The faces in rows, as the depth mesh was built: OpenMesh attaches a face next to faces
// already there cheaply, and one in the middle of nowhere (a new boundary fan) dearly.
void sortFacesInRows(std::vector<std::array<int, 3>>& faces, const std::vector<Point2>& position) {
  std::vector<std::pair<double, std::size_t>> row_order(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const auto& t = faces[i];
    const double v = std::min({position[t[0]].y(), position[t[1]].y(), position[t[2]].y()});
    const double u = std::min({position[t[0]].x(), position[t[1]].x(), position[t[2]].x()});
    row_order[i] = {v * 1e6 + u, i};
  }
  std::sort(row_order.begin(), row_order.end());
  std::vector<std::array<int, 3>> sorted(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) sorted[i] = faces[row_order[i].second];
  faces = std::move(sorted);
}

}  // namespace

const char* holeFillMethodName(HoleFillMethod method) {
  switch (method) {
    case HoleFillMethod::ImageSpace: return "image_space";
    case HoleFillMethod::TriangulateRefineFair: return "triangulate_refine_fair";
    case HoleFillMethod::Triangulate: return "triangulate";
    case HoleFillMethod::CentroidFan: return "centroid_fan";
  }
  return "unknown";
}

HolePatch fillHolePolyline(const std::vector<Eigen::Vector3d>& boundary, HoleFillMethod method,
                           const HoleFillOptions& options) {
  HolePatch patch;
  const int n = static_cast<int>(boundary.size());
  if (n < 3) {
    patch.failure = "boundary has fewer than 3 vertices";
    return patch;
  }
  std::vector<Point> polyline;
  for (const auto& p : boundary) {
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) {
      patch.failure = "boundary has a non-finite coordinate";
      return patch;
    }
    polyline.push_back(toPoint(p));
  }
  for (int i = 0; i < n; ++i)
    if (polyline[i] == polyline[(i + 1) % n]) {
      patch.failure = "boundary has an edge of zero length";
      return patch;
    }
  bool all_collinear = true;
  for (int i = 2; i < n && all_collinear; ++i) all_collinear = CGAL::collinear(polyline[0], polyline[1], polyline[i]);
  if (all_collinear) {
    patch.failure = "boundary is collinear: every triangle over it is degenerate";
    return patch;
  }

  const Stopwatch clock;
  try {
    if (method == HoleFillMethod::CentroidFan) {
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (const auto& p : boundary) centroid += p;
      centroid /= n;
      patch.new_points.push_back(centroid);
      std::vector<Point> points = polyline;
      points.push_back(toPoint(centroid));
      for (int i = 0; i < n; ++i) {
        const std::array<int, 3> f{i, (i + 1) % n, n};
        if (faceIsDegenerate(points, f)) {
          patch.failure = "centroid fan has a degenerate triangle";
          patch.new_points.clear();
          patch.faces.clear();
          return patch;
        }
        patch.faces.push_back(f);
      }
      patch.filled = true;
      return patch;
    }
    if (!triangulatePolyline(polyline, options, clock, patch.faces, patch.failure)) {
      patch.triangulation_failed = true;
      return patch;
    }
    if (method == HoleFillMethod::TriangulateRefineFair) refineAndFair(polyline, options, clock, patch);
    patch.filled = true;
  } catch (const DeadlineExceeded&) {
    const bool triangulated = !patch.faces.empty();
    patch = HolePatch{};
    patch.triangulation_failed = !triangulated;
    patch.failure = "exceeded its time limit of " + std::to_string(options.time_limit_s) + " s";
  } catch (const std::exception& e) {
    patch = HolePatch{};
    patch.failure = std::string("CGAL failed: ") + e.what();
  }
  return patch;
}

HolePatch fillHoleInImage(const std::vector<Eigen::Vector3d>& boundary, const PinholeCamera& camera,
                          const HoleFillOptions& options, const std::function<double(int, int)>& obstacle_depth_m,
                          const std::vector<Eigen::Vector2d>& closing_path_px,
                          const std::vector<int>& closing_path_after, const ImageBackdrop* backdrop_mode) {
  const bool backdrop = backdrop_mode != nullptr;
  HolePatch patch;
  const int n = static_cast<int>(boundary.size());  // points of known depth
  const int f = static_cast<int>(closing_path_px.size());
  const int polygon_size = n + f;
  if (polygon_size < 3 || n < 2) {
    patch.failure = "boundary has fewer than 3 vertices";
    return patch;
  }
  std::vector<int> order;
  std::vector<Point2> uv;
  if (!polygonOrder(n, f, closing_path_after, order, patch.failure) ||
      !imagePositions(boundary, camera, closing_path_px, uv, patch.failure))
    return patch;
  std::vector<Point2> polygon_uv;
  std::vector<std::uint8_t> polygon_known;  // a boundary point (known depth), not a path point
  for (const int i : order) polygon_uv.push_back(uv[i]), polygon_known.push_back(i < n);
  double twice_area = 0;
  for (int i = 0; i < polygon_size; ++i)
    twice_area += polygon_uv[i].x() * polygon_uv[(i + 1) % polygon_size].y() -
                  polygon_uv[(i + 1) % polygon_size].x() * polygon_uv[i].y();
  if (!(std::abs(twice_area) > 0)) {
    patch.failure = "the hole's image polygon has no area";
    return patch;
  }
  const CGAL::Orientation orientation = twice_area > 0 ? CGAL::LEFT_TURN : CGAL::RIGHT_TURN;
  const Stopwatch clock;
  try {
    // A polygon that touches itself (two vertices on one pixel position, a vertex on an edge)
    // has no triangulation in the image without a degenerate triangle, and one that crosses
    // itself none without overlap: both are left to the 3D methods.
    if (!CGAL::is_simple_2(polygon_uv.begin(), polygon_uv.end(), Kernel())) {
      patch.failure = "the hole's image polygon touches or crosses itself";
      return patch;
    }
    Cdt cdt;
    // The unknowns: the closing path's points (free: their depth comes from the extension too),
    // then the interior pixel centres; index polygon_size + k is interior[k].
    const std::vector<Point2> interior =
        triangulateImagePolygon(uv, order, polygon_uv, polygon_known, options, backdrop_mode, cdt);
    const int m_interior = static_cast<int>(interior.size());
    const int m = f + m_interior;
    std::vector<Point2> unknown_uv(uv.begin() + n, uv.end());
    unknown_uv.insert(unknown_uv.end(), interior.begin(), interior.end());
    if (m > 0 || backdrop) markNesting(cdt);
    if (clock.seconds() > options.time_limit_s) {
      patch.failure = "image-space triangulation exceeded its time limit";
      return patch;
    }
    std::vector<std::array<int, 3>> faces = insideFaces(cdt, orientation);
    if (static_cast<int>(cdt.number_of_vertices()) != polygon_size + m_interior ||
        static_cast<int>(faces.size()) != polygon_size - 2 + 2 * m_interior) {
      patch.failure = "image-space triangulation is incomplete (" + std::to_string(faces.size()) + " of " +
                      std::to_string(polygon_size - 2 + 2 * m_interior) + " triangles)";
      return patch;
    }

    std::vector<Point2> position(uv);
    position.insert(position.end(), interior.begin(), interior.end());
    AffineInverseDepth affine;
    if (f > 0 && !backdrop) affine = fitAffineInverseDepth(uv, boundary);
    affine.zero = backdrop;
    const EdgeWeights weight = cotangentWeights(faces, position, n);
    if (m > 0) {
      const HarmonicInverseDepth harmonic{boundary, position, unknown_uv, weight, affine, f > 0, backdrop};
      Eigen::VectorXd inverse_depth;
      if (!harmonic.solve(obstacleDepths(faces, position, unknown_uv, n, backdrop_mode, obstacle_depth_m),
                          inverse_depth, patch.failure))
        return patch;
      for (int k = 0; k < m; ++k)
        patch.new_points.push_back(camera.backproject(unknown_uv[k].x(), unknown_uv[k].y(), 1.0 / inverse_depth[k]));
    }
    if (backdrop) sortFacesInRows(faces, position);
    patch.faces = std::move(faces);
    patch.filled = true;
  } catch (const std::exception& e) {
    patch = HolePatch{};
    patch.failure = std::string("image-space triangulation failed: ") + e.what();
  }
  return patch;
}

bool patchFacesIntersect(const std::vector<Eigen::Vector3d>& points_in, const std::array<int, 3>& a,
                         const std::array<int, 3>& b) {
  // Only the (at most six) corners are converted: callers test pairs one at a time.
  std::vector<Point> points(6);
  std::array<int, 3> la{}, lb{};
  int used = 0;
  int ids[6];
  const auto local = [&](int i) {
    for (int k = 0; k < used; ++k)
      if (ids[k] == i) return k;
    ids[used] = i;
    points[used] = toPoint(points_in[i]);
    return used++;
  };
  for (int k = 0; k < 3; ++k) la[k] = local(a[k]);
  for (int k = 0; k < 3; ++k) lb[k] = local(b[k]);
  if (faceIsDegenerate(points, la) || faceIsDegenerate(points, lb)) return false;
  return facesIntersect(points, la, lb);
}

namespace {

using FaceBox = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::size_t>;

// The boxes of the non-degenerate faces, with their indices.
std::vector<FaceBox> faceBoxes(const std::vector<Point>& points, const std::vector<std::array<int, 3>>& faces) {
  std::vector<FaceBox> boxes;
  boxes.reserve(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (faceIsDegenerate(points, faces[i])) continue;
    const auto& f = faces[i];
    boxes.emplace_back(points[f[0]].bbox() + points[f[1]].bbox() + points[f[2]].bbox(), i);
  }
  return boxes;
}

// The candidate boxes split by group (-1 last, as `ungrouped`), and each group's own box.
struct GroupedBoxes {
  std::vector<std::vector<FaceBox>> groups;
  std::vector<FaceBox> ungrouped, bounds;  // bounds: one per group, info = its index in groups
};

GroupedBoxes groupBoxes(const std::vector<FaceBox>& boxes, const std::vector<int>& group) {
  GroupedBoxes out;
  std::vector<int> ids;
  for (const FaceBox& box : boxes)
    if (group[box.info()] >= 0) ids.push_back(group[box.info()]);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  out.groups.resize(ids.size());
  for (const FaceBox& box : boxes) {
    const int id = group[box.info()];
    if (id < 0) {
      out.ungrouped.push_back(box);
      continue;
    }
    out.groups[static_cast<std::size_t>(std::lower_bound(ids.begin(), ids.end(), id) - ids.begin())].push_back(box);
  }
  for (std::size_t g = 0; g < out.groups.size(); ++g) {
    CGAL::Bbox_3 bound = out.groups[g].front().bbox();
    for (const FaceBox& box : out.groups[g]) bound += box.bbox();
    out.bounds.emplace_back(bound, g);
  }
  return out;
}

}  // namespace

std::vector<std::uint8_t> findIntersectingFaces(const std::vector<Eigen::Vector3d>& points_in,
                                                const std::vector<std::array<int, 3>>& candidates,
                                                const std::vector<std::array<int, 3>>& others,
                                                bool candidates_among_themselves,
                                                const std::vector<int>& candidate_group) {
  CGAL_precondition(candidate_group.empty() || candidate_group.size() == candidates.size());
  std::vector<Point> points;
  points.reserve(points_in.size());
  for (const auto& p : points_in) points.push_back(toPoint(p));
  std::vector<FaceBox> candidate_boxes = faceBoxes(points, candidates), other_boxes = faceBoxes(points, others);
  std::vector<std::uint8_t> hit(candidates.size(), 0);
  const auto among_candidates = [&](const FaceBox& a, const FaceBox& b) {
    if ((hit[a.info()] && hit[b.info()]) || !facesIntersect(points, candidates[a.info()], candidates[b.info()])) return;
    hit[a.info()] = hit[b.info()] = 1;
  };
  if (candidates_among_themselves && candidate_group.empty()) {
    CGAL::box_self_intersection_d(candidate_boxes.begin(), candidate_boxes.end(), among_candidates);
  } else if (candidates_among_themselves) {
    // Ungrouped faces against each other and every group; groups against the groups whose
    // bounds they meet, never within themselves.
    GroupedBoxes grouped = groupBoxes(candidate_boxes, candidate_group);
    CGAL::box_self_intersection_d(grouped.ungrouped.begin(), grouped.ungrouped.end(), among_candidates);
    for (std::vector<FaceBox>& group : grouped.groups)
      if (!grouped.ungrouped.empty())
        CGAL::box_intersection_d(grouped.ungrouped.begin(), grouped.ungrouped.end(), group.begin(), group.end(),
                                 among_candidates);
    std::vector<std::pair<std::size_t, std::size_t>> meeting;
    CGAL::box_self_intersection_d(grouped.bounds.begin(), grouped.bounds.end(),
                                  [&](const FaceBox& a, const FaceBox& b) { meeting.emplace_back(a.info(), b.info()); });
    for (const auto& [g, h] : meeting)
      CGAL::box_intersection_d(grouped.groups[g].begin(), grouped.groups[g].end(), grouped.groups[h].begin(),
                               grouped.groups[h].end(), among_candidates);
  }
  if (!other_boxes.empty() && !candidate_boxes.empty())
    CGAL::box_intersection_d(candidate_boxes.begin(), candidate_boxes.end(), other_boxes.begin(), other_boxes.end(),
                             [&](const FaceBox& a, const FaceBox& b) {
                               if (!hit[a.info()] && facesIntersect(points, candidates[a.info()], others[b.info()]))
                                 hit[a.info()] = 1;
                             });
  return hit;
}

}  // namespace solo
