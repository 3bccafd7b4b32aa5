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

/// `solo eval ...`: where the results go besides (or instead of) the terminal table.
struct EvalOutputOptions {
  bool json = false;                       ///< print JSON on stdout instead of the table
  std::optional<std::filesystem::path> csv;  ///< append one row (header when the file is new)
};

struct EvalDepthOptions {
  std::filesystem::path prediction, ground_truth;
  std::optional<std::filesystem::path> mask;  ///< 8/16-bit or integer map, non-zero = evaluate
  std::optional<double> min_depth_m, max_depth_m;  ///< evaluate only min < gt < max
  bool median_scaling = false;
  bool clamp_prediction = false;  ///< clamp the prediction into the depth range after scaling
  double prediction_scale_m_per_unit = 0;    ///< for integer prediction files
  double ground_truth_scale_m_per_unit = 0;  ///< for integer ground-truth files
  EvalOutputOptions output;
};
int runEvalDepth(const EvalDepthOptions& options);

struct EvalNormalsOptions {
  std::filesystem::path prediction, ground_truth;
  std::optional<std::filesystem::path> mask;  ///< 8/16-bit or integer map, non-zero = evaluate
  EvalOutputOptions output;
};
int runEvalNormals(const EvalNormalsOptions& options);

struct EvalMeshOptions {
  std::filesystem::path mesh;
  std::optional<std::filesystem::path> reference;  ///< for the Hausdorff and Chamfer distances
  std::int64_t samples = 100000;  ///< random surface points per direction
  std::uint64_t seed = 0;         ///< seeds the surface sampling
  EvalOutputOptions output;
};
int runEvalMesh(const EvalMeshOptions& options);

struct SynthOptions {
  std::filesystem::path output;  ///< folder to create
  std::uint64_t seed = 1;
  int width = 960, height = 540;  ///< pixels
  std::string variant = "default";  ///< see streetVariantName
  bool force = false;               ///< replace an existing folder
};
int runSynth(const SynthOptions& options);

}  // namespace solo::tools
