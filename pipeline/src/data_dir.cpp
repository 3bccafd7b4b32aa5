#include <solo/pipeline/data_dir.h>

#include "solo_config.h"

#include <solo/core/error.h>

#include <cstdlib>

namespace fs = std::filesystem;

namespace solo {

namespace {
const char* kDefaultSceneManifest = "default/scene.json";
}

fs::path dataDirectory() {
  if (const char* env = std::getenv("SOLO_DATA_DIR"); env && *env) {
    if (!fs::exists(fs::path(env) / kDefaultSceneManifest))
      throw InputError(env, "SOLO_DATA_DIR does not hold " + std::string(kDefaultSceneManifest));
    return env;
  }
  for (const fs::path& candidate : {fs::path(SOLO_SOURCE_DATA_DIR), fs::path(SOLO_INSTALL_DATA_DIR)})
    if (fs::exists(candidate / kDefaultSceneManifest)) return candidate;
  throw InputError(SOLO_INSTALL_DATA_DIR, "bundled data not found (set SOLO_DATA_DIR to the project's data/ folder)");
}

fs::path defaultScene() { return dataDirectory() / kDefaultSceneManifest; }
fs::path defaultIlluminantTable() { return dataDirectory() / "illuminants" / "night_illuminants.csv"; }

}  // namespace solo
