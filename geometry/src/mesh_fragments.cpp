#include "solo/geometry/mesh_fragments.h"

#include <algorithm>

namespace solo {

std::vector<int> faceComponents(const SurfaceMesh& mesh, int* component_count) {
  // Union-find over the edges in index order (sequential memory access: a search face by face
  // jumps around the half-edge arrays of a mesh of millions of faces), then components numbered
  // in the order of their first face, as a search from each unvisited face in order would.
  const int n = static_cast<int>(mesh.n_faces());
  std::vector<int> parent(n, -1);
  for (int i = 0; i < n; ++i)
    if (!mesh.status(OpenMesh::FaceHandle(i)).deleted()) parent[i] = i;
  const auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  const int edges = static_cast<int>(mesh.n_edges());
  for (int e = 0; e < edges; ++e) {
    const OpenMesh::EdgeHandle eh(e);
    if (mesh.status(eh).deleted()) continue;
    const auto f0 = mesh.face_handle(mesh.halfedge_handle(eh, 0));
    const auto f1 = mesh.face_handle(mesh.halfedge_handle(eh, 1));
    if (!f0.is_valid() || !f1.is_valid() || parent[f0.idx()] < 0 || parent[f1.idx()] < 0) continue;
    const int a = find(f0.idx()), b = find(f1.idx());
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
  std::vector<int> component(n, -1), label(n, -1);
  int count = 0;
  for (int i = 0; i < n; ++i) {
    if (parent[i] < 0) continue;
    const int root = find(i);
    if (label[root] < 0) label[root] = count++;
    component[i] = label[root];
  }
  if (component_count) *component_count = count;
  return component;
}

FragmentRemoval removeSmallComponents(SurfaceMesh& mesh, std::int64_t min_faces) {
  FragmentRemoval result;
  int count = 0;
  const std::vector<int> component = faceComponents(mesh, &count);
  result.components_before = count;
  std::vector<std::int64_t> size(count, 0);
  for (const int c : component)
    if (c >= 0) ++size[c];
  for (const std::int64_t s : size) result.components_removed += s < min_faces;
  for (const auto f : mesh.faces()) {
    const int c = component[f.idx()];
    if (c < 0 || size[c] >= min_faces) continue;
    mesh.delete_face(f, true);
    ++result.faces_removed;
  }
  return result;
}

PinchResolution resolvePinchedVertices(SurfaceMesh& mesh, int max_passes) {
  PinchResolution result;
  for (int pass = 0; pass < max_passes; ++pass) {
    // Outgoing border half-edges per vertex, found by a scan of all half-edges: OpenMesh's
    // circulators see only one fan of a pinched vertex.
    std::vector<int> boundary_out(mesh.n_vertices(), 0);
    std::vector<std::pair<int, int>> border;  // (from vertex, half-edge)
    for (const auto h : mesh.halfedges())
      if (!mesh.status(mesh.edge_handle(h)).deleted() && mesh.is_boundary(h)) {
        ++boundary_out[mesh.from_vertex_handle(h).idx()];
        border.emplace_back(mesh.from_vertex_handle(h).idx(), h.idx());
      }
    border.erase(std::remove_if(border.begin(), border.end(), [&](const auto& e) { return boundary_out[e.first] < 2; }),
                 border.end());
    std::sort(border.begin(), border.end());
    std::int64_t pinched = 0;
    for (std::size_t i = 0; i < border.size();) {
      std::size_t j = i;
      while (j < border.size() && border[j].first == border[i].first) ++j;
      ++pinched;
      // Each outgoing border half-edge starts one fan: rotate collecting the faces.
      // Deletions at an earlier vertex of this pass may have changed this one: the next pass
      // sees it afresh.
      bool stale = false;
      for (std::size_t k = i; k < j; ++k) {
        const OpenMesh::HalfedgeHandle h(border[k].second);
        stale = stale || mesh.status(mesh.edge_handle(h)).deleted() || !mesh.is_boundary(h);
      }
      if (stale) {
        i = j;
        continue;
      }
      std::vector<std::vector<OpenMesh::FaceHandle>> fans;
      for (std::size_t k = i; k < j; ++k) {
        std::vector<OpenMesh::FaceHandle> fan;
        OpenMesh::HalfedgeHandle h(border[k].second);
        for (std::size_t guard = 0; guard < 4096; ++guard) {
          const auto opposite = mesh.opposite_halfedge_handle(h);
          if (mesh.is_boundary(opposite)) break;
          fan.push_back(mesh.face_handle(opposite));
          h = mesh.next_halfedge_handle(opposite);
        }
        fans.push_back(std::move(fan));
      }
      i = j;
      if (fans.size() < 2) continue;
      const auto largest = std::max_element(fans.begin(), fans.end(),
                                            [](const auto& a, const auto& b) { return a.size() < b.size(); });
      for (auto fan = fans.begin(); fan != fans.end(); ++fan) {
        if (fan == largest) continue;
        for (const auto f : *fan)
          if (!mesh.status(f).deleted()) {
            mesh.delete_face(f, true);
            ++result.faces_removed;
          }
      }
    }
    if (pass == 0) result.pinched_vertices = pinched;
    if (pinched == 0) break;
  }
  return result;
}

}  // namespace solo
