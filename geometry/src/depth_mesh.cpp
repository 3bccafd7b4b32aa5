#include "solo/geometry/depth_mesh.h"

#include "solo/core/scene.h"

#include <cmath>
#include <stdexcept>

namespace solo {
namespace {

// A grid of n pixels has about n vertices, 3n edges and 2n faces; room is kept for half as many
// again (in halves of a pixel's share).
constexpr std::size_t kReservedVertexHalvesPerPixel = 3;
constexpr std::size_t kReservedEdgeHalvesPerPixel = 9;
constexpr std::size_t kReservedFaceHalvesPerPixel = 6;

}  // namespace

DepthMesh meshFromDepth(const cv::Mat& depth_m, const PinholeCamera& camera, const cv::Mat& instances) {
  if (depth_m.type() != CV_32F) throw std::invalid_argument("meshFromDepth: depth must be CV_32F");
  if (!instances.empty() && (instances.type() != CV_32S || instances.size() != depth_m.size()))
    throw std::invalid_argument("meshFromDepth: instance map must be CV_32S of the depth map's size");
  DepthMesh out;
  out.width = depth_m.cols;
  out.height = depth_m.rows;
  out.camera = camera.scaledTo(out.width, out.height);
  out.properties = ImageVertexProperties::getOrAdd(out.mesh);
  out.vertex_of_pixel.assign(static_cast<std::size_t>(out.width) * out.height, -1);
  SurfaceMesh& mesh = out.mesh;
  // Room for the grid and for what the cleanup adds (hole patches, closed solids: a solid's back
  // and walls can double a sheet), so that no array is copied to grow. Reserved pages that are
  // never written cost address space only.
  const std::size_t pixels = out.vertex_of_pixel.size();
  mesh.reserve(pixels * kReservedVertexHalvesPerPixel / 2, pixels * kReservedEdgeHalvesPerPixel / 2,
               pixels * kReservedFaceHalvesPerPixel / 2);

  for (int v = 0; v < out.height; ++v) {
    const float* d = depth_m.ptr<float>(v);
    const int* id = instances.empty() ? nullptr : instances.ptr<int>(v);
    for (int u = 0; u < out.width; ++u) {
      const float z = d[u];
      if (!(z > 0.0f) || !std::isfinite(z)) continue;
      const int instance = id ? id[u] : 0;
      if (id && cityscapesClassOfInstance(instance) == kSkyClassId) continue;
      const Eigen::Vector3d p = out.camera.backproject(u, v, z);
      const auto vh = mesh.add_vertex(SurfaceMesh::Point(p.x(), p.y(), p.z()));
      mesh.property(out.properties.pixel, vh) = OpenMesh::Vec2i(u, v);
      mesh.property(out.properties.instance, vh) = instance;
      mesh.property(out.properties.origin, vh) = static_cast<std::uint8_t>(VertexOrigin::Pixel);
      out.vertex_of_pixel[static_cast<std::size_t>(v) * out.width + u] = vh.idx();
    }
  }

  const auto handle = [](int i) { return OpenMesh::VertexHandle(i); };
  const auto inverse = [&](int u, int v) { return 1.0 / depth_m.at<float>(v, u); };
  for (int v = 0; v + 1 < out.height; ++v) {
    for (int u = 0; u + 1 < out.width; ++u) {
      const int a = out.vertexAt(u, v), b = out.vertexAt(u + 1, v);
      const int c = out.vertexAt(u, v + 1), d = out.vertexAt(u + 1, v + 1);
      const int valid = (a >= 0) + (b >= 0) + (c >= 0) + (d >= 0);
      if (valid < 3) continue;
      // Corners in camera-facing cyclic order: a (u,v), c (u,v+1), d (u+1,v+1), b (u+1,v).
      if (valid == 4) {
        const double along_ad = std::abs(inverse(u, v) - inverse(u + 1, v + 1));
        const double along_bc = std::abs(inverse(u + 1, v) - inverse(u, v + 1));
        if (along_ad <= along_bc) {
          mesh.add_face(handle(a), handle(c), handle(d));
          mesh.add_face(handle(a), handle(d), handle(b));
        } else {
          mesh.add_face(handle(a), handle(c), handle(b));
          mesh.add_face(handle(b), handle(c), handle(d));
        }
        continue;
      }
      int ring[4] = {a, c, d, b};
      int corners[3], n = 0;
      for (int k = 0; k < 4; ++k)
        if (ring[k] >= 0) corners[n++] = ring[k];
      mesh.add_face(handle(corners[0]), handle(corners[1]), handle(corners[2]));
    }
  }
  return out;
}

}  // namespace solo
