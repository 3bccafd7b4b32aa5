#pragma once
// Boundary loops of a SurfaceMesh, and for a mesh made from a depth map, which of them are holes.
//
// A depth mesh is open along what the camera sees last: the image frame and the sky line (and
// invalid pixels). Those border loops are expected and stay open. What must be closed: holes
// behind removed occluders. In pixel space a loop that encloses its sheet (positive signed area
// in (u, v)) is an outer loop, one enclosed by it an inner loop. Edges whose two ends lie on the
// same side of the frame, or both next to a pixel without depth (sky, invalid), are border edges.
//  - inner loop without border edge: a hole behind an occluder -> filled;
//  - inner loop with border edges: sky seen through a gap -> stays open (sky_opening);
//  - outer loop with border edges: the border; each run of non-border edges lying behind a
//    nearer surface (an occluder touching the frame or the sky line) is a frame hole, closed
//    along the image frame, or along the sky line over the occluder's silhouette, or joined
//    with the runs of other sheets around the same occluder (paths along its outline between
//    them), or by the chord between its two ends, and filled (frame_hole); runs none of these
//    closes are chained into a backdrop, a patch behind everything seen in its region;
//  - outer loop without border edge: the outline of a floating sheet (silhouette); foreground
//    things are closed into solids, and so are floating sheets of other classes (slabs).

#include "solo/geometry/depth_mesh.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace solo {

using VertexLoop = std::vector<OpenMesh::VertexHandle>;

/// Every boundary loop, each listed in the direction of its border half-edges (a face lies to
/// the right when walking the loop on the camera-facing side). A loop through a pinched vertex
/// is split there, so no vertex appears twice in one loop.
std::vector<VertexLoop> findBoundaryLoops(const SurfaceMesh& mesh);

enum class LoopKind { Hole, SkyOpening, Border, Silhouette };
const char* loopKindName(LoopKind kind);

struct DepthLoops {
  std::vector<VertexLoop> loops;
  std::vector<LoopKind> kinds;
  std::vector<VertexLoop> holes;        ///< closed polylines to fill: inner holes and frame holes
  /// Per hole: for a frame hole closed along the image frame, the frame pixels (u, v) that
  /// close it, in order from the hole's last vertex to its first (both excluded; possibly none
  /// when the two ends are neighbouring pixels); for one closed along the sky line, the pixels
  /// of the occluder's outline against the sky (and the frame) that close it, in the same
  /// order; empty for the others (closed by a chord).
  std::vector<std::vector<OpenMesh::Vec2i>> frame_paths;
  /// Per hole: 1 for a frame hole closed by the chord between its ends (no frame path).
  std::vector<std::uint8_t> chord_closed;
  /// Per hole: 1 for a frame hole closed along the sky line (its frame_paths entry is that path).
  std::vector<std::uint8_t> sky_line_closed;
  std::int64_t inner_holes = 0, frame_holes = 0;
  std::int64_t border_loops = 0, sky_openings = 0, silhouettes = 0;
  /// Frame holes (counted in frame_holes, and in holes) closed along the sky line: no closing
  /// path along the frame, but the outline of the pixels with depth leads from their last vertex
  /// back to their first over nearer pixels only (an occluder rising into the sky); tried
  /// before the chord.
  std::int64_t frame_holes_sky_line = 0;
  /// Frame holes (counted in frame_holes, not in holes) that cannot be closed: no closing path
  /// along the frame (sky between their ends, or an end on the sky line), none along the sky
  /// line, and, closed by their chord, they enclose their own sheet. One note each.
  std::int64_t frame_holes_unclosable = 0;
  /// Per hole: for a frame hole joining the runs of several sheets around one occluder, the
  /// index in `holes[i]` of the vertex after which each pixel of frame_paths[i] goes (the
  /// paths between the runs); empty for the others (the whole path follows the last vertex).
  std::vector<std::vector<int>> path_after;
  /// Per hole: 1 for a frame hole joining several sheets' runs (no chord: it spans sheets).
  std::vector<std::uint8_t> merged;
  /// Frame holes (counted in frame_holes, and in holes) made of the runs of several sheets
  /// around one occluder, none closable alone, joined by paths along the occluder's outline
  /// over nearer pixels only (tried last, before the chord); and how many runs they hold.
  std::int64_t frame_holes_merged = 0, frame_hole_runs_merged = 0;
  /// Per hole: 1 for a frame hole closed as a backdrop (also 1 in `merged`: it may span sheets).
  std::vector<std::uint8_t> backdrop;
  /// Per hole: 1 for a frame hole, 0 for an inner hole.
  std::vector<std::uint8_t> frame_hole;
  /// Frame holes (counted in frame_holes, and in holes) closed as a backdrop: runs that no path
  /// over nearer pixels closes and whose chord encloses their own sheet (a patchwork of far
  /// sheets behind a band of occluders), chained as above with no depth condition along the
  /// outline of the pixels with depth until it comes back, alone or with others; the region
  /// inside is what lies behind everything seen there, and its patch is pinned behind every
  /// vertex inside (fillHoleInImage's backdrop mode). And how many runs they hold.
  std::int64_t frame_holes_backdrop = 0, frame_hole_runs_backdrop = 0;
  /// Runs closed by their chord that touch or cross it (no simple chord polygon), cut where they
  /// meet it; and the pieces turning the hole's way, each closed by its own chord (counted in
  /// frame_holes, and in holes). The pieces turning the loop's way lie on the sheet: border.
  std::int64_t frame_hole_runs_cut_at_chord = 0, frame_holes_chord_pieces = 0;
  std::vector<std::string> unclosable_notes;
};

/// Where a pixel path (a frame-hole run, at least two points) meets its chord, the segment from
/// its last point back to its first: index ranges [first, last] of the pieces between the
/// points where it touches the chord (a point on it) or crosses it (an edge whose ends lie on
/// opposite sides of the chord's line and that separates the chord's ends; cut at the edge's
/// end nearer the line). One range, the whole path, when it does not meet its chord: then its
/// chord polygon is simple. None for a path of fewer than two points.
std::vector<std::pair<std::size_t, std::size_t>> chordPieces(const std::vector<OpenMesh::Vec2i>& path);

/// How frame holes become backdrops: never (those a backdrop would close are reported
/// unclosable), those no other closing reaches, or every one (after the other closings failed).
enum class BackdropMode { Off, Unclosable, EveryFrameHole };

/// Classifies the loops of a depth mesh. `had_depth` (CV_8U, the depth map's size) marks the
/// pixels that had a vertex before any face was removed: its complement is sky and invalid depth.
/// `depth_m` is the map the mesh was made from.
DepthLoops classifyDepthLoops(const DepthMesh& mesh, const cv::Mat& had_depth, const cv::Mat& depth_m,
                              BackdropMode backdrops = BackdropMode::Unclosable);

}  // namespace solo
