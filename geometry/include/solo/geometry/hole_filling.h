#pragma once
// Filling one hole given as a closed polyline, with CGAL Polygon Mesh Processing: triangulation
// (2D constrained Delaunay when the boundary is near planar, else Liepa's minimum-weight
// triangulation over the 3D Delaunay search space, the exhaustive O(n^3) search only for small
// holes), then refinement to the boundary's edge density and bi-Laplacian fairing of the new
// vertices (boundary fixed). Every call is guarded: a deadline checked by a CGAL visitor, CGAL
// exceptions caught, the result checked for completeness. The caller verifies the patch against
// the mesh (findIntersectingFaces) and falls back to a simpler method. Units: those of the points.
// For depth meshes, fillHoleInImage triangulates the hole in image space instead (see there).

#include "solo/core/camera.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace solo {

enum class HoleFillMethod {
  ImageSpace,             ///< depth meshes: triangulated in pixel space, lifted (fillHoleInImage)
  TriangulateRefineFair,  ///< the full CGAL pipeline
  Triangulate,            ///< the triangulation only (no new vertex): the first fallback
  CentroidFan,            ///< one new vertex at the boundary's centroid: the last fallback
};
const char* holeFillMethodName(HoleFillMethod method);

struct HoleFillOptions {
  double density_control_factor = 1.41421356237309504880;  ///< CGAL refine's default (sqrt 2)
  int fairing_continuity = 1;                 ///< 0: C0, 1: tangent (CGAL's default), 2: curvature
  double time_limit_s = 10.0;                 ///< per hole and method, checked between CGAL steps
  int max_cubic_boundary_vertices = 300;      ///< exhaustive search only for holes this small
  /// Patches whose refinement would add more vertices than this (estimated from the
  /// triangulation's area and the boundary's mean edge length) keep the triangulation alone:
  /// the sparse LU of the fairing grows faster than linearly.
  int max_fair_vertices = 10000;
  /// Holes with at most this many boundary vertices (one or two missing pixel quads) get the
  /// triangulation only: refining them adds next to nothing and costs a CGAL mesh per hole.
  int max_triangulation_only_vertices = 6;
  /// Depth meshes: try fillHoleInImage before the 3D methods.
  bool image_space_first = true;
  /// fillHoleInImage: at most this many interior vertices (the pixel grid is thinned to fit).
  int max_image_interior_vertices = 20000;
};

/// A patch: triangles over the boundary points (indices 0..n-1) and new points (index n + k is
/// new_points[k]). Oriented so that the boundary edge (i -> i+1) appears as (i -> i+1): the
/// polyline must run in the direction of the mesh's border half-edges, which the patch takes over.
struct HolePatch {
  std::vector<Eigen::Vector3d> new_points;
  std::vector<std::array<int, 3>> faces;
  bool filled = false;
  std::string failure;  ///< why nothing was produced
  bool faired = false;  ///< fairing ran and succeeded
  /// The triangulation itself failed (so a triangulation-only retry would fail the same way).
  bool triangulation_failed = false;
};

/// Fills the closed polyline `boundary` (first point not repeated) with `method`. Never throws
/// for geometric reasons: a failure leaves `filled` false with the reason.
HolePatch fillHolePolyline(const std::vector<Eigen::Vector3d>& boundary, HoleFillMethod method,
                           const HoleFillOptions& options = {});

/// What the backdrop mode of fillHoleInImage (its `backdrop` argument) asks of the depth mesh.
struct ImageBackdrop {
  /// Whether the mesh has an edge between the vertices of pixels (u0, v0) and (u1, v1).
  std::function<bool(int u0, int v0, int u1, int v1)> mesh_has_edge;
  /// The depth (metres) the patch must stay behind within radius_px of pixel (u, v) (the
  /// farthest surface seen there plus a clearance); 0 for none.
  std::function<double(int u, int v, int radius_px)> obstacle_within_m;
  /// Whether a surface of the mesh is seen at pixel (u, v) (the patch is hidden there); unset:
  /// wherever obstacle_within_m(u, v, 0) is positive.
  std::function<bool(int u, int v)> surface_seen;
  int hidden_spacing_px = 4;
};

