#include "solo/geometry/occlusion_skirts.h"

#include "solo/geometry/mesh_holes.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <optional>
#include <tuple>
#include <unordered_map>

namespace solo {
namespace {

using VH = OpenMesh::VertexHandle;
using Corners = std::array<VH, 3>;  // an invalid handle: a vertex still to be made

// Passes over the candidates: a face that attaches only through another skirt face waits for it.
constexpr int kMaxSkirtPasses = 16;
// Relative depth step between two copies of one vertex (they must not coincide).
constexpr double kCopySpacing = 1e-3;
// How close (pixels) a vertex's projection must be to a pixel centre to lie on it.
constexpr double kPixelCentreTolerancePx = 1e-3;

struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// The near-corner bits of a face split at the larger of its two depth ratios.
std::uint8_t nearCornersByDepth(const std::array<double, 3>& z) {
  std::array<int, 3> order{0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int a, int b) { return z[a] < z[b] || (z[a] == z[b] && a < b); });
  const double lower = z[order[1]] / z[order[0]], upper = z[order[2]] / z[order[1]];
  std::uint8_t bits = static_cast<std::uint8_t>(1u << order[0]);
  if (upper > lower) bits |= static_cast<std::uint8_t>(1u << order[1]);
  return bits;
}

// The near-corner bits of a face cut as an instance boundary: the instance holding the nearer
// corner, when the face has exactly two; 0 otherwise.
std::uint8_t nearCornersByInstance(const std::array<double, 3>& z, const std::array<int, 3>& instance) {
  const int first = instance[0];
  int other = first;
  for (const int id : instance)
    if (id != first) other = id;
  for (const int id : instance)
    if (id != first && id != other) return 0;
  if (other == first) return 0;
  int nearest = 0;
  for (int k = 1; k < 3; ++k)
    if (z[k] < z[nearest]) nearest = k;
  std::uint8_t bits = 0;
  for (int k = 0; k < 3; ++k)
    if (instance[k] == instance[nearest]) bits |= static_cast<std::uint8_t>(1u << k);
  return bits;
}

// Projection of a point to pixel coordinates of the depth map.
Eigen::Vector2d projectPoint(const DepthMesh& m, const SurfaceMesh::Point& p) {
  return m.camera.project(Eigen::Vector3d(p[0], p[1], p[2]));
}

// A vertex made by a skirt: its point, the pixel it projects to (clamped) and an instance.
VH addSkirtVertex(DepthMesh& m, const SurfaceMesh::Point& p, int instance) {
  const VH v = m.mesh.add_vertex(p);
  const Eigen::Vector2d uv = projectPoint(m, p);
  const int u = std::clamp(static_cast<int>(std::lround(uv.x())), 0, m.width - 1);
  const int w = std::clamp(static_cast<int>(std::lround(uv.y())), 0, m.height - 1);
  m.mesh.property(m.properties.pixel, v) = OpenMesh::Vec2i(u, w);
  m.mesh.property(m.properties.instance, v) = instance;
  m.mesh.property(m.properties.origin, v) = static_cast<std::uint8_t>(VertexOrigin::Skirt);
  return v;
}

bool freeHalfedge(const SurfaceMesh& mesh, VH from, VH to) {
  const auto h = mesh.find_halfedge(from, to);
  return h.is_valid() && mesh.is_boundary(h);
}

// Whether face `c` can be added to the mesh, keeping it manifold: at least one corner has
// faces, none of its edges is already taken on its side, and every corner that has faces is a
// boundary vertex the face attaches to by an edge (else the corner would get a second fan).
// Deleted or invalid corners count as new.
bool attaches(const SurfaceMesh& mesh, const Corners& c) {
  const auto fresh = [&](VH v) { return !v.is_valid() || mesh.status(v).deleted() || mesh.is_isolated(v); };
  if (fresh(c[0]) && fresh(c[1]) && fresh(c[2])) return false;
  for (int k = 0; k < 3; ++k) {
    const VH a = c[k], b = c[(k + 1) % 3];
    if (fresh(a) || fresh(b)) continue;
    const auto h = mesh.find_halfedge(a, b);
    if (h.is_valid() && !mesh.is_boundary(h)) return false;
  }
  for (int k = 0; k < 3; ++k) {
    const VH v = c[k], prev = c[(k + 2) % 3], next = c[(k + 1) % 3];
    if (fresh(v)) continue;
    if (!mesh.is_boundary(v)) return false;
    const bool by_prev = !fresh(prev) && freeHalfedge(mesh, prev, v);
    const bool by_next = !fresh(next) && freeHalfedge(mesh, v, next);
    if (!by_prev && !by_next) return false;
  }
  return true;
}

// Farthest solid back (metres) at each pixel, 0 where none: a skirt stays behind it.
std::vector<float> solidBackDepth(const DepthMesh& m) {
  std::vector<float> back(static_cast<std::size_t>(m.width) * m.height, 0.0f);
  for (const auto v : m.mesh.vertices()) {
    if (m.mesh.status(v).deleted() ||
        m.mesh.property(m.properties.origin, v) != static_cast<std::uint8_t>(VertexOrigin::SolidBack))
      continue;
    const OpenMesh::Vec2i p = m.mesh.property(m.properties.pixel, v);
    if (p[0] < 0 || p[1] < 0 || p[0] >= m.width || p[1] >= m.height) continue;
    float& slot = back[static_cast<std::size_t>(p[1]) * m.width + p[0]];
    slot = std::max(slot, static_cast<float>(m.mesh.point(v)[2]));
  }
  return back;
}

// The occlusion skirts: which recorded faces can have one, which near corners share a copy,
// the depth of each copy, and the faces added pass by pass.
class OcclusionSkirt {
 public:
  OcclusionSkirt(DepthMesh& m, const SkirtSources& s) : m_(m), s_(s), sets_(3 * s.corners.size()) {}

