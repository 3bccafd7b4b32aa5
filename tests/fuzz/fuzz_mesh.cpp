// libFuzzer target: the mesh reader on one format (SOLO_FUZZ_EXTENSION: .ply, .off, .obj or .stl).

#include "fuzz_support.h"

#include <solo/geometry/triangle_mesh.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return solo::fuzz::readInput(data, size, SOLO_FUZZ_EXTENSION, [](const std::filesystem::path& file) {
    solo::MeshReadStats stats;
    (void)solo::readMesh(file, &stats);
  });
}
