#include "solo/geometry/mesh_holes.h"
#include "solo/core/report.h"
#include "triangle_raster.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

namespace solo {
namespace {

using Face = std::array<int, 3>;

struct Attempt {
  std::size_t hole = 0;
  HoleFillMethod method = HoleFillMethod::TriangulateRefineFair;
  std::string large_method;  ///< fillLargeHole's method when it made the patch
  HolePatch patch;
  std::vector<Face> faces;  ///< global indices: mesh vertex handles, then new points
};

std::vector<Face> liveFaces(const SurfaceMesh& mesh) {
  std::vector<Face> faces;
  faces.reserve(mesh.n_faces());
  for (const auto f : mesh.faces()) {
    if (mesh.status(f).deleted()) continue;
    Face t{};
    int k = 0;
    for (const auto v : mesh.fv_range(f)) t[k++] = v.idx();
    faces.push_back(t);
  }
  return faces;
}

int majorityInstance(const SurfaceMesh& mesh, const ImageVertexProperties& p, const VertexLoop& loop) {
  std::map<int, int> votes;
  for (const auto v : loop) ++votes[mesh.property(p.instance, v)];
  return std::max_element(votes.begin(), votes.end(), [](const auto& a, const auto& b) { return a.second < b.second; })
      ->first;
}

/// The method tried after `method` failed or was rejected; false when none is left. After the
/// image-space fill come the 3D methods, starting where a hole of `hole_vertices` would start.
bool nextMethod(HoleFillMethod& method, std::size_t hole_vertices, const HoleFillOptions& options) {
  switch (method) {
    case HoleFillMethod::ImageSpace:
      method = static_cast<int>(hole_vertices) <= options.max_triangulation_only_vertices
                   ? HoleFillMethod::Triangulate
                   : HoleFillMethod::TriangulateRefineFair;
      return true;
    case HoleFillMethod::TriangulateRefineFair: method = HoleFillMethod::Triangulate; return true;
    case HoleFillMethod::Triangulate: method = HoleFillMethod::CentroidFan; return true;
    case HoleFillMethod::CentroidFan: return false;
  }
  return false;
}

/// Whether the segment a-b, less a thousandth of it at each end (its ends are mesh vertices),
/// crosses one of `faces` (Moller-Trumbore in doubles: a heuristic for choosing chords; the patch
/// itself is verified exactly).
bool segmentCrossesFaces(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const std::vector<Eigen::Vector3d>& p,
                         const std::vector<Face>& faces) {
  const Eigen::Vector3d origin = a + 1e-3 * (b - a), direction = (b - a) * (1.0 - 2e-3);
  for (const Face& f : faces) {
    const Eigen::Vector3d e1 = p[f[1]] - p[f[0]], e2 = p[f[2]] - p[f[0]];
    const Eigen::Vector3d h = direction.cross(e2);
    const double det = e1.dot(h);
    if (std::abs(det) < 1e-300) continue;
    const Eigen::Vector3d s = origin - p[f[0]];
    const double u = s.dot(h) / det;
    if (u < 0 || u > 1) continue;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = direction.dot(q) / det;
    if (v < 0 || u + v > 1) continue;
    const double t = e2.dot(q) / det;
    if (t >= 0 && t <= 1) return true;
  }
  return false;
}

/// The faces of a patch reordered so that each shares an edge with the mesh or with a face
/// before it (breadth first from the faces on the mesh's edges); the rest keep their order.
std::vector<Face> grownFromMesh(const SurfaceMesh& mesh, const std::vector<Face>& faces, int first_new) {
  std::map<std::pair<int, int>, std::vector<std::size_t>> by_edge;
  for (std::size_t i = 0; i < faces.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const int a = faces[i][k], b = faces[i][(k + 1) % 3];
      by_edge[{std::min(a, b), std::max(a, b)}].push_back(i);
    }
  std::vector<std::uint8_t> queued(faces.size(), 0);
  std::vector<std::size_t> queue;
  for (const auto& [edge, users] : by_edge) {
    if (edge.first >= first_new || edge.second >= first_new) continue;
    if (!mesh.find_halfedge(OpenMesh::VertexHandle(edge.first), OpenMesh::VertexHandle(edge.second)).is_valid()) continue;
    for (const std::size_t i : users)
      if (!queued[i]) queued[i] = 1, queue.push_back(i);
  }
  for (std::size_t head = 0; head < queue.size(); ++head)
    for (int k = 0; k < 3; ++k) {
      const int a = faces[queue[head]][k], b = faces[queue[head]][(k + 1) % 3];
      for (const std::size_t i : by_edge[{std::min(a, b), std::max(a, b)}])
        if (!queued[i]) queued[i] = 1, queue.push_back(i);
    }
  std::vector<Face> out;
  for (const std::size_t i : queue) out.push_back(faces[i]);
  for (std::size_t i = 0; i < faces.size(); ++i)
    if (!queued[i]) out.push_back(faces[i]);
  return out;
}

bool boxesOverlap(const std::vector<Eigen::Vector3d>& p, const Face& a, const Face& b) {
  for (int axis = 0; axis < 3; ++axis) {
    const double a0 = std::min({p[a[0]][axis], p[a[1]][axis], p[a[2]][axis]});
    const double a1 = std::max({p[a[0]][axis], p[a[1]][axis], p[a[2]][axis]});
    const double b0 = std::min({p[b[0]][axis], p[b[1]][axis], p[b[2]][axis]});
    const double b1 = std::max({p[b[0]][axis], p[b[1]][axis], p[b[2]][axis]});
    if (a1 < b0 || b1 < a0) return false;
  }
  return true;
}

/// x extent of the triangle `uv` inside the horizontal strip y0 <= y <= y1 (false: it misses).
bool xRangeInStrip(const Eigen::Vector2d uv[3], double y0, double y1, double& x0, double& x1) {
  x0 = 1e300, x1 = -1e300;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector2d& a = uv[k];
    const Eigen::Vector2d& b = uv[(k + 1) % 3];
    if (a.y() >= y0 && a.y() <= y1) x0 = std::min(x0, a.x()), x1 = std::max(x1, a.x());
    for (const double y : {y0, y1}) {
      if ((a.y() - y) * (b.y() - y) >= 0 || a.y() == b.y()) continue;
      const double x = a.x() + (b.x() - a.x()) * (y - a.y()) / (b.y() - a.y());
      x0 = std::min(x0, x), x1 = std::max(x1, x);
    }
  }
  return x0 <= x1;
}

/// Whether a patch's faces [begin, end) meet a face of a depth mesh: each patch face is tested
/// against the mesh faces around a pixel within one pixel (both axes) of its projection.
bool patchMeetsDepthMesh(const Attempt& attempt, std::size_t begin, std::size_t end,
                         const std::vector<Eigen::Vector3d>& points, const SurfaceMesh& mesh,
                         const PixelMapping& pixels) {
  std::vector<int> near;
  // Faces already listed for the current patch face: stamped with its number (no sort).
  thread_local std::vector<std::uint32_t> stamp;
  thread_local std::uint32_t current = 0;
  if (stamp.size() < mesh.n_faces()) stamp.assign(mesh.n_faces(), 0), current = 0;
  for (std::size_t face = begin; face < end; ++face) {
    const Face& g = attempt.faces[face];
    if (++current == 0) std::fill(stamp.begin(), stamp.end(), 0), current = 1;
    Eigen::Vector2d uv[3];
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = points[g[k]];
      if (!(p.z() > 0)) return true;  // cannot be placed in the image: not verified, not kept
      uv[k] = pixels.camera.project(p);
    }
    const double ymin = std::min({uv[0].y(), uv[1].y(), uv[2].y()}), ymax = std::max({uv[0].y(), uv[1].y(), uv[2].y()});
    const int r0 = std::max(0, static_cast<int>(std::ceil(ymin - 1))), r1 = std::min(pixels.height - 1, static_cast<int>(std::floor(ymax + 1)));
    near.clear();
    for (int y = r0; y <= r1; ++y) {
      double x0 = 0, x1 = 0;
      if (!xRangeInStrip(uv, y - 1.0, y + 1.0, x0, x1)) continue;
      const int c0 = std::max(0, static_cast<int>(std::ceil(x0 - 1))), c1 = std::min(pixels.width - 1, static_cast<int>(std::floor(x1 + 1)));
      for (int x = c0; x <= c1; ++x) {
        const int vi = (*pixels.vertex_of_pixel)[static_cast<std::size_t>(y) * pixels.width + x];
        if (vi < 0) continue;
        const OpenMesh::VertexHandle vh(vi);
        if (mesh.status(vh).deleted()) continue;
        for (const auto f : mesh.vf_range(vh))
          if (stamp[f.idx()] != current && !mesh.status(f).deleted()) {
            stamp[f.idx()] = current;
            near.push_back(f.idx());
          }
      }
    }
    for (const int fi : near) {
      Face t{};
      int k = 0;
      for (const auto v : mesh.fv_range(OpenMesh::FaceHandle(fi))) t[k++] = v.idx();
      if (boxesOverlap(points, g, t) && patchFacesIntersect(points, g, t)) return true;
    }
  }
  return false;
}