  void build(SkirtCounts& counts) {
    findCandidates(counts);
    joinSharedCopies();
    copyDepths();
    addFaces(counts);
  }

 private:
  bool isNear(std::size_t face, int k) const { return (s_.near_corners[face] >> k) & 1u; }
  VH vertex(std::size_t face, int k) const { return VH(s_.corners[face][k]); }
  double depth(std::size_t face, int k) const { return m_.mesh.point(vertex(face, k))[2]; }

  // A face has a skirt when it has near and far corners and its far vertices are still in the
  // mesh.
  void findCandidates(SkirtCounts& counts) {
    candidate_.assign(s_.corners.size(), 0);
    for (std::size_t f = 0; f < s_.corners.size(); ++f) {
      const std::uint8_t near = s_.near_corners[f];
      if (near == 0 || near == 7) continue;
      bool usable = true;
      for (int k = 0; k < 3; ++k) {
        const VH v = vertex(f, k);
        if (!isNear(f, k) && m_.mesh.status(v).deleted()) usable = false;
      }
      candidate_[f] = usable;
      counts.candidates += usable;
    }
  }

  // Two skirt faces of `faces` that shared an edge share it again when its ends play the same
  // part (near or far) in both: the pairs of their near corners at those ends, as (face,
  // corner, face, corner).
  std::vector<std::array<int, 4>> sharedCorners(const std::vector<std::uint8_t>& faces) const {
    std::vector<std::tuple<std::uint64_t, std::uint32_t, std::uint8_t>> edges;
    for (std::size_t f = 0; f < s_.corners.size(); ++f) {
      if (!faces[f]) continue;
      for (int k = 0; k < 3; ++k) {
        const auto a = static_cast<std::uint64_t>(s_.corners[f][k]);
        const auto b = static_cast<std::uint64_t>(s_.corners[f][(k + 1) % 3]);
        edges.emplace_back(std::min(a, b) << 32 | std::max(a, b), static_cast<std::uint32_t>(f), static_cast<std::uint8_t>(k));
      }
    }
    std::sort(edges.begin(), edges.end());
    std::vector<std::array<int, 4>> pairs;
    for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
      const auto [key, f, k] = edges[i];
      const auto [key2, g, j] = edges[i + 1];
      if (key != key2) continue;
      // Edge k of f runs a -> b; the same edge in g runs b -> a (corners j + 1 and j).
      const int fa = k, fb = (k + 1) % 3, ga = (j + 1) % 3, gb = j;
      if (isNear(f, fa) != isNear(g, ga) || isNear(f, fb) != isNear(g, gb)) continue;
      const int ff = static_cast<int>(f), gg = static_cast<int>(g);
      if (isNear(f, fa)) pairs.push_back({ff, fa, gg, ga});
      if (isNear(f, fb)) pairs.push_back({ff, fb, gg, gb});
    }
    return pairs;
  }

  // Near corners that share an edge in the skirt share one copy.
  void joinSharedCopies() {
    for (const auto& [f, fa, g, ga] : sharedCorners(candidate_)) sets_.unite(3 * f + fa, 3 * g + ga);
  }

