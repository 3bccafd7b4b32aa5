// libFuzzer target: the scene manifest (scene.json), read and its files listed.

#include "fuzz_support.h"

#include <solo/core/scene.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return solo::fuzz::readInput(data, size, ".json", [](const std::filesystem::path& file) {
    const solo::SceneManifest manifest = solo::readSceneManifest(file);
    (void)solo::manifestFiles(manifest);
  });
}