/// Fills a hole of a depth mesh in image space. `boundary`: camera-frame points (metres, z > 0)
/// of the hole's loop in border half-edge order; their projections through `camera` form the
/// hole's polygon (pixels). A simple polygon is triangulated by a constrained Delaunay
/// triangulation with interior vertices at the pixel centres inside it that are about 2 pixels
/// or more from its edges (every k-th pixel in both axes, k the smallest that keeps at most
/// options.max_image_interior_vertices); their inverse depth is the discrete harmonic
/// (cotangent-weight) interpolation of the boundary's inverse depth, which reproduces any plane
/// exactly. Each triangle's 3D corners project onto its 2D
/// corners, so the patch covers exactly the hole's image region, where the depth mesh has no face.
/// `obstacle_depth_m(u, v)` (optional): the depth (metres) behind which the patch must stay at
/// pixel (u, v), 0 for none (the occluder in front of the hole); an interior vertex whose
/// harmonic depth comes in front of it is pinned there and the others are solved again.
/// Fails (filled false, with the reason) when a point is behind the camera or the polygon is
/// not simple: touching itself (two vertices at one position, a vertex on an edge) it has no
/// triangulation in the image without a degenerate triangle; crossing itself, none without
/// overlap. Loops through one vertex twice are split by findBoundaryLoops, so pinched holes of
/// a depth mesh arrive here as separate simple polygons.
///
/// `closing_path_px` (optional; a frame hole of a depth mesh): pixel positions closing the
/// polygon from the last boundary point back to the first along the image frame, or along the
/// sky line over an occluder's outline (DepthLoops::frame_paths). They become
/// new points (new_points[0..size-1], in order; the interior vertices follow) whose inverse
/// depth is free, extended like the interior's: the boundary's least-squares affine inverse
/// depth (a plane stays exact) plus the harmonic extension of the residual, with no flux across
/// the closing path; they are pinned behind obstacles too. The patch's edges along the path
/// have no face beyond them (the frame, the sky). Fails when the extension is not in front of the camera,
/// or when more than 5 % of the unknown vertices whose pixel holds an obstacle see it more than
/// 10 % behind the extension (a farther surface is seen there: the region is not behind an
/// occluder, and a patch pinned behind that surface would be a wall nobody sees).
/// `closing_path_after` (optional, one per closing-path point, non-decreasing): the boundary
/// index each point follows in the polygon, so that the path may come in several pieces
/// between known runs (a hole joining several sheets' runs); empty: all after the last.
/// `backdrop` (a frame hole closed as a backdrop, DepthLoops::backdrop): the region is what
/// lies behind everything seen in it, so farther surfaces inside are expected (no 5 % rule).
/// Every vertex is pinned behind every surface within the reach of its faces
/// (obstacle_within_m at the length of its longest edge plus a pixel), so no patch face passes
/// in front of a mesh surface. Interior vertices: every pixel centre within about 1.5 pixels of
/// an edge between two boundary points (where the patch meets the mesh at the runs) and
/// wherever no surface is seen (the visible part), every hidden_spacing_px-th elsewhere; in each pixel quad with all four
/// corners the patch takes the mesh's diagonal, where it has one (two halves split differently
/// overlap, and a patch face beside a run vertex would cross a farther mesh face). The
/// extension has no affine part (over a region this large the boundary's plane may reach
/// behind the camera): the inverse depth is harmonic with the run's values and no flux across
/// the path, so it stays within their range (one solve), then clamped behind the obstacles.
HolePatch fillHoleInImage(const std::vector<Eigen::Vector3d>& boundary, const PinholeCamera& camera,
                          const HoleFillOptions& options = {},
                          const std::function<double(int, int)>& obstacle_depth_m = {},
                          const std::vector<Eigen::Vector2d>& closing_path_px = {},
                          const std::vector<int>& closing_path_after = {}, const ImageBackdrop* backdrop = nullptr);

/// For each face of `candidates`, whether it intersects a face of `candidates` or of `others`
/// other than in what they share by index (the rules of evaluateMesh: no shared vertex, any
/// contact; a shared vertex, the opposite edge of one meets the other; a shared edge, coplanar
/// and folded onto the same side). Faces index into `points`; degenerate faces are skipped.
/// candidate_group: empty, or one id per candidate. Candidates that share an id >= 0 are known
/// not to meet one another (the faces of one image-space patch lie over disjoint triangles of
/// the image) and are not tested against each other, only against the other groups, the
/// ungrouped candidates (-1) and `others`; the result is that of the ungrouped test whenever
/// that holds.
std::vector<std::uint8_t> findIntersectingFaces(const std::vector<Eigen::Vector3d>& points,
                                                const std::vector<std::array<int, 3>>& candidates,
                                                const std::vector<std::array<int, 3>>& others,
                                                bool candidates_among_themselves = true,
                                                const std::vector<int>& candidate_group = {});

/// The same rule for one pair of faces (indices into `points`); false when either is degenerate.
bool patchFacesIntersect(const std::vector<Eigen::Vector3d>& points, const std::array<int, 3>& a,
                         const std::array<int, 3>& b);

}  // namespace solo
