#pragma once
// Spurious faces of a depth mesh: faces that bridge an occlusion boundary (they are not part
// of any real surface, and would block light and cast false shadows). Four criteria, each
// counted on its own:
//  - depth jump: an edge whose depth difference exceeds `depth_jump_factor` pixel footprints
//    at the nearer depth (footprint = z / f metres per pixel, times the edge's length in
//    pixels), and which the surfaces on either side do not explain: the inverse depth of each
//    side, extrapolated linearly along the edge from the pixel behind it (a plane's inverse
//    depth is linear in u and v), does not meet the other side's within the edge or come within
//    `continuity_tolerance_footprints` of it (a crease such as a wall meeting the road does; an
//    occlusion does not), and whose sides are at least `min_step_m` apart (a window 6 cm proud
//    of a side facade jumps by metres in depth at grazing angles but is a 6 cm step). Without
//    the extrapolation a road seen at grazing angles would be cut wherever z / camera_height
//    exceeds the factor. The step is measured from the lines through each side's point and the
//    pixels one and two behind it (the latter only when those pixels sample one surface: a line
//    across a jump runs along the viewing rays and passes near everything beside them) and from
//    the planes of the 2x2 pixel blocks behind it (a tyre standing on the road is centimetres
//    from the road's plane but metres from its line along the edge). The line through a side's
//    point and the pixel one behind it does not count either when those two are no surface and
//    jump by more than `occluded_line_factor` footprints (it runs along the viewing rays).
//    Jumps between `small_jump_fraction` of the criterion and the criterion go through the same
//    tests and are cut when the step is also at least that many footprints (the 20 cm step
//    between the parts of a street-light head 26 m away is 6.9 footprints).
//    Where a side has no pixel behind it (frame, sky) only jumps over `edge_of_data_factor`
//    times the criterion are cut.
//  - grazing: the face normal is more than `grazing_angle_deg` from the viewing ray;
//  - uncertain: a vertex lies in the uncertain mask (depth refinement) and an edge between two
//    semantic classes jumps by more than `uncertain_jump_factor` pixel footprints (without the
//    extrapolation and step tests, which the unreliable depth there defeats), except inside one
//    thing instance whose depth span is at most `uncertain_same_object_span_m` (as the reference
//    implementation does);
//  - instance boundary: the vertices carry different instance ids and one of them is a
//    foreground thing (vehicle, person, pole, sign, traffic light), so that the thing becomes
//    a separate sheet that can be closed into a solid. This is a segmentation cut, not an
//    occlusion test: where a thing touches the ground (tyres on the road) it cuts faces that are
//    not spurious, so scores of the occlusion criteria are reported apart from it.
// Defaults were chosen by measurement on synthetic scenes (docs/mesh.md).

#include "solo/geometry/depth_mesh.h"

#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

