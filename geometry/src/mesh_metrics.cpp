// Mesh evaluation. The only CGAL translation unit of the evaluation tools: exact predicates
// (Epick) for degeneracy and intersections, PMP self_intersections on a Surface_mesh when the
// soup is a valid polygon mesh, box intersection otherwise, an AABB tree for distances.

#include "solo/geometry/mesh_metrics.h"

#include "solo/core/error.h"
#include "solo/core/quantile.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace solo {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Segment = Kernel::Segment_3;
using Face = std::array<std::uint32_t, 3>;

constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;

/// Union-find with path halving.
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), std::size_t{0}); }
  std::size_t find(std::size_t i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  void unite(std::size_t a, std::size_t b) { parent_[find(a)] = find(b); }

 private:
  std::vector<std::size_t> parent_;
};

bool hasDistinctCorners(const Face& f) { return f[0] != f[1] && f[1] != f[2] && f[0] != f[2]; }

std::vector<Point> toPoints(const TriangleMesh& mesh) {
  std::vector<Point> points;
  points.reserve(mesh.vertices.size());
  for (const Eigen::Vector3d& v : mesh.vertices) points.emplace_back(v.x(), v.y(), v.z());
  return points;
}

void requireValidIndices(const TriangleMesh& mesh) {
  for (std::size_t f = 0; f < mesh.faces.size(); ++f)
    for (const std::uint32_t v : mesh.faces[f])
      if (v >= mesh.vertices.size())
        throw std::invalid_argument("face " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
                                    " of a mesh with " + std::to_string(mesh.vertices.size()) + " vertices");
}

/// Faces that are not degenerate: three distinct indices and corners not collinear (exact).
std::vector<bool> nonDegenerateFaces(const TriangleMesh& mesh, const std::vector<Point>& points) {
  std::vector<bool> ok(mesh.faces.size());
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const Face& t = mesh.faces[f];
    ok[f] = hasDistinctCorners(t) && !CGAL::collinear(points[t[0]], points[t[1]], points[t[2]]);
  }
  return ok;
}

/// Index (0..2) of vertex v in face f.
int cornerOf(const Face& f, std::uint32_t v) { return f[0] == v ? 0 : (f[1] == v ? 1 : 2); }

