#pragma once
// Closed form shared by the render tests: the irradiance a Lambertian rectangle of unit radiance
// gives a point below it.

#include <Eigen/Geometry>

#include <cmath>
#include <vector>

namespace solo::test {

/// int cos cos / r^2 dA over the rectangle [0, a] x [0, b] parallel to the receiver at height h,
/// with a corner right above the point (the form factor times pi); a or b negative for the
/// rectangle on the other side.
inline double cornerIntegral(double a, double b, double h) {
  const double A = std::abs(a) / h, B = std::abs(b) / h;
  const double f = 0.5 * (A / std::sqrt(1 + A * A) * std::atan(B / std::sqrt(1 + A * A)) +
                          B / std::sqrt(1 + B * B) * std::atan(A / std::sqrt(1 + B * B)));
  return (a < 0) != (b < 0) ? -f : f;
}

/// The same over [x0, x1] x [y0, y1] relative to the point: the irradiance under unit radiance.
inline double rectangleIntegral(double x0, double x1, double y0, double y1, double h) {
  return cornerIntegral(x1, y1, h) - cornerIntegral(x0, y1, h) - cornerIntegral(x1, y0, h) + cornerIntegral(x0, y0, h);
}

/// Lambert (1760): irradiance at `point` with unit normal n from a uniform polygon of unit
/// radiance wholly above its horizon: 1/2 sum over edges of the angle the edge subtends times
/// n . (unit normal of the plane through the point and the edge).
inline double polygonIrradiance(const Eigen::Vector3d& point, const Eigen::Vector3d& n, const std::vector<Eigen::Vector3d>& polygon) {
  double sum = 0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector3d v0 = (polygon[i] - point).normalized(), v1 = (polygon[(i + 1) % polygon.size()] - point).normalized();
    sum += std::atan2(v0.cross(v1).norm(), v0.dot(v1)) * n.dot(v0.cross(v1).normalized());
  }
  return 0.5 * std::abs(sum);
}

}  // namespace solo::test