/// What closeHoles shares between its steps: the holes (those given, then the pieces of large
/// holes split by chords, each a hole of its own), what became of each, the points (the mesh's
/// vertices, then the accepted patches' new points) and the faces a patch must not meet.
struct HoleCloser {
  HoleCloser(SurfaceMesh& mesh, const std::vector<VertexLoop>& input_holes, const HoleFillOptions& options,
             const std::optional<PixelMapping>& pixels, const LargeHoleOptions& large, HoleClosing& result);
  HoleCloser(const HoleCloser&) = delete;
  HoleCloser& operator=(const HoleCloser&) = delete;

  void readPoints();
  void listObstacleFaces();
  void chooseFirstMethods();
  void prepareImageSpace();

  bool largeRoot(std::size_t hole) const;
  bool largeEligible(std::size_t hole) const;
  ChordTest chordTest(const std::vector<Eigen::Vector3d>& boundary) const;
  bool splitHole(std::size_t hole, std::vector<std::size_t>& into);
  double obstacleDepthAt(int u, int v) const;
  double backdropObstacleWithin(int u, int v, int radius) const;
  bool meshHasEdge(int u0, int v0, int u1, int v1) const;

  void fillAll();
  void runRound();
  void tryHole(std::size_t hole, Attempt& attempt) const;
  void tryLargeHole(std::size_t hole, const std::vector<Eigen::Vector3d>& boundary, Attempt& attempt) const;
  HolePatch tryInImage(std::size_t hole, const std::vector<Eigen::Vector3d>& boundary) const;
  void retry(std::size_t hole, const std::string& why, std::vector<std::size_t>& next);
  std::vector<Attempt> placeTries(std::vector<Attempt>& tries, std::vector<Eigen::Vector3d>& round_points,
                                  std::vector<std::size_t>& next);
  std::vector<Face> globalFaces(const Attempt& attempt, int base) const;
  std::vector<std::uint8_t> rejectedAttempts(const std::vector<Attempt>& attempts,
                                             const std::vector<Eigen::Vector3d>& round_points) const;
  void accept(Attempt& attempt);

  void attachAccepted();
  bool addPatchFaces(const Attempt& attempt, int first_new, const std::vector<OpenMesh::VertexHandle>& handle_of_new,
                     std::vector<OpenMesh::FaceHandle>& added);
  void labelNewVertices(const Attempt& attempt, int first_new,
                        const std::vector<OpenMesh::VertexHandle>& handle_of_new);

