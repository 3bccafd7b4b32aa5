#pragma once
// The sweeps of `solo bench accuracy` (docs/accuracy.md): on a scene with exact ground truth,
// each knob that trades accuracy for time is set to a series of values, every point is timed
// (wall seconds, median of repeats when one run is cheap) and measured against the truth:
//  - refine: Ceres L-BFGS iterations and function tolerance, Adam iterations, the filter alone
//    -> depth AbsRel and RMSE (m), mean and median angle (deg) of the depth's normals;
//  - mesh: hole filling on/off, fairing limit, foreground solids on/off -> distances to the
//    true box mesh (m), holes left open;
//  - render: samples per pixel, light sampler, adaptive noise target -> relative RMSE of the
//    luminance of non-emitting pixels against a converged render of the same scene;
//  - end to end: the pipeline of `solo night` at a few settings -> relative RMSE of the linear
//    render against a converged render of the scene made from the exact depth.
// Each sweep returns one table: a row per point, the seed in every row.

#include <solo/core/scene.h>
#include <solo/geometry/triangle_mesh.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace solo {

/// One CSV file: column names, rows of formatted cells (empty = not applicable), and notes
/// for the README (what a stage could not measure, and why).
struct SweepTable {
  std::string stage;  ///< "refine", "mesh", "render", "end_to_end": the file's stem
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> notes;

  /// Index of a column by name; throws std::out_of_range when there is none.
  std::size_t column(const std::string& name) const;
  /// The table as CSV text, header first.
  std::string csv() const;
};

struct AccuracySweepOptions {
  std::uint64_t seed = 1;     ///< lights, renders (the reference uses seed + kReferenceSeedOffset), surface sampling
  bool quick = false;         ///< fewer points, smaller samples: for tests and a first look
  int repeats = 3;            ///< timing runs of a point whose first run is cheap
  double cheap_seconds = 2;   ///< a point is run again only when one run took less than this
  int reference_spp = 256;    ///< samples per pixel of the converged reference renders
  std::int64_t distance_samples = 50000;  ///< surface points per direction for the mesh distances
  double input_seconds = 0;   ///< time of reading the scene, added to every end-to-end row
  std::filesystem::path illuminant_table;
  std::function<void(const std::string&)> progress;  ///< one line per point; may be empty
};

/// A scene with exact ground truth as the sweeps read it.
struct AccuracySweepInput {
  std::filesystem::path manifest, truth_manifest;  ///< the scene's and its ground truth's (groundTruthManifest)
  Scene scene, truth;
  TriangleMesh truth_mesh;   ///< <truth folder>/mesh.ply; empty when there is none
  double input_seconds = 0;  ///< reading the scene (its ground truth not counted)
};

/// Reads `manifest`, its ground truth and the true mesh beside it. Throws InputError when the
/// ground truth's depth or normals are not of the image's size.
AccuracySweepInput readAccuracySweepInput(const std::filesystem::path& manifest);

/// Seeds of the reference renders differ from the sweep's so that their noise is independent.
inline constexpr std::uint64_t kReferenceSeedOffset = 1000003;

/// Holds the scene and the products shared between the sweeps (the default refinement, mesh,
/// lights and night scene are made once, on first use).
class AccuracySweep {
 public:
  /// scene: the estimated inputs; truth: its ground-truth scene (exact depth and normals at the
  /// image resolution); truth_mesh: the true surfaces (may be empty: the mesh sweep then
  /// measures no distance and says so).
  AccuracySweep(Scene scene, Scene truth, TriangleMesh truth_mesh, AccuracySweepOptions options);
  ~AccuracySweep();
  AccuracySweep(const AccuracySweep&) = delete;
  AccuracySweep& operator=(const AccuracySweep&) = delete;

  SweepTable refine();
  SweepTable mesh();
  SweepTable render();
  SweepTable endToEnd();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// 1-minute load average of the machine (getloadavg), -1 when unknown.
double loadAverage1Min();

}  // namespace solo