/// Edges, components, boundary loops and manifoldness over the faces with distinct corners.
void measureTopology(const TriangleMesh& mesh, MeshMetrics& m) {
  struct EdgeUse {
    std::uint64_t key;  // (min << 32) | max
    std::uint32_t face;
  };
  std::vector<EdgeUse> uses;
  uses.reserve(mesh.faces.size() * 3);
  std::vector<bool> referenced(mesh.vertices.size(), false);
  std::int64_t topological_faces = 0;
  for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) {
    const Face& t = mesh.faces[f];
    if (!hasDistinctCorners(t)) continue;
    ++topological_faces;
    for (int k = 0; k < 3; ++k) {
      referenced[t[k]] = true;
      const std::uint64_t a = t[k], b = t[(k + 1) % 3];
      uses.push_back({(std::min(a, b) << 32) | std::max(a, b), f});
    }
  }
  std::sort(uses.begin(), uses.end(),
            [](const EdgeUse& x, const EdgeUse& y) { return x.key < y.key || (x.key == y.key && x.face < y.face); });

  // Corner (f, k) has id 3f + k. Corners of one vertex are joined when their faces share an
  // edge through that vertex: each resulting set is one fan of the vertex.
  DisjointSets fans(mesh.faces.size() * 3);
  DisjointSets face_sets(mesh.faces.size());
  std::vector<std::pair<std::size_t, std::size_t>> boundary_corner_pairs;
  for (std::size_t begin = 0; begin < uses.size();) {
    std::size_t end = begin;
    while (end < uses.size() && uses[end].key == uses[begin].key) ++end;
    const std::size_t incident = end - begin;
    const auto a = static_cast<std::uint32_t>(uses[begin].key >> 32);
    const auto b = static_cast<std::uint32_t>(uses[begin].key & 0xffffffffu);
    ++m.edges;
    if (incident == 1) ++m.boundary_edges;
    if (incident > 2) ++m.non_manifold_edges;
    const std::uint32_t f0 = uses[begin].face;
    for (std::size_t i = begin + 1; i < end; ++i) {
      const std::uint32_t f = uses[i].face;
      face_sets.unite(f0, f);
      fans.unite(3 * std::size_t{f0} + cornerOf(mesh.faces[f0], a), 3 * std::size_t{f} + cornerOf(mesh.faces[f], a));
      fans.unite(3 * std::size_t{f0} + cornerOf(mesh.faces[f0], b), 3 * std::size_t{f} + cornerOf(mesh.faces[f], b));
    }
    if (incident == 1)
      boundary_corner_pairs.emplace_back(3 * std::size_t{f0} + cornerOf(mesh.faces[f0], a),
                                         3 * std::size_t{f0} + cornerOf(mesh.faces[f0], b));
    begin = end;
  }

  // Fans per vertex: distinct fan roots among the vertex's corners.
  std::vector<std::pair<std::uint32_t, std::size_t>> vertex_fans;
  for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) {
    if (!hasDistinctCorners(mesh.faces[f])) continue;
    for (int k = 0; k < 3; ++k) vertex_fans.emplace_back(mesh.faces[f][k], fans.find(3 * std::size_t{f} + k));
  }
  std::sort(vertex_fans.begin(), vertex_fans.end());
  vertex_fans.erase(std::unique(vertex_fans.begin(), vertex_fans.end()), vertex_fans.end());
  for (std::size_t i = 0; i < vertex_fans.size();) {
    std::size_t j = i;
    while (j < vertex_fans.size() && vertex_fans[j].first == vertex_fans[i].first) ++j;
    if (j - i > 1) ++m.non_manifold_vertices;
    i = j;
  }

  // Boundary loops: the fans at either end of each boundary edge are joined; every resulting
  // set that holds a boundary edge is one loop.
  for (const auto& [from, to] : boundary_corner_pairs) fans.unite(from, to);
  std::vector<std::size_t> loop_roots;
  loop_roots.reserve(boundary_corner_pairs.size());
  for (const auto& corners : boundary_corner_pairs) loop_roots.push_back(fans.find(corners.first));
  std::sort(loop_roots.begin(), loop_roots.end());
  m.boundary_loops = std::unique(loop_roots.begin(), loop_roots.end()) - loop_roots.begin();

  std::vector<std::size_t> component_roots;
  for (std::uint32_t f = 0; f < mesh.faces.size(); ++f)
    if (hasDistinctCorners(mesh.faces[f])) component_roots.push_back(face_sets.find(f));
  std::sort(component_roots.begin(), component_roots.end());
  m.components = std::unique(component_roots.begin(), component_roots.end()) - component_roots.begin();

  const auto used_vertices = static_cast<std::int64_t>(std::count(referenced.begin(), referenced.end(), true));
  m.euler_characteristic = used_vertices - m.edges + topological_faces;
  m.closed = topological_faces > 0 && m.boundary_edges == 0;
}

