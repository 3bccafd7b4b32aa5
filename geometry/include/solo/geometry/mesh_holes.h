#pragma once
// Closing holes of a SurfaceMesh: each hole (a closed loop of existing vertices) is filled in
// image space on a depth mesh (fillHoleInImage), else or failing that by fillHolePolyline with
// the full CGAL pipeline; every patch is then checked for intersections
// with the other patches and with the mesh (findIntersectingFaces). A patch that intersects, or
// that OpenMesh cannot attach, is replaced by the next simpler method (triangulation only, then
// a centroid fan); a hole no method can close safely is left open with a warning. On a general
// mesh (no pixels) a hole the CGAL methods cannot close gets fillLargeHole (membrane, chord
// splits) before the centroid fan.

#include "solo/geometry/boundary_loops.h"
#include "solo/geometry/hole_filling.h"
#include "solo/geometry/large_hole_filling.h"
#include "solo/geometry/surface_mesh.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace solo {

struct HoleClosing {
  std::int64_t holes = 0, filled = 0, left_open = 0;
  std::int64_t by_image_space = 0, by_refine_fair = 0, by_triangulation = 0, by_centroid_fan = 0;
  std::int64_t by_membrane = 0, by_chord_split = 0;  ///< fillLargeHole (general meshes)
  std::int64_t patches_rejected_for_intersection = 0;  ///< attempts that intersected and were replaced
  std::int64_t faces_added = 0, vertices_added = 0;
  std::int64_t largest_hole_vertices = 0;
  std::vector<std::string> warnings;                    ///< one per hole left open, with the reason
  std::vector<OpenMesh::FaceHandle> patch_faces;        ///< faces added
  /// Per hole (in the order given): the method that closed it ("refine_fair", "triangulation",
  /// "centroid_fan", "image_space", "membrane", "chord_split"), "backdrop" for a depth mesh's
  /// frame hole whose own patch was taken out and which a backdrop closes (mesh_cleanup.h), or
  /// "open".
  std::vector<std::string> hole_methods;
  /// Per hole (in the order given): the faces its patch added (empty for a hole left open; a
  /// general mesh's hole closed in pieces, or in the refill pass, lists them under patch_faces
  /// only).
  std::vector<std::vector<OpenMesh::FaceHandle>> hole_faces;
};

struct PixelMapping {
  ImageVertexProperties properties;
  PinholeCamera camera;  ///< of the depth map; new vertices get the pixel they project to
  int width = 0, height = 0;
  /// The depth mesh's vertex of each pixel (DepthMesh::vertex_of_pixel): patches are verified
  /// only against the faces around the pixels they project onto (every mesh face lies within
  /// its pixel quad, so one that meets a patch face has a corner within one pixel of the
  /// patch face's projection).
  const std::vector<int>* vertex_of_pixel = nullptr;
  /// Optional, per hole (DepthLoops::frame_paths): the pixels closing a frame hole along the
  /// image frame or the sky line (fillHoleInImage's closing path), empty for a hole closed by
  /// its own loop.
  const std::vector<std::vector<OpenMesh::Vec2i>>* frame_paths = nullptr;
  /// Optional, per hole (DepthLoops::path_after): where each frame_paths pixel goes in the
  /// polygon (after that loop index), for a hole joining several runs; empty: after the last.
  const std::vector<std::vector<int>>* frame_path_after = nullptr;
  /// Optional, per hole (DepthLoops::image_space_only): non-zero = no 3D fallback after the
  /// image-space fill (a large frame hole closed by its chord, on which every 3D patch fails).
  const std::vector<std::uint8_t>* image_space_only = nullptr;
  /// Optional, per hole (DepthLoops::backdrop): non-zero = fillHoleInImage in backdrop mode.
  const std::vector<std::uint8_t>* backdrop = nullptr;
  /// Optional (CV_32F, width x height, metres, 0 for none): the farthest surface at each pixel
  /// centre (farthestSurfaceDepth), which backdrops stay behind (ImageBackdrop's obstacles and
  /// where a surface is seen). Given for the backdrops' pass, after every other hole.
  const cv::Mat* farthest_surface_m = nullptr;
  /// Optional (CV_32F, width x height, metres, 0 for none): the depth observed where the mesh
  /// shows no surface (pixels whose faces were all removed: foliage, far fragments, depth-jump
  /// strips). A backdrop stays behind it too: where the removed surface was farther than the
  /// backdrop's extension (a far building cut into fragments), the backdrop follows it.
  const cv::Mat* observed_depth_m = nullptr;
};

/// The depth (metres) of the farthest live face of `mesh` along each pixel centre's ray
/// (`camera`, a width x height image; CV_32F, 0 where no face covers the centre): rasterized
/// in inverse depth, which is affine in the image over a planar triangle. `left_out`, when
/// given: per face index, non-zero for a face not counted (as if deleted).
cv::Mat farthestSurfaceDepth(const SurfaceMesh& mesh, const PinholeCamera& camera, int width, int height,
                             const std::vector<std::uint8_t>* left_out = nullptr);

/// Fills the holes (loops in border half-edge direction, see findBoundaryLoops). With `pixels`
/// (and options.image_space_first) every hole is first filled in image space (fillHoleInImage);
/// the 3D methods below are its fallbacks. Holes up to
/// options.max_triangulation_only_vertices boundary vertices start at the triangulation (no
/// refinement or fairing). Patches are computed in parallel. When `pixels` is given, new
/// vertices get their projected pixel (clamped to the map), origin hole_fill and the instance
/// most boundary vertices carry, and every face of the mesh must have its corners on pixels.
/// Without `pixels`, holes of more than options.max_triangulation_only_vertices that the CGAL
/// methods cannot close get fillLargeHole (when `large.enabled`) before the centroid fan.
HoleClosing closeHoles(SurfaceMesh& mesh, const std::vector<VertexLoop>& holes, const HoleFillOptions& options,
                       const std::optional<PixelMapping>& pixels = std::nullopt, const LargeHoleOptions& large = {});

}  // namespace solo
