#include <solo/core/error.h>
#include <solo/geometry/triangle_mesh.h>

#include "test_support.h"

#include <cstdint>
#include <limits>

using solo::test::TempDir;

namespace {
// A unit tetrahedron with coordinates that need full double precision.
solo::TriangleMesh tetrahedron() {
  solo::TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1.0 / 3.0, 0, 0}, {0, 1e-7, 0}, {0, 0, 123456.789}};
  m.faces = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  return m;
}
}  // namespace

TEST(MeshIo, RoundTripsInEveryFormat) {
  TempDir dir;
  const solo::TriangleMesh m = tetrahedron();
  for (const char* name : {"t.off", "t.obj", "t.ply", "t.stl"}) {
    SCOPED_TRACE(name);
    solo::writeMesh(dir / name, m);
    const solo::TriangleMesh back = solo::readMesh(dir / name);
    ASSERT_EQ(back.faces.size(), 4u);
    // STL stores float triangles without shared vertices; CGAL merges equal points back.
    const double tolerance = std::string(name) == "t.stl" ? 1e-2 : 1e-12;
    ASSERT_EQ(back.vertices.size(), 4u);
    for (std::size_t f = 0; f < 4; ++f)
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d a = m.vertices[m.faces[f][k]], b = back.vertices[back.faces[f][k]];
        EXPECT_LE((a - b).norm(), tolerance * std::max(1.0, a.norm()));
      }
  }
}

TEST(MeshIo, PolygonsAreFanTriangulatedAndCounted) {
  TempDir dir;
  solo::test::writeText(dir / "quad.off", "OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n4 0 1 2 3\n3 1 4 2\n");
  solo::MeshReadStats stats;
  const solo::TriangleMesh m = solo::readMesh(dir / "quad.off", &stats);
  ASSERT_EQ(m.faces.size(), 3u);
  EXPECT_EQ(stats.polygons_triangulated, 1);
  EXPECT_EQ(m.faces[0], (std::array<std::uint32_t, 3>{0, 1, 2}));
  EXPECT_EQ(m.faces[1], (std::array<std::uint32_t, 3>{0, 2, 3}));
}

TEST(MeshIo, BadFilesNameTheFile) {
  TempDir dir;
  auto message = [](const std::filesystem::path& p) {
    try {
      solo::readMesh(p);
    } catch (const solo::InputError& e) {
      return std::string(e.what());
    }
    return std::string("read");
  };
  EXPECT_NE(message(dir / "none.off").find("none.off: file not found"), std::string::npos);
  solo::test::writeText(dir / "junk.off", "OFF\n3 1 0\n0 0\n");
  EXPECT_NE(message(dir / "junk.off").find("junk.off: cannot read as a mesh"), std::string::npos);
  solo::test::writeText(dir / "m.xyz", "1 2 3\n");
  EXPECT_NE(message(dir / "m.xyz").find("unknown mesh format"), std::string::npos);
}

// The message readMesh refuses `file` with, or "read".
std::string readError(const std::filesystem::path& file) {
  try {
    solo::readMesh(file);
  } catch (const solo::InputError& e) {
    return e.what();
  }
  return "read";
}

TEST(MeshIo, ANonFiniteStlVertexIsRefusedBeforeItIsMergedAway) {
  TempDir dir;
  // Two triangles sharing two corners; corner 1 of triangle 1 (vertex 4) is NaN, then infinite.
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (const float bad : {nan, inf, -inf}) {
    const float corners[2][9] = {{0, 0, 0, 1, 0, 0, 0, 1, 0}, {1, 0, 0, bad, 1, 0, 0, 1, 0}};
    std::string bytes(80, '\0');
    const std::uint32_t count = 2;
    bytes.append(reinterpret_cast<const char*>(&count), 4);
    for (const auto& triangle : corners) {
      bytes.append(12, '\0');  // normal
      bytes.append(reinterpret_cast<const char*>(triangle), sizeof triangle);
      bytes.append(2, '\0');  // attribute
    }
    solo::test::writeText(dir / "n.stl", bytes);
    EXPECT_NE(readError(dir / "n.stl").find("n.stl: vertex 4 (triangle 1, corner 1) has a non-finite coordinate"),
              std::string::npos)
        << readError(dir / "n.stl");
  }
  solo::test::writeText(dir / "n.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 inf 0\n3 0 1 2\n");
  const std::string off = readError(dir / "n.off");
  EXPECT_TRUE(off.find("n.off: vertex 2 has a non-finite coordinate") != std::string::npos ||
              off.find("n.off: cannot read as a mesh") != std::string::npos)
      << off;
}

TEST(MeshIo, AFaceReferringToAVertexTheFileLacksIsRefusedNamingBoth) {
  TempDir dir;
  solo::test::writeText(dir / "f.ply",
                        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                        "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
                        "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 7 3\n");
  EXPECT_NE(readError(dir / "f.ply").find("f.ply: face 1 refers to vertex 7, but the file has 4 vertices"),
            std::string::npos)
      << readError(dir / "f.ply");
  solo::test::writeText(dir / "f.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 3\n");
  // The same in OFF: refused whether by the reader or by the index check, never read.
  EXPECT_EQ(readError(dir / "f.off").rfind((dir / "f.off").string() + ": ", 0), 0u) << readError(dir / "f.off");
}

TEST(MeshIo, ReadsTheRealScansWithTheirDocumentedCounts) {
  SOLO_REQUIRE_SHARED_DATA(pig, "meshes/pig.off");
  const solo::TriangleMesh m = solo::readMesh(pig);
  EXPECT_EQ(m.vertices.size(), 468u);
  EXPECT_EQ(m.faces.size(), 891u);
  SOLO_REQUIRE_SHARED_DATA(bunny, "meshes/bun_zipper.ply");
  const solo::TriangleMesh b = solo::readMesh(bunny);
  EXPECT_EQ(b.vertices.size(), 35947u);
  EXPECT_EQ(b.faces.size(), 69451u);
}
