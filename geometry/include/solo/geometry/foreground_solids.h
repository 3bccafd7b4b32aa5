#pragma once
// Foreground things (vehicles, people, poles, signs, traffic lights) seen in a depth map are
// sheets: only their front is known. Each connected sheet whose vertices are mostly of a thing
// class is closed into a solid: every vertex gets a back copy pushed away from the camera along
// its viewing ray by the class's thickness, back faces are the front faces reversed, and side
// walls (two triangles per border edge) join front and back along every boundary loop. The
// thickness is clamped so the back stays `clearance_m` in front of the surface behind it (the
// hole patches rasterised in the depth map's pixels, however close behind the front), never
// below `min_thickness_m` unless the surface behind is nearer than clearance plus minimum: then
// the back stays halfway to it (a thinner solid rather than one through the patch).
// Each solid is closed and consistently oriented. Its back is not checked against other geometry
// beyond the clamp: the final evaluation reports any self-intersection that remains.

#include "solo/geometry/depth_mesh.h"

#include <cstdint>
#include <string>
#include <vector>

namespace solo {

struct ForegroundSolidOptions {
  double min_thickness_m = 0.02;
  double clearance_m = 0.05;  ///< gap kept between a solid's back and the surface behind it
  /// A sheet of any other class whose outline touches neither the frame nor a pixel without
  /// depth (a piece of a far surface seen through a gap, its surroundings removed) is closed
  /// the same way with this thickness: its outline would be a boundary loop that is neither the
  /// frame nor the sky line. 0: left open.
  double floating_sheet_thickness_m = 0.2;
};

/// Plausible depth extent along the viewing ray of a thing of this Cityscapes class, metres
/// (0 for classes that do not become solids): person 0.5, rider 0.8, car 1.8, truck 2.5,
/// bus 2.5, train/tram 2.6, motorcycle 0.8, bicycle 0.6, pole 0.25, traffic light 0.35, sign 0.05.
double classThicknessM(int class_id);

struct SolidClosing {
  std::int64_t sheets = 0;           ///< components considered
  std::int64_t solids = 0;           ///< closed into solids
  std::int64_t faces_added = 0, vertices_added = 0;
  std::int64_t vertices_clamped = 0; ///< back vertices held in front of the surface behind
  std::int64_t floating_sheets = 0;  ///< of the solids, sheets of other classes closed as floating
  std::vector<std::string> classes;  ///< one "class:count" entry per class closed
};

/// Per component (`component`: faceComponents' numbering, `count` of them; the mesh before its
/// garbage collection): 1 for a floating sheet, one with a boundary none of whose vertices is on
/// the frame or beside a pixel that had no vertex.
std::vector<std::uint8_t> floatingSheets(const DepthMesh& mesh, const std::vector<int>& component, int count);

/// Closes the foreground sheets of `mesh` (before its garbage collection: the pixels that had
/// a vertex tell the frame and the sky apart). `background_faces` are the faces whose depth
/// limits the thickness (the hole patches).
SolidClosing closeForegroundSolids(DepthMesh& mesh, const std::vector<OpenMesh::FaceHandle>& background_faces,
                                   const ForegroundSolidOptions& options = {});

}  // namespace solo
