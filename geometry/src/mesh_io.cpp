#include "solo/core/atomic_file.h"
#include <solo/core/output_path.h>
#include "solo/core/error.h"
#include "solo/core/input_file.h"
#include "solo/core/stderr_capture.h"
#include "solo/geometry/triangle_mesh.h"

#include "mesh_header_bounds.h"
#include "off_reader.h"

#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>

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

// A binary STL (84-byte header and count, then 50 bytes a triangle: normal, three corners,
// attribute) whose corners hold a NaN or infinity is refused here, naming the vertex: the soup
// reader merges equal points through comparisons a NaN defeats, so the value would vanish into
// another vertex before the coordinates could be checked. An ASCII STL fails to parse instead.
void requireFiniteBinaryStlVertices(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  char header[84];
  if (!in.read(header, sizeof header)) return;
  std::uint32_t triangles = 0;
  std::memcpy(&triangles, header + 80, sizeof triangles);
  std::error_code ec;
  const std::uintmax_t size_bytes = fs::file_size(file, ec);
  if (ec || size_bytes != 84 + 50 * static_cast<std::uintmax_t>(triangles)) return;  // not binary: CGAL decides
  char record[50];
  for (std::uint32_t t = 0; t < triangles && in.read(record, sizeof record); ++t)
    for (int corner = 0; corner < 3; ++corner) {
      float xyz[3];
      std::memcpy(xyz, record + 12 + 12 * corner, sizeof xyz);
      if (std::isfinite(xyz[0]) && std::isfinite(xyz[1]) && std::isfinite(xyz[2])) continue;
      throw InputError(file, "vertex " + std::to_string(3 * std::uint64_t{t} + corner) + " (triangle " +
                                 std::to_string(t) + ", corner " + std::to_string(corner) +
                                 ") has a non-finite coordinate (NaN or infinity)");
    }
}

// The file's points and polygons: plain OFF by solo's reader, the other formats by CGAL's
// (whose parse errors, printed on stderr, become part of solo's one error line).
void readSoup(const fs::path& file, std::vector<Point>& points, std::vector<std::vector<std::size_t>>& polygons) {
  if (lowercaseExtension(file) == ".off") {
    std::vector<std::array<double, 3>> xyz;
    readPlainOff(file, xyz, polygons);
    points.reserve(xyz.size());
    for (const auto& p : xyz) points.emplace_back(p[0], p[1], p[2]);
    return;
  }
  StderrCapture capture;
  bool read = false;
  try {
    read = CGAL::IO::read_polygon_soup(file.string(), points, polygons);
  } catch (const std::length_error&) {  // a list whose (signed) size reads negative
    throw InputError(file, "cannot read as a mesh: a list declares a negative or impossible size (corrupt file)");
  }
  const std::string cgal_text = joinedLines(capture.finish());
  if (!read)
    throw InputError(file, "cannot read as a mesh: malformed or truncated" +
                               (cgal_text.empty() ? std::string() : " (" + cgal_text + ")"));
}

}  // namespace

TriangleMesh readMesh(const fs::path& file, MeshReadStats* stats) {
  requireMeshExtension(file);
  requireMeshHeaderFitsFile(file, requireNonEmptyRegularFile(file, "mesh"));
  std::vector<Point> points;
  std::vector<std::vector<std::size_t>> polygons;
  if (lowercaseExtension(file) == ".stl") requireFiniteBinaryStlVertices(file);
  readSoup(file, points, polygons);
  if (points.empty()) throw InputError(file, "mesh has no vertices");

  TriangleMesh mesh;
  MeshReadStats s;
  mesh.vertices.reserve(points.size());
  for (std::size_t v = 0; v < points.size(); ++v) {
    const Point& p = points[v];
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()))
      throw InputError(file, "vertex " + std::to_string(v) + " has a non-finite coordinate (NaN or infinity)");
    mesh.vertices.emplace_back(p.x(), p.y(), p.z());
  }
  mesh.faces.reserve(polygons.size());
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    const std::vector<std::size_t>& polygon = polygons[f];
    const auto bad = std::find_if(polygon.begin(), polygon.end(), [&](std::size_t i) { return i >= points.size(); });
    if (bad != polygon.end())
      throw InputError(file, "face " + std::to_string(f) + " refers to vertex " + std::to_string(*bad) +
                                 ", but the file has " + std::to_string(points.size()) + " vertices (0 to " +
                                 std::to_string(points.size() - 1) + ")");
    if (polygon.size() < 3) {
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
