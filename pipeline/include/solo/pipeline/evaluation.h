#pragma once
// The evaluations of `solo eval depth|normals|mesh|scene` as a library (docs/evaluation.md):
// each reads its files, computes the metrics (solo_geometry) and returns one record
// (evaluation_record.h) whose fields are those the command prints. Bad input throws InputError
// naming the file.

#include <solo/pipeline/evaluation_record.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace solo {

/// A depth map against its ground truth, or a dataset of them: two folders (prediction and
/// ground truth, matched by file stem) or a list file of pairs.
struct DepthFilesEvaluationOptions {
  std::filesystem::path prediction, ground_truth;  ///< files, or folders; empty with `list`
  /// A text file, a line "PREDICTION GROUND_TRUTH [MASK]" per image (fields split at tabs when
  /// the line holds one, else at spaces; relative paths from the list's folder; # comments).
  std::optional<std::filesystem::path> list;
  /// 8/16-bit or integer map, non-zero = evaluate; for folders, a folder of masks by stem or
  /// one mask for every image.
  std::optional<std::filesystem::path> mask;
  std::optional<double> min_depth_m, max_depth_m;  ///< evaluate only min < gt < max
  bool median_scaling = false;
  bool clamp_prediction = false;  ///< clamp the prediction into the depth range after scaling
  double prediction_scale_m_per_unit = 0;    ///< for integer prediction files
  double ground_truth_scale_m_per_unit = 0;  ///< for integer ground-truth files
};

/// Throws InputError naming the option for a depth bound outside [0, 1e9] m ("--min-depth",
/// "--max-depth"), a minimum not below the maximum, a file scale outside [0, 1e6] m/unit
/// ("--pred-scale", "--gt-scale"; 0: none given), a list given with a prediction or ground
/// truth ("--list"), or neither ("--pred", "--gt").
void validateDepthFilesEvaluationOptions(const DepthFilesEvaluationOptions& options);

/// "eval depth": the pixel accounting and AbsRel, SqRel, RMSE, RMSElog, SILog, delta < 1.25^k.
/// Validates the options first (validateDepthFilesEvaluationOptions).
EvaluationRecord evaluateDepthFiles(const DepthFilesEvaluationOptions& options);

/// True when the options name a dataset: a list, or a prediction folder.
bool isDepthDataset(const DepthFilesEvaluationOptions& options);

/// A dataset's evaluation: each image on its own, then combined.
struct DepthDatasetEvaluation {
  /// "eval depth dataset": the counts (images, evaluated, failed, predictions without ground
  /// truth), the summed pixel accounting, each metric averaged over the images (mean_*) and
  /// computed over all their pixels at once (pooled_*); none when no image was evaluated.
  EvaluationRecord summary;
  /// One per pair, in order (folders: by ground-truth stem; list: by line): "image" and the
  /// files, the options, "error" (none when it was evaluated) and the metrics of evaluateDepthFiles.
  std::vector<EvaluationRecord> images;
  std::vector<std::string> failures;  ///< "<file>: <problem>" of each image that failed
};

/// "eval depth" over a dataset: every pair is evaluated (median scaling per image) and a pair
/// that cannot be (a file missing or unreadable, sizes that differ, no valid pixel) is recorded
/// with its error while the others go on. Throws InputError for bad options, an unreadable or
/// malformed list, or a ground-truth folder without depth files (.png .exr .tif .tiff .pfm .npy).
DepthDatasetEvaluation evaluateDepthDataset(const DepthFilesEvaluationOptions& options);

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
  /// F-score threshold, metres (mesh units); none: kDefaultFScoreTauFraction of the
  /// reference's bounding-box diagonal (mesh_metrics.h).
  std::optional<double> tau_m;
};

/// "eval mesh": topology, defects, triangle quality and, with a reference, the distances,
/// precision, recall and F-score (none without one). Throws InputError("--tau") for a
/// threshold outside (0, 1e9].
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