namespace solo {

struct SpuriousFaceOptions {
  double depth_jump_factor = 8.0;       ///< pixel footprints at the nearer depth (MVE uses 5; 8 measured best)
  bool extrapolation_test = true;       ///< keep jumps the surfaces on either side explain (creases)
  double crossing_slack_edges = 0.5;    ///< the sides may meet this far (in edge lengths) outside the edge
  double continuity_tolerance_footprints = 2.0;  ///< sides closer than this (footprints) are continuous
  /// Where a side has no pixel behind it (image frame, sky) nothing can be extrapolated: there
  /// an edge is cut when its jump exceeds this many times depth_jump_factor footprints.
  double edge_of_data_factor = 4.0;
  /// Steps whose sides are closer than this (each point's distance from the other side's
  /// surface lines and block planes) are surface detail, not occlusions: metres.
  double min_step_m = 0.10;
  /// The step is also measured from the planes of the 2x2 pixel blocks behind each side (a
  /// line along the edge misses a thin face standing on a surface seen at a grazing angle): a
  /// block is a plane when its fourth point is within this many footprints of the plane of the
  /// other three (exact depth: 0.1 measured best, docs/mesh.md); 0 = lines only.
  double block_plane_tolerance_footprints = 0.1;
  /// The line through a side's point and the pixel two back counts only when those pixels
  /// sample one surface: within the footprint criterion, or inverse depth linear over three
  /// pixels to this fraction of its first step (0 on a plane, 1 for a jump onto a flat
  /// surface; 0.5 measured, docs/mesh.md).
  double surface_line_linearity = 0.5;
  /// Jumps of more than this fraction of depth_jump_factor footprints are tested too, and cut
  /// only when the step measured from the surfaces on either side is also at least that many
  /// footprints (and min_step_m): the 20 cm step between the parts of a street-light head
  /// 26 m away is 6.9 footprints. The step, not the depth difference, is what a grazing surface
  /// cannot fake. 0.5 measured; 0 = off (docs/mesh.md).
  double small_jump_fraction = 0.5;
  /// The line through a side's point and the pixel behind it does not count when those two
  /// pixels are no surface line (see surface_line_linearity) and jump by more than this many
  /// footprints: such a line runs along the viewing rays (a facade seen through a one-pixel gap
  /// beside a pole, the facade's next pixel 4 m nearer) and passes within centimetres of any
  /// point beside it. Smaller jumps keep the line (side facades whose pixels alternate between
  /// wall and window faces, 20-30 footprints: the line follows the facade). 64 measured (twice
  /// the edge-of-data threshold); 0 = the line always counts (docs/mesh.md).
  double occluded_line_factor = 64.0;
  /// With a normal map, the step is also measured from the plane through each side's point
  /// with its normal, where the two sides' normals agree within normal_plane_max_angle_deg: the
  /// windows of a facade seen at grazing, whose pixels alternate between window and wall faces
  /// that no line or 2x2 block of depths follows (docs/mesh.md).
  bool use_normals = true;
  double normal_plane_max_angle_deg = 30.0;
  double grazing_angle_deg = 90.0;      ///< 90 = criterion off; MeshLab's 75 cuts every road beyond 6 m
  bool use_uncertain_mask = true;
  double uncertain_same_object_span_m = 3.0;
  /// A face in the uncertain mask is removed only when one of its edges also jumps by more
  /// than this many pixel footprints (the footprint test alone): the mask by itself removed
  /// ~100 000 faces of the default scene's refined mesh that bridge nothing (docs/mesh.md).
  double uncertain_jump_factor = 8.0;
  /// The uncertain criterion also cuts edges inside one semantic class. Off: a road or facade
  /// seen at grazing inside the mask (10 px around every object's outline) changes depth by
  /// more than 8 footprints per pixel and is still one surface; cutting it left bands without
  /// a surface at the foot of every car (docs/mesh.md). Without an instance map every edge counts.
  bool uncertain_within_class = false;
  bool cut_instance_boundaries = true;
};

/// Bits of SpuriousFaceResult::criteria.
enum SpuriousCriterion : std::uint8_t {
  kDepthJump = 1,
  kGrazing = 2,
  kUncertain = 4,
  kInstanceBoundary = 8,
  kOcclusionCriteria = kDepthJump | kGrazing | kUncertain,  ///< what ground truth calls spurious
};

struct SpuriousFaceResult {
  std::vector<std::uint8_t> spurious;  ///< per face handle index: 1 = remove
  std::vector<std::uint8_t> criteria;  ///< per face handle index: the SpuriousCriterion bits that flag it
  std::int64_t faces_checked = 0;
  std::int64_t removed = 0;            ///< faces flagged by at least one criterion
  // Faces flagged by each criterion (a face may be flagged by several):
  std::int64_t by_depth_jump = 0, by_grazing = 0, by_uncertain = 0, by_instance_boundary = 0;
};

/// Flags the spurious faces of `mesh` (not deleted: see removeFlaggedFaces). depth_m is the map
/// the mesh was made from; instances (CV_32S) and uncertain (CV_8U, non-zero = uncertain) are of
/// the same size or empty (their criteria then flag nothing). normals (CV_32FC3 unit vectors,
/// camera frame, zero = unknown) of the same size or empty: the depth-jump criterion's step test
/// also uses them (SpuriousFaceOptions::use_normals). Throws std::invalid_argument for a normal
/// map of another type or size.
SpuriousFaceResult findSpuriousFaces(const DepthMesh& mesh, const cv::Mat& depth_m, const cv::Mat& instances,
                                     const cv::Mat& uncertain, const SpuriousFaceOptions& options = {},
                                     const cv::Mat& normals = {});

/// Ground truth of spuriousness from exact maps: a face is spurious when two of its vertices lie
/// on different true surfaces across a depth jump, i.e. the planes through them (true depth and
/// true normal at each pixel) do not meet between the two pixels (their inverse depths, linear
/// along the edge, do not cross within it) and are at least `min_gap_m` apart (each pixel's
/// point at least that far from the other pixel's plane). A crease
/// (a wall meeting the pavement) is not spurious; an occlusion is; a step thinner than the gap
/// (a window 6 cm proud of its facade) is surface detail. Faces on one plane never are.
/// Sub-pixel detail: an edge is not spurious either when the true points of its two pixels and
/// of the next pixel beyond each end along the edge lie within min_gap_m / 2 of one straight
/// line, sampled evenly (no step between them more than twice another). That is a surface
/// the depth map samples smoothly while each pixel hits a different face smaller than a pixel
/// (the 6 cm ends of a side facade's windows seen at grazing angles, 2.6 m apart): the per-pixel
/// planes are parallel and metres apart, the face follows the facade within centimetres.
std::vector<std::uint8_t> spuriousFacesFromGroundTruth(const DepthMesh& mesh, const cv::Mat& true_depth_m,
                                                       const cv::Mat& true_normals, double min_gap_m = 0.10);

/// Precision and recall of a removal against the truth (faces flagged in both, in either).
struct DetectionScore {
  std::int64_t true_positives = 0, false_positives = 0, false_negatives = 0;
  double precision = 1, recall = 1;  ///< 1 when there is nothing to find or nothing flagged
};
DetectionScore scoreDetection(const std::vector<std::uint8_t>& flagged, const std::vector<std::uint8_t>& truth);

/// Cityscapes classes that become closed solids: pole 17, traffic light 19, sign 20, person 24,
/// rider 25, car 26, truck 27, bus 28, train 31, motorcycle 32, bicycle 33.
bool isForegroundThingClass(int class_id);

}  // namespace solo