  void finish();
  void refill(std::vector<std::uint8_t>& open, std::vector<std::uint8_t>& refilled);
  void countRoots(const std::vector<std::uint8_t>& open, const std::vector<std::uint8_t>& refilled);
  void warnOpen(const std::vector<std::uint8_t>& open);

  SurfaceMesh& mesh;
  const std::vector<VertexLoop>& input_holes;
  const HoleFillOptions& options;
  const std::optional<PixelMapping>& pixels;
  const LargeHoleOptions& large;
  HoleClosing& result;
  const bool by_pixels;

  std::vector<VertexLoop> holes;
  std::vector<std::size_t> root_of;
  std::vector<std::uint8_t> was_split, attached;
  std::vector<int> pieces_of_root;
  // Large-hole stage per hole, between the triangulation and the centroid fan (general meshes):
  // 0 not yet, 1 tangent-continuous fit, 2 membrane without the mesh's slope (method_of says
  // centroid_fan meanwhile), 3 done.
  std::vector<std::uint8_t> large_stage;
  std::vector<std::string> large_failure;
  std::vector<std::string> last_failure;
  std::vector<HoleFillMethod> method_of;
  std::vector<int> split_depth;

  std::vector<Eigen::Vector3d> points;
  // Without pixels every live face is a potential obstacle; with them the mesh is looked up
  // per pixel and only accepted patches are listed here.
  std::vector<Face> others;

  /// The holes of the current round; after fillAll, those given up.
  std::vector<std::size_t> pending;
  std::vector<std::size_t> given_up;
  std::vector<Attempt> accepted;

  std::function<double(int, int)> obstacle_depth;
  // A backdrop's obstacles: the farthest surface within a radius, from maximum filters of
  // radius 0, 1, 2, 4, 8 and 16 pixels (a longer reach is scanned directly).
  std::vector<cv::Mat> farthest_within;
  ImageBackdrop backdrop;
};

// Inside a hole's image region the only mesh vertices are those of an occluder in front of
// it: an image-space patch stays kObstacleClearance_m behind them, leaving room for the
// occluder's solid back (foreground_solids.cpp clamps it in front of the patch).
constexpr double kObstacleClearance_m = 0.10;

// A large hole (or piece) no method closed is cut by a chord into two pieces that go through
// the whole chain again; each patch is verified alone, so the pieces that close stay closed.
constexpr int kMinSplitVertices = 24, kMaxSplitDepth = 8;

HoleCloser::HoleCloser(SurfaceMesh& mesh, const std::vector<VertexLoop>& input_holes, const HoleFillOptions& options,
                       const std::optional<PixelMapping>& pixels, const LargeHoleOptions& large, HoleClosing& result)
    : mesh(mesh),
      input_holes(input_holes),
      options(options),
      pixels(pixels),
      large(large),
      result(result),
      by_pixels(pixels && pixels->vertex_of_pixel),
      holes(input_holes) {
  root_of.resize(holes.size());
  for (std::size_t i = 0; i < holes.size(); ++i) root_of[i] = i;
  was_split.assign(holes.size(), 0), attached.assign(holes.size(), 0);
  pieces_of_root.assign(holes.size(), 1);
  result.hole_methods.assign(holes.size(), "open");
  result.hole_faces.assign(holes.size(), {});
  large_stage.assign(holes.size(), 0);
  large_failure.resize(holes.size());
  readPoints();
  listObstacleFaces();
  chooseFirstMethods();
  split_depth.assign(holes.size(), 0);
  prepareImageSpace();
}

void HoleCloser::readPoints() {
  points.reserve(mesh.n_vertices());
  for (const auto v : mesh.all_vertices()) {
    const auto& p = mesh.point(v);
    points.emplace_back(p[0], p[1], p[2]);
  }
}

// Faces with a vertex off the pixel grid (earlier patches) are not found per pixel: listed.
void HoleCloser::listObstacleFaces() {
  if (!by_pixels) {
    others = liveFaces(mesh);
    return;
  }
  std::vector<std::uint8_t> listed(mesh.n_faces(), 0);
  for (const auto v : mesh.vertices()) {
    if (mesh.property(pixels->properties.origin, v) == static_cast<std::uint8_t>(VertexOrigin::Pixel)) continue;
    for (const auto f : mesh.vf_range(v)) {
      if (listed[f.idx()]) continue;
      listed[f.idx()] = 1;
      Face g{};
      int k = 0;
      for (const auto u : mesh.fv_range(f)) g[k++] = u.idx();
      others.push_back(g);
    }
  }
}

// Every hole pending, at the method its size (or the image) calls for first.
void HoleCloser::chooseFirstMethods() {
  last_failure.resize(holes.size());
  pending.resize(holes.size());
  method_of.assign(holes.size(), HoleFillMethod::TriangulateRefineFair);
  for (std::size_t i = 0; i < holes.size(); ++i) {
    pending[i] = i;
    result.largest_hole_vertices = std::max<std::int64_t>(result.largest_hole_vertices, holes[i].size());
    if (static_cast<int>(holes[i].size()) <= options.max_triangulation_only_vertices)
      method_of[i] = HoleFillMethod::Triangulate;
    // A depth mesh's hole is first closed in the image, where the mesh has no face.
    if (by_pixels && options.image_space_first) method_of[i] = HoleFillMethod::ImageSpace;
  }
}

