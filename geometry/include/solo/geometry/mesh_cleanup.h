#pragma once
// The mesh stage. From a depth map: backprojection, spurious-face removal, fragment and pinch
// removal, hole filling (inner holes and holes against the frame or sky line), foreground solids,
// and the quality counts of the result. From any triangle mesh: soup repair and hole filling.
// Each returns a StageReport with counts before and after, removals per criterion, holes found
// and filled, and the time of every step (docs/mesh.md lists every metric).

#include "solo/geometry/depth_mesh.h"
#include "solo/geometry/foreground_solids.h"
#include "solo/geometry/hole_filling.h"
#include "solo/geometry/large_hole_filling.h"
#include "solo/geometry/mesh_intersection_repair.h"
#include "solo/geometry/mesh_metrics.h"
#include "solo/core/report.h"
#include "solo/geometry/spurious_faces.h"

#include <opencv2/core.hpp>

namespace solo {

struct DepthMeshCleanupOptions {
  SpuriousFaceOptions spurious;
  std::int64_t min_fragment_faces = 64;  ///< smaller connected pieces are removed
  bool fill_holes = true;
  HoleFillOptions hole_filling;
  /// Close the frame holes no path over nearer pixels closes (a patchwork of far sheets behind
  /// a band of occluders) as a backdrop behind everything seen in their region
  /// (DepthLoops::backdrop); off: they stay open, reported unclosable.
  bool backdrops = true;
  bool close_solids = true;
  ForegroundSolidOptions solids;
  bool evaluate = true;  ///< run evaluateMesh on the result (self-intersections included)
};

/// Cleans a mesh made by meshFromDepth from `depth_m` in place and collects its garbage
/// (vertex_of_pixel is rebuilt). instances (CV_32S) and uncertain (CV_8U) are of the depth map's
/// size or empty. The report's name is "mesh". With `spurious_truth` (per face, from
/// spuriousFacesFromGroundTruth) the report adds the removal's precision and recall. normals
/// (CV_32FC3 camera frame, of the depth map's size, or empty) go to the spurious-face test.
StageReport cleanDepthMesh(DepthMesh& mesh, const cv::Mat& depth_m, const cv::Mat& instances,
                           const cv::Mat& uncertain, const DepthMeshCleanupOptions& options = {},
                           const std::vector<std::uint8_t>* spurious_truth = nullptr, const cv::Mat& normals = {});

/// The whole stage from a scene's maps: the instance map (when present) is resampled to the
/// depth map's size (nearest), the mesh is built at the depth map's resolution and cleaned.
/// `uncertain` (CV_8U, any size, or empty) and `normals` (the scene's normal map, CV_32FC3, any
/// size, or empty: the spurious-face test uses it) are resampled likewise. With exact maps of the
/// depth map's size (true_depth_m CV_32F, true_normals CV_32FC3), the spurious-face removal is
/// scored against them (spuriousFacesFromGroundTruth); otherwise a note says why it is not.
DepthMesh meshFromScene(const cv::Mat& depth_m, const PinholeCamera& camera, const cv::Mat& instances,
                        const cv::Mat& uncertain, const DepthMeshCleanupOptions& options, StageReport& report,
                        const cv::Mat& true_depth_m = {}, const cv::Mat& true_normals = {},
                        const cv::Mat& normals = {});

struct MeshCleanupOptions {
  bool fill_holes = true;
  HoleFillOptions hole_filling;
  LargeHoleOptions large_holes;  ///< the fallback for holes the CGAL methods cannot close
  bool repair_intersections = true;  ///< remove self-intersections after hole filling
  IntersectionRepairOptions intersection_repair;
  bool wrap = false;           ///< alpha-wrap the closed mesh instead of repairing its intersections
  bool wrap_fallback = true;   ///< alpha-wrap when the repaired mesh is still not closed (with fill_holes)
  WrapOptions wrapping;
  std::int64_t distance_samples = 20000;  ///< random points per direction for the input/output distances
  std::uint64_t distance_seed = 0;        ///< seeds that sampling
};

/// Repairs and closes an arbitrary triangle mesh: the soup repair of repairSoup, every boundary
/// loop filled (verified, with fallbacks), self-intersections removed (repairSelfIntersections),
/// and, with `wrap` or when the result is still not closed, its alpha wrap (wrapMesh). The
/// report counts what each step removed or changed, the distances between input and output
/// (fractions of the input's bounding-box diagonal) and says whether the output is closed
/// (watertight: no boundary, 2-manifold, no self-intersection, no degenerate face) or what
/// remains; a warning says when the wrap replaced a failed repair or a time limit was hit.
/// Throws InputError naming `source` for a mesh with a non-finite coordinate, a face index out
/// of range, or faces none of which has an area.
TriangleMesh cleanMesh(const TriangleMesh& input, const MeshCleanupOptions& options, StageReport& report,
                       const std::filesystem::path& source = "mesh");

/// Closed in the strict sense `solo mesh clean` prints: at least one face, no boundary edge, no
/// non-manifold edge or vertex, no self-intersecting pair, no degenerate face.
bool isWatertight(const MeshMetrics& metrics);

/// What keeps a mesh from being watertight ("2 boundary loops, 36 self-intersecting pairs"),
/// empty when it is.
std::string watertightDefects(const MeshMetrics& metrics);

/// Adds the counts of evaluateMesh to a report, each name prefixed ("before_", "after_");
/// "closed" is isWatertight.
void addMeshCounts(StageReport& report, const std::string& prefix, const MeshMetrics& metrics);

}  // namespace solo
