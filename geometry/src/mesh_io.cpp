#include "solo/core/atomic_file.h"
#include <solo/core/output_path.h>
#include "solo/core/error.h"
#include "solo/core/input_file.h"
#include "solo/geometry/triangle_mesh.h"

#include "mesh_header_bounds.h"

#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <fstream>

namespace fs = std::filesystem;

namespace solo {
namespace {
using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;

void requireMeshExtension(const fs::path& file) {
  const std::string ext = lowercaseExtension(file);
  if (ext != ".off" && ext != ".obj" && ext != ".ply" && ext != ".stl")
    throw InputError(file, "unknown mesh format \"" + ext + "\" (OFF, OBJ, PLY or STL)");
}
// Binary PLY and STL, ASCII OFF and OBJ, 17 significant digits in text.
bool writeSoup(std::ofstream& out, const std::string& ext, const std::vector<Point>& points,
               const std::vector<std::vector<std::size_t>>& polygons) {
  const auto np = CGAL::parameters::stream_precision(17);
  if (ext == ".ply" || ext == ".stl") {
    CGAL::IO::set_mode(out, CGAL::IO::BINARY);
    return ext == ".ply" ? CGAL::IO::write_PLY(out, points, polygons, np)
                         : CGAL::IO::write_STL(out, points, polygons, np);
  }
  CGAL::IO::set_mode(out, CGAL::IO::ASCII);
  return ext == ".obj" ? CGAL::IO::write_OBJ(out, points, polygons, np)
                       : CGAL::IO::write_OFF(out, points, polygons, np);
}
}  // namespace

TriangleMesh readMesh(const fs::path& file, MeshReadStats* stats) {
  requireMeshExtension(file);
  requireMeshHeaderFitsFile(file, requireNonEmptyRegularFile(file, "mesh"));
  std::vector<Point> points;
  std::vector<std::vector<std::size_t>> polygons;
  if (!CGAL::IO::read_polygon_soup(file.string(), points, polygons))
    throw InputError(file, "cannot read as a mesh: malformed or truncated");
  if (points.empty()) throw InputError(file, "mesh has no vertices");

  TriangleMesh mesh;
  MeshReadStats s;
  mesh.vertices.reserve(points.size());
  for (const Point& p : points) {
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()))
      throw InputError(file, "mesh has a non-finite vertex coordinate");
    mesh.vertices.emplace_back(p.x(), p.y(), p.z());
  }
  mesh.faces.reserve(polygons.size());
  for (const auto& polygon : polygons) {
    const bool indices_ok = std::all_of(polygon.begin(), polygon.end(), [&](std::size_t i) { return i < points.size(); });
    if (polygon.size() < 3 || !indices_ok) {
      ++s.faces_dropped;
      continue;
    }
    if (polygon.size() > 3) ++s.polygons_triangulated;
    for (std::size_t k = 1; k + 1 < polygon.size(); ++k)
      mesh.faces.push_back({static_cast<std::uint32_t>(polygon[0]), static_cast<std::uint32_t>(polygon[k]),
                            static_cast<std::uint32_t>(polygon[k + 1])});
  }
  if (stats) *stats = s;
  return mesh;
}

void writeMesh(const fs::path& file, const TriangleMesh& mesh) {
  requireMeshExtension(file);
  std::vector<Point> points;
  points.reserve(mesh.vertices.size());
  for (const Eigen::Vector3d& v : mesh.vertices) points.emplace_back(v.x(), v.y(), v.z());
  std::vector<std::vector<std::size_t>> polygons;
  polygons.reserve(mesh.faces.size());
  for (const auto& f : mesh.faces) polygons.push_back({f[0], f[1], f[2]});
  writeAtomically(file, [&](const fs::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw InputError(file, "cannot open for writing");
    const bool ok = writeSoup(out, lowercaseExtension(file), points, polygons);
    out.close();  // the last buffered bytes are written here: checked too
    if (!ok || !out) throw InputError(file, "write failed");
  });
}

}  // namespace solo
