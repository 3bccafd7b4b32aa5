#pragma once
// A plain indexed triangle mesh (a soup: nothing is assumed about manifoldness), the
// exchange type between mesh readers, evaluation and the renderer. Units: metres.

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace solo {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<std::uint32_t, 3>> faces;
};

struct MeshReadStats {
  std::int64_t polygons_triangulated = 0;  ///< faces with more than 3 corners, fan-split
  std::int64_t faces_dropped = 0;          ///< faces with fewer than 3 corners
};

/// Reads OFF, OBJ, PLY (ASCII or binary) or STL as a soup, keeping every face as stored
/// (non-manifold configurations included). Polygons are fan-triangulated and counted.
/// Throws InputError naming the file for a missing, unreadable or malformed file, a vertex
/// with a NaN or infinite coordinate (named by its index; in a binary STL, 3 x triangle +
/// corner, checked before equal points are merged) and a face referring to a vertex the file
/// does not have (named by the face's index and the vertex index).
TriangleMesh readMesh(const std::filesystem::path& file, MeshReadStats* stats = nullptr);

/// Writes OFF, OBJ, PLY (binary) or STL by extension, atomically.
void writeMesh(const std::filesystem::path& file, const TriangleMesh& mesh);

}  // namespace solo
