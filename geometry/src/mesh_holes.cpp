#include "solo/geometry/mesh_holes.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

namespace solo {
namespace {

using Face = std::array<int, 3>;

struct Attempt {
  std::size_t hole = 0;
  HoleFillMethod method = HoleFillMethod::triangulate_refine_fair;
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
    case HoleFillMethod::image_space:
      method = static_cast<int>(hole_vertices) <= options.max_triangulation_only_vertices
                   ? HoleFillMethod::triangulate
                   : HoleFillMethod::triangulate_refine_fair;
      return true;
    case HoleFillMethod::triangulate_refine_fair: method = HoleFillMethod::triangulate; return true;
    case HoleFillMethod::triangulate: method = HoleFillMethod::centroid_fan; return true;
    case HoleFillMethod::centroid_fan: return false;
  }
  return false;
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

/// Whether a patch meets a face of a depth mesh: each patch face is tested against the mesh
/// faces around a pixel within one pixel (both axes) of its projection.
bool patchMeetsDepthMesh(const Attempt& attempt, const std::vector<Eigen::Vector3d>& points, const SurfaceMesh& mesh,
                         const PixelMapping& pixels) {
  std::vector<int> near;
  std::vector<Face> corners;
  for (const Face& g : attempt.faces) {
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
          if (!mesh.status(f).deleted()) near.push_back(f.idx());
      }
    }
    std::sort(near.begin(), near.end());
    near.erase(std::unique(near.begin(), near.end()), near.end());
    for (const int fi : near) {
      Face t{};
      int k = 0;
      for (const auto v : mesh.fv_range(OpenMesh::FaceHandle(fi))) t[k++] = v.idx();
      if (boxesOverlap(points, g, t) && patchFacesIntersect(points, g, t)) return true;
    }
  }
  return false;
}

}  // namespace