// The obstacles of image-space patches, and the backdrops' maximum filters and callbacks.
void HoleCloser::prepareImageSpace() {
  obstacle_depth = [this](int u, int v) { return obstacleDepthAt(u, v); };
  const bool farthest_given = by_pixels && pixels->farthest_surface_m && !pixels->farthest_surface_m->empty();
  if (farthest_given) {
    cv::Mat base = pixels->farthest_surface_m->clone();
    if (pixels->observed_depth_m && pixels->observed_depth_m->size() == base.size())
      cv::max(base, *pixels->observed_depth_m, base);
    farthest_within.push_back(base);
    for (int radius = 1; radius <= 16; radius *= 2) {
      cv::Mat wider;
      cv::dilate(base, wider, cv::Mat::ones(2 * radius + 1, 2 * radius + 1, CV_8U));
      farthest_within.push_back(std::move(wider));
    }
  }
  backdrop.obstacle_within_m = [this](int u, int v, int radius) { return backdropObstacleWithin(u, v, radius); };
  if (farthest_given)
    backdrop.surface_seen = [this](int u, int v) {
      const cv::Mat& seen = *pixels->farthest_surface_m;
      return seen.at<float>(std::clamp(v, 0, seen.rows - 1), std::clamp(u, 0, seen.cols - 1)) > 0;
    };
  backdrop.mesh_has_edge = [this](int u0, int v0, int u1, int v1) { return meshHasEdge(u0, v0, u1, v1); };
}

// Large holes (beyond the exhaustive search) of general meshes, and their pieces.
bool HoleCloser::largeRoot(std::size_t hole) const {
  return !by_pixels && large.enabled &&
         (large.any_size || static_cast<int>(input_holes[root_of[hole]].size()) > options.max_cubic_boundary_vertices);
}

bool HoleCloser::largeEligible(std::size_t hole) const {
  return largeRoot(hole) && static_cast<int>(holes[hole].size()) > options.max_triangulation_only_vertices;
}

// Faces that can block a chord of a loop: those meeting its bounding box (chords lie inside).
ChordTest HoleCloser::chordTest(const std::vector<Eigen::Vector3d>& boundary) const {
  Eigen::Vector3d low = boundary[0], high = boundary[0];
  for (const auto& p : boundary) low = low.cwiseMin(p), high = high.cwiseMax(p);
  auto near = std::make_shared<std::vector<Face>>();
  for (const Face& f : others) {
    bool overlaps = true;
    for (int axis = 0; axis < 3 && overlaps; ++axis)
      overlaps = std::max({points[f[0]][axis], points[f[1]][axis], points[f[2]][axis]}) >= low[axis] &&
                 std::min({points[f[0]][axis], points[f[1]][axis], points[f[2]][axis]}) <= high[axis];
    if (overlaps) near->push_back(f);
  }
  return ChordTest([&points = points, near](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return segmentCrossesFaces(a, b, points, *near);
  });
}

// Cuts a large hole by a chord into two pieces, appended to the holes and to `into`; false
// when it is not large, too small or split too often, or no chord fits.
bool HoleCloser::splitHole(std::size_t hole, std::vector<std::size_t>& into) {
  const std::size_t root = root_of[hole];
  if (!largeRoot(hole) || static_cast<int>(holes[hole].size()) < kMinSplitVertices ||
      split_depth[hole] >= kMaxSplitDepth || pieces_of_root[root] + 1 > large.max_pieces)
    return false;
  std::vector<Eigen::Vector3d> boundary;
  for (const auto v : holes[hole]) boundary.push_back(points[v.idx()]);
  const VertexLoop& loop = holes[hole];
  // A chord that is already an edge of the mesh (across a narrow strip) cannot be added.
  int a = -1, b = -1;
  for (const auto& [i, j] : chooseChords(boundary, 8, chordTest(boundary)))
    if (!mesh.find_halfedge(loop[i], loop[j]).is_valid() && !mesh.find_halfedge(loop[j], loop[i]).is_valid()) {
      a = i, b = j;
      break;
    }
  if (a < 0) return false;
  VertexLoop first(loop.begin() + a, loop.begin() + b + 1), second(loop.begin() + b, loop.end());
  second.insert(second.end(), loop.begin(), loop.begin() + a + 1);
  was_split[hole] = 1;
  ++pieces_of_root[root];
  for (VertexLoop* piece : {&first, &second}) {
    const std::size_t id = holes.size();
    const bool tiny = static_cast<int>(piece->size()) <= options.max_triangulation_only_vertices;
    holes.push_back(std::move(*piece));
    root_of.push_back(root);
    was_split.push_back(0);
    attached.push_back(0);
    pieces_of_root.push_back(0);
    split_depth.push_back(split_depth[hole] + 1);
    result.hole_methods.push_back("open");
    large_stage.push_back(0);
    large_failure.push_back({});
    last_failure.push_back({});
    method_of.push_back(tiny ? HoleFillMethod::Triangulate : HoleFillMethod::TriangulateRefineFair);
    into.push_back(id);
  }
  return true;
}

double HoleCloser::obstacleDepthAt(int u, int v) const {
  if (u < 0 || v < 0 || u >= pixels->width || v >= pixels->height) return 0.0;
  const int vi = (*pixels->vertex_of_pixel)[static_cast<std::size_t>(v) * pixels->width + u];
  if (vi < 0) return 0.0;
  const OpenMesh::VertexHandle vh(vi);
  if (mesh.status(vh).deleted() || mesh.is_isolated(vh)) return 0.0;
  return points[vi].z() + kObstacleClearance_m;
}

double HoleCloser::backdropObstacleWithin(int u, int v, int radius) const {
  if (farthest_within.empty()) return 0.0;
  const cv::Mat& base = farthest_within.front();
  u = std::clamp(u, 0, base.cols - 1), v = std::clamp(v, 0, base.rows - 1);
  double farthest = 0;
  if (radius <= 16) {
    std::size_t level = 0;
    while (level < farthest_within.size() && (level == 0 ? 0 : 1 << (level - 1)) < radius) ++level;
    farthest = farthest_within[level].at<float>(v, u);
  } else {
    for (int y = std::max(0, v - radius); y <= std::min(base.rows - 1, v + radius); ++y)
      for (int x = std::max(0, u - radius); x <= std::min(base.cols - 1, u + radius); ++x)
        farthest = std::max(farthest, static_cast<double>(base.at<float>(y, x)));
  }
  return farthest > 0 ? farthest + kObstacleClearance_m : 0.0;
}