/// PMP's rule for two triangles of a soup: they intersect unless they only meet in the
/// vertices or the edge they share by index. Sharing an edge: intersect when coplanar and
/// folded onto each other. Sharing a vertex: when the edge opposite it in one crosses the
/// other. Sharing all three vertices: a duplicated face, always intersecting.
bool soupFacesIntersect(const Face& f, const Face& g, const std::vector<Point>& p) {
  int shared = 0, f_shared[3], g_shared[3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (f[i] == g[j]) {
        f_shared[shared] = i;
        g_shared[shared] = j;
        ++shared;
      }
  const Triangle tf(p[f[0]], p[f[1]], p[f[2]]), tg(p[g[0]], p[g[1]], p[g[2]]);
  if (shared == 3) return true;
  if (shared == 2) {
    const Point& a = p[f[f_shared[0]]];
    const Point& b = p[f[f_shared[1]]];
    const Point& c = p[f[3 - f_shared[0] - f_shared[1]]];
    const Point& d = p[g[3 - g_shared[0] - g_shared[1]]];
    return CGAL::coplanar(a, b, c, d) && CGAL::coplanar_orientation(a, b, c, d) == CGAL::POSITIVE;
  }
  if (shared == 1) {
    const int i = f_shared[0], j = g_shared[0];
    const Segment opposite_f(p[f[(i + 1) % 3]], p[f[(i + 2) % 3]]);
    const Segment opposite_g(p[g[(j + 1) % 3]], p[g[(j + 2) % 3]]);
    return CGAL::do_intersect(tf, opposite_g) || CGAL::do_intersect(tg, opposite_f);
  }
  return CGAL::do_intersect(tf, tg);
}

using FacePairs = std::vector<std::pair<std::size_t, std::size_t>>;

FacePairs soupSelfIntersections(const TriangleMesh& mesh, const std::vector<Point>& points,
                                const std::vector<bool>& non_degenerate) {
  using Box =
      CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::size_t, CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>;
  std::vector<Box> boxes;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    if (!non_degenerate[f]) continue;
    const Face& t = mesh.faces[f];
    boxes.emplace_back(points[t[0]].bbox() + points[t[1]].bbox() + points[t[2]].bbox(), f);
  }
  std::vector<const Box*> box_pointers;
  box_pointers.reserve(boxes.size());
  for (const Box& b : boxes) box_pointers.push_back(&b);
  FacePairs pairs;
  CGAL::box_self_intersection_d(box_pointers.begin(), box_pointers.end(), [&](const Box* x, const Box* y) {
    if (soupFacesIntersect(mesh.faces[x->info()], mesh.faces[y->info()], points))
      pairs.emplace_back(std::min(x->info(), y->info()), std::max(x->info(), y->info()));
  });
  return pairs;
}

/// When the soup (faces with distinct corners) is a valid polygon mesh, PMP on a Surface_mesh;
/// otherwise the soup rules above. Pairs of non-degenerate faces, by index into mesh.faces.
FacePairs selfIntersections(const TriangleMesh& mesh, const std::vector<Point>& points,
                            const std::vector<bool>& non_degenerate, SelfIntersectionCheck& check) {
  std::vector<std::vector<std::size_t>> polygons;
  std::vector<std::size_t> polygon_face;  // polygon index -> mesh face index
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const Face& t = mesh.faces[f];
    if (!hasDistinctCorners(t)) continue;
    polygons.push_back({t[0], t[1], t[2]});
    polygon_face.push_back(f);
  }
  if (!CGAL::Polygon_mesh_processing::is_polygon_soup_a_polygon_mesh(polygons)) {
    check = SelfIntersectionCheck::TriangleSoup;
    return soupSelfIntersections(mesh, points, non_degenerate);
  }
  check = SelfIntersectionCheck::PolygonMesh;
  using SurfaceMesh = CGAL::Surface_mesh<Point>;
  SurfaceMesh surface;
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, polygons, surface);
  // Faces are created in polygon order, so face index i is polygons[i].
  std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> found;
  CGAL::Polygon_mesh_processing::self_intersections(surface, std::back_inserter(found));
  FacePairs pairs;
  for (const auto& [a, b] : found) {
    if (a == b) continue;  // PMP reports each degenerate face as (f, f); counted apart
    const std::size_t fa = polygon_face[static_cast<std::size_t>(a)], fb = polygon_face[static_cast<std::size_t>(b)];
    pairs.emplace_back(std::min(fa, fb), std::max(fa, fb));
  }
  return pairs;
}

/// Smallest interior angle (degrees) and aspect ratio of a non-degenerate triangle.
std::pair<double, double> triangleShape(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d corners[3] = {a, b, c};
  double min_angle = 180, longest_squared = 0;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d u = corners[(k + 1) % 3] - corners[k], v = corners[(k + 2) % 3] - corners[k];
    min_angle = std::min(min_angle, std::atan2(u.cross(v).norm(), u.dot(v)) * kDegPerRad);
    longest_squared = std::max(longest_squared, u.squaredNorm());
  }
  const double twice_area = (b - a).cross(c - a).norm();
  return {min_angle, std::sqrt(3.0) * longest_squared / (2.0 * twice_area)};
}

}  // namespace

const char* selfIntersectionCheckName(SelfIntersectionCheck check) {
  return check == SelfIntersectionCheck::PolygonMesh ? "polygon_mesh" : "triangle_soup";
}

