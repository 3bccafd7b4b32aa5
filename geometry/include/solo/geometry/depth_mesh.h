#pragma once
// Backprojection of a depth map into a triangle mesh: one vertex per valid pixel at
// x = d K^-1 (u, v, 1) (metres, camera frame), two triangles per pixel quad.
//
// Diagonal choice: a quad whose four corners are valid is split along the diagonal whose two
// ends are closer in inverse depth (|1/d00 - 1/d11| against |1/d10 - 1/d01|; ties take
// 00-11). Across a depth edge that cuts the quad corner-wise, this keeps one triangle wholly on
// one surface instead of two triangles both bridging the edge, and on a plane (where inverse
// depth is linear in u and v) it is the flatter split. A quad with exactly three valid corners
// gets the one triangle of those three, so silhouettes against the sky are not staircased.
// Triangles face the camera (their normal n has n . ray < 0).

#include "solo/core/camera.h"
#include "solo/geometry/surface_mesh.h"

#include <opencv2/core.hpp>

#include <vector>

namespace solo {

/// Cityscapes sky class: pixels of this class make no vertex even when they have a depth.
constexpr int kSkyClassId = 23;

struct DepthMesh {
  SurfaceMesh mesh;
  ImageVertexProperties properties;  ///< pixel, instance, origin of every vertex
  int width = 0, height = 0;         ///< depth-map size, pixels
  PinholeCamera camera;              ///< scaled to the depth map
  /// Vertex handle index of each pixel (row-major, v * width + u), -1 = no vertex.
  std::vector<int> vertex_of_pixel;
  /// Set by cleanDepthMesh (empty before): CV_8U of the depth map's size holding, at the pixel
  /// of every vertex of a face removed as spurious, that face's SpuriousCriterion bits (ORed);
  /// 0 elsewhere. For pictures of what was cut (the contact sheet).
  cv::Mat removed_spurious;
  /// Set by cleanDepthMesh (empty before): CV_8U of the depth map's size, 1 at every pixel that
  /// made a vertex before cleanup (depth, not sky), also where cleanup removed that vertex.
  cv::Mat had_depth;

  int vertexAt(int u, int v) const {
    return (u < 0 || v < 0 || u >= width || v >= height) ? -1 : vertex_of_pixel[static_cast<std::size_t>(v) * width + u];
  }
};

/// Builds the mesh. depth_m: CV_32F metres, 0 (or non-finite, or negative) = no vertex.
/// instances: CV_32S Cityscapes instanceIds of the same size, or empty (instance 0 for every
/// vertex); sky pixels (class 23) make no vertex. The camera is scaled to the depth map's size.
/// Throws std::invalid_argument for a depth map that is not CV_32F or an instance map of
/// another size.
DepthMesh meshFromDepth(const cv::Mat& depth_m, const PinholeCamera& camera, const cv::Mat& instances = {});

}  // namespace solo