bool HoleCloser::meshHasEdge(int u0, int v0, int u1, int v1) const {
  const auto live = [&](int u, int v) {
    if (u < 0 || v < 0 || u >= pixels->width || v >= pixels->height) return OpenMesh::VertexHandle();
    const int vi = (*pixels->vertex_of_pixel)[static_cast<std::size_t>(v) * pixels->width + u];
    if (vi < 0 || mesh.status(OpenMesh::VertexHandle(vi)).deleted()) return OpenMesh::VertexHandle();
    return OpenMesh::VertexHandle(vi);
  };
  const OpenMesh::VertexHandle a = live(u0, v0), b = live(u1, v1);
  if (!a.is_valid() || !b.is_valid()) return false;
  const auto he = mesh.find_halfedge(a, b);
  return he.is_valid() && !mesh.status(mesh.edge_handle(he)).deleted();
}

// Rounds of patches until no hole is pending; then `pending` lists the holes given up.
void HoleCloser::fillAll() {
  while (!pending.empty()) runRound();
  pending = std::move(given_up);
}

// One round: a patch per pending hole, verified; the accepted kept, the others retried.
void HoleCloser::runRound() {
  for (const std::size_t hole : pending)
    if (method_of[hole] == HoleFillMethod::CentroidFan && large_stage[hole] == 0 && largeEligible(hole))
      large_stage[hole] = 1;
  // Patches of independent holes: computed in parallel, each into its own slot.
  std::vector<Attempt> tries(pending.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(pending.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) tryHole(pending[i], tries[i]);
  });
  std::vector<std::size_t> still_pending;
  std::vector<Eigen::Vector3d> round_points = points;
  std::vector<Attempt> attempts = placeTries(tries, round_points, still_pending);
  const std::vector<std::uint8_t> rejected = rejectedAttempts(attempts, round_points);
  for (std::size_t a = 0; a < attempts.size(); ++a) {
    if (rejected[a]) {
      ++result.patches_rejected_for_intersection;
      retry(attempts[a].hole, "the patch intersects the mesh", still_pending);
      continue;
    }
    accept(attempts[a]);
  }
  std::sort(still_pending.begin(), still_pending.end());
  pending = std::move(still_pending);
}

// The patch of one hole by its current method (or large-hole stage).
void HoleCloser::tryHole(std::size_t hole, Attempt& attempt) const {
  std::vector<Eigen::Vector3d> boundary;
  for (const auto v : holes[hole]) boundary.push_back(points[v.idx()]);
  attempt.hole = hole;
  attempt.method = method_of[hole];
  if (large_stage[hole] == 1 || large_stage[hole] == 2) {
    tryLargeHole(hole, boundary, attempt);
    return;
  }
  attempt.patch = method_of[hole] == HoleFillMethod::ImageSpace ? tryInImage(hole, boundary)
                                                                 : fillHolePolyline(boundary, method_of[hole], options);
}

void HoleCloser::tryLargeHole(std::size_t hole, const std::vector<Eigen::Vector3d>& boundary, Attempt& attempt) const {
  // The mesh neighbours off the loop: the fit continues the surface across the boundary.
  std::vector<std::vector<Eigen::Vector3d>> ring(holes[hole].size());
  std::vector<int> on_loop;
  for (const auto v : holes[hole]) on_loop.push_back(v.idx());
  std::sort(on_loop.begin(), on_loop.end());
  for (std::size_t k = 0; k < holes[hole].size(); ++k)
    for (const auto u : mesh.vv_range(holes[hole][k]))
      if (!std::binary_search(on_loop.begin(), on_loop.end(), u.idx())) ring[k].push_back(points[u.idx()]);
  // Second try without the slope: where the surface meets the hole at a crease (a wall
  // around a flat opening) continuing its slope overshoots into the mesh.
  LargeHoleOptions this_try = large;
  this_try.tangent_continuous = large_stage[hole] == 1;
  LargeHolePatch filled = fillLargeHole(boundary, ring, options, this_try, chordTest(boundary));
  attempt.large_method = filled.patch.filled ? filled.method : "large_hole";
  attempt.patch = std::move(filled.patch);
}

HolePatch HoleCloser::tryInImage(std::size_t hole, const std::vector<Eigen::Vector3d>& boundary) const {
  std::vector<Eigen::Vector2d> closing_path;
  if (pixels->frame_paths && hole < pixels->frame_paths->size())
    for (const auto& p : (*pixels->frame_paths)[hole]) closing_path.emplace_back(p[0], p[1]);
  std::vector<int> closing_after;
  if (!closing_path.empty() && pixels->frame_path_after && hole < pixels->frame_path_after->size())
    closing_after = (*pixels->frame_path_after)[hole];
  const bool as_backdrop = pixels->backdrop && hole < pixels->backdrop->size() && (*pixels->backdrop)[hole];
  return fillHoleInImage(boundary, pixels->camera, options, obstacle_depth, closing_path, closing_after,
                         as_backdrop ? &backdrop : nullptr);
}

// A hole whose patch failed or was rejected: its next large-hole stage or method, else its
// pieces (into `next`), else given up.
void HoleCloser::retry(std::size_t hole, const std::string& why, std::vector<std::size_t>& next) {
  if (large_stage[hole] == 1 || large_stage[hole] == 2) {  // then without the slope, then the fan
    large_failure[hole] += (large_stage[hole] == 1 ? "; large-hole fill (tangent): " : "; (membrane): ") + why;
    ++large_stage[hole];
    next.push_back(hole);
    return;
  }
  last_failure[hole] = std::string(holeFillMethodName(method_of[hole])) + ": " + why;
  const bool image_only = method_of[hole] == HoleFillMethod::ImageSpace && by_pixels && pixels->image_space_only &&
                          hole < pixels->image_space_only->size() && (*pixels->image_space_only)[hole];
  if (!image_only && nextMethod(method_of[hole], holes[hole].size(), options)) next.push_back(hole);
  else if (!splitHole(hole, next)) given_up.push_back(hole);
}