MeshMetrics evaluateMesh(const TriangleMesh& mesh) {
  requireValidIndices(mesh);
  MeshMetrics m;
  m.vertices = static_cast<std::int64_t>(mesh.vertices.size());
  m.faces = static_cast<std::int64_t>(mesh.faces.size());
  std::vector<bool> referenced(mesh.vertices.size(), false);
  for (const Face& f : mesh.faces)
    for (const std::uint32_t v : f) referenced[v] = true;
  m.unreferenced_vertices = static_cast<std::int64_t>(std::count(referenced.begin(), referenced.end(), false));

  const std::vector<Point> points = toPoints(mesh);
  const std::vector<bool> non_degenerate = nonDegenerateFaces(mesh, points);
  m.degenerate_faces = static_cast<std::int64_t>(std::count(non_degenerate.begin(), non_degenerate.end(), false));

  measureTopology(mesh, m);

  const FacePairs pairs = selfIntersections(mesh, points, non_degenerate, m.self_intersection_check);
  m.self_intersecting_pairs = static_cast<std::int64_t>(pairs.size());
  std::vector<std::size_t> faces_hit;
  for (const auto& [a, b] : pairs) {
    faces_hit.push_back(a);
    faces_hit.push_back(b);
  }
  std::sort(faces_hit.begin(), faces_hit.end());
  m.self_intersecting_faces = std::unique(faces_hit.begin(), faces_hit.end()) - faces_hit.begin();

  std::vector<double> aspect_ratios;
  double min_angle = 180;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    if (!non_degenerate[f]) continue;
    const Face& t = mesh.faces[f];
    const auto [angle, aspect] = triangleShape(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]);
    min_angle = std::min(min_angle, angle);
    aspect_ratios.push_back(aspect);
  }
  if (!aspect_ratios.empty()) {
    TriangleQuality q;
    q.min_angle_deg = min_angle;
    q.aspect_ratio_min = *std::min_element(aspect_ratios.begin(), aspect_ratios.end());
    q.aspect_ratio_max = *std::max_element(aspect_ratios.begin(), aspect_ratios.end());
    q.aspect_ratio_median = sampleQuantile(aspect_ratios, 0.5);
    q.aspect_ratio_p95 = sampleQuantile(aspect_ratios, 0.95);
    m.quality = q;
  }
  return m;
}

namespace {

/// The non-degenerate triangles of a mesh, their areas and the vertices they use.
struct Surface {
  std::vector<Triangle> triangles;
  std::vector<double> cumulative_area;
  std::vector<Point> vertices;
};

Surface surfaceOf(const TriangleMesh& mesh, const std::filesystem::path& file) {
  requireValidIndices(mesh);
  const std::vector<Point> points = toPoints(mesh);
  const std::vector<bool> non_degenerate = nonDegenerateFaces(mesh, points);
  Surface s;
  std::vector<bool> used(points.size(), false);
  double total = 0;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    if (!non_degenerate[f]) continue;
    const Face& t = mesh.faces[f];
    s.triangles.emplace_back(points[t[0]], points[t[1]], points[t[2]]);
    const Eigen::Vector3d& a = mesh.vertices[t[0]];
    total += 0.5 * (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).norm();
    s.cumulative_area.push_back(total);
    for (const std::uint32_t v : t) used[v] = true;
  }
  if (s.triangles.empty() || !(total > 0))
    throw InputError(file, "mesh has no face with non-zero area to measure distances on");
  for (std::size_t v = 0; v < points.size(); ++v)
    if (used[v]) s.vertices.push_back(points[v]);
  return s;
}

/// Area-uniform random points on a surface.
std::vector<Point> samplePoints(const Surface& s, std::int64_t count, std::mt19937_64& random) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double total = s.cumulative_area.back();
  std::vector<Point> samples;
  samples.reserve(static_cast<std::size_t>(count));
  for (std::int64_t i = 0; i < count; ++i) {
    const double pick = uniform(random) * total;
    std::size_t f = static_cast<std::size_t>(
        std::upper_bound(s.cumulative_area.begin(), s.cumulative_area.end(), pick) - s.cumulative_area.begin());
    f = std::min(f, s.triangles.size() - 1);
    const double r1 = std::sqrt(uniform(random)), r2 = uniform(random);
    const Triangle& t = s.triangles[f];
    const double wa = 1 - r1, wb = r1 * (1 - r2), wc = r1 * r2;
    samples.emplace_back(wa * t[0].x() + wb * t[1].x() + wc * t[2].x(), wa * t[0].y() + wb * t[1].y() + wc * t[2].y(),
                         wa * t[0].z() + wb * t[1].z() + wc * t[2].z());
  }
  return samples;
}

