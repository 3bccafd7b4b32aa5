#pragma once
// Ray casting against a triangle mesh with Embree. The vertex buffer is shared with Embree, not
// copied: the caster owns it for its lifetime. Consecutive triangles that share an edge go to
// Embree as one quad (fewer primitives, faster traversal), in an index buffer the caster builds
// and owns instead of the triangles' (not kept); hits still name the input triangle and its
// barycentrics.

#include <Eigen/Core>

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace solo {

struct RayHit {
  bool hit = false;
  float distance = 0;                  ///< ray parameter t; metres for a unit direction
  std::uint32_t triangle = 0;          ///< index of the triangle hit
  Eigen::Vector3f geometric_normal{};  ///< unnormalised, (v1 - v0) x (v2 - v0)
  float u = 0, v = 0;                  ///< barycentrics of v1 and v2
};

/// A closest hit as Embree names it: the half of one of its quads, with no lookup of the input
/// triangle (on a large mesh that lookup is a cache miss per ray). Renderers that keep their
/// per-face data by slot (RayCaster::slotTriangles) read one place per hit instead of two.
struct SlotHit {
  bool hit = false;
  float distance = 0;      ///< ray parameter t; metres for a unit direction
  std::uint32_t slot = 0;  ///< 2 * quad + half, in [0, RayCaster::slotCount())
};

class RayCaster {
 public:
  /// vertices: x0 y0 z0 x1 y1 z1 ... (metres); triangles: i0 j0 k0 i1 j1 k1 ...
  /// Preconditions: sizes are multiples of 3, every index < vertex count.
  /// quality_high trades a slower build (about 4x) for faster traversal.
  RayCaster(std::vector<float> vertices, std::vector<std::uint32_t> triangles, bool quality_high = false);
  ~RayCaster();
  RayCaster(const RayCaster&) = delete;
  RayCaster& operator=(const RayCaster&) = delete;

  /// Closest hit along origin + t * direction for t in [t_near, t_far].
  RayHit intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_near = 0.f,
                   float t_far = std::numeric_limits<float>::infinity()) const;
  /// intersect() without the input triangle, its normal or barycentrics.
  SlotHit intersectSlot(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_near = 0.f,
                        float t_far = std::numeric_limits<float>::infinity()) const;
  /// Whether anything lies on the segment t in [t_near, t_far].
  bool occluded(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_near, float t_far) const;

  std::size_t triangleCount() const;
  /// Primitives in Embree's BVH: triangles that share an edge with the next one in the input
  /// (the two halves of a pixel quad) are handed over as one quad.
  std::size_t primitiveCount() const;
  /// 2 * primitiveCount(): the two halves of every quad.
  std::size_t slotCount() const { return 2 * primitiveCount(); }
  /// The input triangle in each slot. A quad that holds a single triangle names it in both
  /// halves, so that a hit on its degenerate half still finds the triangle's data.
  std::vector<std::uint32_t> slotTriangles() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Versions the render module was built against: Embree, TBB.
std::vector<std::pair<std::string, std::string>> renderDependencyVersions();

}  // namespace solo