// The filled tries with their faces in global indices (their new points appended to
// `round_points`); the failed ones retried.
std::vector<Attempt> HoleCloser::placeTries(std::vector<Attempt>& tries, std::vector<Eigen::Vector3d>& round_points,
                                            std::vector<std::size_t>& next) {
  std::vector<Attempt> attempts;
  for (Attempt& attempt : tries) {
    const std::size_t hole = attempt.hole;
    if (!attempt.patch.filled) {
      // A triangulation that failed inside the full pipeline fails alone too: go to the fan.
      const bool skip = attempt.patch.triangulation_failed && method_of[hole] == HoleFillMethod::TriangulateRefineFair;
      retry(hole, attempt.patch.failure, next);
      if (skip && !next.empty() && next.back() == hole) method_of[hole] = HoleFillMethod::CentroidFan;
      continue;
    }
    const int base = static_cast<int>(round_points.size());
    round_points.insert(round_points.end(), attempt.patch.new_points.begin(), attempt.patch.new_points.end());
    attempt.faces = globalFaces(attempt, base);
    attempts.push_back(std::move(attempt));
  }
  return attempts;
}

// The patch's faces in global indices: its boundary positions become the hole's vertices, its
// new points are numbered from `base`.
std::vector<Face> HoleCloser::globalFaces(const Attempt& attempt, int base) const {
  const VertexLoop& loop = holes[attempt.hole];
  const int n = static_cast<int>(loop.size());
  std::vector<Face> faces;
  for (const auto& f : attempt.patch.faces) {
    Face g{};
    for (int k = 0; k < 3; ++k) g[k] = f[k] < n ? loop[f[k]].idx() : base + (f[k] - n);
    faces.push_back(g);
  }
  return faces;
}

// Verification: against the mesh (per pixel, in parallel, or all faces at once), then the
// survivors against each other and against the patches accepted in earlier rounds.
std::vector<std::uint8_t> HoleCloser::rejectedAttempts(const std::vector<Attempt>& attempts,
                                                       const std::vector<Eigen::Vector3d>& round_points) const {
  std::vector<std::uint8_t> rejected(attempts.size(), 0);
  if (by_pixels) {
    // In pieces of at most 4096 faces, so that one large patch (a backdrop) is shared out too.
    constexpr std::size_t kPiece = 4096;
    std::vector<std::array<std::size_t, 3>> pieces;  // attempt, first face, end
    for (std::size_t a = 0; a < attempts.size(); ++a)
      for (std::size_t b = 0; b < attempts[a].faces.size(); b += kPiece)
        pieces.push_back({a, b, std::min(attempts[a].faces.size(), b + kPiece)});
    std::vector<std::uint8_t> piece_meets(pieces.size(), 0);
    cv::parallel_for_(cv::Range(0, static_cast<int>(pieces.size())), [&](const cv::Range& range) {
      for (int i = range.start; i < range.end; ++i)
        piece_meets[i] =
            patchMeetsDepthMesh(attempts[pieces[i][0]], pieces[i][1], pieces[i][2], round_points, mesh, *pixels);
    });
    for (std::size_t i = 0; i < pieces.size(); ++i) rejected[pieces[i][0]] |= piece_meets[i];
  }
  // An image-space patch cannot meet itself: its faces lie over disjoint triangles of the
  // image, lifted along their rays. Its faces form one group, tested only against the others.
  std::vector<Face> candidates;
  std::vector<std::size_t> owner;
  std::vector<int> group;
  for (std::size_t a = 0; a < attempts.size(); ++a) {
    if (rejected[a]) continue;
    const int id = attempts[a].method == HoleFillMethod::ImageSpace ? static_cast<int>(a) : -1;
    for (const auto& f : attempts[a].faces) {
      candidates.push_back(f);
      owner.push_back(a);
      group.push_back(id);
    }
  }
  const std::vector<std::uint8_t> hit = findIntersectingFaces(round_points, candidates, others, true, group);
  for (std::size_t i = 0; i < hit.size(); ++i)
    if (hit[i]) rejected[owner[i]] = 1;
  return rejected;
}

// Keeps a verified patch: its new points numbered after the accepted ones, its faces among the
// obstacles, its method counted.
void HoleCloser::accept(Attempt& attempt) {
  const int base = static_cast<int>(points.size());
  points.insert(points.end(), attempt.patch.new_points.begin(), attempt.patch.new_points.end());
  attempt.faces = globalFaces(attempt, base);
  others.insert(others.end(), attempt.faces.begin(), attempt.faces.end());
  std::string& name = result.hole_methods[attempt.hole];
  if (!attempt.large_method.empty()) {
    ++(attempt.large_method == "chord_split" ? result.by_chord_split : result.by_membrane);
    name = attempt.large_method;
  } else {
    switch (attempt.method) {  // a patch too large to fair came back as its triangulation
      case HoleFillMethod::ImageSpace: ++result.by_image_space, name = "image_space"; break;
      case HoleFillMethod::TriangulateRefineFair:
        ++(attempt.patch.new_points.empty() ? result.by_triangulation : result.by_refine_fair);
        name = attempt.patch.new_points.empty() ? "triangulation" : "refine_fair";
        break;
      case HoleFillMethod::Triangulate: ++result.by_triangulation, name = "triangulation"; break;
      case HoleFillMethod::CentroidFan: ++result.by_centroid_fan, name = "centroid_fan"; break;
    }
  }
  accepted.push_back(std::move(attempt));
}

