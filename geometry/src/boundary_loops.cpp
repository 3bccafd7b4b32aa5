#include "solo/geometry/boundary_loops.h"

#include <algorithm>
#include <unordered_map>

namespace solo {

std::vector<VertexLoop> findBoundaryLoops(const SurfaceMesh& mesh) {
  std::vector<VertexLoop> loops;
  std::vector<std::uint8_t> visited(mesh.n_halfedges(), 0);
  for (const auto start : mesh.halfedges()) {
    if (visited[start.idx()] || mesh.status(mesh.edge_handle(start)).deleted() || !mesh.is_boundary(start)) continue;
    VertexLoop cycle;
    OpenMesh::HalfedgeHandle h = start;
    while (h.is_valid() && !visited[h.idx()]) {
      visited[h.idx()] = 1;
      cycle.push_back(mesh.from_vertex_handle(h));
      h = mesh.next_halfedge_handle(h);
    }
    // Split at repeated vertices: a -> ... -> v -> x ... -> v -> ... becomes (v x ...) and the rest.
    VertexLoop stack;
    std::unordered_map<int, std::size_t> position;
    for (const auto v : cycle) {
      const auto found = position.find(v.idx());
      if (found == position.end()) {
        position.emplace(v.idx(), stack.size());
        stack.push_back(v);
        continue;
      }
      const std::size_t at = found->second;
      VertexLoop sub(stack.begin() + static_cast<std::ptrdiff_t>(at), stack.end());
      for (std::size_t k = at + 1; k < stack.size(); ++k) position.erase(stack[k].idx());
      stack.resize(at + 1);
      if (sub.size() >= 3) loops.push_back(std::move(sub));
    }
    if (stack.size() >= 3) loops.push_back(std::move(stack));
  }
  return loops;
}

const char* loopKindName(LoopKind kind) {
  switch (kind) {
    case LoopKind::hole: return "hole";
    case LoopKind::sky_opening: return "sky_opening";
    case LoopKind::border: return "border";
    case LoopKind::silhouette: return "silhouette";
  }
  return "unknown";
}

DepthLoops classifyDepthLoops(const DepthMesh& m, const cv::Mat& had_depth, const cv::Mat& depth_m) {
  DepthLoops out;
  out.loops = findBoundaryLoops(m.mesh);
  const SurfaceMesh& mesh = m.mesh;
  const int w = m.width, h = m.height;
  const auto pixelOf = [&](OpenMesh::VertexHandle v) { return mesh.property(m.properties.pixel, v); };
  const auto frameSides = [&](const OpenMesh::Vec2i& p) {
    return (p[0] == 0 ? 1 : 0) | (p[0] == w - 1 ? 2 : 0) | (p[1] == 0 ? 4 : 0) | (p[1] == h - 1 ? 8 : 0);
  };
  const auto nextToNoDepth = [&](const OpenMesh::Vec2i& p) {
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) {
        const int u = p[0] + du, v = p[1] + dv;
        if (u >= 0 && v >= 0 && u < w && v < h && !had_depth.at<std::uint8_t>(v, u)) return true;
      }
    return false;
  };
  // Behind an occluder: a neighbouring pixel, not joined to this vertex by an edge, is nearer.
  const auto behindOccluder = [&](OpenMesh::VertexHandle vh) {
    const OpenMesh::Vec2i p = pixelOf(vh);
    const double z = depth_m.at<float>(p[1], p[0]);
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) {
        const int u = p[0] + du, v = p[1] + dv;
        if ((du == 0 && dv == 0) || u < 0 || v < 0 || u >= w || v >= h || !had_depth.at<std::uint8_t>(v, u)) continue;
        if (depth_m.at<float>(v, u) >= 0.99 * z) continue;
        const int q = m.vertexAt(u, v);
        bool joined = false;
        if (q >= 0)
          for (const auto n : mesh.vv_range(vh)) joined = joined || n.idx() == q;
        if (!joined) return true;
      }
    return false;
  };

  for (const VertexLoop& loop : out.loops) {
    const std::size_t n = loop.size();
    std::vector<std::uint8_t> border_edge(n, 0);
    bool any_border = false, any_pixel_less = false;
    double twice_area = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const auto a = loop[i], b = loop[(i + 1) % n];
      if (mesh.property(m.properties.origin, a) != static_cast<std::uint8_t>(VertexOrigin::pixel)) any_pixel_less = true;
      const OpenMesh::Vec2i pa = pixelOf(a), pb = pixelOf(b);
      twice_area += double(pa[0]) * pb[1] - double(pb[0]) * pa[1];
      border_edge[i] = (frameSides(pa) & frameSides(pb)) != 0 || (nextToNoDepth(pa) && nextToNoDepth(pb));
      any_border = any_border || border_edge[i];
    }
    LoopKind kind;
    if (any_pixel_less) kind = LoopKind::hole;  // a loop through added vertices: not from the image grid
    else if (twice_area < 0) kind = any_border ? LoopKind::sky_opening : LoopKind::hole;
    else kind = any_border ? LoopKind::border : (twice_area == 0 ? LoopKind::hole : LoopKind::silhouette);
    out.kinds.push_back(kind);
    switch (kind) {
      case LoopKind::hole: ++out.inner_holes; out.holes.push_back(loop); break;
      case LoopKind::sky_opening: ++out.sky_openings; break;
      case LoopKind::silhouette: ++out.silhouettes; break;
      case LoopKind::border: ++out.border_loops; break;
    }
    if (kind != LoopKind::border) continue;
    // Runs of non-border edges, starting after a border edge.
    std::size_t first = 0;
    while (!border_edge[first]) ++first;
    for (std::size_t k = 1; k <= n;) {
      const std::size_t i = (first + k) % n;
      if (border_edge[i]) {
        ++k;
        continue;
      }
      std::size_t length = 0;  // edges in the run
      while (k + length <= n && !border_edge[(first + k + length) % n]) ++length;
      VertexLoop run;
      for (std::size_t e = 0; e <= length; ++e) run.push_back(loop[(i + e) % n]);
      k += length;
      if (run.size() < 3) continue;
      std::size_t behind = 0;
      for (std::size_t e = 1; e + 1 < run.size(); ++e) behind += behindOccluder(run[e]);
      if (2 * behind >= run.size() - 2) {
        out.holes.push_back(std::move(run));
        ++out.frame_holes;
      }
    }
  }
  return out;
}

}  // namespace solo
