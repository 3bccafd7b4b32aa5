#pragma once
// The evaluations of `solo eval depth|normals|mesh|scene` as a library (docs/evaluation.md):
// each reads its files, computes the metrics (solo_geometry) and returns one record
// (evaluation_record.h) whose fields are those the command prints. Bad input throws InputError
// naming the file.

#include <solo/pipeline/evaluation_record.h>

#include <cstdint>
#include <filesystem>
#include <optional>

namespace solo {

/// A depth map against its ground truth.
struct DepthFilesEvaluationOptions {
  std::filesystem::path prediction, ground_truth;
  std::optional<std::filesystem::path> mask;  ///< 8/16-bit or integer map, non-zero = evaluate
  std::optional<double> min_depth_m, max_depth_m;  ///< evaluate only min < gt < max
  bool median_scaling = false;
  bool clamp_prediction = false;  ///< clamp the prediction into the depth range after scaling
  double prediction_scale_m_per_unit = 0;    ///< for integer prediction files
  double ground_truth_scale_m_per_unit = 0;  ///< for integer ground-truth files
};

/// Throws InputError naming the option for a depth bound outside [0, 1e9] m ("--min-depth",
/// "--max-depth"), a minimum not below the maximum, or a file scale outside [0, 1e6] m/unit
/// ("--pred-scale", "--gt-scale"; 0: none given).
void validateDepthFilesEvaluationOptions(const DepthFilesEvaluationOptions& options);

/// "eval depth": the pixel accounting and AbsRel, SqRel, RMSE, RMSElog, delta < 1.25^k.
/// Validates the options first (validateDepthFilesEvaluationOptions).
EvaluationRecord evaluateDepthFiles(const DepthFilesEvaluationOptions& options);

/// A normal map against its ground truth.
struct NormalFilesEvaluationOptions {
  std::filesystem::path prediction, ground_truth;
  std::optional<std::filesystem::path> mask;  ///< 8/16-bit or integer map, non-zero = evaluate
};

/// "eval normals": the pixel accounting and the angular errors (mean, median, RMSE, shares).
EvaluationRecord evaluateNormalFiles(const NormalFilesEvaluationOptions& options);

/// A mesh, and optionally a reference surface to measure its distance to.
struct MeshFileEvaluationOptions {
  std::filesystem::path mesh;
  std::optional<std::filesystem::path> reference;  ///< for the Hausdorff and Chamfer distances
  std::int64_t samples = 100000;  ///< random surface points per direction
  std::uint64_t seed = 0;         ///< seeds the surface sampling
};

/// "eval mesh": topology, defects, triangle quality and, with a reference, the distances
/// (none without one).
EvaluationRecord evaluateMeshFile(const MeshFileEvaluationOptions& options);

/// A synthetic scene folder (`solo synth -o DIR`) and the outputs written into it.
struct SceneFolderEvaluationOptions {
  std::filesystem::path scene_dir;                ///< holds scene.json with "ground_truth"
  std::optional<std::filesystem::path> refined;   ///< none: <scene_dir>/refined.exr when present
  std::optional<std::filesystem::path> mesh;      ///< none: <scene_dir>/mesh.ply when present
  std::int64_t samples = 100000;  ///< random surface points per direction for the mesh distances
  std::uint64_t seed = 0;         ///< seeds the surface sampling
};

/// "eval scene": the estimated maps (upsampled to the image), the refined depth and its
/// normals, the spurious faces of the depth mesh and the mesh in the folder against the
/// scene's ground truth. A part whose input is missing keeps its fields, without values, and
/// a "..._skipped" field says why.
EvaluationRecord evaluateSceneFolder(const SceneFolderEvaluationOptions& options);

}  // namespace solo
