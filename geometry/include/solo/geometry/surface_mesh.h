#pragma once
// The editable mesh of the mesh stage: an OpenMesh triangle mesh (half-edge connectivity,
// double-precision points in metres, deletion status) and the per-vertex properties that tie a
// vertex made from an image back to its pixel, so that materials and lights can be mapped back.

#include "solo/geometry/triangle_mesh.h"

// OpenMesh's PropertyT<Vec3d>::push_back() copies a default-constructed (uninitialised) vector,
// which GCC 12 reports as maybe-uninitialised wherever it is inlined: a false positive.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#pragma GCC diagnostic pop

#include <cstdint>
#include <optional>
#include <vector>

namespace solo {

struct SurfaceMeshTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
  VertexAttributes(OpenMesh::Attributes::Status);
  FaceAttributes(OpenMesh::Attributes::Status);
  EdgeAttributes(OpenMesh::Attributes::Status);
  HalfedgeAttributes(OpenMesh::Attributes::Status | OpenMesh::Attributes::PrevHalfedge);
};
using SurfaceMesh = OpenMesh::TriMesh_ArrayKernelT<SurfaceMeshTraits>;

/// Where a vertex comes from.
enum class VertexOrigin : std::uint8_t {
  Pixel = 0,      ///< backprojected from a depth pixel
  HoleFill = 1,   ///< added by hole filling (its pixel is where it projects, clamped to the map)
  SolidBack = 2,  ///< back side of a foreground solid (same pixel as its front vertex)
  Input = 3,      ///< read from a mesh file (no pixel)
};

/// Handles of the image properties, stored in the mesh under the names "solo:pixel",
/// "solo:instance" and "solo:origin".
struct ImageVertexProperties {
  OpenMesh::VPropHandleT<OpenMesh::Vec2i> pixel;  ///< (u, v) in depth-map pixels; (-1, -1) = none
  OpenMesh::VPropHandleT<int> instance;           ///< Cityscapes instanceId; 0 = unknown
  OpenMesh::VPropHandleT<std::uint8_t> origin;    ///< a VertexOrigin

  /// The mesh's properties, added (with no values set) when absent.
  static ImageVertexProperties getOrAdd(SurfaceMesh& mesh);
  /// The mesh's properties, or none when the mesh was not made from an image.
  static std::optional<ImageVertexProperties> find(const SurfaceMesh& mesh);
};

/// Silences OpenMesh's error stream (where add_face reports a face it refuses; callers count
/// them) while an instance lives. Instances may nest and live on several threads at once: the
/// stream is restored when the last one ends.
class QuietOpenMeshErrors {
 public:
  QuietOpenMeshErrors();
  ~QuietOpenMeshErrors();
  QuietOpenMeshErrors(const QuietOpenMeshErrors&) = delete;
  QuietOpenMeshErrors& operator=(const QuietOpenMeshErrors&) = delete;
};

/// OpenMesh's garbage collection (deleted elements removed, handles renumbered densely),
/// instantiated here rather than run from libOpenMeshCore: Debian builds that library with its
/// assertions on, and each status lookup there compares property type names. A binary holding
/// this instantiation also serves the library's own garbage_collection() with it (the library
/// calls the template by its exported name). The mesh stage's last step on the 5-million-face
/// 1080p street: 0.74-0.81 s before, 0.23-0.25 s after (docs/mesh.md).
void collectGarbage(SurfaceMesh& mesh);

/// The live (not deleted) faces as a plain triangle soup, vertices renumbered densely in
/// handle order (deleted and isolated vertices left out). `vertex_of_index`, when given,
/// receives the handle index of every output vertex.
TriangleMesh toTriangleMesh(const SurfaceMesh& mesh, std::vector<int>* vertex_of_index = nullptr);

/// A soup as a SurfaceMesh, face by face. Faces OpenMesh cannot add (a third face on an edge,
/// an edge used twice in one direction) are left out and counted in `faces_refused`.
SurfaceMesh toSurfaceMesh(const TriangleMesh& soup, std::int64_t* faces_refused = nullptr);

}  // namespace solo
