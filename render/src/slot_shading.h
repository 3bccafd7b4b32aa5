#pragma once
// What the path tracer reads of the face a ray hit, kept by the ray caster's slot (the half of
// one of Embree's quads, RayCaster::slotTriangles) rather than by input triangle: both halves
// of a quad share one 64-byte cache line, so a hit costs one memory access where reading the
// face's normal, reflectance, roughness and emitter from their own arrays cost five (on the
// 5-million-triangle 1080p mesh, each one a cache miss). Private to the render module.

#include "solo/render/render_scene.h"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace solo {

/// A unit vector in two floats (octahedral mapping, Cigolle et al. 2014, "A Survey of
/// Efficient Representations for Independent Unit Vectors"); decoding error about 1e-7.
Eigen::Vector2f encodeOctahedral(const Eigen::Vector3f& unit);
inline Eigen::Vector3f decodeOctahedral(const Eigen::Vector2f& e) {
  Eigen::Vector3f n(e.x(), e.y(), 1.f - std::abs(e.x()) - std::abs(e.y()));
  if (n.z() < 0.f) {
    const float x = n.x();
    n.x() = (1.f - std::abs(n.y())) * (x >= 0.f ? 1.f : -1.f);
    n.y() = (1.f - std::abs(x)) * (n.y() >= 0.f ? 1.f : -1.f);
  }
  return n.normalized();
}

struct SlotShading {
  Eigen::Vector3f reflectance;  ///< XYZ, the face's
  float roughness;              ///< 0.5 where the scene has no roughness map
  Eigen::Vector2f normal;       ///< the face's unit geometric normal, octahedral
  std::int32_t emitter;         ///< index into RenderScene::emitters; -1 for none
  std::int32_t emissive;        ///< index into the emissive triangles (light samplers); -1 for none
};
static_assert(sizeof(SlotShading) == 32, "two slots per cache line");

struct alignas(64) QuadShading {
  SlotShading half[2];
};

/// One entry per quad of the caster: `slot_triangles` from RayCaster::slotTriangles,
/// `face_to_emissive` maps faces to emissive-triangle indices (-1 for none). A face of zero
/// area gets the normal +z (no ray can hit it).
std::vector<QuadShading> buildSlotShading(const RenderScene& scene, const std::vector<std::uint32_t>& slot_triangles,
                                          const std::vector<int>& face_to_emissive);

inline const SlotShading& slotShading(const std::vector<QuadShading>& table, std::uint32_t slot) {
  return table[slot >> 1].half[slot & 1u];
}

}  // namespace solo