  // Each copy's depth: the mean depth of the far corners one pixel away along an image axis
  // (else of every far corner) of its faces, at least kSkirtDepthMargin behind the vertex and
  // its solid's back.
  void copyDepths() {
    const std::size_t n = 3 * s_.corners.size();
    std::vector<double> sum_axis(n, 0.0), sum_all(n, 0.0);
    std::vector<int> count_axis(n, 0), count_all(n, 0);
    for (std::size_t f = 0; f < s_.corners.size(); ++f) {
      if (!candidate_[f]) continue;
      for (int k = 0; k < 3; ++k) {
        if (!isNear(f, k)) continue;
        const int root = sets_.find(3 * static_cast<int>(f) + k);
        const OpenMesh::Vec2i p = m_.mesh.property(m_.properties.pixel, vertex(f, k));
        for (int j = 0; j < 3; ++j) {
          if (isNear(f, j)) continue;
          const OpenMesh::Vec2i q = m_.mesh.property(m_.properties.pixel, vertex(f, j));
          const double z = depth(f, j);
          sum_all[root] += z, ++count_all[root];
          if (std::abs(p[0] - q[0]) + std::abs(p[1] - q[1]) == 1) sum_axis[root] += z, ++count_axis[root];
        }
      }
    }
    solid_back_ = solidBackDepth(m_);
    const std::vector<float>& back = solid_back_;
    copy_depth_.assign(n, 0.0);
    for (std::size_t c = 0; c < n; ++c) {
      if (count_all[c] == 0 || sets_.find(static_cast<int>(c)) != static_cast<int>(c)) continue;
      const VH v = vertex(c / 3, static_cast<int>(c % 3));
      const OpenMesh::Vec2i p = m_.mesh.property(m_.properties.pixel, v);
      const double solid_back = back[static_cast<std::size_t>(p[1]) * m_.width + p[0]];
      const double background = count_axis[c] > 0 ? sum_axis[c] / count_axis[c] : sum_all[c] / count_all[c];
      copy_depth_[c] = std::max({background, m_.mesh.point(v)[2] * (1 + kSkirtDepthMargin),
                                 solid_back * (1 + kSkirtDepthMargin)});
    }
  }

  // The vertex of corner k of face f: the far vertex itself, or its near vertex's copy (made on
  // first use; invalid until then).
  VH corner(std::size_t f, int k) const {
    if (!isNear(f, k)) return vertex(f, k);
    return VH(copy_vertex_[sets_.parent[3 * f + k]]);
  }

  void addFaces(SkirtCounts& counts) {
    for (std::size_t c = 0; c < sets_.parent.size(); ++c) sets_.find(static_cast<int>(c));  // flatten
    copy_vertex_.assign(sets_.parent.size(), -1);
    added_.assign(s_.corners.size(), 0);
    addInPasses(counts, [&](std::size_t f, int k) { return corner(f, k); },
                [&](std::size_t f, int k) {
                  const int root = sets_.parent[3 * f + k];
                  copy_vertex_[root] = makeCopy(vertex(f, k), copy_depth_[root]).idx();
                  return VH(copy_vertex_[root]);
                });
    for (std::size_t f = 0; f < s_.corners.size(); ++f) counts.not_attached += candidate_[f] && !added_[f];
  }

  // Adds the candidates not added yet, in passes until none attaches: `corner_of` gives a
  // corner's vertex (invalid: to be made by `make`, once the face attaches).
  template <class CornerOf, class Make>
  void addInPasses(SkirtCounts& counts, CornerOf corner_of, Make make) {
    for (int pass = 0; pass < kMaxSkirtPasses; ++pass) {
      std::int64_t added_now = 0;
      for (std::size_t f = 0; f < s_.corners.size(); ++f) {
        if (!candidate_[f] || added_[f]) continue;
        Corners c{corner_of(f, 0), corner_of(f, 1), corner_of(f, 2)};
        if (!attaches(m_.mesh, c) || behindCornerTaken(f)) continue;
        for (int k = 0; k < 3; ++k)
          if (!c[k].is_valid()) c[k] = make(f, k), ++counts.vertices;
        if (m_.mesh.add_face(c[0], c[1], c[2]).is_valid()) ++counts.faces, ++added_now;
        added_[f] = 1;
      }
      if (added_now == 0) break;
    }
  }

  // Whether something other than its own solid lies behind a corner at its pixel (a hole patch
  // or backdrop reaching behind the occluder or the background): the skirt could cross it.
  bool behindCornerTaken(std::size_t f) {
    if (farthest_.empty()) farthest_ = farthestSurfaceDepth(m_.mesh, m_.camera, m_.width, m_.height);
    for (int k = 0; k < 3; ++k) {
      const OpenMesh::Vec2i p = m_.mesh.property(m_.properties.pixel, vertex(f, k));
      const double own = std::max<double>(depth(f, k), solid_back_[static_cast<std::size_t>(p[1]) * m_.width + p[0]]);
      if (farthest_.at<float>(p[1], p[0]) > own * (1 + kCopySpacing)) return true;
    }
    return false;
  }

