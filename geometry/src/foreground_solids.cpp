#include "solo/geometry/foreground_solids.h"

#include "solo/geometry/mesh_fragments.h"
#include "solo/core/scene.h"
#include "triangle_raster.h"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace solo {
namespace {

/// Depth of the nearest listed face behind the visible surface at each pixel (inf = none),
/// rasterised at pixel centres.
cv::Mat depthBehind(const DepthMesh& m, const std::vector<OpenMesh::FaceHandle>& faces) {
  const SurfaceMesh& mesh = m.mesh;
  cv::Mat behind(m.height, m.width, CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  const auto visibleDepth = [&](int u, int v) {
    const int i = m.vertexAt(u, v);
    return (i < 0 || mesh.status(OpenMesh::VertexHandle(i)).deleted()) ? 0.0 : mesh.point(OpenMesh::VertexHandle(i))[2];
  };
  for (const auto f : faces) {
    if (mesh.status(f).deleted()) continue;
    Eigen::Vector2d uv[3];
    double w[3];
    bool ok = true;
    int k = 0;
    for (const auto v : mesh.fv_range(f)) {
      const auto& p = mesh.point(v);
      if (!(p[2] > 0)) ok = false;
      uv[k] = m.camera.project(Eigen::Vector3d(p[0], p[1], p[2]));
      w[k] = 1.0 / p[2];
      ++k;
    }
    if (!ok) continue;
    raster::forEachCoveredPixelCentre(uv, w, m.width, m.height, [&](int u, int v, double z) {
      // Every patch strictly behind the visible surface counts, however close: one a few
      // centimetres behind a thing (the road patch at a tyre's contact) is what a back pushed
      // the full class thickness would pierce.
      if (z <= visibleDepth(u, v)) return;
      float& slot = behind.at<float>(v, u);
      slot = std::min(slot, static_cast<float>(z));
    });
  }
  return behind;
}

}  // namespace

std::vector<std::uint8_t> floatingSheets(const DepthMesh& m, const std::vector<int>& component, int count) {
  const SurfaceMesh& mesh = m.mesh;
  const auto atBorder = [&](OpenMesh::VertexHandle v) {
    const OpenMesh::Vec2i p = mesh.property(m.properties.pixel, v);
    if (p[0] <= 0 || p[1] <= 0 || p[0] >= m.width - 1 || p[1] >= m.height - 1) return true;
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du)
        if (m.vertexAt(p[0] + du, p[1] + dv) < 0) return true;
    return false;
  };
  // The half-edges in slices, each with its own flags (1: has a boundary, 2: touches the border).
  const int halfedges = static_cast<int>(mesh.n_halfedges());
  const int slices = std::max(1, cv::getNumThreads());
  std::vector<std::vector<std::uint8_t>> flags(slices, std::vector<std::uint8_t>(count, 0));
  cv::parallel_for_(cv::Range(0, slices), [&](const cv::Range& range) {
    for (int slice = range.start; slice < range.end; ++slice) {
      std::vector<std::uint8_t>& flag = flags[slice];
      const int first = static_cast<int>(std::int64_t(halfedges) * slice / slices);
      const int last = static_cast<int>(std::int64_t(halfedges) * (slice + 1) / slices);
      for (int i = first; i < last; ++i) {
        const OpenMesh::HalfedgeHandle h(i);
        if (mesh.status(mesh.edge_handle(h)).deleted() || !mesh.is_boundary(h)) continue;
        const int c = component[mesh.face_handle(mesh.opposite_halfedge_handle(h)).idx()];
        if (c < 0) continue;
        flag[c] |= 1;
        if (!(flag[c] & 2) && atBorder(mesh.from_vertex_handle(h))) flag[c] |= 2;
      }
    }
  });
  std::vector<std::uint8_t> floating(count, 0);
  for (int c = 0; c < count; ++c) {
    std::uint8_t any = 0;
    for (const auto& flag : flags) any |= flag[c];
    floating[c] = any == 1;
  }
  return floating;
}

double classThicknessM(int class_id) {
  switch (class_id) {
    case 17: return 0.25;
    case 19: return 0.35;
    case 20: return 0.05;
    case 24: return 0.5;
    case 25: return 0.8;
    case 26: return 1.8;
    case 27: return 2.5;
    case 28: return 2.5;
    case 31: return 2.6;
    case 32: return 0.8;
    case 33: return 0.6;
    default: return 0.0;
  }
}