// Attaches the accepted patches. Points beyond the mesh's vertices are new vertices, in order.
void HoleCloser::attachAccepted() {
  const int first_new = static_cast<int>(mesh.n_vertices());
  std::vector<OpenMesh::VertexHandle> handle_of_new;
  for (std::size_t i = first_new; i < points.size(); ++i) {
    const auto vh = mesh.add_vertex(SurfaceMesh::Point(points[i].x(), points[i].y(), points[i].z()));
    handle_of_new.push_back(vh);
  }
  const QuietOpenMeshErrors quiet;
  // General meshes: a patch whose faces OpenMesh refuses in their order (at a vertex with two
  // boundary fans, e.g. a merged pinch) is tried again grown face by face from the mesh's edges,
  // after the other patches.
  std::vector<std::size_t> order(accepted.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::vector<std::uint8_t> tried_again(accepted.size(), 0);
  for (std::size_t next = 0; next < order.size(); ++next) {
    Attempt& attempt = accepted[order[next]];
    if (tried_again[order[next]]) attempt.faces = grownFromMesh(mesh, attempt.faces, first_new);
    std::vector<OpenMesh::FaceHandle> added;
    if (!addPatchFaces(attempt, first_new, handle_of_new, added)) {
      if (!by_pixels && !tried_again[order[next]]) {
        tried_again[order[next]] = 1;
        order.push_back(order[next]);
        continue;
      }
      last_failure[attempt.hole] = "the patch could not be attached (non-manifold configuration)";
      result.hole_methods[attempt.hole] = "open";
      pending.push_back(attempt.hole);
      continue;
    }
    attached[attempt.hole] = 1;
    result.faces_added += static_cast<std::int64_t>(added.size());
    result.vertices_added += static_cast<std::int64_t>(attempt.patch.new_points.size());
    result.patch_faces.insert(result.patch_faces.end(), added.begin(), added.end());
    if (attempt.hole < result.hole_faces.size()) result.hole_faces[attempt.hole] = added;
    if (pixels) labelNewVertices(attempt, first_new, handle_of_new);
  }
  // New vertices of patches that were not attached are isolated: remove them.
  for (const auto vh : handle_of_new)
    if (!mesh.status(vh).deleted() && mesh.is_isolated(vh)) mesh.delete_vertex(vh, false);
}

// Adds a patch's faces to the mesh (into `added`); false, with none of them left, when
// OpenMesh refuses one.
bool HoleCloser::addPatchFaces(const Attempt& attempt, int first_new,
                               const std::vector<OpenMesh::VertexHandle>& handle_of_new,
                               std::vector<OpenMesh::FaceHandle>& added) {
  for (const auto& f : attempt.faces) {
    OpenMesh::VertexHandle v[3];
    for (int k = 0; k < 3; ++k) v[k] = f[k] < first_new ? OpenMesh::VertexHandle(f[k]) : handle_of_new[f[k] - first_new];
    const auto fh = mesh.add_face(v[0], v[1], v[2]);
    if (!fh.is_valid()) {
      for (const auto added_face : added) mesh.delete_face(added_face, false);
      return false;
    }
    added.push_back(fh);
  }
  return true;
}

// A depth mesh's new vertices: the pixel they project to (clamped), origin hole_fill and the
// instance most boundary vertices carry.
void HoleCloser::labelNewVertices(const Attempt& attempt, int first_new,
                                  const std::vector<OpenMesh::VertexHandle>& handle_of_new) {
  const int instance = majorityInstance(mesh, pixels->properties, holes[attempt.hole]);
  for (const auto& f : attempt.faces)
    for (const int i : f) {
      if (i < first_new) continue;
      const auto vh = handle_of_new[i - first_new];
      const Eigen::Vector2d uv = points[i].z() > 0 ? pixels->camera.project(points[i]) : Eigen::Vector2d(-1.0, -1.0);
      const int u = std::clamp(static_cast<int>(std::lround(uv.x())), 0, pixels->width - 1);
      const int v = std::clamp(static_cast<int>(std::lround(uv.y())), 0, pixels->height - 1);
      mesh.property(pixels->properties.pixel, vh) = OpenMesh::Vec2i(u, v);
      mesh.property(pixels->properties.instance, vh) = instance;
      mesh.property(pixels->properties.origin, vh) = static_cast<std::uint8_t>(VertexOrigin::HoleFill);
    }
}

// Which holes given stay open (after a refill pass on general meshes), their counts and warnings.
void HoleCloser::finish() {
  // A hole given is closed when it or every piece of it got a patch attached.
  std::vector<std::uint8_t> open(input_holes.size(), 0);
  for (std::size_t hole = 0; hole < holes.size(); ++hole)
    if (!was_split[hole] && !attached[hole]) open[root_of[hole]] = 1;
  std::vector<std::uint8_t> refilled(input_holes.size(), 0);
  if (!by_pixels && large.refill_passes > 0) refill(open, refilled);
  countRoots(open, refilled);
  warnOpen(open);
}

// General meshes: a piece whose patch could not be attached (its edges clash with a sibling's
// patch) leaves a smaller hole inside its split hole: one more pass over the loops open there.
void HoleCloser::refill(std::vector<std::uint8_t>& open, std::vector<std::uint8_t>& refilled) {
  std::vector<int> root_of_vertex(mesh.n_vertices(), -1);
  for (std::size_t root = 0; root < input_holes.size(); ++root)
    if (open[root] && was_split[root])
      for (const auto v : input_holes[root]) root_of_vertex[v.idx()] = static_cast<int>(root);
  std::vector<VertexLoop> again;
  std::vector<std::size_t> owner;
  for (VertexLoop& loop : findBoundaryLoops(mesh)) {
    const int r = root_of_vertex[loop.front().idx()];
    bool inside = r >= 0;
    for (const auto v : loop) inside = inside && root_of_vertex[v.idx()] == r;
    if (!inside) continue;
    again.push_back(std::move(loop));
    owner.push_back(static_cast<std::size_t>(r));
  }
  if (again.empty()) return;
  LargeHoleOptions next = large;
  --next.refill_passes;
  next.any_size = true;  // what is left of a large hole, however small
  HoleClosing more = closeHoles(mesh, again, options, std::nullopt, next);
  std::vector<std::uint8_t> still_open(input_holes.size(), 0);
  for (std::size_t i = 0; i < again.size(); ++i) {
    if (more.hole_methods[i] == "open") still_open[owner[i]] = 1;
    refilled[owner[i]] = 1;
  }
  for (std::size_t root = 0; root < input_holes.size(); ++root)
    if (refilled[root] && !still_open[root]) open[root] = 0;
  result.by_refine_fair += more.by_refine_fair, result.by_triangulation += more.by_triangulation;
  result.by_centroid_fan += more.by_centroid_fan, result.by_membrane += more.by_membrane;
  result.by_chord_split += more.by_chord_split;
  result.patches_rejected_for_intersection += more.patches_rejected_for_intersection;
  result.faces_added += more.faces_added, result.vertices_added += more.vertices_added;
  result.patch_faces.insert(result.patch_faces.end(), more.patch_faces.begin(), more.patch_faces.end());
  for (const auto& w : more.warnings) result.warnings.push_back("refill: " + w);
}

// The method of each hole given and the filled and open counts.
void HoleCloser::countRoots(const std::vector<std::uint8_t>& open, const std::vector<std::uint8_t>& refilled) {
  for (std::size_t root = 0; root < input_holes.size(); ++root) {
    if (open[root]) {
      result.hole_methods[root] = "open";
      continue;
    }
    ++result.filled;
    if (was_split[root]) {
      ++result.by_chord_split;
      result.hole_methods[root] = "chord_split (" + std::to_string(pieces_of_root[root]) + " pieces" +
                                  (refilled[root] ? ", one refilled)" : ")");
    }
  }
  result.hole_methods.resize(input_holes.size());
  result.left_open = static_cast<std::int64_t>(input_holes.size()) - result.filled;
}

// A warning per hole or piece given up whose hole given stayed open, with the reasons.
void HoleCloser::warnOpen(const std::vector<std::uint8_t>& open) {
  std::sort(pending.begin(), pending.end());
  for (const std::size_t hole : pending) {
    if (!open[root_of[hole]]) continue;  // refilled
    result.warnings.push_back((root_of[hole] == hole ? std::string("hole of ")
                                                     : "piece (of a hole of " + std::to_string(input_holes[root_of[hole]].size()) + ") of ") +
                              std::to_string(holes[hole].size()) + " boundary vertices left open: " + last_failure[hole] +
                              large_failure[hole]);
  }
}

}  // namespace