  // A copy of `original` on its ray at `depth_m`; the k-th copy of one vertex (k from 1) lies
  // (k - 1) * kCopySpacing further (relative), so that no two copies coincide.
  VH makeCopy(VH original, double depth_m) {
    const int k = ++copies_of_[original.idx()];
    const double z = depth_m * (1 + (k - 1) * kCopySpacing);
    const SurfaceMesh::Point p = m_.mesh.point(original) * (z / m_.mesh.point(original)[2]);
    return addSkirtVertex(m_, p, m_.mesh.property(m_.properties.instance, original));
  }

  DepthMesh& m_;
  const SkirtSources& s_;
  DisjointSets sets_;
  std::vector<std::uint8_t> candidate_;
  std::vector<double> copy_depth_;  // per copy (disjoint-set root)
  std::vector<int> copy_vertex_;    // per copy: its vertex handle index, -1 until made
  std::vector<std::uint8_t> added_;
  std::vector<float> solid_back_;  // solidBackDepth
  cv::Mat farthest_;               // farthestSurfaceDepth before the skirts, made on first use
  std::unordered_map<int, int> copies_of_;  // copies made of each vertex
};

// Signed area of a triangle's projection (negative: the triangle faces the camera).
double imageArea(const DepthMesh& m, const Corners& c) {
  const Eigen::Vector2d a = projectPoint(m, m.mesh.point(c[0]));
  const Eigen::Vector2d b = projectPoint(m, m.mesh.point(c[1]));
  const Eigen::Vector2d d = projectPoint(m, m.mesh.point(c[2]));
  return (b.x() - a.x()) * (d.y() - a.y()) - (b.y() - a.y()) * (d.x() - a.x());
}

// The border skirt: half-pixel strips outside every boundary edge along the frame or the sky
// line (no depth beyond it), and the quarter pixels at the frame's corners.
class BorderSkirt {
 public:
  explicit BorderSkirt(DepthMesh& m) : m_(m) {}

