// libFuzzer target: the map readers on one format (SOLO_FUZZ_EXTENSION: .png, .exr, .tif, .npy
// or .pfm). The input's size picks the reader (depth, normals, labels, colour, scalar map), so
// every reader sees every format's mutations.

#include "fuzz_support.h"

#include <solo/core/image_io.h>

#include <OpenImageIO/imageio.h>

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  solo::fuzz::limitImageSize();
  // One thread: no thread pool started and stopped around every decode.
  OIIO::attribute("threads", 1);
  OIIO::attribute("exr_threads", 1);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return solo::fuzz::readInput(data, size, SOLO_FUZZ_EXTENSION, [size](const std::filesystem::path& file) {
    switch (size % 5) {
      case 0:
        (void)solo::readDepth(file, 0.01);
        break;
      case 1:
        (void)solo::readNormals(file);
        break;
      case 2:
        (void)solo::readLabels(file);
        break;
      case 3:
        (void)solo::readColorImage(file);
        break;
      default:
        (void)solo::readScalarMap(file);
        break;
    }
  });
}