SolidClosing closeForegroundSolids(DepthMesh& m, const std::vector<OpenMesh::FaceHandle>& background_faces,
                                   const ForegroundSolidOptions& options) {
  SolidClosing result;
  SurfaceMesh& mesh = m.mesh;
  const ImageVertexProperties& props = m.properties;
  int count = 0;
  const std::vector<int> component = faceComponents(mesh, &count);
  result.sheets = count;

  // Class of each component: the majority class of its image vertices.
  std::vector<std::map<int, std::int64_t>> votes(count);
  for (const auto f : mesh.faces()) {
    const int c = component[f.idx()];
    if (c < 0) continue;
    for (const auto v : mesh.fv_range(f))
      if (mesh.property(props.origin, v) == static_cast<std::uint8_t>(VertexOrigin::Pixel))
        ++votes[c][cityscapesClassOfInstance(mesh.property(props.instance, v))];
  }
  std::vector<double> thickness(count, 0.0);
  std::vector<int> class_of(count, 0);
  for (int c = 0; c < count; ++c) {
    if (votes[c].empty()) continue;
    class_of[c] = std::max_element(votes[c].begin(), votes[c].end(),
                                   [](const auto& a, const auto& b) { return a.second < b.second; })->first;
    thickness[c] = classThicknessM(class_of[c]);
  }
  if (options.floating_sheet_thickness_m > 0) {
    const std::vector<std::uint8_t> floating = floatingSheets(m, component, count);
    for (int c = 0; c < count; ++c)
      if (thickness[c] <= 0 && floating[c] && !votes[c].empty()) {
        thickness[c] = options.floating_sheet_thickness_m;
        ++result.floating_sheets;
      }
  }
  if (std::none_of(thickness.begin(), thickness.end(), [](double t) { return t > 0; })) return result;

  const cv::Mat behind = depthBehind(m, background_faces);
  std::vector<int> vertex_component(mesh.n_vertices(), -1);
  std::vector<OpenMesh::FaceHandle> solid_faces;
  for (const auto f : mesh.faces()) {
    const int c = component[f.idx()];
    if (c < 0 || thickness[c] <= 0) continue;
    solid_faces.push_back(f);
    for (const auto v : mesh.fv_range(f)) vertex_component[v.idx()] = c;
  }
  std::vector<OpenMesh::HalfedgeHandle> walls;
  for (const auto h : mesh.halfedges()) {
    if (mesh.status(mesh.edge_handle(h)).deleted() || !mesh.is_boundary(h)) continue;
    const int c = vertex_component[mesh.from_vertex_handle(h).idx()];
    if (c >= 0 && thickness[c] > 0) walls.push_back(h);
  }

  // Back vertices.
  const std::size_t front_vertices = mesh.n_vertices();
  std::vector<int> back_of(front_vertices, -1);
  std::map<int, std::int64_t> solids_per_class;
  std::vector<std::uint8_t> counted(count, 0);
  for (std::size_t i = 0; i < front_vertices; ++i) {
    const int c = vertex_component[i];
    if (c < 0) continue;
    const OpenMesh::VertexHandle vh(static_cast<int>(i));
    const SurfaceMesh::Point p = mesh.point(vh);
    const OpenMesh::Vec2i pixel = mesh.property(props.pixel, vh);
    double t = thickness[c];
    if (pixel[0] >= 0 && pixel[1] >= 0 && pixel[0] < m.width && pixel[1] < m.height) {
      const double z_behind = behind.at<float>(pixel[1], pixel[0]);
      if (std::isfinite(z_behind) && z_behind > p[2]) {
        const double gap = z_behind - p[2];
        if (gap - options.clearance_m < t) {
          // Keep the clearance when there is room for the minimum thickness; otherwise stay
          // halfway to the surface behind: thinner than the minimum, but never through it.
          t = gap - options.clearance_m >= options.min_thickness_m ? gap - options.clearance_m
                                                                    : std::min(options.min_thickness_m, 0.5 * gap);
          ++result.vertices_clamped;
        }
      }
    }
    const auto back = mesh.add_vertex(p * ((p[2] + t) / p[2]));
    mesh.property(props.pixel, back) = pixel;
    mesh.property(props.instance, back) = mesh.property(props.instance, vh);
    mesh.property(props.origin, back) = static_cast<std::uint8_t>(VertexOrigin::SolidBack);
    back_of[i] = back.idx();
    ++result.vertices_added;
    if (!counted[c]) {
      counted[c] = 1;
      ++result.solids;
      ++solids_per_class[class_of[c]];
    }
  }
  const auto backOf = [&](OpenMesh::VertexHandle v) { return OpenMesh::VertexHandle(back_of[v.idx()]); };
  const QuietOpenMeshErrors quiet;  // refused faces are counted, not printed
  for (const auto f : solid_faces) {
    OpenMesh::VertexHandle v[3];
    int k = 0;
    for (const auto vh : mesh.fv_range(f)) v[k++] = vh;
    result.faces_added += mesh.add_face(backOf(v[0]), backOf(v[2]), backOf(v[1])).is_valid();
  }
  for (const auto h : walls) {
    const auto a = mesh.from_vertex_handle(h), b = mesh.to_vertex_handle(h);
    result.faces_added += mesh.add_face(a, b, backOf(b)).is_valid();
    result.faces_added += mesh.add_face(a, backOf(b), backOf(a)).is_valid();
  }
  for (const auto& [class_id, n] : solids_per_class)
    result.classes.push_back(std::to_string(class_id) + ":" + std::to_string(n));
  return result;
}

}  // namespace solo
