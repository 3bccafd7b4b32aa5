#pragma once
// Private to the geometry library: the pixel centres a projected triangle covers, with the
// depth of the triangle there. Used where a mesh is rasterized in its depth map's pixels
// (farthestSurfaceDepth in mesh_holes.cpp, the surface behind a solid in foreground_solids.cpp).

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace solo::raster {

/// Calls visit(x, y, depth_m) for every pixel centre (x, y) of a width x height image inside
/// the triangle with image corners `uv` (pixels) and inverse depths `inverse_depth` (1/m, all
/// positive); a centre on an edge counts (tolerance 1e-9 in barycentric weight). The depth is
/// perspective-correct: inverse depth is affine in the image over a planar triangle.
/// Degenerate triangles (image area below 1e-12 square pixels) cover nothing.
template <class Visit>
void forEachCoveredPixelCentre(const Eigen::Vector2d (&uv)[3], const double (&inverse_depth)[3], int width,
                               int height, Visit&& visit) {
  const double area = (uv[1] - uv[0]).x() * (uv[2] - uv[0]).y() - (uv[1] - uv[0]).y() * (uv[2] - uv[0]).x();
  if (!(std::abs(area) > 1e-12)) return;
  const int x0 = std::max(0, static_cast<int>(std::ceil(std::min({uv[0].x(), uv[1].x(), uv[2].x()}))));
  const int x1 = std::min(width - 1, static_cast<int>(std::floor(std::max({uv[0].x(), uv[1].x(), uv[2].x()}))));
  const int y0 = std::max(0, static_cast<int>(std::ceil(std::min({uv[0].y(), uv[1].y(), uv[2].y()}))));
  const int y1 = std::min(height - 1, static_cast<int>(std::floor(std::max({uv[0].y(), uv[1].y(), uv[2].y()}))));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      double w[3];
      bool inside = true;
      for (int i = 0; i < 3 && inside; ++i) {
        const Eigen::Vector2d& a = uv[(i + 1) % 3];
        const Eigen::Vector2d& b = uv[(i + 2) % 3];
        w[i] = ((b - a).x() * (y - a.y()) - (b - a).y() * (x - a.x())) / area;
        inside = w[i] > -1e-9;
      }
      if (!inside) continue;
      const double s = w[0] * inverse_depth[0] + w[1] * inverse_depth[1] + w[2] * inverse_depth[2];
      if (s > 0) visit(x, y, 1.0 / s);
    }
}

}  // namespace solo::raster
