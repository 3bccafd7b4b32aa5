#include "solo/geometry/surface_mesh.h"

#include <mutex>

namespace solo {
namespace {

// OpenMesh's error stream is one global object: silencing is counted across threads.
struct QuietState {
  std::mutex mutex;
  int holders = 0;
  bool was_enabled = false;
};

QuietState& quietState() {
  static QuietState state;
  return state;
}

}  // namespace

QuietOpenMeshErrors::QuietOpenMeshErrors() {
  QuietState& state = quietState();
  const std::lock_guard<std::mutex> lock(state.mutex);
  if (state.holders++ == 0) {
    state.was_enabled = omerr().is_enabled();
    omerr().disable();
  }
}

QuietOpenMeshErrors::~QuietOpenMeshErrors() {
  QuietState& state = quietState();
  const std::lock_guard<std::mutex> lock(state.mutex);
  if (--state.holders == 0 && state.was_enabled) omerr().enable();
}

ImageVertexProperties ImageVertexProperties::getOrAdd(SurfaceMesh& mesh) {
  ImageVertexProperties p;
  if (!mesh.get_property_handle(p.pixel, "solo:pixel")) mesh.add_property(p.pixel, "solo:pixel");
  if (!mesh.get_property_handle(p.instance, "solo:instance")) mesh.add_property(p.instance, "solo:instance");
  if (!mesh.get_property_handle(p.origin, "solo:origin")) mesh.add_property(p.origin, "solo:origin");
  return p;
}

std::optional<ImageVertexProperties> ImageVertexProperties::find(const SurfaceMesh& mesh) {
  ImageVertexProperties p;
  if (!mesh.get_property_handle(p.pixel, "solo:pixel") || !mesh.get_property_handle(p.instance, "solo:instance") ||
      !mesh.get_property_handle(p.origin, "solo:origin"))
    return std::nullopt;
  return p;
}

void collectGarbage(SurfaceMesh& mesh) {
  std::vector<OpenMesh::VertexHandle*> vertices_to_update;
  std::vector<OpenMesh::HalfedgeHandle*> halfedges_to_update;
  std::vector<OpenMesh::FaceHandle*> faces_to_update;
  mesh.garbage_collection(vertices_to_update, halfedges_to_update, faces_to_update);
}

TriangleMesh toTriangleMesh(const SurfaceMesh& mesh, std::vector<int>* vertex_of_index) {
  TriangleMesh soup;
  std::vector<std::uint32_t> index(mesh.n_vertices(), UINT32_MAX);
  std::vector<bool> used(mesh.n_vertices(), false);
  for (const auto f : mesh.faces())
    if (!mesh.status(f).deleted())
      for (const auto v : mesh.fv_range(f)) used[v.idx()] = true;
  if (vertex_of_index) vertex_of_index->clear();
  for (std::size_t i = 0; i < used.size(); ++i) {
    if (!used[i]) continue;
    index[i] = static_cast<std::uint32_t>(soup.vertices.size());
    const auto& p = mesh.point(OpenMesh::VertexHandle(static_cast<int>(i)));
    soup.vertices.emplace_back(p[0], p[1], p[2]);
    if (vertex_of_index) vertex_of_index->push_back(static_cast<int>(i));
  }
  soup.faces.reserve(mesh.n_faces());
  for (const auto f : mesh.faces()) {
    if (mesh.status(f).deleted()) continue;
    std::array<std::uint32_t, 3> t{};
    int k = 0;
    for (const auto v : mesh.fv_range(f)) t[k++] = index[v.idx()];
    soup.faces.push_back(t);
  }
  return soup;
}

SurfaceMesh toSurfaceMesh(const TriangleMesh& soup, std::int64_t* faces_refused) {
  SurfaceMesh mesh;
  mesh.reserve(soup.vertices.size(), soup.faces.size() * 3 / 2, soup.faces.size());
  for (const Eigen::Vector3d& p : soup.vertices) mesh.add_vertex(SurfaceMesh::Point(p.x(), p.y(), p.z()));
  std::int64_t refused = 0;
  // OpenMesh reports refused faces on its error stream; they are counted here instead.
  {
    const QuietOpenMeshErrors quiet;
    for (const auto& f : soup.faces) {
      const auto h = mesh.add_face(OpenMesh::VertexHandle(static_cast<int>(f[0])),
                                   OpenMesh::VertexHandle(static_cast<int>(f[1])),
                                   OpenMesh::VertexHandle(static_cast<int>(f[2])));
      if (!h.is_valid()) ++refused;
    }
  }
  if (faces_refused) *faces_refused = refused;
  return mesh;
}

}  // namespace solo