HoleClosing closeHoles(SurfaceMesh& mesh, const std::vector<VertexLoop>& holes, const HoleFillOptions& options,
                       const std::optional<PixelMapping>& pixels) {
  HoleClosing result;
  result.holes = static_cast<std::int64_t>(holes.size());
  if (holes.empty()) return result;
  const bool by_pixels = pixels && pixels->vertex_of_pixel;

  std::vector<Eigen::Vector3d> points;
  points.reserve(mesh.n_vertices());
  for (const auto v : mesh.all_vertices()) {
    const auto& p = mesh.point(v);
    points.emplace_back(p[0], p[1], p[2]);
  }
  // Without pixels every live face is a potential obstacle; with them the mesh is looked up
  // per pixel and only accepted patches are listed here.
  std::vector<Face> others = by_pixels ? std::vector<Face>{} : liveFaces(mesh);
  std::vector<std::string> last_failure(holes.size());
  std::vector<std::size_t> pending(holes.size());
  std::vector<HoleFillMethod> method_of(holes.size(), HoleFillMethod::triangulate_refine_fair);
  for (std::size_t i = 0; i < holes.size(); ++i) {
    pending[i] = i;
    result.largest_hole_vertices = std::max<std::int64_t>(result.largest_hole_vertices, holes[i].size());
    if (static_cast<int>(holes[i].size()) <= options.max_triangulation_only_vertices)
      method_of[i] = HoleFillMethod::triangulate;
    // A depth mesh's hole is first closed in the image, where the mesh has no face.
    if (by_pixels && options.image_space_first) method_of[i] = HoleFillMethod::image_space;
  }
  std::vector<Attempt> accepted;
  std::vector<std::size_t> given_up;

  // Inside a hole's image region the only mesh vertices are those of an occluder in front of
  // it: an image-space patch stays kObstacleClearance_m behind them, leaving room for the
  // occluder's solid back (foreground_solids.cpp clamps it in front of the patch).
  constexpr double kObstacleClearance_m = 0.10;
  const std::function<double(int, int)> obstacleDepth = [&](int u, int v) {
    if (u < 0 || v < 0 || u >= pixels->width || v >= pixels->height) return 0.0;
    const int vi = (*pixels->vertex_of_pixel)[static_cast<std::size_t>(v) * pixels->width + u];
    if (vi < 0) return 0.0;
    const OpenMesh::VertexHandle vh(vi);
    if (mesh.status(vh).deleted() || mesh.is_isolated(vh)) return 0.0;
    return points[vi].z() + kObstacleClearance_m;
  };

  while (!pending.empty()) {
    // Patches of independent holes: computed in parallel, each into its own slot.
    std::vector<Attempt> tries(pending.size());
    cv::parallel_for_(cv::Range(0, static_cast<int>(pending.size())), [&](const cv::Range& range) {
      for (int i = range.start; i < range.end; ++i) {
        const std::size_t hole = pending[i];
        std::vector<Eigen::Vector3d> boundary;
        for (const auto v : holes[hole]) boundary.push_back(points[v.idx()]);
        tries[i].hole = hole;
        tries[i].method = method_of[hole];
        tries[i].patch = method_of[hole] == HoleFillMethod::image_space
                             ? fillHoleInImage(boundary, pixels->camera, options, obstacleDepth)
                             : fillHolePolyline(boundary, method_of[hole], options);
      }
    });
    std::vector<Attempt> attempts;
    std::vector<std::size_t> still_pending;
    const auto retry = [&](std::size_t hole, const std::string& why) {
      last_failure[hole] = std::string(holeFillMethodName(method_of[hole])) + ": " + why;
      if (nextMethod(method_of[hole], holes[hole].size(), options)) still_pending.push_back(hole);
      else given_up.push_back(hole);
    };
    std::vector<Eigen::Vector3d> round_points = points;
    for (Attempt& attempt : tries) {
      const std::size_t hole = attempt.hole;
      if (!attempt.patch.filled) {
        // A triangulation that failed inside the full pipeline fails alone too: go to the fan.
        const bool skip = attempt.patch.triangulation_failed && method_of[hole] == HoleFillMethod::triangulate_refine_fair;
        retry(hole, attempt.patch.failure);
        if (skip && !still_pending.empty() && still_pending.back() == hole) method_of[hole] = HoleFillMethod::centroid_fan;
        continue;
      }
      const int n = static_cast<int>(holes[hole].size());
      const int base = static_cast<int>(round_points.size());
      round_points.insert(round_points.end(), attempt.patch.new_points.begin(), attempt.patch.new_points.end());
      for (const auto& f : attempt.patch.faces) {
        Face g{};
        for (int k = 0; k < 3; ++k) g[k] = f[k] < n ? holes[hole][f[k]].idx() : base + (f[k] - n);
        attempt.faces.push_back(g);
      }
      attempts.push_back(std::move(attempt));
    }

    // Verification: against the mesh (per pixel, in parallel, or all faces at once), then the
    // survivors against each other and against the patches accepted in earlier rounds.
    std::vector<std::uint8_t> rejected(attempts.size(), 0);
    if (by_pixels) {
      cv::parallel_for_(cv::Range(0, static_cast<int>(attempts.size())), [&](const cv::Range& range) {
        for (int a = range.start; a < range.end; ++a)
          rejected[a] = patchMeetsDepthMesh(attempts[a], round_points, mesh, *pixels) ? 1 : 0;
      });
    }
    std::vector<Face> candidates;
    std::vector<std::size_t> owner;
    for (std::size_t a = 0; a < attempts.size(); ++a) {
      if (rejected[a]) continue;
      for (const auto& f : attempts[a].faces) {
        candidates.push_back(f);
        owner.push_back(a);
      }
    }
    const std::vector<std::uint8_t> hit = findIntersectingFaces(round_points, candidates, others);
    for (std::size_t i = 0; i < hit.size(); ++i)
      if (hit[i]) rejected[owner[i]] = 1;
    for (std::size_t a = 0; a < attempts.size(); ++a) {
      Attempt& attempt = attempts[a];
      if (rejected[a]) {
        ++result.patches_rejected_for_intersection;
        retry(attempt.hole, "the patch intersects the mesh");
        continue;
      }
      // Renumber the new points after the accepted ones.
      const int n = static_cast<int>(holes[attempt.hole].size());
      const int base = static_cast<int>(points.size());
      points.insert(points.end(), attempt.patch.new_points.begin(), attempt.patch.new_points.end());
      attempt.faces.clear();
      for (const auto& f : attempt.patch.faces) {
        Face g{};
        for (int k = 0; k < 3; ++k) g[k] = f[k] < n ? holes[attempt.hole][f[k]].idx() : base + (f[k] - n);
        attempt.faces.push_back(g);
        others.push_back(g);
      }
      switch (attempt.method) {  // a patch too large to fair came back as its triangulation
        case HoleFillMethod::image_space: ++result.by_image_space; break;
        case HoleFillMethod::triangulate_refine_fair:
          ++(attempt.patch.new_points.empty() ? result.by_triangulation : result.by_refine_fair);
          break;
        case HoleFillMethod::triangulate: ++result.by_triangulation; break;
        case HoleFillMethod::centroid_fan: ++result.by_centroid_fan; break;
      }
      accepted.push_back(std::move(attempt));
    }
    std::sort(still_pending.begin(), still_pending.end());
    pending = std::move(still_pending);
  }
  pending = std::move(given_up);

  // Attach the accepted patches. Points beyond the mesh's vertices are new vertices, in order.
  const int first_new = static_cast<int>(mesh.n_vertices());
  std::vector<OpenMesh::VertexHandle> handle_of_new;
  for (std::size_t i = first_new; i < points.size(); ++i) {
    const auto vh = mesh.add_vertex(SurfaceMesh::Point(points[i].x(), points[i].y(), points[i].z()));
    handle_of_new.push_back(vh);
  }
  const bool was_enabled = omerr().is_enabled();
  omerr().disable();
  for (const Attempt& attempt : accepted) {
    std::vector<OpenMesh::FaceHandle> added;
    bool ok = true;
    for (const auto& f : attempt.faces) {
      OpenMesh::VertexHandle v[3];
      for (int k = 0; k < 3; ++k) v[k] = f[k] < first_new ? OpenMesh::VertexHandle(f[k]) : handle_of_new[f[k] - first_new];
      const auto fh = mesh.add_face(v[0], v[1], v[2]);
      if (!fh.is_valid()) {
        ok = false;
        break;
      }
      added.push_back(fh);
    }
    if (!ok) {
      for (const auto fh : added) mesh.delete_face(fh, false);
      last_failure[attempt.hole] = "the patch could not be attached (non-manifold configuration)";
      pending.push_back(attempt.hole);
      continue;
    }
    ++result.filled;
    result.faces_added += static_cast<std::int64_t>(added.size());
    result.vertices_added += static_cast<std::int64_t>(attempt.patch.new_points.size());
    result.patch_faces.insert(result.patch_faces.end(), added.begin(), added.end());
    if (pixels) {
      const int instance = majorityInstance(mesh, pixels->properties, holes[attempt.hole]);
      for (const auto& f : attempt.faces)
        for (const int i : f) {
          if (i < first_new) continue;
          const auto vh = handle_of_new[i - first_new];
          const Eigen::Vector2d uv =
              points[i].z() > 0 ? pixels->camera.project(points[i]) : Eigen::Vector2d(-1.0, -1.0);
          const int u = std::clamp(static_cast<int>(std::lround(uv.x())), 0, pixels->width - 1);
          const int v = std::clamp(static_cast<int>(std::lround(uv.y())), 0, pixels->height - 1);
          mesh.property(pixels->properties.pixel, vh) = OpenMesh::Vec2i(u, v);
          mesh.property(pixels->properties.instance, vh) = instance;
          mesh.property(pixels->properties.origin, vh) = static_cast<std::uint8_t>(VertexOrigin::hole_fill);
        }
    }
  }
  if (was_enabled) omerr().enable();
  // New vertices of patches that were not attached are isolated: remove them.
  for (const auto vh : handle_of_new)
    if (!mesh.status(vh).deleted() && mesh.is_isolated(vh)) mesh.delete_vertex(vh, false);

  std::sort(pending.begin(), pending.end());
  result.left_open = static_cast<std::int64_t>(pending.size());
  for (const std::size_t hole : pending)
    result.warnings.push_back("hole of " + std::to_string(holes[hole].size()) + " boundary vertices left open: " +
                              last_failure[hole]);
  return result;
}

}  // namespace solo
