#pragma once
// Skirts: faces that close the image-space gaps a cleaned depth mesh leaves, so that every camera
// ray through a pixel with depth meets a face.
//
// The mesh has one vertex per pixel centre. Where a face spanning a depth edge is removed as
// spurious, nothing covers the strip between the foreground's last pixel centre and the
// background's first, unless a hole patch closes the background behind the occluder. An
// occlusion skirt replaces each removed face by a face over the same pixels at the background's
// depth: its far corners are the background's own vertices, its near corners copies of the
// foreground's vertices pushed back along their rays to the background's depth (the mean depth
// of the far corners one pixel away along an image axis, else of every far corner), and never
// nearer than kSkirtDepthMargin behind the foreground vertex or the back of its solid. So the
// background reaches under the foreground's edge. A skirt face is added only where it attaches
// to the mesh by an edge at every vertex that already has faces (no complex edge, no second fan
// at a vertex); where a hole patch already closes the background, its skirt is not added.
//
// A border skirt extends the mesh by half a pixel beyond every boundary edge along the image
// frame or the sky line (the outer half of those pixels; edges between pixel centres one pixel
// apart along an image axis), at the depth of each edge vertex, with a quarter-pixel patch at
// each frame corner.

#include "solo/geometry/depth_mesh.h"
#include "solo/geometry/spurious_faces.h"

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace solo {

/// Relative depth (fraction) by which a skirt's copied vertex stays behind the foreground
/// vertex it copies, and behind that vertex's solid back.
constexpr double kSkirtDepthMargin = 0.01;

/// The removed faces that skirts replace, recorded before they are deleted.
struct SkirtSources {
  std::vector<std::array<int, 3>> corners;  ///< vertex handle indices, in the face's order
  std::vector<std::uint8_t> near_corners;   ///< bit k: corner k is on the near (foreground) side
};

/// The spurious faces of `result` with their near and far corners. A face cut for its depth
/// splits at the larger of its two depth ratios (sorted corners); a face cut only as an
/// instance boundary splits by instance when it has two (the instance with the nearer corner is
/// the near side), else by depth. Call before the faces are deleted.
SkirtSources recordSkirtSources(const DepthMesh& mesh, const SpuriousFaceResult& result);

struct SkirtCounts {
  std::int64_t candidates = 0;       ///< removed faces whose far corners are still there
  std::int64_t faces = 0;            ///< occlusion skirt faces added
  std::int64_t vertices = 0;         ///< copied near vertices added
  std::int64_t not_attached = 0;     ///< candidates left out (region closed already, or no edge to attach by)
  std::int64_t frame_faces = 0;      ///< border skirt faces added
  std::int64_t frame_vertices = 0;   ///< border skirt vertices added
};

/// Adds the occlusion skirts of `sources` to the mesh, then the border skirt. New vertices are
/// VertexOrigin::Skirt with the pixel they project to (clamped to the map) and the instance
/// of the vertex they copy. Deterministic: faces are tried in the order of `sources`.
SkirtCounts addSkirts(DepthMesh& mesh, const SkirtSources& sources);

}  // namespace solo
