#pragma once
// The solo subcommands. Each takes an options struct that maps one to one onto its
// command-line flags (main.cpp is the only file that knows CLI11) and returns an exit code.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace solo::tools {

/// Folder of the bundled data: $SOLO_DATA_DIR, else the source tree's data/, else the
/// install prefix. Throws InputError if none holds the default scene.
std::filesystem::path dataDirectory();
/// The embedded default scene's manifest.
std::filesystem::path defaultScene();

/// Libraries solo was built against, name -> version (compile-time).
std::vector<std::pair<std::string, std::string>> dependencyVersions();
/// `solo --version`: solo's version and dependencyVersions().
std::string versionText();

struct InfoOptions {
  std::filesystem::path scene;
  bool json = false;
};
int runInfo(const InfoOptions& options);

struct NightOptions {
  std::optional<std::filesystem::path> scene;  ///< none: the embedded default scene
  std::filesystem::path output = "night.png";
  std::optional<std::filesystem::path> report;  ///< none: <output stem>.report.json
  std::uint64_t seed = 0;
};
int runNight(const NightOptions& options);

struct ConvertOptions {
  std::string kind = "depth";  ///< "depth" or "normals"
  std::filesystem::path input, output;
  double input_scale_m_per_unit = 0;    ///< for integer depth inputs
  double output_scale_m_per_unit = 1.0 / 256.0;  ///< for 16-bit PNG depth outputs
};
int runConvert(const ConvertOptions& options);

}  // namespace solo::tools
