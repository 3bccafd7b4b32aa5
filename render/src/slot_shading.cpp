#include "slot_shading.h"

#include <Eigen/Geometry>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <stdexcept>

namespace solo {

Eigen::Vector2f encodeOctahedral(const Eigen::Vector3f& unit) {
  const float l1 = std::abs(unit.x()) + std::abs(unit.y()) + std::abs(unit.z());
  Eigen::Vector2f e(unit.x() / l1, unit.y() / l1);
  if (unit.z() < 0.f) {
    const float x = e.x();
    e.x() = (1.f - std::abs(e.y())) * (x >= 0.f ? 1.f : -1.f);
    e.y() = (1.f - std::abs(x)) * (e.y() >= 0.f ? 1.f : -1.f);
  }
  return e;
}

namespace {

// A slot's entry: its face's reflectance, roughness, normal (the shading normal where it
// has one) and lights.
void fillSlot(const RenderScene& scene, std::uint32_t face, int emissive, bool has_roughness, bool has_emitters,
              SlotShading& s) {
  const auto& f = scene.faces[face];
  // The normal in double: a sliver's cross product can underflow in single precision.
  const Eigen::Vector3d cross = (scene.vertices[f[1]] - scene.vertices[f[0]])
                                    .cast<double>()
                                    .cross((scene.vertices[f[2]] - scene.vertices[f[0]]).cast<double>());
  const double norm = cross.norm();
  Eigen::Vector3f normal = norm > 0 ? Eigen::Vector3f((cross / norm).cast<float>()) : Eigen::Vector3f::UnitZ();
  if (face < scene.face_shading_normal.size()) {
    const Eigen::Vector3f& shading = scene.face_shading_normal[face];
    const float length = shading.norm();
    if (std::isfinite(length) && length > 0.5f) normal = shading / length;
  }
  s.reflectance = scene.face_reflectance[face];
  s.roughness = has_roughness ? scene.face_roughness[face] : 0.5f;
  s.normal = encodeOctahedral(normal);
  s.emitter = has_emitters ? scene.face_emitter[face] : -1;
  s.emissive = emissive;
}

}  // namespace

std::vector<QuadShading> buildSlotShading(const RenderScene& scene, const std::vector<std::uint32_t>& slot_triangles,
                                          const std::vector<int>& face_to_emissive) {
  if (slot_triangles.size() % 2 != 0) throw std::invalid_argument("buildSlotShading: an odd slot count");
  for (const std::uint32_t face : slot_triangles)
    if (face >= scene.faces.size()) throw std::invalid_argument("buildSlotShading: a slot names no face");
  const bool has_roughness = !scene.face_roughness.empty();
  const bool has_emitters = !scene.face_emitter.empty();
  std::vector<QuadShading> table(slot_triangles.size() / 2);
  // Each slot reads only its face: the quads are filled in parallel.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, table.size()), [&](const tbb::blocked_range<std::size_t>& quads) {
    for (std::size_t quad = quads.begin(); quad != quads.end(); ++quad)
      for (std::size_t half = 0; half < 2; ++half) {
        const std::uint32_t face = slot_triangles[2 * quad + half];
        fillSlot(scene, face, face_to_emissive[face], has_roughness, has_emitters, table[quad].half[half]);
      }
  });
  return table;
}

}  // namespace solo
