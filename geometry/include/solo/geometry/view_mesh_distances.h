#pragma once
// How far a mesh made from one view (a depth mesh) lies from the true surfaces, split the way
// its error arises: by face origin (depth surface, hole-fill patch, solid side or back) and by
// the distance from the camera, absolute (metres) and relative to that distance; and how much
// of the truly visible surface the mesh covers.
//
// Why the split: the area-weighted mean distance of measureMeshDistances is dominated by the
// farthest surfaces. A pixel at depth z covers an area growing as z^2 and a relative depth
// error e moves it by e z, so the pixels at z contribute as z^3: on the default synthetic
// street the 2.5 % of pixels beyond 160 m are a third of the refined mesh's area and 87 % of its
// 4.9 m mean distance (docs/accuracy.md). A mesh that lost its far surfaces (cut into
// fragments by the depth-jump criterion) looks far better by that one number. The relative
// distance d / z is what AbsRel is to depth, and the coverage says what a one-sided distance
// cannot: which true surfaces the mesh left out.
//
// Camera frame throughout (camera at the origin, +z forward, metres), as solo's meshes are.

#include "solo/core/camera.h"
#include "solo/geometry/surface_mesh.h"
#include "solo/geometry/triangle_mesh.h"

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace solo {

/// What made a face of a depth mesh: its vertices' VertexOrigin, a solid back vertex winning
/// over a hole-fill one (a solid's side wall joins a front and a back vertex).
enum class FaceOrigin : std::uint8_t { DepthSurface = 0, HoleFill = 1, Solid = 2 };
constexpr int kFaceOriginCount = 3;
const char* faceOriginName(FaceOrigin origin);  ///< "depth_surface", "hole_fill", "solid"

/// The origin of every live face, in the order of toTriangleMesh(mesh). Faces of a mesh without
/// image properties (or of `input` vertices) are depth_surface.
std::vector<FaceOrigin> faceOrigins(const SurfaceMesh& mesh);

struct ViewMeshDistanceOptions {
  std::int64_t samples = 100000;  ///< random points on the mesh (area-uniform), and at most this many true pixels
  std::uint64_t seed = 0;         ///< seeds both samplings (std::mt19937_64)
  /// Upper edges of the depth bands, metres, increasing; the last band is open-ended.
  std::vector<double> depth_band_edges_m = {10, 20, 40, 80, 160};
  /// A true pixel is covered when the mesh passes within this fraction of its depth.
  double covered_relative = 0.05;
};

/// The mesh -> truth distance of one part of the mesh (an origin or a depth band).
struct DistancePart {
  double area_m2 = 0;             ///< area of the part's faces
  double area_share = 0;          ///< of the whole mesh's area
  std::int64_t samples = 0;       ///< random points that fell on it
  double mean_m = 0;              ///< mean d(x, truth) over those points (0 without points)
  double mean_relative = 0;       ///< mean d(x, truth) / z(x) over them
  double contribution_m = 0;      ///< its share of the whole mean: sum of its d / all samples
};

struct ViewMeshDistances {
  double area_m2 = 0;
  std::int64_t samples = 0;
  double mean_to_truth_m = 0;        ///< area-weighted mean d(x, truth), as measureMeshDistances' mean_to_reference
  double mean_relative_to_truth = 0; ///< area-weighted mean of d(x, truth) / z(x)
  std::array<DistancePart, kFaceOriginCount> by_origin;
  std::vector<DistancePart> by_depth;  ///< one per band of options.depth_band_edges_m (edges + 1 bands)
  /// From the true visible surface (pixels with a true depth, sky and invalid left out; a
  /// seeded random subset when there are more than options.samples): the point p at the true
  /// depth of the pixel centre, its distance to the mesh relative to its depth.
  std::int64_t truth_pixels = 0;               ///< true pixels measured
  double truth_mean_relative_to_mesh = 0;      ///< mean d(p, mesh) / z(p)
  double truth_covered = 0;                    ///< fraction with d(p, mesh) / z(p) < covered_relative
  std::vector<double> truth_covered_by_depth;  ///< the same per depth band (0 for a band without pixels)
  std::vector<std::int64_t> truth_pixels_by_depth;
};

/// Measures `mesh` (camera frame, metres) against the true surfaces `truth` (the scene's exact
/// mesh) and the true depth map (CV_32F metres, 0 or non-finite = no surface; may be empty:
/// then the truth_* fields stay 0) seen through `camera` (scaled to the depth map here).
/// face_origin: one per face of `mesh`, or empty (every face a depth surface). Degenerate faces
/// (zero area) are never sampled. Throws std::invalid_argument for a mesh or truth without area,
/// a face_origin of another length, samples < 1 or unsorted band edges.
ViewMeshDistances measureViewMeshDistances(const TriangleMesh& mesh, const std::vector<FaceOrigin>& face_origin,
                                           const TriangleMesh& truth, const cv::Mat& true_depth_m,
                                           const PinholeCamera& camera, const ViewMeshDistanceOptions& options = {});

}  // namespace solo
