#include "solo/render/render_scene.h"

#include <Eigen/Geometry>

#include <cmath>

namespace solo {

Eigen::Vector3f reflectanceFromLinearSrgb(const Eigen::Vector3f& rgb) {
  // IEC 61966-2-1 linear sRGB to XYZ (D65); its white (1,1,1) maps to the row sums.
  Eigen::Matrix3f m;
  m << 0.4124564f, 0.3575761f, 0.1804375f,  //
      0.2126729f, 0.7151522f, 0.0721750f,   //
      0.0193339f, 0.1191920f, 0.9503041f;
  const Eigen::Vector3f white = m.rowwise().sum();
  return (m * rgb).cwiseQuotient(white);
}

std::vector<RectangleLight> egoHeadlights(float luminance_y) {
  // Reference: Blender rotation (135 deg, +-18 deg, 0) of a light that points along its
  // local -Z, in Blender's world (x, z, -y) of the OpenCV camera frame. Rx(135) then Ry(+-18)
  // turns -Z into (sin(yaw) sin(135), sin(135), -cos(135) cos(yaw)) in Blender axes; back in
  // the OpenCV frame that is (x, y, z) = (Bx, -Bz, By).
  const float pitch = 135.f * 3.14159265f / 180.f;
  std::vector<RectangleLight> lights;
  for (const float side : {-1.f, 1.f}) {
    const float yaw = side * 18.f * 3.14159265f / 180.f;
    const Eigen::Vector3f blender(-std::cos(pitch) * std::sin(yaw), std::sin(pitch), -std::cos(pitch) * std::cos(yaw));
    const Eigen::Vector3f normal = Eigen::Vector3f(blender.x(), -blender.z(), blender.y()).normalized();
    RectangleLight light;
    light.centre = {side * 0.5f, 0.3f, 0.5f};
    light.normal = normal;
    const Eigen::Vector3f across = Eigen::Vector3f::UnitY().cross(normal).normalized();
    light.edge_u = across * 0.3f;
    light.edge_v = normal.cross(across).normalized() * 0.15f;
    // Reference colour RGB (0.5169, 0.4913, 0.3301) taken as linear sRGB, scaled to luminance Y.
    Eigen::Vector3f xyz = reflectanceFromLinearSrgb({0.5169f, 0.4913f, 0.3301f});
    light.radiance = xyz * (luminance_y / xyz.y());
    light.spread_rad = 125.f * 3.14159265f / 180.f;
    lights.push_back(light);
  }
  return lights;
}

}  // namespace solo
