#pragma once
// Connectivity clean-up of a SurfaceMesh after faces were deleted: tiny disconnected fragments
// (flying pixels, slivers cut off by spurious-face removal) and pinched vertices (a vertex whose
// faces form several fans, joined at the vertex only).

#include "solo/geometry/surface_mesh.h"

#include <cstdint>
#include <vector>

namespace solo {

/// Connected components of the live faces (through shared edges): component id per face handle
/// index (-1 for deleted faces) and the number of components.
std::vector<int> faceComponents(const SurfaceMesh& mesh, int* component_count = nullptr);

struct FragmentRemoval {
  std::int64_t components_before = 0, components_removed = 0, faces_removed = 0;
};

/// Deletes every component with fewer than `min_faces` faces (isolated vertices go too).
/// Needs the status attributes; does not collect garbage.
FragmentRemoval removeSmallComponents(SurfaceMesh& mesh, std::int64_t min_faces);

struct PinchResolution {
  std::int64_t pinched_vertices = 0, faces_removed = 0;
};

/// Makes every vertex manifold by deleting, at each pinched vertex, the faces of all fans but
/// the largest (repeated until none is left, at most `max_passes` times).
PinchResolution resolvePinchedVertices(SurfaceMesh& mesh, int max_passes = 8);

}  // namespace solo