  std::int64_t build(SkirtCounts& counts) {
    std::vector<std::tuple<int, VH, VH>> edges;  // side, from, to
    for (const auto h : m_.mesh.halfedges()) {
      if (m_.mesh.status(m_.mesh.edge_handle(h)).deleted() || !m_.mesh.is_boundary(h)) continue;
      const VH a = m_.mesh.from_vertex_handle(h), b = m_.mesh.to_vertex_handle(h);
      const int side = openSide(a, b);
      if (side >= 0) edges.emplace_back(side, a, b);
    }
    std::vector<std::uint8_t> done(2 * edges.size(), 0);
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t e = 0; e < edges.size(); ++e) {
        const auto& [side, a, b] = edges[e];
        if (!done[2 * e]) done[2 * e] = addStrip({a, b, copy(b, side)}, counts);
        if (!done[2 * e + 1]) done[2 * e + 1] = addStrip({a, copy(b, side), copy(a, side)}, counts);
      }
    addCorners(counts);
    return made_;
  }

 private:
  // The pixel a vertex projects to, when it projects to a pixel centre.
  std::optional<OpenMesh::Vec2i> pixelCentre(VH v) const {
    const Eigen::Vector2d uv = projectPoint(m_, m_.mesh.point(v));
    const double u = std::round(uv.x()), w = std::round(uv.y());
    if (std::abs(uv.x() - u) > kPixelCentreTolerancePx || std::abs(uv.y() - w) > kPixelCentreTolerancePx)
      return std::nullopt;
    return OpenMesh::Vec2i(static_cast<int>(u), static_cast<int>(w));
  }

  // Sides: 0 up, 1 down, 2 left, 3 right (image axes). The side of the free halfedge a -> b
  // between pixel centres one pixel apart along an axis, when the pixels beyond it on that side
  // are outside the frame or have no depth (sky); -1 otherwise.
  int openSide(VH a, VH b) const {
    const auto pa = pixelCentre(a), pb = pixelCentre(b);
    if (!pa || !pb) return -1;
    const int du = (*pb)[0] - (*pa)[0], dv = (*pb)[1] - (*pa)[1];
    if (std::abs(du) + std::abs(dv) != 1) return -1;
    // Outward n: the triangle (a, b, a + n) faces the camera (negative image area).
    const int nu = dv, nv = -du;
    const int side = nv < 0 ? 0 : nv > 0 ? 1 : nu < 0 ? 2 : 3;
    const auto empty = [&](const OpenMesh::Vec2i& p) {
      const int u = p[0] + nu, w = p[1] + nv;
      return u < 0 || w < 0 || u >= m_.width || w >= m_.height || m_.vertexAt(u, w) < 0;
    };
    return empty(*pa) && empty(*pb) ? side : -1;
  }

  // The copy of v half a pixel outward of frame side `side` (side 4: both ways, for a corner).
  VH copy(VH v, int side) {
    const auto key = static_cast<std::int64_t>(v.idx()) * 8 + side;
    const auto found = copies_.find(key);
    if (found != copies_.end()) return VH(found->second);
    static constexpr double kOffset[4][2] = {{0, -0.5}, {0, 0.5}, {-0.5, 0}, {0.5, 0}};
    const SurfaceMesh::Point p = m_.mesh.point(v);
    const Eigen::Vector2d uv = projectPoint(m_, p);
    double du = 0, dv = 0;
    if (side < 4) du = kOffset[side][0], dv = kOffset[side][1];
    else du = uv.x() < 1 ? -0.5 : 0.5, dv = uv.y() < 1 ? -0.5 : 0.5;
    const Eigen::Vector3d q = m_.camera.backproject(uv.x() + du, uv.y() + dv, p[2]);
    const VH c = addSkirtVertex(m_, SurfaceMesh::Point(q.x(), q.y(), q.z()), m_.mesh.property(m_.properties.instance, v));
    copies_.emplace(key, c.idx());
    ++made_;
    return c;
  }

  // A strip face (its first edge the frame edge's free side: it faces the camera).
  bool addStrip(const Corners& c, SkirtCounts& counts) {
    if (imageArea(m_, c) >= 0 || !attaches(m_.mesh, c)) return false;
    if (!m_.mesh.add_face(c[0], c[1], c[2]).is_valid()) return false;
    ++counts.frame_faces;
    return true;
  }

  // At each corner pixel with strips along both sides: two triangles to the frame's corner.
  void addCorners(SkirtCounts& counts) {
    const int corners[4][4] = {{0, 0, 0, 2}, {m_.width - 1, 0, 0, 3}, {0, m_.height - 1, 1, 2},
                               {m_.width - 1, m_.height - 1, 1, 3}};
    for (const auto& [u, v, side_a, side_b] : corners) {
      const int i = m_.vertexAt(u, v);
      if (i < 0 || m_.mesh.status(VH(i)).deleted()) continue;
      const auto a = copies_.find(static_cast<std::int64_t>(i) * 8 + side_a);
      const auto b = copies_.find(static_cast<std::int64_t>(i) * 8 + side_b);
      if (a == copies_.end() || b == copies_.end()) continue;
      const VH corner = copy(VH(i), 4);
      for (Corners c : {Corners{VH(i), VH(a->second), corner}, Corners{VH(i), corner, VH(b->second)}}) {
        if (imageArea(m_, c) >= 0) std::swap(c[1], c[2]);
        addStrip(c, counts);
      }
    }
  }

  DepthMesh& m_;
  std::unordered_map<std::int64_t, int> copies_;
  std::int64_t made_ = 0;
};

}  // namespace

SkirtSources recordSkirtSources(const DepthMesh& m, const SpuriousFaceResult& result) {
  SkirtSources s;
  for (const auto f : m.mesh.faces()) {
    if (!result.spurious[f.idx()]) continue;
    std::array<int, 3> corners{};
    std::array<double, 3> z{};
    std::array<int, 3> instance{};
    int k = 0;
    for (const auto v : m.mesh.fv_range(f)) {
      if (k == 3) break;
      corners[k] = v.idx();
      z[k] = m.mesh.point(v)[2];
      instance[k] = m.mesh.property(m.properties.instance, v);
      ++k;
    }
    if (k != 3) continue;
    std::uint8_t near = 0;
    if (result.criteria[f.idx()] == kInstanceBoundary) near = nearCornersByInstance(z, instance);
    if (near == 0) near = nearCornersByDepth(z);
    s.corners.push_back(corners);
    s.near_corners.push_back(near);
  }
  return s;
}

SkirtCounts addSkirts(DepthMesh& m, const SkirtSources& sources) {
  SkirtCounts counts;
  if (!sources.corners.empty()) OcclusionSkirt(m, sources).build(counts);
  counts.frame_vertices = BorderSkirt(m).build(counts);
  return counts;
}

}  // namespace solo