cv::Mat farthestSurfaceDepth(const SurfaceMesh& mesh, const PinholeCamera& camera, int width, int height,
                             const std::vector<std::uint8_t>* left_out) {
  if (left_out && left_out->size() != mesh.n_faces())
    throw std::invalid_argument("farthestSurfaceDepth: left_out has " + std::to_string(left_out->size()) +
                                " entries for " + std::to_string(mesh.n_faces()) + " faces");
  // Each vertex projected once; the faces rasterized in one slice per thread, each into its
  // own map, merged by the maximum.
  const int vertex_count = static_cast<int>(mesh.n_vertices());
  std::vector<Eigen::Vector2d> projected(vertex_count);
  std::vector<double> inverse_depth_of(vertex_count, 0.0);
  cv::parallel_for_(cv::Range(0, vertex_count), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      const auto& p = mesh.point(OpenMesh::VertexHandle(i));
      if (!(p[2] > 0)) continue;
      projected[i] = camera.project(Eigen::Vector3d(p[0], p[1], p[2]));
      inverse_depth_of[i] = 1.0 / p[2];
    }
  });
  const int slices = std::max(1, cv::getNumThreads());
  const int face_count = static_cast<int>(mesh.n_faces());
  std::vector<cv::Mat> partial(slices);
  cv::parallel_for_(cv::Range(0, slices), [&](const cv::Range& range) {
    for (int slice = range.start; slice < range.end; ++slice) {
      cv::Mat farthest(height, width, CV_32F, cv::Scalar(0.0f));
      const int first = static_cast<int>(std::int64_t(face_count) * slice / slices);
      const int last = static_cast<int>(std::int64_t(face_count) * (slice + 1) / slices);
      for (int fi = first; fi < last; ++fi) {
        const OpenMesh::FaceHandle f(fi);
        if (mesh.status(f).deleted() || (left_out && (*left_out)[fi])) continue;
        Eigen::Vector2d uv[3];
        double inverse_depth[3];
        int k = 0;
        bool in_front = true;
        for (const auto v : mesh.fv_range(f)) {
          if (k == 3) break;
          inverse_depth[k] = inverse_depth_of[v.idx()];
          in_front = in_front && inverse_depth[k] > 0;
          uv[k++] = projected[v.idx()];
        }
        if (!in_front || k != 3) continue;
        raster::forEachCoveredPixelCentre(uv, inverse_depth, width, height, [&](int x, int y, double depth_m) {
          float& out = farthest.at<float>(y, x);
          out = std::max(out, static_cast<float>(depth_m));
        });
      }
      partial[slice] = std::move(farthest);
    }
  });
  cv::Mat farthest = partial.front();
  for (int slice = 1; slice < slices; ++slice) cv::max(farthest, partial[slice], farthest);
  return farthest;
}

HoleClosing closeHoles(SurfaceMesh& mesh, const std::vector<VertexLoop>& input_holes, const HoleFillOptions& options,
                       const std::optional<PixelMapping>& pixels, const LargeHoleOptions& large) {
  HoleClosing result;
  result.holes = static_cast<std::int64_t>(input_holes.size());
  if (input_holes.empty()) return result;
  HoleCloser closer(mesh, input_holes, options, pixels, large, result);
  closer.fillAll();
  closer.attachAccepted();
  closer.finish();
  return result;
}

}  // namespace solo
