#include "solo/geometry/mesh_holes.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <opencv2/core.hpp>

namespace solo {
namespace {

using Face = std::array<int, 3>;

struct Attempt {
  std::size_t hole = 0;
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

}  // namespace

HoleClosing closeHoles(SurfaceMesh& mesh, const std::vector<VertexLoop>& holes, const HoleFillOptions& options,
                       const std::optional<PixelMapping>& pixels) {
  HoleClosing result;
  result.holes = static_cast<std::int64_t>(holes.size());
  if (holes.empty()) return result;

  std::vector<Eigen::Vector3d> points;
  points.reserve(mesh.n_vertices());
  for (const auto v : mesh.all_vertices()) {
    const auto& p = mesh.point(v);
    points.emplace_back(p[0], p[1], p[2]);
  }
  std::vector<Face> others = liveFaces(mesh);
  std::vector<std::string> last_failure(holes.size());
  std::vector<std::size_t> pending(holes.size());
  for (std::size_t i = 0; i < holes.size(); ++i) {
    pending[i] = i;
    result.largest_hole_vertices = std::max<std::int64_t>(result.largest_hole_vertices, holes[i].size());
  }
  std::vector<Attempt> accepted;

  for (const HoleFillMethod method :
       {HoleFillMethod::triangulate_refine_fair, HoleFillMethod::triangulate, HoleFillMethod::centroid_fan}) {
    if (pending.empty()) break;
    std::vector<Attempt> attempts;
    std::vector<std::size_t> still_pending;
    std::vector<Eigen::Vector3d> round_points = points;
    for (const std::size_t hole : pending) {
      std::vector<Eigen::Vector3d> boundary;
      for (const auto v : holes[hole]) boundary.push_back(points[v.idx()]);
      Attempt attempt;
      attempt.hole = hole;
      attempt.patch = fillHolePolyline(boundary, method, options);
      if (!attempt.patch.filled) {
        last_failure[hole] = std::string(holeFillMethodName(method)) + ": " + attempt.patch.failure;
        still_pending.push_back(hole);
        continue;
      }
      const int n = static_cast<int>(boundary.size());
      const int base = static_cast<int>(round_points.size());
      round_points.insert(round_points.end(), attempt.patch.new_points.begin(), attempt.patch.new_points.end());
      for (const auto& f : attempt.patch.faces) {
        Face g{};
        for (int k = 0; k < 3; ++k) g[k] = f[k] < n ? holes[hole][f[k]].idx() : base + (f[k] - n);
        attempt.faces.push_back(g);
      }
      attempts.push_back(std::move(attempt));
    }
    std::vector<Face> candidates;
    std::vector<std::size_t> owner;
    for (std::size_t a = 0; a < attempts.size(); ++a)
      for (const auto& f : attempts[a].faces) {
        candidates.push_back(f);
        owner.push_back(a);
      }
    // For a mesh made from an image, a face can only meet a patch where their projections overlap:
    // check against the faces with a corner inside the patches' pixel bounding boxes.
    std::vector<Face> nearby;
    if (pixels) {
      cv::Mat region = cv::Mat::zeros(pixels->height, pixels->width, CV_8U);
      for (const Attempt& attempt : attempts) {
        double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
        for (const auto& f : attempt.faces)
          for (const int i : f) {
            const Eigen::Vector3d& p = round_points[i];
            if (!(p.z() > 0)) continue;
            const Eigen::Vector2d uv = pixels->camera.project(p);
            u0 = std::min(u0, uv.x()), v0 = std::min(v0, uv.y()), u1 = std::max(u1, uv.x()), v1 = std::max(v1, uv.y());
          }
        if (u0 > u1) continue;
        const int a = std::clamp(static_cast<int>(std::floor(u0)) - 2, 0, pixels->width - 1);
        const int b = std::clamp(static_cast<int>(std::ceil(v0 - 1)) - 2, 0, pixels->height - 1);
        const int c = std::clamp(static_cast<int>(std::ceil(u1)) + 2, 0, pixels->width - 1);
        const int d = std::clamp(static_cast<int>(std::ceil(v1)) + 2, 0, pixels->height - 1);
        region(cv::Rect(a, b, c - a + 1, d - b + 1)).setTo(1);
      }
      const auto inside = [&](int vertex) {
        if (vertex >= static_cast<int>(mesh.n_vertices())) return true;  // an accepted patch's new vertex
        const OpenMesh::Vec2i p = mesh.property(pixels->properties.pixel, OpenMesh::VertexHandle(vertex));
        return p[0] < 0 || p[1] < 0 || p[0] >= pixels->width || p[1] >= pixels->height || region.at<std::uint8_t>(p[1], p[0]);
      };
      for (const Face& f : others)
        if (inside(f[0]) || inside(f[1]) || inside(f[2])) nearby.push_back(f);
    }
    const std::vector<std::uint8_t> hit = findIntersectingFaces(round_points, candidates, pixels ? nearby : others);
    std::vector<std::uint8_t> rejected(attempts.size(), 0);
    for (std::size_t i = 0; i < hit.size(); ++i)
      if (hit[i]) rejected[owner[i]] = 1;
    for (std::size_t a = 0; a < attempts.size(); ++a) {
      Attempt& attempt = attempts[a];
      if (rejected[a]) {
        ++result.patches_rejected_for_intersection;
        last_failure[attempt.hole] = std::string(holeFillMethodName(method)) + ": the patch intersects the mesh";
        still_pending.push_back(attempt.hole);
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
      switch (method) {
        case HoleFillMethod::triangulate_refine_fair: ++result.by_refine_fair; break;
        case HoleFillMethod::triangulate: ++result.by_triangulation; break;
        case HoleFillMethod::centroid_fan: ++result.by_centroid_fan; break;
      }
      accepted.push_back(std::move(attempt));
    }
    std::sort(still_pending.begin(), still_pending.end());
    pending = std::move(still_pending);
  }

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