struct OneWayDistance {
  double max = 0, mean = 0;
  double share_within_tau = 0;  ///< share of the random samples closer than tau
};

/// Distances from `from` (its random samples for the mean and the share within tau; samples and
/// vertices for the max) to the surface `to`.
OneWayDistance distanceBetween(const Surface& from, const std::vector<Point>& samples, const Surface& to, double tau) {
  using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
  Tree tree(to.triangles.begin(), to.triangles.end());
  tree.accelerate_distance_queries();
  OneWayDistance d;
  double sum = 0;
  std::int64_t within = 0;
  for (const Point& p : samples) {
    const double distance = std::sqrt(tree.squared_distance(p));
    sum += distance;
    within += distance < tau;
    d.max = std::max(d.max, distance);
  }
  d.mean = sum / static_cast<double>(samples.size());
  d.share_within_tau = static_cast<double>(within) / static_cast<double>(samples.size());
  for (const Point& p : from.vertices) d.max = std::max(d.max, std::sqrt(tree.squared_distance(p)));
  return d;
}

/// Diagonal of the bounding box of a surface's vertices.
double boundingBoxDiagonal(const Surface& s) {
  const CGAL::Bbox_3 box = CGAL::bbox_3(s.vertices.begin(), s.vertices.end());
  return std::sqrt(std::pow(box.xmax() - box.xmin(), 2) + std::pow(box.ymax() - box.ymin(), 2) +
                   std::pow(box.zmax() - box.zmin(), 2));
}

}  // namespace

MeshDistances measureMeshDistances(const TriangleMesh& mesh, const TriangleMesh& reference,
                                   const MeshDistanceOptions& options, const std::filesystem::path& mesh_file,
                                   const std::filesystem::path& reference_file) {
  if (options.samples < 1)
    throw std::invalid_argument("mesh distance needs at least one sample, got " + std::to_string(options.samples));
  if (options.tau && !(std::isfinite(*options.tau) && *options.tau > 0))
    throw std::invalid_argument("F-score threshold tau must be finite and > 0, got " + std::to_string(*options.tau));
  const Surface mesh_surface = surfaceOf(mesh, mesh_file);
  const Surface reference_surface = surfaceOf(reference, reference_file);
  const double reference_diagonal = boundingBoxDiagonal(reference_surface);
  const double tau = options.tau.value_or(kDefaultFScoreTauFraction * reference_diagonal);
  std::mt19937_64 random(options.seed);
  const std::vector<Point> mesh_samples = samplePoints(mesh_surface, options.samples, random);
  const std::vector<Point> reference_samples = samplePoints(reference_surface, options.samples, random);
  const OneWayDistance to_reference = distanceBetween(mesh_surface, mesh_samples, reference_surface, tau);
  const OneWayDistance from_reference = distanceBetween(reference_surface, reference_samples, mesh_surface, tau);

  MeshDistances r;
  r.hausdorff_to_reference = to_reference.max;
  r.hausdorff_from_reference = from_reference.max;
  r.hausdorff = std::max(to_reference.max, from_reference.max);
  r.mean_to_reference = to_reference.mean;
  r.mean_from_reference = from_reference.mean;
  r.chamfer = (to_reference.mean + from_reference.mean) / 2;
  r.samples_per_direction = options.samples;
  r.mesh_vertices_checked = static_cast<std::int64_t>(mesh_surface.vertices.size());
  r.reference_vertices_checked = static_cast<std::int64_t>(reference_surface.vertices.size());
  r.reference_bbox_diagonal = reference_diagonal;
  r.tau = tau;
  r.tau_given = options.tau.has_value();
  r.precision = to_reference.share_within_tau;
  r.recall = from_reference.share_within_tau;
  const double sum = r.precision + r.recall;
  r.f_score = sum > 0 ? 2 * r.precision * r.recall / sum : 0;
  return r;
}

}  // namespace solo
