#pragma once
// Where the bundled data lives: the embedded default scene and the illuminant table.

#include <filesystem>

namespace solo {

/// Folder of the bundled data: $SOLO_DATA_DIR, else the source tree's data/, else the
/// install prefix. Throws InputError if none holds the default scene.
std::filesystem::path dataDirectory();
/// The embedded default scene's manifest.
std::filesystem::path defaultScene();
/// The bundled night-illuminant table.
std::filesystem::path defaultIlluminantTable();

}  // namespace solo
